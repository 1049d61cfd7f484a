// Browser test of Undo and Redo (issue #37): three edits on the page (a glass sphere, a bigger
// one, none), then Undo three times: each press shows the version before, by content — the
// session's refractive index as that version had it, its VDB the size of that version's — and
// the status names the new version and the one it shows, and the viewport's live stream shows the
// new version's frame; Redo steps forward again.
// Usage: NODE_PATH=…/node_modules node e2e_undo.cjs URL OUT.png
'use strict';
const { browserTest, openPainting, waitStatus: waitFor } = require('./browser.cjs');

browserTest('undo', async ({ url, screenshot, browser, check }) => {
  const page = await openPainting(browser, url);
  const session = () => page.evaluate(async () => {
    const sid = document.getElementById('download-vdb').href.split('/sessions/')[1].split('/')[0];
    return (await fetch(`api/v1/sessions/${sid}`)).json();
  });
  const vdbSize = (version) => page.evaluate(async (v) => {
    const href = document.getElementById('download-vdb').href;
    return (await (await fetch(v ? `${href}?version=${v}` : href)).arrayBuffer()).byteLength;
  }, version);
  const waitStatus = (prefix) => waitFor(page, prefix);
  await check(await page.$eval('#undo', (b) => b.disabled), 'Undo is off before any edit');

  // Three edits: versions 2 (glass r 0.3), 3 (glass r 0.6), 4 (no glass).
  const glass = [];
  for (const radius of [0.3, 0.6]) {
    await page.$eval('#glass-radius', (e, r) => { e.value = r; e.dispatchEvent(new Event('input')); }, radius);
    await page.click('#glass-add');
    await waitStatus('glass sphere in version');
  }
  await page.click('#glass-remove');
  await waitStatus('glass removed');
  let s = await session();
  await check(s.volume.version === 4 && s.volume.undo === 3, `after three edits: version ${s.volume.version}, undo ${s.volume.undo}`);
  const sizes = {};
  for (const v of [1, 2, 3, 4]) sizes[v] = await vdbSize(v);
  const hasGlass = { 1: false, 2: true, 3: true, 4: false };

  // Undo three times: 3, 2, 1, each by content.
  for (const [press, shows] of [[1, 3], [2, 2], [3, 1]]) {
    await page.click('#undo');
    await waitStatus(`undone: version ${4 + press} shows version ${shows}`);
    s = await session();
    await check(s.volume.shows === shows, `undo ${press}: the session shows ${s.volume.shows}, not ${shows}`);
    await check(s.volume.grids.includes('refractive_index') === hasGlass[shows], `undo ${press}: the glass of version ${shows}`);
    await check(await vdbSize() === sizes[shows], `undo ${press}: the VDB is version ${shows}'s`);
    await check((await page.$eval('#session-info', (e) => e.textContent)).includes(`version ${4 + press} (shows ${shows})`), 'the header names both');
    // The viewport is a live stream (issue #40): its frame on screen is this version's.
    const info = await page.$eval('#viewport-info', (e) => e.textContent);
    await check(info.startsWith(`version ${4 + press} ·`) && info.includes('fps'), `undo ${press}: the streamed viewport shows "${info}"`);
  }
  await check(await page.$eval('#undo', (b) => b.disabled), 'Undo is off at the first version');
  await page.click('#redo');
  await waitStatus('redone: version 8 shows version 2');
  s = await session();
  await check(s.volume.shows === 2 && s.volume.grids.includes('refractive_index'), 'redo brings version 2 back');
  await page.screenshot({ path: screenshot });
});
