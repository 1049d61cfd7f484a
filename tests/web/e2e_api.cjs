// Browser test of the API page (issue #37): web/api.html renders /api/v1/openapi.json with no
// build step: every operation of the document is listed (by tag), an operation opens to its
// parameters and answers, and its body's schema link leads to that schema. Saves a screenshot.
// Usage: NODE_PATH=…/node_modules node e2e_api.cjs URL OUT.png
'use strict';
const { openBrowser } = require('./browser.cjs');

(async () => {
const { url, screenshot, browser, fail } = await openBrowser();
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.goto(url + 'api.html');
  await page.waitForFunction(() => document.querySelectorAll('#api-operations details.op').length > 0, null, { timeout: 30000 });
  const doc = await (await fetch(url + 'api/v1/openapi.json')).json();
  const operations = Object.values(doc.paths).reduce((n, item) => n + Object.keys(item).length, 0);
  const shown = await page.$$eval('#api-operations details.op', (l) => l.length);
  if (shown !== operations) await fail(`the page lists ${shown} operations, the document has ${operations}`);
  const solve = 'details.op#' + doc.paths['/sessions/{sid}/solve'].post.operationId;
  await page.click(solve + ' > summary');
  const text = await page.$eval(solve, (d) => d.innerText);
  for (const want of ['Idempotency-Key', '202', 'solve_options']) if (!text.includes(want)) await fail(`the solve operation does not show ${want}`);
  await page.click(solve + ' a[href="#schema-solve_options"]');
  await page.waitForFunction(() => location.hash === '#schema-solve_options' && document.getElementById('schema-solve_options').open);
  const shownSchema = await page.$eval('#schema-solve_options pre', (p) => p.innerText);
  if (!shownSchema.includes('max_iterations')) await fail('the solve_options schema does not show its fields');
  if (errors.length) await fail('page errors: ' + errors.join('; '));
  await page.screenshot({ path: screenshot, fullPage: false });
  console.log(`api page: ${shown} operations listed, solve opens with its parameters and answers`);
} catch (e) {
  await fail(e.stack || String(e));
}
await browser.close();
})();
