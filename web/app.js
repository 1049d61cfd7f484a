// volstyle painting page: talks only to /api/v1 (docs/API.md). No build step.
'use strict';

const api = '/api/v1';
const $ = (id) => document.getElementById(id);
const state = {
  sid: null, version: 1,
  orbit: { azimuth: 0, elevation: 0.06, distance: 3.4 }, target: [0, -0.05, 0],
  views: [], selected: null, job: null, events: null, objectives: [], maxIterations: 30,
};

// The status line, and its recent history with the requests still in flight: what a bug report
// (or a browser test that waited in vain) needs to say what the page last did and awaits.
const pageLog = { statuses: [], inflight: new Map(), next: 0 };
function status(message, kind = '') {
  const s = $('status');
  s.textContent = message;
  s.className = kind;
  pageLog.statuses.push({ at: Math.round(performance.now()), message, kind });
  if (pageLog.statuses.length > 50) pageLog.statuses.shift();
}

// fetch wrapper: JSON in, JSON or Blob out; API errors become exceptions with the server's words.
async function call(method, path, body, { raw = false, type = 'application/json' } = {}) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.body = type === 'application/json' ? JSON.stringify(body) : body;
    init.headers['Content-Type'] = type;
  }
  const id = ++pageLog.next;
  pageLog.inflight.set(id, `${method} ${path} since ${Math.round(performance.now())} ms`);
  try {
    return await fetchCall(method, path, init, raw);
  } finally {
    pageLog.inflight.delete(id);
  }
}

async function fetchCall(method, path, init, raw) {
  const res = await fetch(api + path, init);
  if (!res.ok) {
    let message = `${res.status} ${res.statusText}`;
    try {
      const e = (await res.json()).error;
      message = e.message + (e.details.length ? ' — ' + e.details.map((d) => `${d.path}: ${d.message}`).join('; ') : '');
    } catch (_) { /* not JSON */ }
    throw new Error(message);
  }
  if (res.status === 204) return null;
  return raw ? res.blob() : res.json();
}

function guard(fn) {
  return async (...args) => {
    try { await fn(...args); } catch (e) { status(e.message, 'error'); }
  };
}

const kFovYDeg = 38;

// Frames a volume's bounding box (issue #37): the orbit aims at its centre from the distance at
// which the box's largest side fills the view with a 15% margin (for the built-in 2-unit box,
// 3.3 units: the page's framing before), the zoom range is relative to that distance, and the
// clip planes hug the box's bounding sphere, so an asset off the origin, of 20 units or of 0.05,
// is in view at once. Called when the box changes (a new session or an upload).
function frameVolume(bbox) {
  const [lo, hi] = bbox;
  state.target = lo.map((x, k) => (x + hi[k]) / 2);
  const half = Math.max(...hi.map((x, k) => x - lo[k])) / 2;
  const fit = 1.15 * half / Math.tan((kFovYDeg / 2) * Math.PI / 180);
  state.frame = { radius: Math.hypot(...hi.map((x, k) => x - lo[k])) / 2, fit, box: JSON.stringify(bbox) };
  state.orbit.distance = fit;
}

function camera(size) {
  const { azimuth, elevation, distance } = state.orbit;
  const t = state.target, r = state.frame ? state.frame.radius : 2;
  return {
    eye: [t[0] + distance * Math.sin(azimuth) * Math.cos(elevation), t[1] + distance * Math.sin(elevation),
          t[2] + distance * Math.cos(azimuth) * Math.cos(elevation)],
    target: t, up: [0, 1, 0], fov_y_deg: kFovYDeg, width: size, height: size,
    near: Math.max(0, distance - 1.5 * r), far: distance + 1.5 * r,
  };
}

// The translucent preview's parameters from the sliders (docs/TRANSLUCENT.md).
function translucentOptions() {
  const hex = $('tl-transport').value, rgb = [1, 3, 5].map((i) => Math.max(0.01, parseInt(hex.slice(i, i + 2), 16) / 255));
  return {
    slice_spacing: Number($('tl-spacing').value),
    light_buffer: 256,  // interactive: a quarter of the default's light texels (≈ 0.7 s a frame at 320² here)
    surface_shading: Number($('tl-surface').value),
    indirect: { blur_angle_deg: Number($('tl-blur').value), extinction: Number($('tl-extinction').value), transport_color: rgb },
    perturbation: perturbationOptions(),
  };
}

function perturbationOptions() {
  return { amplitude: Number($('tl-amplitude').value), frequency: Number($('tl-frequency').value), time: Number($('tl-time').value) };
}

// Bakes the noise detail into the volume (a new version; Undo takes it back).
const bakeDetail = guard(async () => {
  if (Number($('tl-amplitude').value) <= 0) throw new Error('set some detail first');
  const s = await call('POST', `/sessions/${state.sid}/perturb`, perturbationOptions());
  showSession(s);
  $('tl-amplitude').value = 0; $('tl-amplitude').dispatchEvent(new Event('input'));
  status(`detail baked into version ${s.volume.version}`, 'ok');
});

