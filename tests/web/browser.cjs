// What the browser tests share: the page's URL and the screenshot path from the command line,
// Debian's chromium launched headless, and a `fail` that reports, closes it and exits 1.
'use strict';
const { chromium } = require('playwright-core');

async function openBrowser() {
  const [urlArg, screenshot] = process.argv.slice(2);
  const url = urlArg === '@URL@' ? process.env.VOLSTYLE_URL + '/' : urlArg;
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
           '--disable-component-update', '--disable-sync'],
  });
  const fail = async (message) => { console.error('FAIL: ' + message); await browser.close(); process.exit(1); };
  return { url, screenshot, browser, fail };
}

// Opens the page in "Light shafts" mode once its session is ready; the live frame's helpers:
// revision() on screen, newFrame(after, what) waits for a newer one, settle() waits until no scene
// PUT is in flight (the frame on screen is then the newest).
async function openShafts(browser, url, fail, viewport) {
  const page = await browser.newPage({ viewport });
  page.on('pageerror', (e) => console.error('page error:', e.message));
  await page.goto(url);
  await page.waitForFunction(() => document.getElementById('status').textContent.startsWith('session ready'), null, { timeout: 60000 });
  // On a loaded machine a click can land while the layout still shifts: click until the mode took.
  for (let k = 0; k < 5; ++k) {
    await page.click('#mode-shafts');
    try {
      await page.waitForFunction(() => document.getElementById('mode-shafts').classList.contains('selected') &&
                                        document.getElementById('status').textContent.startsWith('light shafts'), null, { timeout: 5000 });
      break;
    } catch (e) {
      console.error(`the shafts mode did not open on click ${k + 1} (status: ${await page.textContent('#status')}); again`);
    }
  }
  const revision = () => page.evaluate(() => Number(document.getElementById('shafts-frame').dataset.revision || 0));
  const newFrame = async (after, what) => {
    try {
      await page.waitForFunction((a) => Number(document.getElementById('shafts-frame').dataset.revision || 0) > a, after, { timeout: 120000 });
    } catch (e) {
      await fail(`no new frame after ${what} (still revision ${await revision()}; status: ${await page.textContent('#status')})`);
    }
    return revision();
  };
  const settle = async () => {
    await page.waitForFunction(() => document.getElementById('shafts-busy').style.display === 'none', null, { timeout: 60000 });
    return revision();
  };
  return { page, revision, newFrame, settle };
}

// What the page last said and still awaits (app.js's pageLog): the clue a failed wait reports.
async function pageReport(page) {
  return page.evaluate(() => {
    const at = Math.round(performance.now());
    const said = pageLog.statuses.slice(-8).map((s) => `  ${s.at} ms: ${s.kind ? s.kind + ': ' : ''}${s.message}`).join('\n');
    const waiting = [...pageLog.inflight.values()].join('; ') || 'none';
    return `the page at ${at} ms; its last statuses:\n${said}\nrequests in flight: ${waiting}`;
  }).catch((e) => `(no report: ${e.message})`);
}

// Waits until the page has said a status starting with `prefix`, the one on screen or any said
// since the wait began (a status can be replaced within one frame, before a poll sees it). On
// timeout it throws with pageReport's clue.
async function waitStatus(page, prefix, timeout = 180000) {
  const since = await page.evaluate(() => pageLog.statuses.length - 1);
  try {
    await page.waitForFunction(([p, k]) => pageLog.statuses.slice(Math.max(0, k)).some((s) => s.message.startsWith(p)) ||
                                           document.getElementById('status').textContent.startsWith(p), [prefix, since], { timeout });
  } catch (e) {
    throw new Error(`no status "${prefix}…" within ${timeout / 1000} s; ${await pageReport(page)}`);
  }
}

// Opens the painting page once its session is ready (console errors logged). The waits are long:
// CTest runs a browser test beside the heaviest GL tests under -j2 (a first render took over 60 s).
// One CI run saw a page whose first session never became ready in 180 s, with no clue left: the
// wait now names what the status said, and after 80 s the page is loaded once more (said aloud);
// both waits fit the shortest browser test's 300 s limit with room for the test itself.
async function openPainting(browser, url, viewport = { width: 1280, height: 800 }) {
  const page = await browser.newPage({ viewport });
  page.on('pageerror', (e) => console.error('page error:', e.message));
  const ready = () => document.getElementById('status').textContent.startsWith('session ready') ||
                      document.getElementById('status').className === 'error';
  const started = Date.now();
  for (let attempt = 1; ; ++attempt) {
    await page.goto(url);
    try {
      await page.waitForFunction(ready, null, { timeout: 80000 });
      break;
    } catch (e) {
      const where = `the session was not ready ${(Date.now() - started) / 1000} s after the page opened; ${await pageReport(page)}`;
      if (attempt === 2) throw new Error(where);
      console.error(where + '; loading the page again');
    }
  }
  const shown = await page.textContent('#status');
  if (!shown.startsWith('session ready')) throw new Error(`the page's first session failed: ${shown}`);
  return page;
}

// check(ok, message): fails the test (through `fail`) on the first that does not hold; counts the rest.
function checker(fail) {
  const c = { passed: 0 };
  c.check = async (ok, message) => { if (!ok) await fail(message); ++c.passed; };
  return c;
}

// Runs a browser test: `body({ url, screenshot, browser, fail, check })` with checks counted;
// any throw fails the test; the browser is closed at the end. Prints "`name`: N checks passed".
async function browserTest(name, body) {
  const { url, screenshot, browser, fail } = await openBrowser();
  const checks = checker(fail);
  try {
    await body({ url, screenshot, browser, fail, check: checks.check });
    console.log(`${name}: ${checks.passed} checks passed`);
  } catch (e) {
    await fail(e.stack || String(e));
  }
  await browser.close();
}

module.exports = { openBrowser, openShafts, openPainting, waitStatus, pageReport, checker, browserTest };
