// node view_page.mjs JOBS.json OUT.json: one headless Chromium (Debian's, driven by puppeteer-core)
// opens each job's page (a file:// URL written by `cgaskin view` or cgaskin.show) and runs its steps
// against window.cgaskinView, in the page or in its first iframe (a notebook's srcdoc view).
// Every request other than the page itself and data:/blob:/about: URLs is aborted and reported, as are
// console errors and uncaught exceptions. Steps:
//   ["call", method, ...args]      the result of window.cgaskinView[method](...args)
//   ["get", name]                  the value of window.cgaskinView[name] (clips, bones, vertices)
//   ["dom", selector, value, event] set an input's value (or checkbox state) and dispatch the event
//   ["value", selector]            an input's or a menu's value as the page shows it
//   ["hover", x, y]                move the mouse to canvas pixel (x, y) (top-level pages only)
//   ["hoverBone", name]            move the mouse onto that bone's origin; the name the page then shows
//   ["pixels"]                     the canvas as {width, height, rgba: base64}
// OUT.json: per job {requests: [blocked URLs], errors: [messages], results: [per step]}.
import { readFileSync, writeFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';

const [jobsPath, outPath] = process.argv.slice(2);
const jobs = JSON.parse(readFileSync(jobsPath, 'utf8'));
const browser = await puppeteer.launch({
    executablePath: process.env.CGASKIN_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    pipe: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--headless=new',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--no-first-run', '--allow-file-access-from-files=false'],
});

function pixels() {   // (runs in the page)
    const canvas = document.querySelector('#cgaskin-view canvas');
    window.cgaskinView.render();
    const copy = document.createElement('canvas');
    copy.width = canvas.width; copy.height = canvas.height;
    const context = copy.getContext('2d');
    context.drawImage(canvas, 0, 0);
    const bytes = context.getImageData(0, 0, copy.width, copy.height).data;
    let text = '';
    for (let i = 0; i < bytes.length; i += 0x8000)
        text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return {width: copy.width, height: copy.height, rgba: btoa(text)};
}

function setInput(selector, value, event) {   // (runs in the page)
    const input = document.querySelector(selector);
    if (!input) throw new Error(`no element ${selector}`);
    if (input.type === 'checkbox') input.checked = Boolean(value); else input.value = String(value);
    input.dispatchEvent(new Event(event, {bubbles: true}));
    return null;
}

const out = [];
try {
    for (const job of jobs) {
        const record = {requests: [], errors: [], results: []};
        out.push(record);
        const page = await browser.newPage();
        await page.setViewport({width: job.width || 480, height: job.height || 360});
        await page.setRequestInterception(true);
        page.on('request', (request) => {
            const url = request.url();
            if (url === job.url || /^(data|blob|about):/.test(url)) request.continue();
            else { record.requests.push(url); request.abort(); }
        });
        page.on('console', (message) => {
            if (message.type() === 'error') record.errors.push(`console: ${message.text()}`);
        });
        page.on('pageerror', (error) => record.errors.push(`page error: ${error}`));
        try {
            await page.goto(job.url, {waitUntil: 'load'});
            const target = job.frame ? page.mainFrame().childFrames()[0] : page;
            if (!target) throw new Error('the page has no iframe');
            await target.waitForFunction(() => window.cgaskinView && window.cgaskinView.ready, {timeout: 30000});
            await target.evaluate(() => window.cgaskinView.ready);
            for (const [kind, ...args] of job.steps) {
                if (kind === 'call') {
                    record.results.push(await target.evaluate(
                        (method, args) => window.cgaskinView[method](...args), args[0], args.slice(1)));
                } else if (kind === 'get') {
                    record.results.push(await target.evaluate((name) => window.cgaskinView[name], args[0]));
                } else if (kind === 'dom') {
                    record.results.push(await target.evaluate(setInput, ...args));
                } else if (kind === 'value') {
                    record.results.push(await target.evaluate((selector) => document.querySelector(selector).value, args[0]));
                } else if (kind === 'hover') {
                    await page.mouse.move(args[0], args[1]);
                    record.results.push(null);
                } else if (kind === 'hoverBone') {
                    const [x, y] = await target.evaluate((name) => window.cgaskinView.boneScreenPositions()[name], args[0]);
                    await page.mouse.move(x + 40, y + 40);   // (away first: a move onto the same spot fires no event)
                    await page.mouse.move(x, y);
                    record.results.push(await target.evaluate(() => window.cgaskinView.hoveredBone()));
                } else if (kind === 'pixels') {
                    record.results.push(await target.evaluate(pixels));
                } else {
                    throw new Error(`unknown step ${kind}`);
                }
            }
        } catch (error) {
            record.errors.push(`driver: ${error && error.stack || error}`);
        } finally {
            await page.close();
        }
    }
} finally {
    writeFileSync(outPath, JSON.stringify(out));
    await browser.close();
}