// A glass sphere as the volume's refractive index, or none (a new version each; Undo takes it back).
const addGlass = guard(async () => {
  if (!state.sid) throw new Error('create a session first');
  const s = await call('POST', `/sessions/${state.sid}/refraction`, { index: Number($('glass-index').value), radius: Number($('glass-radius').value) });
  showSession(s);
  await renderViewport();
  status(`glass sphere in version ${s.volume.version}: renders and solves bend through it`, 'ok');
});
const removeGlass = guard(async () => {
  if (!state.sid) throw new Error('create a session first');
  const s = await call('DELETE', `/sessions/${state.sid}/refraction`);
  showSession(s);
  await renderViewport();
  status(`glass removed in version ${s.volume.version}`, 'ok');
});

function showSession(s) {
  state.sid = s.id;
  state.version = s.volume.version;
  if (!state.frame || state.frame.box !== JSON.stringify(s.volume.bbox)) frameVolume(s.volume.bbox);
  const shows = s.volume.shows !== undefined && s.volume.shows !== s.volume.version ? ` (shows ${s.volume.shows})` : '';
  $('session-info').textContent = `${s.scene} · ${s.volume.dims.join('×')} · version ${s.volume.version}${shows}`;
  $('undo').disabled = !s.volume.undo;
  $('redo').disabled = !s.volume.redo;
  $('download-vdb').href = `${api}/sessions/${s.id}/volume.vdb`;
  document.dispatchEvent(new CustomEvent('volstyle-session', { detail: s.id }));  // the light-shaft mode follows (shafts.js)
}

const newSession = guard(async () => {
  status('creating session…');
  const s = await call('POST', '/sessions', { scene: 'builtin:' + $('scene').value, resolution: Number($('resolution').value) });
  showSession(s);
  state.views = []; state.selected = null; state.environment = false;
  $('env-preview').style.display = 'none'; $('env-hint').style.display = '';
  renderViews(); clearPaint(); clearBase();
  await renderViewport();
  status('session ready: orbit the view, add views, paint them, solve', 'ok');
});

const uploadVdb = guard(async (file) => {
  if (!state.sid) await newSession();
  status(`uploading ${file.name}…`);
  const s = await call('PUT', `/sessions/${state.sid}/volume`, file, { type: 'application/octet-stream' });
  showSession(s);
  await renderViewport();
  status(`${file.name} loaded`, 'ok');
});

// Views and their thumbnails.
function renderViews() {
  const box = $('views');
  box.innerHTML = '';
  for (const v of state.views) {
    const b = document.createElement('button');
    b.className = v.id === state.selected ? 'selected' : '';
    const img = document.createElement('img');
    img.src = `${api}/sessions/${state.sid}/views/${v.id}/${v.has_target ? 'target.png' : 'render.png'}?t=${Date.now()}`;
    b.append(img, `${v.id}${v.has_target ? ' ✓' : ''}${v.has_background ? ' · plate' : ''}`);
    b.onclick = () => selectView(v.id);
    box.append(b);
  }
}

async function refreshViews() {
  state.views = await call('GET', `/sessions/${state.sid}/views`);
  renderViews();
}

const addView = guard(async () => {
  if (!state.sid) return;
  const v = await call('POST', `/sessions/${state.sid}/views`, { camera: camera(256) });
  await refreshViews();
  selectView(v.id);
  status(`${v.id} added: paint over it, then "Use as target" (or drop a painted PNG/EXR)`, 'ok');
});

// A background plate for the selected view: what lies behind the volume there (SPEC §1).
const uploadPlate = guard(async (file) => {
  if (!state.selected) throw new Error('add a view first, then give it a plate');
  await call('PUT', `/sessions/${state.sid}/views/${state.selected}/background`, file, { type: 'application/octet-stream' });
  await refreshViews();
  selectView(state.selected);  // paint over the view as it now renders, plate behind
  status(`${file.name} is the plate behind ${state.selected}`, 'ok');
});

// The session's environment map (docs/LIGHTING.md): uploaded once, then named "session" by the
// lighting, as the map its lobes are fitted to and, when ticked, as the background.
async function useEnvironment() {
  const l = await call('GET', `/sessions/${state.sid}/lighting`);
  const colour = Array.isArray(l.background) ? l.background : (l.background.color || [0, 0, 0]);
  l.background = $('env-background').checked ? { color: colour, environment: 'session' } : colour;
  l.environment = { lobes: Number($('env-lobes').value), map: 'session', light_volume_resolution: 32 };
  await call('PUT', `/sessions/${state.sid}/lighting`, l);
  await renderViewport(); renderViews();
}

