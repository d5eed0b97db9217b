// node page_result.mjs URL OUT.json: one headless Chromium (Debian's, driven by puppeteer-core) opens URL
// and waits (30 s at most) for the page to set window.result; OUT.json: {result, errors}.
import { writeFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';

const [url, outPath] = process.argv.slice(2);
const browser = await puppeteer.launch({
    executablePath: process.env.CGASKIN_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    pipe: true,
    args: ['--no-sandbox', '--headless=new', '--disable-background-networking', '--disable-component-update',
           '--disable-sync', '--no-first-run'],
});
const errors = [];
try {
    const page = await browser.newPage();
    page.on('pageerror', (error) => errors.push(`page error: ${error}`));
    await page.goto(url, {waitUntil: 'load'});
    await page.waitForFunction(() => window.result !== undefined, {timeout: 30000});
    writeFileSync(outPath, JSON.stringify({result: await page.evaluate(() => window.result), errors}));
} finally {
    await browser.close();
}
