// Browser test of the HTML report of `penumbra compare` (apps/penumbra/compare.cpp,
// src/eval/html_report.cpp): renders a small report with every registered technique, opens its
// index.html from disk in headless Chromium (Debian's /usr/bin/chromium driven by playwright-core;
// no browser download) with the network cut off, and checks what a person relies on:
//   - nothing is fetched but the page's own files (file://), and no script error is raised;
//   - every image loads (complete, non-zero natural size) and every row of compare.json is in the table;
//   - clicking a column header sorts the table by that column's unrounded values, both ways;
//   - the legend's check boxes hide a technique in the plots;
//   - over a sequence (--motion-path), the frame slider shows every image at the chosen frame and play steps on;
// then saves a full-page screenshot (a CI artifact) to OUT/report.png.
//
// Usage: node report_test.mjs PENUMBRA_BINARY OUT_DIR   (run.sh checks Chromium and installs playwright-core)
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

import { check, summary } from './check.mjs';

const [binary, outArg] = process.argv.slice(2);
if (!binary || !outArg) {
  console.error('usage: node report_test.mjs PENUMBRA_BINARY OUT_DIR');
  process.exit(2);
}
const outDir = path.resolve(outArg);
const executablePath = process.env.PENUMBRA_CHROMIUM || '/usr/bin/chromium';


// A fresh report: a small image keeps it to a few seconds; two map sizes give the map-size plot.
fs.rmSync(outDir, { recursive: true, force: true });
fs.mkdirSync(outDir, { recursive: true });
const args = ['compare', '--scene', 'torus', '--width', '96', '--height', '96', '--spp', '16',
  '--map-sizes', '64,128', '--threads', '2', '--out', outDir];
const render = spawnSync(binary, args, { encoding: 'utf8' });
if (render.status !== 0) {
  console.error(`penumbra ${args.join(' ')} failed (exit ${render.status}):\n${render.stdout}\n${render.stderr}`);
  process.exit(1);
}
const reportDir = path.join(outDir, 'report');
const report = JSON.parse(fs.readFileSync(path.join(reportDir, 'compare.json'), 'utf8'));

