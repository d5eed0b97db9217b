// node site_pages.mjs SITE OUT PAGE...: open each PAGE (a path under SITE, the built documentation) in
// headless Chromium (Debian's, driven by the puppeteer-core that tests/clients/js installs), from
// file://, wait until it has loaded and MathJax has typeset, and save a screenshot OUT/<page>.png.
// Every request outside SITE (any other URL than file:// under SITE, data:, blob: and about:) is
// aborted and reported, as are console errors, uncaught exceptions and requests that fail.
// Prints one JSON object: {page: {outside: [URLs], errors: [messages], failed: [URLs], title}}.
import { createRequire } from 'node:module';
import { mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(join(here, '..', 'clients', 'js', 'package.json'));
const puppeteer = require('puppeteer-core');

const [site, out, ...pages] = process.argv.slice(2);
const siteUrl = pathToFileURL(resolve(site)).href + '/';
mkdirSync(out, { recursive: true });
const browser = await puppeteer.launch({
    executablePath: process.env.CGASKIN_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    pipe: true,
    args: ['--no-sandbox', '--headless=new', '--disable-background-networking', '--disable-component-update',
           '--disable-sync', '--no-first-run', '--disable-gpu'],
});
const report = {};
try {
    for (const page of pages) {
        const tab = await browser.newPage();
        await tab.setViewport({ width: 1280, height: 900 });
        const seen = { outside: [], errors: [], failed: [], title: '' };
        await tab.setRequestInterception(true);
        tab.on('request', (request) => {
            const url = request.url();
            const inside = url.startsWith(siteUrl) || /^(data|blob|about):/.test(url);
            if (inside) request.continue();
            else { seen.outside.push(url); request.abort(); }
        });
        tab.on('requestfailed', (request) => {
            const url = request.url();
            if (url.startsWith(siteUrl)) seen.failed.push(url);
        });
        tab.on('console', (message) => { if (message.type() === 'error') seen.errors.push(message.text()); });
        tab.on('pageerror', (error) => seen.errors.push(String(error)));
        await tab.goto(siteUrl + page, { waitUntil: 'networkidle0', timeout: 60000 });
        await tab.evaluate(async () => {           // MathJax 3 typesets after load: wait for it where it is
            if (window.MathJax && window.MathJax.startup && window.MathJax.startup.promise)
                await window.MathJax.startup.promise;
        });
        seen.title = await tab.title();
        await tab.screenshot({ path: join(out, page.replaceAll('/', '_').replace(/\.html$/, '.png')) });
        report[page] = seen;
        await tab.close();
    }
} finally {
    await browser.close();
}
console.log(JSON.stringify(report));
