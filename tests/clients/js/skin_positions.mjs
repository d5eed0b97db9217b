// node skin_positions.mjs BASE_URL JOBS.json OUT.json: one headless Chromium (Debian's, driven by
// puppeteer-core: no browser download) opens BASE_URL/page.html and runs every job of JOBS.json
// through window.skinPositions (page.mjs); the results go to OUT.json in the jobs' order.
import { readFileSync, writeFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';

const [base, jobsPath, outPath] = process.argv.slice(2);
const jobs = JSON.parse(readFileSync(jobsPath, 'utf8'));
const browser = await puppeteer.launch({
    executablePath: process.env.CGASKIN_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    pipe: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--headless=new',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--no-first-run'],
});
try {
    const page = await browser.newPage();
    page.on('console', (message) => process.stderr.write(`page: ${message.text()}\n`));
    page.on('pageerror', (error) => process.stderr.write(`page error: ${error}\n`));
    await page.goto(`${base}/page.html`);
    await page.waitForFunction(() => window.ready === true, {timeout: 30000});
    const results = await page.evaluate((jobs) => window.skinPositions(jobs), jobs);
    writeFileSync(outPath, JSON.stringify(results));
} finally {
    await browser.close();
}
