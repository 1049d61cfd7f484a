// Browser test of framing (issue #37): an artist's own VDB frames itself on the page. Uploads the
// built-in cloud as a 20-unit asset at (20, 10, 5), a 0.05-unit one at (0.28, 0.08, −0.23), a
// 0.01-unit one and a 10⁴-unit one (tests/tools/make_framed_vdb): after each upload the medium covers 10–80% of the viewport and
// touches none of its edges (pixels that differ from the background). Before, the orbit aimed at
// (0, −0.05, 0) from 1.2–10 units: the first was invisible, the second a speck.
// Usage: MAKE_FRAMED_VDB=… NODE_PATH=…/node_modules node e2e_frame.cjs URL OUT.png
'use strict';
const { execFileSync } = require('child_process');
const path = require('path');
const { browserTest, openPainting, waitStatus } = require('./browser.cjs');

browserTest('frame', async ({ url, screenshot, browser, check }) => {
  const page = await openPainting(browser, url);
  const assets = [{ name: 'far-cloud.vdb', size: 20, centre: [20, 10, 5] }, { name: 'tiny-cloud.vdb', size: 0.05, centre: [0.28, 0.08, -0.23] },
                  { name: 'speck-cloud.vdb', size: 0.01, centre: [-3, 2, 1] }, { name: 'huge-cloud.vdb', size: 1e4, centre: [5000, -2000, 300] }];
  for (const a of assets) {
    const file = path.join(path.dirname(screenshot), a.name);
    execFileSync(process.env.MAKE_FRAMED_VDB, [file, String(a.size), ...a.centre.map(String)]);
    await page.setInputFiles('#vdb-file', file);
    await waitStatus(page, `${a.name} loaded`);
    await page.waitForFunction(() => !state.renderBusy && !state.renderPending, null, { timeout: 180000 });
    // The share of the viewport's pixels that differ from its corner (the background), and how
    // many of them lie on its outermost 3 pixels.
    const m = await page.evaluate(async () => {
      const bmp = await createImageBitmap(await (await fetch(document.getElementById('viewport').src)).blob());
      const c = new OffscreenCanvas(bmp.width, bmp.height), g = c.getContext('2d');
      g.drawImage(bmp, 0, 0);
      const d = g.getImageData(0, 0, bmp.width, bmp.height).data, w = bmp.width, h = bmp.height;
      let medium = 0, edge = 0;
      for (let y = 0; y < h; ++y)
        for (let x = 0; x < w; ++x) {
          const i = 4 * (y * w + x);
          if (Math.max(Math.abs(d[i] - d[0]), Math.abs(d[i + 1] - d[1]), Math.abs(d[i + 2] - d[2])) <= 10) continue;
          ++medium;
          if (x < 3 || y < 3 || x >= w - 3 || y >= h - 3) ++edge;
        }
      return { cover: medium / (w * h), edge };
    });
    console.log(`${a.name}: the medium covers ${(100 * m.cover).toFixed(1)}% of the viewport, ${m.edge} pixels on its edges`);
    await check(m.cover >= 0.1 && m.cover <= 0.8, `${a.name}: the medium covers ${(100 * m.cover).toFixed(1)}% of the viewport (10–80% expected)`);
    await check(m.edge === 0, `${a.name}: the medium touches the viewport's edge (${m.edge} pixels)`);
    await page.screenshot({ path: screenshot.replace(/\.png$/, '_' + a.name.replace('.vdb', '.png')) });
  }
});
