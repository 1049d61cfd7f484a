// Browser test of painting over a base that clips (issue #37): under the default lighting the
// view's render is brighter than the screen in places. The page reads the view's EXR (its own
// EXR reader: ZIP, half; medium over background), shows it at an exposure with a warning where
// it clips, and sends a linear float target. Checked: the page's base at +0 stops is the server's
// render.png to within 8-bit rounding; the warning counts the clipped pixels and Auto exposure
// clears most of them; a warm glow is dabbed on them at that exposure; the uploaded target is an EXR with no clipped pixels and weight 0 where erased; the
// solve's reach report suggests no other unknowns and gives no advice.
// Usage: NODE_PATH=…/node_modules node e2e_paint.cjs URL OUT.png
'use strict';
const { browserTest, openPainting, waitStatus } = require('./browser.cjs');

browserTest('paint', async ({ screenshot, url, browser, check }) => {
  const page = await openPainting(browser, url);
  await page.click('#add-view');
  await page.waitForFunction(() => document.getElementById('paint-base').dataset.view === 'v1', null, { timeout: 180000 });

  // The page's float base at +0 stops against the server's own 8-bit encoding of the same render.
  const diff = await page.evaluate(async () => {
    const sid = document.getElementById('download-vdb').href.split('/sessions/')[1].split('/')[0];
    const bmp = await createImageBitmap(await (await fetch(`/api/v1/sessions/${sid}/views/v1/render.png?t=${Date.now()}`)).blob());
    const c = new OffscreenCanvas(bmp.width, bmp.height), g = c.getContext('2d');
    g.drawImage(bmp, 0, 0);
    const png = g.getImageData(0, 0, bmp.width, bmp.height).data;
    const b = document.getElementById('paint-base');
    const ours = b.getContext('2d').getImageData(0, 0, b.width, b.height).data;
    let worst = 0, clipped = 0;
    const whites = [];
    for (let i = 0; i < png.length; i += 4) {
      const white = png[i] === 255 && png[i + 1] === 255 && png[i + 2] === 255;
      clipped += white;
      if (white) whites.push([((i / 4) % bmp.width + 0.5) / bmp.width, (Math.floor(i / 4 / bmp.width) + 0.5) / bmp.height]);
      if (png[i] === 255 || png[i + 1] === 255 || png[i + 2] === 255) continue;  // clips: striped on the page
      for (let k = 0; k < 3; ++k) worst = Math.max(worst, Math.abs(png[i + k] - ours[i + k]));
    }
    return { worst, clipped, size: [b.width, b.height], dots: whites.filter((_, k) => k % Math.ceil(whites.length / 24) === 0) };
  });
  console.log(`[ measured ] page base vs render.png: worst ${diff.worst} levels; ${diff.clipped} white pixels in the PNG`);
  await check(diff.size[0] === 256 && diff.size[1] === 256, `the base is the view's size (${diff.size})`);
  await check(diff.worst <= 2, `the page's EXR base at +0 stops differs from render.png by ${diff.worst} levels (allowed: 2, half-float and rounding)`);
  await check(diff.clipped > 0, 'the default lighting clips this view (the case under test)');
  const warning = await page.$eval('#clip-warning', (w) => ({ hidden: w.hidden, clipped: Number(w.dataset.clipped), text: w.textContent }));
  console.log(`[ measured ] ${warning.text}`);
  await check(!warning.hidden && warning.clipped >= diff.clipped, `the warning counts ${warning.clipped} clipped pixels (the PNG has ${diff.clipped} white)`);
  await page.click('#paint-auto');
  const auto = await page.$eval('#paint-exposure', (e) => Number(e.value));
  const after = await page.$eval('#clip-warning', (w) => (w.hidden ? 0 : Number(w.dataset.clipped)));
  console.log(`[ measured ] Auto exposure: ${auto} stops, ${after} pixels clip`);
  await check(auto < 0 && after <= 0.005 * 256 * 256, `Auto exposure (${auto} stops) leaves ${after} pixels clipping`);

  // A warm glow dabbed on the clipped pixels, at the Auto exposure where the artist can see them
  // (a glow: brighter than the base there, as shown); a small erased spot in a corner.
  const box = await page.locator('#paint').boundingBox();
  await page.fill('#brush-colour', '#ffc080');
  await page.fill('#brush-opacity', '70');
  await page.fill('#brush-size', '3');
  for (const [x, y] of diff.dots) await page.mouse.click(box.x + box.width * x, box.y + box.height * y);
  await page.fill('#brush-size', '18');
  await page.check('#eraser');
  await page.mouse.click(box.x + box.width * 0.1, box.y + box.height * 0.1);
  await page.uncheck('#eraser');
  await page.click('#upload-target');
  await waitStatus(page, 'target of v1 uploaded', 60000);
  const { view, weights } = await page.evaluate(async (c0) => {
    const sid = document.getElementById('download-vdb').href.split('/sessions/')[1].split('/')[0];
    const bmp = await createImageBitmap(await (await fetch(`/api/v1/sessions/${sid}/views/v1/target.png`)).blob(),
                                        { premultiplyAlpha: 'none' });
    const c = new OffscreenCanvas(bmp.width, bmp.height), g = c.getContext('2d');
    g.drawImage(bmp, 0, 0);
    const alpha = (x, y) => g.getImageData(x, y, 1, 1).data[3];
    return { view: await (await fetch(`/api/v1/sessions/${sid}/views/v1`)).json(),
             weights: { erased: alpha(26, 26), painted: alpha(Math.floor(256 * c0[0]), Math.floor(256 * c0[1])), kept: alpha(230, 230) } };
  }, diff.dots[0]);
  console.log(`[ measured ] ${await page.textContent('#status')}; clipped_pixels ${view.clipped_pixels}; weights ${JSON.stringify(weights)}`);
  await check(view.has_target && view.clipped_pixels === 0, 'the target is float: no pixel of it counts as clipped');
  await check(weights.erased === 0 && weights.painted === 255 && weights.kept === 255, 'weight 0 where erased, 1 where painted or kept');

  await page.fill('#iterations', '15');
  await page.click('#solve');
  await page.waitForFunction(() => /^(solved|failed|cancelled)/.test(document.getElementById('status').textContent), null, { timeout: 600000 });
  const solved = await page.textContent('#status');
  console.log(`[ measured ] ${solved}`);
  await check(solved.startsWith('solved'), `the solve finished: ${solved}`);
  const reach = await page.evaluate(async () => (await (await fetch(`/api/v1/jobs/${state.job}`)).json()).result.report.reach);
  console.log(`[ measured ] reach: ${JSON.stringify(reach)}`);
  await check(reach.suggested_unknowns === null && !reach.advice, `the reach report blames the unknowns: ${reach.advice}`);
  await check(reach.clipped_pixels === 0, 'no target pixel was left out as clipped');
  await page.screenshot({ path: screenshot });
});