const browser = await chromium.launch({
  executablePath,
  // As root in a container Chromium needs --no-sandbox; the rest keep it from reaching for the network.
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});
try {
  const context = await browser.newContext({ viewport: { width: 1400, height: 1000 }, offline: true });
  const page = await context.newPage();
  const requests = [];
  const pageErrors = [];
  page.on('request', (request) => requests.push(request.url()));
  page.on('pageerror', (error) => pageErrors.push(String(error)));
  page.on('console', (message) => { if (message.type() === 'error') pageErrors.push(message.text()); });
  // Anything that is not a file of the report is refused (and recorded above, so the check below fails).
  await context.route(/^(?!file:)/, (route) => route.abort());
  await page.goto(pathToFileURL(path.join(reportDir, 'index.html')).href, { waitUntil: 'load' });

  const foreign = requests.filter((url) => !url.startsWith('file:') && !url.startsWith('data:'));
  check(foreign.length === 0, 'the page fetches nothing but its own files', foreign.join(', '));
  check(requests.every((url) => !url.startsWith('file:') || decodeURIComponent(url).includes(reportDir)),
    'every file it loads is in the report directory', requests.join(', '));

  const images = await page.$$eval('img', (imgs) => imgs.map((img) => ({
    src: img.getAttribute('src'), complete: img.complete, width: img.naturalWidth, height: img.naturalHeight,
  })));
  const broken = images.filter((img) => !img.complete || img.width === 0 || img.height === 0);
  check(images.length >= 2 + 4 * report.techniques.length, `the page shows ${images.length} images`,
    `expected at least ${2 + 4 * report.techniques.length}`);
  check(broken.length === 0, 'every image loads', broken.map((img) => img.src).join(', '));
  check(images.every((img) => img.width === report.image.width && img.height === report.image.height),
    `every image is ${report.image.width}x${report.image.height}`);

  const labels = await page.$$eval('#results tbody tr[data-technique]', (rows) => rows.map((row) => row.dataset.technique));
  const expected = report.techniques.map((t) => t.label);
  check(JSON.stringify(labels) === JSON.stringify(expected), 'the table lists every technique of compare.json',
    `${labels} vs ${expected}`);
  const registered = spawnSync(binary, ['techniques'], { encoding: 'utf8' }).stdout
    .split('\n').filter((line) => /^[a-z][a-z0-9-]*  /.test(line)).map((line) => line.split(/\s+/)[0]);
  const listed = new Set([...report.techniques.map((t) => t.name), ...(report.skipped || []).map((s) => s.name)]);
  check(registered.length > 0 && registered.every((name) => listed.has(name)),
    'every registered technique is in the table or listed as not run', registered.filter((n) => !listed.has(n)).join(', '));

  // Sorting: by RMSE8 (column 1) up, then down, then by name.
  const columnValues = (column) => page.$$eval('#results tbody tr[data-technique]',
    (rows, c) => rows.map((row) => row.cells[c].dataset.value), column);
  const header = (name) => page.locator('#results thead th', { hasText: new RegExp(`^${name}`) }).first();
  const numbers = (values) => values.filter((v) => v !== '').map(Number);
  const isSorted = (values, sign) => values.every((v, i) => i === 0 || sign * (v - values[i - 1]) >= 0);

  await header('RMSE8').locator('button').click();
  let values = numbers(await columnValues(1));
  check(values.length === report.techniques.length && isSorted(values, +1), 'RMSE8 sorts ascending', values.join(' '));
  check(await header('RMSE8').getAttribute('aria-sort') === 'ascending', 'the sorted header says ascending');
  const jsonAscending = report.techniques.map((t) => t.rmse8).sort((a, b) => a - b);
  check(JSON.stringify(values) === JSON.stringify(jsonAscending), 'the sorted values are compare.json\'s RMSE8');
  await header('RMSE8').locator('button').click();
  values = numbers(await columnValues(1));
  check(isSorted(values, -1), 'a second click sorts descending', values.join(' '));
  await header('total ms').locator('button').click();
  values = numbers(await columnValues(8));
  check(isSorted(values, +1), 'total ms sorts ascending', values.join(' '));
  await header('technique').locator('button').click();
  const names = await columnValues(0);
  check(names.every((n, i) => i === 0 || names[i - 1].localeCompare(n) <= 0), 'technique sorts by name', names.join(' '));
  const shown = await page.$$eval('#results tbody tr[data-technique] td:nth-child(2)', (cells) => cells.map((c) => c.textContent));
  const byLabel = Object.fromEntries(report.techniques.map((t) => [t.label, t.rmse8.toFixed(2)]));
  check(names.every((n, i) => byLabel[n] === shown[i]), 'the shown RMSE8 is compare.json\'s, rounded to 0.01');

  // Plots: one point per technique on the error-time plot; the legend hides a series everywhere.
  const points = await page.$$eval('#plot-error-time circle.point', (c) => c.length);
  check(points === report.techniques.length, `error-time plot has ${points} points`);
  check(await page.locator('#plot-map-size').count() === 1, 'the map-size plot is there (--map-sizes)');
  const profileLines = await page.$$eval('#plot-profile polyline.line', (p) => p.length);
  check(profileLines === report.techniques.length + 1, `profile plot has ${profileLines} lines (every technique + truth)`);
  await page.locator('#series-legend input[data-series="0"]').uncheck();
  const hidden = await page.$$eval('.series[data-series="0"]',
    (groups) => groups.every((g) => getComputedStyle(g).display === 'none'));
  check(hidden, 'unchecking a legend entry hides that technique in every plot');
  await page.locator('#series-legend input[data-series="0"]').check();

  check(pageErrors.length === 0, 'no script errors', pageErrors.join('; '));

  await header('RMSE8').locator('button').click();  // the screenshot shows the table sorted by error
  const screenshot = path.join(outDir, 'report.png');
  await page.screenshot({ path: screenshot, fullPage: true });
  check(fs.statSync(screenshot).size > 10000, `screenshot saved to ${screenshot}`);

  // A sequence: the frame slider shows every image at the chosen frame, each of which loads; play steps on.
  const sequenceOut = path.join(outDir, 'sequence');
  const sequenceArgs = ['compare', '--scene', 'torus', '--width', '64', '--height', '64', '--spp', '8',
    '--techniques', 'hard,pcss,raytraced-hard', '--motion-path', '0.4,8,-1;0.6,8,-1', '--frames', '3',
    '--threads', '2', '--out', sequenceOut];
  const sequenceRun = spawnSync(binary, sequenceArgs, { encoding: 'utf8' });
  check(sequenceRun.status === 0, 'penumbra compare over a sequence runs', `${sequenceRun.stdout}\n${sequenceRun.stderr}`);
  const sequenceDir = path.join(sequenceOut, 'report');
  const sequenceReport = JSON.parse(fs.readFileSync(path.join(sequenceDir, 'compare.json'), 'utf8'));
  await page.goto(pathToFileURL(path.join(sequenceDir, 'index.html')).href, { waitUntil: 'load' });
  const sequenceRows = await page.$$eval('#sequence tbody tr', (rows) => rows.length);
  check(sequenceRows === sequenceReport.techniques.length + 1,
    `the sequence table has a row per technique and the noise floor (${sequenceRows})`);
  const flicker = await page.$$eval('#sequence tbody tr[data-technique]', (rows) => rows.map((row) => Number(row.cells[3].dataset.value)));
  check(JSON.stringify(flicker) === JSON.stringify(sequenceReport.techniques.map((t) => t.sequence.temporal.flicker)),
    'the sequence table shows compare.json\'s flicker', flicker.join(' '));
  const framed = await page.$$eval('img[data-frames]', (imgs) => imgs.length);
  check(framed >= 2 + 4 * sequenceReport.techniques.length, `${framed} images follow the frame slider`);
  await page.$eval('#frame', (slider) => { slider.value = '2'; slider.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => Array.from(document.images).every((img) => img.complete));
  const atFrame = await page.$$eval('img[data-frames]', (imgs) => imgs.map((img) => ({
    src: img.getAttribute('src'), wanted: img.dataset.frames.split('|')[2], width: img.naturalWidth,
  })));
  check(atFrame.every((img) => img.src === img.wanted && img.src.includes('_f002_')),
    'moving the slider to frame 3 shows every image at frame 3', atFrame.filter((i) => i.src !== i.wanted).map((i) => i.src).join(', '));
  check(atFrame.every((img) => img.width === sequenceReport.image.width), 'every frame-3 image loads');
  check(await page.textContent('#frame-label') === 'frame 3 of 3', 'the label names the frame');
  await page.click('#play');
  const stepped = await page.waitForFunction(() => document.getElementById('frame').value !== '2', null, { timeout: 3000 })
    .then(() => true, () => false);
  check(stepped, 'play steps to the next frame within 3 s');
  await page.click('#play');
  check(pageErrors.length === 0, 'no script errors on the sequence page', pageErrors.join('; '));
} finally {
  await browser.close();
}

process.exit(summary(`screenshot in ${outDir}`));
