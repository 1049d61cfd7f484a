// Browser test of the page's layout (issue #37): hidden is hidden (the translucent sliders while
// Translucent is off), the live preview is in view at 1280×800 without scrolling, nothing spills
// sideways at 900 px, the page has a favicon, and the tab's title names the mode on screen.
// Saves a screenshot of each size. Usage: NODE_PATH=…/node_modules node e2e_layout.cjs URL OUT.png
'use strict';
const { browserTest, openPainting } = require('./browser.cjs');

browserTest('layout', async ({ url, screenshot, browser, check }) => {
  const page = await openPainting(browser, url);
  const shown = (id) => page.$eval('#' + id, (e) => e.getClientRects().length > 0 && getComputedStyle(e).display !== 'none');
  await check(!(await shown('translucent-controls')), 'the translucent sliders show while Translucent is off');
  await page.click('#translucent');
  await check(await shown('translucent-controls'), 'the translucent sliders stay hidden with Translucent on');
  await page.click('#translucent');
  await check(!(await shown('translucent-controls')), 'the translucent sliders stay after Translucent is off again');
  const box = await page.$eval('#preview-wrap', (e) => { const r = e.getBoundingClientRect(); return { top: r.top, bottom: r.bottom }; });
  await check(box.top >= 0 && box.top + 60 <= 800, `the live preview is out of view at 1280×800 (its top at ${box.top} px)`);
  await check((await page.$eval('link[rel=icon]', (l) => l.href)).length > 0, 'a favicon');
  await check((await page.title()).includes('paint'), 'the title names the painting mode');
  await page.screenshot({ path: screenshot.replace(/\.png$/, '_1280.png') });
  await page.click('#mode-shafts');
  await page.waitForFunction(() => document.title.includes('light shafts'), null, { timeout: 10000 });
  await page.click('#mode-paint');
  await page.waitForFunction(() => document.title.includes('paint'), null, { timeout: 10000 });
  await check((await page.$eval('#status', (e) => e.textContent)).startsWith('painting'), 'the status names the painting mode after a switch back');
  // 900 px: nothing wider than the window, every panel inside it.
  await page.setViewportSize({ width: 900, height: 800 });
  await page.waitForTimeout(300);
  const spill = await page.evaluate(() => {
    const width = document.documentElement.clientWidth, out = [];
    if (document.documentElement.scrollWidth > width) out.push(`the page is ${document.documentElement.scrollWidth} px wide`);
    for (const e of document.querySelectorAll('header, section, header > *'))
      if (e.getClientRects().length && e.getBoundingClientRect().right > width + 1) out.push(`${e.id || e.tagName} ends at ${Math.round(e.getBoundingClientRect().right)} px`);
    return out;
  });
  await check(spill.length === 0, 'at 900 px: ' + spill.join('; '));
  await page.screenshot({ path: screenshot.replace(/\.png$/, '_900.png'), fullPage: true });
});
