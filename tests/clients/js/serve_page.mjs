// node serve_page.mjs JOB.json OUT.json: one headless Chromium (Debian's, driven by puppeteer-core)
// opens the page of a running `cgaskin serve` in one or more tabs and runs the job's steps, each
// [tab, kind, ...args] (tab: 0, 1, ...; a tab is opened by its first step):
//   [t, "call", method, ...args]         the (awaited) result of window.cgaskinView[method](...args)
//   [t, "drag", fromBone, toBone, n, ms, frames]  press the mouse on fromBone's screen position, move in
//                                         n steps to toBone's (ms between steps: the clip plays meanwhile),
//                                         release; {path, frames}: with frames = k > 0, the canvas (PNG
//                                         data URL) after every step and at k more steps after the release
//   [t, "click", bone, dx, dy]           click at the bone's screen position + (dx, dy)
// Requests to anything but the server (and data:/blob:/about:) are aborted and reported, as are
// console errors and uncaught exceptions.
// OUT.json: {requests: [blocked URLs], errors: [messages], results: [per step]}.
import { readFileSync, writeFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';

const [jobPath, outPath] = process.argv.slice(2);
const job = JSON.parse(readFileSync(jobPath, 'utf8'));
const origin = new URL(job.url).origin;
const record = {requests: [], errors: [], results: []};
const browser = await puppeteer.launch({
    executablePath: process.env.CGASKIN_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    pipe: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--headless=new',
           '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
});
const tabs = [];

async function open() {
    const page = await browser.newPage();
    await page.setViewport({width: job.width || 640, height: job.height || 400});
    await page.setRequestInterception(true);
    page.on('request', (request) => {
        const url = request.url();
        if (url.startsWith(origin + '/') || /^(data|blob|about):/.test(url)) request.continue();
        else { record.requests.push(url); request.abort(); }
    });
    page.on('console', (message) => {
        if (message.type() === 'error') record.errors.push(`tab ${tabs.length}: console: ${message.text()}`);
    });
    page.on('pageerror', (error) => record.errors.push(`tab ${tabs.length}: page error: ${error}`));
    await page.goto(job.url, {waitUntil: 'load'});
    await page.waitForFunction(() => window.cgaskinView && window.cgaskinView.ready, {timeout: 30000});
    await page.evaluate(() => window.cgaskinView.ready);
    await page.waitForFunction(() => typeof window.cgaskinView.counts === 'function', {timeout: 30000});
    return page;
}

const bonePosition = (page, name) => page.evaluate((n) => window.cgaskinView.boneScreenPositions()[n], name);
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

try {
    for (const [t, kind, ...args] of job.steps) {
        while (tabs.length <= t) tabs.push(await open());
        const page = tabs[t];
        await page.bringToFront();
        if (kind === 'call') {
            record.results.push(await page.evaluate(
                (method, args) => window.cgaskinView[method](...args), args[0], args.slice(1)));
        } else if (kind === 'drag') {
            const [from, to, n, ms, more] = args;
            const frames = [];
            const frame = async () => {
                if (more) frames.push(await page.evaluate(
                    () => document.querySelector('#cgaskin-view canvas').toDataURL('image/png')));
            };
            const [x0, y0] = await bonePosition(page, from);
            await page.mouse.move(x0, y0);
            await page.mouse.down();
            const path = [[x0, y0]];
            for (let i = 1; i <= n; i++) {
                await sleep(ms);
                const [x1, y1] = await bonePosition(page, to);      // (where the bone is now: it moves)
                const x = x0 + (x1 - x0) * i / n, y = y0 + (y1 - y0) * i / n;
                await page.mouse.move(x, y);
                path.push([x, y]);
                await frame();
            }
            await page.mouse.up();
            await page.evaluate(() => window.cgaskinView.serveIdle());
            for (let i = 0; i < (more || 0); i++) {
                await sleep(ms);
                await frame();
            }
            record.results.push({path, frames});
        } else if (kind === 'click') {
            const [bone, dx, dy] = args;
            const [x, y] = await bonePosition(page, bone);
            await page.mouse.click(x + (dx || 0), y + (dy || 0));
            await page.evaluate(() => window.cgaskinView.serveIdle());
            record.results.push([x + (dx || 0), y + (dy || 0)]);
        } else {
            throw new Error(`unknown step ${kind}`);
        }
    }
} catch (error) {
    record.errors.push(`driver: ${error && error.stack || error}`);
} finally {
    writeFileSync(outPath, JSON.stringify(record));
    await browser.close();
}
