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

module.exports = { openBrowser };