const uploadEnvironment = guard(async (file) => {
  status(`uploading the environment map ${file.name}…`);
  const m = await call('PUT', `/sessions/${state.sid}/environment`, file, { type: 'application/octet-stream' });
  $('env-preview').src = `${api}/sessions/${state.sid}/environment.png?t=${Date.now()}`;
  $('env-preview').style.display = 'block';
  $('env-hint').style.display = 'none';
  state.environment = true;
  await useEnvironment();
  status(`environment map ${file.name} (${m.width}×${m.height}) lights the volume through ${$('env-lobes').value} lobes`, 'ok');
});
const changeEnvironment = guard(async () => { if (state.environment) await useEnvironment(); });

// Solving, with live progress, a convergence plot and previews.
function drawPlot() {
  const c = $('plot'), g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  const v = state.objectives.filter((x) => x > 0);
  if (v.length < 1) return;
  const lo = Math.log10(Math.min(...v)), hi = Math.log10(Math.max(...v)) + 1e-9;
  g.strokeStyle = '#ff8a3d'; g.lineWidth = 2; g.beginPath();
  v.forEach((x, i) => {
    const px = 8 + (c.width - 16) * i / Math.max(1, state.maxIterations), py = c.height - 8 - (c.height - 16) * (Math.log10(x) - lo) / (hi - lo || 1);
    i ? g.lineTo(px, py) : g.moveTo(px, py);
  });
  g.stroke();
}

const solve = guard(async () => {
  if (!state.sid) return;
  state.maxIterations = Number($('iterations').value);
  const options = {
    unknowns: $('unknowns').value.split(','),
    regularization: { laplacian: Number($('laplacian').value) },
    max_iterations: state.maxIterations,
  };
  if (options.unknowns.includes('lights') && $('lights-background').checked) options.lights = { background: true };
  const { job } = await call('POST', `/sessions/${state.sid}/solve`, options);
  state.job = job; state.objectives = []; drawPlot();
  $('solve').disabled = true; $('cancel').disabled = false;
  $('progress').value = 0; $('progress-text').textContent = 'queued';
  const es = new EventSource(`${api}/jobs/${job}/events`);
  state.events = es;
  const phases = { preparing_views: 'preparing the views', analysing_reach: 'analysing what the paint asks', writing: 'writing the new version' };
  es.addEventListener('progress', (e) => {
    const p = JSON.parse(e.data);
    if (p.phase && p.phase !== 'iterating') {  // a phase begins: the job is at work before (or between) iterations
      $('progress-text').textContent = `${phases[p.phase] || p.phase}… · ${((p.elapsed_ms || 0) / 1000).toFixed(1)} s`;
      if (!p.iteration) $('progress').removeAttribute('value');  // indeterminate until the first iteration
      return;
    }
    state.objectives.push(p.objective);
    $('progress').value = p.iteration / state.maxIterations;
    const rms = p.rms_per_view.reduce((a, b) => a + b, 0) / Math.max(1, p.rms_per_view.length);
    $('progress-text').textContent = `iteration ${p.iteration}/${state.maxIterations} · RMS ${rms.toPrecision(3)} · ${(p.elapsed_ms / 1000).toFixed(1)} s`;
    drawPlot();
  });
  es.addEventListener('preview', (e) => {
    const p = JSON.parse(e.data), url = p.urls[state.selected] || Object.values(p.urls)[0];
    if (url) $('preview').src = url + '?t=' + Date.now();
  });
  const finish = async (e, kind) => {
    es.close();
    $('solve').disabled = false; $('cancel').disabled = true;
    const j = JSON.parse(e.data);
    $('progress-text').textContent = kind;
    if (kind === 'done' && j.result.lighting) {
      // A lights solve (docs/LIGHTING.md): the session's lighting now holds the solved lobes.
      $('progress').value = 1;
      const r = j.result.report, lobes = j.result.lighting.environment.lobes;
      const how = r ? `${r.iterations} iterations (${r.stop_reason}) in ${(r.total_ms / 1000).toFixed(1)} s`
                    : `${j.result.rounds} rounds in ${(j.result.total_ms / 1000).toFixed(1)} s, version ${j.result.version}`;
      status(`lit: ${lobes} lobes solved, ${how}`, 'ok');
      $('environment').src = `${api}/sessions/${state.sid}/lighting/environment.png?t=${Date.now()}`;
      $('environment-wrap').hidden = false;
      showSession(await call('GET', `/sessions/${state.sid}`));
      renderViewport(); renderViews();
    } else if (kind === 'done') {
      $('progress').value = 1;
      const r = j.result.report;
      // Say when the paint asks what the chosen unknowns cannot give, and what would give it.
      const advice = r.reach && r.reach.advice ? ` — ${r.reach.advice}` : '';
      // A re-solve after a stroke moves only what the repainted pixels see: say how much.
      const local = r.local ? ` — re-solved the stroke: ${r.local.changed_pixels} repainted pixels, ${r.local.unknowns} of ${r.hull_unknowns} voxels moved` : '';
      status(`solved: ${r.iterations} iterations (${r.stop_reason}) in ${(r.total_ms / 1000).toFixed(1)} s, version ${j.result.version}${local}${advice}`,
             advice ? 'warn' : 'ok');
      if (r.reach && r.reach.suggested_unknowns) $('unknowns').value = r.reach.suggested_unknowns.join(',');
      showSession(await call('GET', `/sessions/${state.sid}`));
      renderViewport(); renderViews();
    } else {
      status(`${kind}: ${j.error ? j.error.message : ''}`, kind === 'failed' ? 'error' : '');
    }
  };
  for (const kind of ['done', 'failed', 'cancelled']) es.addEventListener(kind, (e) => finish(e, kind));
});

