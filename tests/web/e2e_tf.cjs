// Browser end-to-end test of TF authoring (issue #15): Debian's chromium driven headless by
// playwright-core. In "Light shafts" mode it builds a two-layer TF (a white solid base and a
// diffusion layer), clicks a constraint into the frame, and the clicked pixel must take the
// constraint's colour; then two key frames make a camera path that the slider scrubs. Saves a
// screenshot. Usage: NODE_PATH=…/node_modules node e2e_tf.cjs URL OUT.png
'use strict';
const { openBrowser, openShafts, waitStatus } = require('./browser.cjs');

(async () => {
const { url, screenshot, browser, fail } = await openBrowser();
let passed = 0;
const check = async (ok, message) => { if (!ok) await fail(message); ++passed; };
try {
  const { page, revision, newFrame, settle } = await openShafts(browser, url, fail, { width: 1400, height: 1000 });
  // Mean R, G, B (0–255) of the frame on screen around (fx, fy), fractions of its size.
  const pixel = (fx, fy) => page.evaluate(async ([fx, fy]) => {
    const bmp = await createImageBitmap(await (await fetch(document.getElementById('shafts-frame').src)).blob());
    const c = new OffscreenCanvas(bmp.width, bmp.height), g = c.getContext('2d');
    g.drawImage(bmp, 0, 0);
    const x = Math.floor(fx * bmp.width), y = Math.floor(fy * bmp.height), d = g.getImageData(x - 2, y - 2, 5, 5).data, m = [0, 0, 0];
    for (let i = 0; i < d.length; i += 4) for (let k = 0; k < 3; ++k) m[k] += d[i + k];
    return m.map((v) => v / 25);
  }, [fx, fy]);

  let r = await newFrame(0, 'opening the mode');
  r = await settle();
  // A shaft-lit spot of the forest (in the haze between the trunks).
  const fx = 0.45, fy = 0.35;
  const before = await pixel(fx, fy);

  // Two layers: a white solid base, then a diffusion layer (multiply mode: white leaves the frame alone).
  await page.selectOption('#tf-add-type', 'solid');
  await page.$eval('#tf-colour', (el) => { el.value = '#ffffff'; });
  await page.click('#tf-add');
  await page.selectOption('#tf-add-type', 'diffusion');
  await page.click('#tf-add');
  await check(await page.$$eval('#tf-layers li', (l) => l.length) === 2, 'two layers listed');
  r = await newFrame(r, 'adding TF layers');
  r = await settle();

  // Click a red constraint into the frame at the spot.
  await page.$eval('#tf-colour', (el) => { el.value = '#ff2010'; });
  await page.check('input[name=drag][value=constrain]');
  const box = await page.locator('#shafts-frame').boundingBox();
  await page.mouse.click(box.x + box.width * fx, box.y + box.height * fy);
  await waitStatus(page, 'TF constraint added', 60000);
  await check((await page.textContent('#tf-picked')).includes('V̄'), 'the pick is reported');
  const ratio = (c) => c[1] / Math.max(c[0], 1);
  let after = await pixel(fx, fy);
  for (let k = 0; k < 20 && !(ratio(after) < 0.8 * ratio(before)); ++k) {
    r = await newFrame(await revision(), 'the clicked constraint');
    after = await pixel(fx, fy);
  }
  console.log(`[ measured ] the clicked pixel before ${before.map((x) => x.toFixed(1)).join(', ')}, after ${after.map((x) => x.toFixed(1)).join(', ')}`);
  await check(ratio(after) < 0.8 * ratio(before), `the clicked pixel takes the red constraint (G/R ${ratio(before).toFixed(2)} -> ${ratio(after).toFixed(2)})`);
  await check(await page.$eval('#tf-layers li.selected', (li) => li.textContent.startsWith('diffusion (1)')), 'the constraint is in the diffusion layer');

  // A second, blue constraint in the shadow of a trunk: the layer interpolates between the two.
  await page.$eval('#tf-colour', (el) => { el.value = '#3050ff'; });
  await page.mouse.click(box.x + box.width * 0.58, box.y + box.height * 0.75);
  await page.waitForFunction(() => document.querySelector('#tf-layers li.selected')?.textContent.startsWith('diffusion (2)'), null, { timeout: 60000 });
  ++passed;
  r = await settle();

  // A camera path: a key, orbit the camera, a second key; scrubbing brings frames.
  await page.click('#key-add');
  await page.check('input[name=drag][value=camera]');
  await page.mouse.move(box.x + box.width * 0.5, box.y + box.height * 0.5);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width * 0.6, box.y + box.height * 0.5, { steps: 4 });
  await page.mouse.up();
  await page.click('#key-add');
  await check(await page.$$eval('#keys li', (l) => l.length) === 2, 'two key frames');
  r = await settle();
  await page.$eval('#path-time', (el) => { el.value = '1'; el.dispatchEvent(new Event('input', { bubbles: true })); });
  r = await newFrame(r, 'scrubbing the path');
  await page.waitForTimeout(300);
  await settle();
  await page.screenshot({ path: screenshot });
  console.log(`${passed} passed, 0 failed`);
} catch (e) {
  await fail(e.message);
}
await browser.close();
})();
