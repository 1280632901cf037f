// Opens a --html page in Debian's headless Chromium RUNS times (a fresh tab each) and prints its
// size, the median time from navigation to the page ready (window.tridexView.ready: the toolpath,
// drawn after the part's first frame, drawn too) and to the part's first frame, and
// where that time goes: the page's own stage times (window.tridexView.timings, ms since
// navigation), as medians over the runs. With --screenshot, keeps a picture of the last load (in a
// window of --viewport pixels, 1280x800 unless given; with --slider F, the toolpath drawn up to
// that fraction of the program). For bench/tools/README.md and docs/.
//   node tests/html/open_page.mjs PAGE.html [--runs N] [--screenshot OUT.png] [--viewport WxH] [--slider F]
//                                 [--chromium PATH]
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import puppeteer from 'puppeteer-core';

const args = process.argv.slice(2);
const option = (name, fallback) => { const k = args.indexOf(name); return k >= 0 ? args[k + 1] : fallback; };
const file = path.resolve(args[0]);
const runs = Number(option('--runs', '3')), screenshot = option('--screenshot', ''), chromium = option('--chromium', '/usr/bin/chromium');
const [width, height] = option('--viewport', '1280x800').split('x').map(Number), slider = option('--slider', '');
const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'tridex-chromium-'));
const browser = await puppeteer.launch({
  executablePath: chromium, headless: true, userDataDir: profile,
  args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
         '--disable-background-networking', '--disable-component-update', '--no-first-run'],
});
const seconds = [], stages = [];
let errors = 0;
try {
  for (let r = 0; r < runs; ++r) {
    const page = await browser.newPage();
    await page.setViewport({ width, height });
    page.on('pageerror', (e) => { ++errors; console.log('page error: ' + e); });
    page.on('console', (m) => { if (m.type() === 'error') { ++errors; console.log('console error: ' + m.text()); } });
    const start = performance.now();
    await page.goto(pathToFileURL(file).href, { waitUntil: 'load', timeout: 300000 });
    await page.waitForFunction('window.tridexView && window.tridexView.ready', { timeout: 300000 });
    seconds.push((performance.now() - start) / 1000);
    stages.push(await page.evaluate(() => window.tridexView.timings));
    if (r === runs - 1 && screenshot) {
      if (slider !== '')
        await page.$eval('#path-slider', (e, f) => { e.value = String(Math.round(f * Number(e.max))); e.dispatchEvent(new Event('input')); },
                         Number(slider));
      await page.screenshot({ path: screenshot });
    }
    await page.close();
  }
} finally {
  await browser.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
seconds.sort((a, b) => a - b);
// The part's first frame (the page's "drawn" stage: the toolpath follows it), in page time.
const first = stages.map((t) => t.drawn / 1000).sort((a, b) => a - b);
console.log(`${path.basename(file)}: ${(fs.statSync(file).size / 1e6).toFixed(2)} MB; ready in ` +
            `${seconds.map((s) => s.toFixed(2)).join(', ')} s (median ${seconds[Math.floor(runs / 2)].toFixed(2)} s)` +
            `; the part first drawn at ${first.map((s) => s.toFixed(2)).join(', ')} s (median ${first[Math.floor(runs / 2)].toFixed(2)} s)` +
            (errors ? `; ${errors} console error(s)` : ''));
// Each stage's median duration (from the previous stage's end; "script" is from navigation, so it
// holds loading and parsing the HTML and running three.js).
const median = (values) => values.sort((a, b) => a - b)[Math.floor(values.length / 2)];
let previous = null;
const parts = [];
for (const stage of Object.keys(stages[0] || {})) {
  parts.push(stage + ' ' + median(stages.map((t) => t[stage] - (previous ? t[previous] : 0))).toFixed(0));
  previous = stage;
}
console.log('stages, median ms: ' + parts.join(', '));
process.exit(errors ? 1 : 0);
