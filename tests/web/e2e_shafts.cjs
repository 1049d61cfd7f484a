// Browser end-to-end test of the "Light shafts" mode (issue #11 item 7): Debian's chromium driven
// headless by playwright-core. Opens the mode on the built-in forest, moves the medium and
// manipulation sliders, drags the camera and the light, plays time, drops a red transfer function
// on the drop zone and uploads a mesh — each change must bring a new live frame (a higher
// revision, streamed as MJPEG with the frame rate shown), and the TF must redden the frame. Saves a screenshot.
// Usage: NODE_PATH=…/node_modules node e2e_shafts.cjs URL OUT.png
'use strict';
const { openBrowser, openShafts, waitStatus } = require('./browser.cjs');

(async () => {
const { url, screenshot, browser, fail } = await openBrowser();
let passed = 0;
const check = async (ok, message) => { if (!ok) await fail(message); ++passed; };
try {
  const { page, revision, newFrame, settle } = await openShafts(browser, url, fail, { width: 1400, height: 820 });
  // Mean R, G, B of the frame on screen (0–255).
  const meanColour = () => page.evaluate(async () => {
    const bmp = await createImageBitmap(await (await fetch(document.getElementById('shafts-frame').src)).blob());
    const c = new OffscreenCanvas(bmp.width, bmp.height), g = c.getContext('2d');
    g.drawImage(bmp, 0, 0);
    const d = g.getImageData(0, 0, bmp.width, bmp.height).data, m = [0, 0, 0];
    for (let i = 0; i < d.length; i += 4) for (let k = 0; k < 3; ++k) m[k] += d[i + k];
    return m.map((x) => x / (d.length / 4));
  });
  const slide = async (id, value) => {
    await page.$eval('#' + id, (el, v) => { el.value = v; el.dispatchEvent(new Event('input', { bubbles: true })); }, String(value));
  };

  let r = await newFrame(0, 'opening the mode');
  r = await settle();
  const first = await meanColour();
  console.log(`[ measured ] first frame (revision ${r}): mean RGB ${first.map((x) => x.toFixed(1)).join(', ')}`);

  await slide('extinction', 0.2);
  r = await newFrame(r, 'the extinction slider');
  let thick = await meanColour();
  for (let k = 0; k < 10 && !(Math.abs(thick[0] - first[0]) > 1); ++k) {  // an older PUT's frame may come first
    r = await newFrame(r, 'the extinction slider');
    thick = await meanColour();
  }
  await check(Math.abs(thick[0] - first[0]) > 1, `σt 0.06 -> 0.2 should change the frame (${first} -> ${thick})`);
  for (const [id, value] of [['albedo', 0.6], ['phase-g', 0.2], ['closing-radius', 6], ['dilation-length', 0.5],
                             ['hole-probability', 0.35], ['hole-frequency', 0.8]]) {
    await slide(id, value);
    r = await newFrame(r, `the ${id} slider`);
    ++passed;
  }

  // Drag the camera, then the light.
  const box = await page.locator('#shafts-frame').boundingBox();
  const drag = async () => {
    await page.mouse.move(box.x + box.width * 0.5, box.y + box.height * 0.5);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width * 0.56, box.y + box.height * 0.52, { steps: 4 });
    await page.mouse.up();
  };
  await drag();
  r = await newFrame(r, 'dragging the camera');
  await page.check('input[name=drag][value=light]');
  await drag();
  r = await newFrame(r, 'dragging the light');
  passed += 2;

  // Play time for a moment: the holes drift, frames keep coming.
  await page.click('#play');
  await page.waitForFunction(() => Number(document.getElementById('time').value) >= 0.5, null, { timeout: 30000 });
  // The frames come over the MJPEG stream (issue #40): shown from the stream's bytes, with the rate.
  const streamed = await page.evaluate(() => ({ src: document.getElementById('shafts-frame').src, info: document.getElementById('shafts-info').textContent }));
  console.log(`[ measured ] while playing: ${streamed.info}`);
  await check(streamed.src.startsWith('blob:'), `the frame should come from the stream (src ${streamed.src.slice(0, 40)})`);
  await check(/[0-9.]+ fps/.test(streamed.info), `the page should show the frame rate (${streamed.info})`);
  await page.click('#play');
  r = await newFrame(r, 'playing time');
  await page.waitForFunction(() => document.getElementById('shafts-busy').style.display === 'none', null, { timeout: 30000 });
  await check(Number(await page.inputValue('#time')) >= 0.5, 'time advanced');

  // Drop a red transfer function (made in the page) on the drop zone: the frame reddens.
  const before = await meanColour();
  await page.evaluate(async () => {
    const c = new OffscreenCanvas(16, 8), g = c.getContext('2d');
    g.fillStyle = 'rgb(255, 60, 60)';
    g.fillRect(0, 0, 16, 8);
    const file = new File([await c.convertToBlob({ type: 'image/png' })], 'red-tf.png', { type: 'image/png' });
    const dt = new DataTransfer();
    dt.items.add(file);
    document.getElementById('tf-drop').dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
  });
  await page.waitForFunction(() => document.getElementById('tf-preview').complete && document.getElementById('tf-preview').naturalWidth === 16, null, { timeout: 30000 });
  await waitStatus(page, 'transfer function', 30000);
  // (A PUT may still be in flight: the TF's scene follows it. Wait for frames until one is red.)
  const reddened = (c) => c[1] / Math.max(c[0], 1) < 0.8 * (before[1] / Math.max(before[0], 1));
  let red = await meanColour();
  for (let k = 0; k < 20 && !reddened(red); ++k) {
    r = await newFrame(await revision(), 'dropping a transfer function');
    red = await meanColour();
  }
  console.log(`[ measured ] mean RGB before the red TF ${before.map((x) => x.toFixed(1)).join(', ')}, with it ${red.map((x) => x.toFixed(1)).join(', ')}`);
  await check(reddened(red), 'the red multiply TF should lower G relative to R');

  // Upload a mesh: a slatted board above the ground.
  let obj = '';
  for (let i = 0; i < 8; ++i) {
    const x0 = -4 + i, x1 = x0 + 0.5, v = 4 * i;
    obj += `v ${x0} 6 -4\nv ${x1} 6 -4\nv ${x1} 6 4\nv ${x0} 6 4\nf ${v + 1} ${v + 2} ${v + 3}\nf ${v + 1} ${v + 3} ${v + 4}\n`;
  }
  await page.setInputFiles('#mesh-file', { name: 'slats.obj', mimeType: 'text/plain', buffer: Buffer.from(obj) });
  await waitStatus(page, 'slats.obj uploaded', 30000);
  r = await newFrame(r, 'uploading a mesh');
  await check((await page.textContent('#status')).includes('32 vertices'), 'the mesh upload reports its vertices');
  await page.selectOption('#shafts-scene', 'builtin:forest/trees');
  r = await newFrame(r, 'going back to the forest');
  await page.screenshot({ path: screenshot });
  console.log(`${passed} passed, 0 failed`);
} catch (e) {
  await fail(e.message);
}
await browser.close();
})();