const cancel = guard(async () => { if (state.job) await call('DELETE', `/jobs/${state.job}`); });

// Undo and redo step through what the session showed (POST …/undo, …/redo): each step is a new
// version holding an earlier one's content, so nothing is lost and the status names both.
const step = (redo) => guard(async () => {
  if (!state.sid) return;
  const s = await call('POST', `/sessions/${state.sid}/${redo ? 'redo' : 'undo'}`);
  showSession(s);
  await renderViewport();
  status(`${redo ? 'redone' : 'undone'}: version ${s.volume.version} shows version ${s.volume.shows}`, 'ok');
});
const undo = step(false), redo = step(true);

// Orbit and zoom.
let dragging = null;
$('viewport').addEventListener('pointerdown', (e) => { dragging = { x: e.clientX, y: e.clientY }; e.target.setPointerCapture(e.pointerId); e.preventDefault(); });
$('viewport').addEventListener('pointermove', (e) => {
  if (!dragging) return;
  state.orbit.azimuth -= (e.clientX - dragging.x) * 0.01;
  state.orbit.elevation = Math.max(-1.4, Math.min(1.4, state.orbit.elevation + (e.clientY - dragging.y) * 0.01));
  dragging = { x: e.clientX, y: e.clientY };
  renderViewport();
});
$('viewport').addEventListener('pointerup', () => { dragging = null; });
$('viewport').addEventListener('wheel', (e) => {
  e.preventDefault();
  const fit = state.frame ? state.frame.fit : 3.4;  // zoom from a fifth of the framing distance to four times it
  state.orbit.distance = Math.max(0.2 * fit, Math.min(4 * fit, state.orbit.distance * (e.deltaY > 0 ? 1.1 : 0.9)));
  renderViewport();
}, { passive: false });

const envDrop = $('env-drop');
envDrop.addEventListener('dragover', (e) => { e.preventDefault(); envDrop.classList.add('drop'); });
envDrop.addEventListener('dragleave', () => envDrop.classList.remove('drop'));
envDrop.addEventListener('drop', (e) => { e.preventDefault(); envDrop.classList.remove('drop'); if (e.dataTransfer.files[0]) uploadEnvironment(e.dataTransfer.files[0]); });
$('env-file').onchange = (e) => e.target.files[0] && uploadEnvironment(e.target.files[0]);
$('env-lobes').onchange = changeEnvironment;
$('env-background').onchange = changeEnvironment;
$('plate-file').onchange = (e) => e.target.files[0] && uploadPlate(e.target.files[0]);

$('translucent').onchange = () => { $('translucent-controls').hidden = !$('translucent').checked; renderViewport(); };
$('tl-bake').onclick = bakeDetail;
$('glass-add').onclick = addGlass;
$('glass-remove').onclick = removeGlass;
for (const id of ['tl-blur', 'tl-extinction', 'tl-surface', 'tl-spacing', 'tl-amplitude', 'tl-frequency', 'tl-time', 'glass-index', 'glass-radius']) {
  const show = () => { document.querySelector(`output[for="${id}"]`).textContent = $(id).value; };
  show();
  $(id).addEventListener('input', () => { show(); if (id.startsWith('tl-')) renderViewport(); });
}
$('tl-transport').addEventListener('input', () => renderViewport());
$('new-session').onclick = newSession;
$('vdb-file').onchange = (e) => e.target.files[0] && uploadVdb(e.target.files[0]);
$('add-view').onclick = addView;
$('solve').onclick = solve;
$('cancel').onclick = cancel;
$('undo').onclick = undo;
$('redo').onclick = redo;

guard(async () => {
  const scenes = await call('GET', '/scenes');
  for (const s of scenes) {
    const o = document.createElement('option');
    o.value = s.name; o.textContent = s.name; o.title = s.description;
    $('scene').append(o);
  }
  await newSession();
})();
