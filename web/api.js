// The API page: renders /api/v1/openapi.json (no build step, no library): each operation by tag
// with its parameters, body and answers, and every schema, linked by name.
'use strict';

const el = (tag, attrs = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  for (const c of children) e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  return e;
};

// A schema reference as a link to its section, or a short type.
function schemaLabel(schema) {
  if (!schema) return '';
  if (schema.$ref) {
    const name = schema.$ref.split('/').pop();
    return el('a', { href: '#schema-' + name }, name);
  }
  if (schema.type === 'array' && schema.items) return el('span', {}, 'array of ', schemaLabel(schema.items));
  if (schema.enum) return schema.enum.join(' | ');
  return schema.type || '';
}

function parameterTable(doc, parameters) {
  const rows = parameters.map((p) => (p.$ref ? doc.components.parameters[p.$ref.split('/').pop()] : p));
  const table = el('table', {}, el('tr', {}, el('th', {}, 'name'), el('th', {}, 'in'), el('th', {}, 'schema'), el('th', {}, 'description')));
  for (const p of rows)
    table.append(el('tr', {}, el('td', {}, p.name + (p.required ? ' *' : '')), el('td', {}, p.in), el('td', {}, schemaLabel(p.schema)),
                    el('td', {}, p.description || '')));
  return table;
}

function contentTypes(content) {
  const span = el('span');
  for (const [type, media] of Object.entries(content || {})) span.append(el('code', {}, type), ' ', schemaLabel(media.schema), ' ');
  return span;
}

function operation(doc, path, method, op) {
  const body = el('div', { class: 'body' });
  if (op.parameters) body.append(el('h4', {}, 'Parameters'), parameterTable(doc, op.parameters));
  if (op.requestBody) body.append(el('h4', {}, 'Body'), contentTypes(op.requestBody.content), op.requestBody.description || '');
  const answers = el('table', {}, el('tr', {}, el('th', {}, 'status'), el('th', {}, 'answer')));
  for (const [status, r] of Object.entries(op.responses)) {
    const response = r.$ref ? doc.components.responses[r.$ref.split('/').pop()] : r;
    answers.append(el('tr', {}, el('td', {}, status), el('td', {}, response.description || '', ' ', contentTypes(response.content))));
  }
  body.append(el('h4', {}, 'Answers'), answers);
  const details = el('details', { class: 'op m-' + method, id: op.operationId },
                     el('summary', {}, el('span', { class: 'method' }, method), el('span', { class: 'path' }, path), el('span', { class: 'muted' }, op.summary || '')),
                     body);
  return details;
}

(async () => {
  const doc = await (await fetch('api/v1/openapi.json')).json();
  document.getElementById('api-intro').textContent = doc.info.description;
  const byTag = new Map((doc.tags || []).map((t) => [t.name, []]));
  for (const [path, item] of Object.entries(doc.paths))
    for (const [method, op] of Object.entries(item)) {
      const tag = (op.tags || ['other'])[0];
      if (!byTag.has(tag)) byTag.set(tag, []);
      byTag.get(tag).push([path, method, op]);
    }
  const toc = document.getElementById('api-toc'), ops = document.getElementById('api-operations');
  for (const [tag, list] of byTag) {
    toc.append(el('a', { href: '#tag-' + tag }, tag));
    ops.append(el('h2', { id: 'tag-' + tag }, tag));
    for (const [path, method, op] of list) ops.append(operation(doc, path, method, op));
  }
  toc.append(el('a', { href: '#schemas' }, 'schemas'));
  const schemas = document.getElementById('api-schemas');
  for (const [name, schema] of Object.entries(doc.components.schemas))
    schemas.append(el('details', { id: 'schema-' + name }, el('summary', {}, name, ' ', el('span', { class: 'muted' }, schema.description || '')),
                      el('pre', {}, JSON.stringify(schema, null, 2))));
  // A link to a schema or an operation opens it.
  const reveal = () => {
    const target = location.hash && document.getElementById(decodeURIComponent(location.hash.slice(1)));
    if (target && target.tagName === 'DETAILS') target.open = true;
    target?.scrollIntoView();
  };
  window.addEventListener('hashchange', reveal);
  reveal();
})().catch((e) => { document.getElementById('api-intro').textContent = 'Could not load the description: ' + e; });
