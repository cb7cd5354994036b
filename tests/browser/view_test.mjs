// Browser test of `penumbra view` (apps/penumbra/view.cpp, view_page.html): starts the server on a free
// loopback port, opens its page in headless Chromium (Debian's /usr/bin/chromium driven by playwright-core)
// with every request outside that server refused, and checks what a person relies on:
//   - the page loads with no script error and asks for nothing but its own server;
//   - the progressive reference's sample count grows while nothing moves;
//   - dragging the light changes the technique's image and its error, and restarts the reference;
//   - switching techniques works, and a parameter value outside the schema's range gets the schema's message;
//   - the split divider moves; the shaded and error displays arrive;
//   - Ctrl-C (SIGINT) stops the server cleanly;
// and saves screenshots to OUT/ (view.png, view_light_moved.png, view_split.png, view_error.png).
//
// Usage: node view_test.mjs PENUMBRA_BINARY OUT_DIR   (run.sh checks Chromium and installs playwright-core)
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

import { check, summary } from './check.mjs';

const [binary, outArg] = process.argv.slice(2);
if (!binary || !outArg) {
  console.error('usage: node view_test.mjs PENUMBRA_BINARY OUT_DIR');
  process.exit(2);
}
const outDir = path.resolve(outArg);
fs.rmSync(outDir, { recursive: true, force: true });
fs.mkdirSync(outDir, { recursive: true });
const executablePath = process.env.PENUMBRA_CHROMIUM || '/usr/bin/chromium';


// `penumbra view ARGS` started, once it has printed its URL: { url, output(), exited (its exit code and
// signal), process }.
async function startView(args) {
  const child = spawn(binary, ['view', ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
  let out = '';
  child.stdout.on('data', (d) => { out += d; });
  child.stderr.on('data', (d) => { out += d; });
  const exited = new Promise((resolve) => child.on('exit', (code, signal) => resolve({ code, signal })));
  const url = await new Promise((resolve, reject) => {
    const timer = setInterval(() => {
      const m = out.match(/http:\/\/127\.0\.0\.1:(\d+)\//);
      if (m) { clearInterval(timer); resolve(m[0]); }
    }, 50);
    exited.then(() => { clearInterval(timer); reject(new Error(`penumbra view exited:\n${out}`)); });
  });
  return { url, output: () => out, exited, process: child };
}

// The server: a small image and a short reference keep it to seconds; --max-seconds ends it should the
// test hang.
const server = await startView(['--scene', 'crowded', '--width', '256', '--height', '256', '--port', '0',
  '--technique', 'hard', '--reference-spp', '126', '--max-seconds', '240', '--threads', '2']);
const url = server.url;
const origin = new URL(url).origin;

const browser = await chromium.launch({
  executablePath,
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});
try {
  const context = await browser.newContext({ viewport: { width: 1100, height: 800 } });
  const foreign = [];
  await context.route('**/*', (route) => {
    const requested = route.request().url();
    if (requested.startsWith(origin + '/')) return route.continue();
    foreign.push(requested);
    return route.abort();
  });
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  // The browser logs every 400 as an error; the one the bad parameter value draws is expected.
  let badRequests = 0;
  page.on('console', (m) => {
    if (m.type() !== 'error') return;
    if (/status of 400/.test(m.text())) badRequests += 1; else errors.push(m.text());
  });

  const frames = () => page.evaluate(() => window.penumbraView.stats.frames);
  const waitFrames = async (after, what) => {
    try {
      await page.waitForFunction((n) => window.penumbraView.stats.frames > n, after, { timeout: 60000 });
      return true;
    } catch {
      check(false, `a frame arrives (${what})`);
      return false;
    }
  };
  const text = (id) => page.$eval(`#${id}`, (e) => e.textContent);
  const samples = async () => Number((await text('refSamples')).split('/')[0]);
  // A checksum of the canvas's pixels in columns [x0, x1).
  const region = (x0, x1) => page.evaluate(([a, b]) => {
    const c = document.getElementById('view');
    const d = c.getContext('2d').getImageData(Math.round(a * c.width), 0, Math.round((b - a) * c.width), c.height).data;
    let sum = 0, sq = 0;
    for (let i = 0; i < d.length; i += 4) { sum += d[i] + 3 * d[i + 1] + 7 * d[i + 2]; sq += d[i] * d[i]; }
    return { sum, sq, pixels: d.length / 4 };
  }, [x0, x1]);

  await page.goto(url);
  await waitFrames(0, 'first');
  const first = await region(0, 0.5);
  check(first.sq > 0, 'the technique side shows an image');
  check((await text('leftLabel')) === 'hard', 'the technique shown first is --technique', await text('leftLabel'));
  check(Number.isFinite(Number(await text('rmse8'))), 'RMSE8 against the reference is shown', await text('rmse8'));

  // Still: the reference accumulates to --reference-spp.
  const s0 = await samples();
  await page.waitForFunction(() => /^126 \//.test(document.getElementById('refSamples').textContent), null,
    { timeout: 120000 }).catch(() => {});
  const s1 = await samples();
  check(s1 > s0 && s1 === 126, 'the reference\'s sample count grows while the view is still', `${s0} -> ${s1}`);
  const rmseStill = await text('rmse8');
  await page.screenshot({ path: path.join(outDir, 'view.png'), fullPage: true });

  // Drag the light: the technique's image and error change, the reference starts again.
  await page.selectOption('#dragMode', 'light');
  const box = await page.$eval('#view', (c) => { const r = c.getBoundingClientRect(); return { x: r.x, y: r.y, w: r.width, h: r.height }; });
  let n = await frames();
  // A burst of moves inside one task of the page (pointer events dispatched on the canvas, to the page's
  // own handlers): no answer can arrive between them, so the page may send one request and must keep
  // the rest as the newest state, whatever the renderer's speed. (With the real mouse each move comes a
  // round trip after the last, and a renderer faster than that was rightly asked for every one.)
  const moves = 30;
  const burst = await page.evaluate(({ x, y, moves }) => {
    const view = document.getElementById('view');
    const event = (type, k, buttons) => new PointerEvent(type, { bubbles: true, cancelable: true, pointerId: 1,
      pointerType: 'mouse', isPrimary: true, clientX: x + 3 * k, clientY: y + k, button: 0, buttons });
    const before = window.penumbraView.stats.requests;
    view.dispatchEvent(event('pointerdown', 0, 1));
    for (let k = 1; k <= moves; ++k) view.dispatchEvent(event('pointermove', k, 1));
    view.dispatchEvent(event('pointerup', moves, 0));
    return window.penumbraView.stats.requests - before;
  }, { x: box.x + box.w * 0.3, y: box.y + box.h * 0.5, moves });
  await waitFrames(n, 'after the light drag');
  check(burst <= 1, 'a burst of moves faster than the renderer asks for at most one frame (the rest wait as one)',
    `${burst} requests for ${moves} moves`);
  await page.waitForFunction(() => !document.getElementById('refSamples').textContent.startsWith('126'), null,
    { timeout: 30000 }).catch(() => {});
  const moved = await region(0, 0.5);
  check(moved.sum !== first.sum, 'dragging the light changes the technique\'s image');
  check((await samples()) < 126, 'moving the light restarts the reference', await text('refSamples'));
  await page.waitForFunction(() => /^126 \//.test(document.getElementById('refSamples').textContent), null,
    { timeout: 120000 }).catch(() => {});
  check((await text('rmse8')) !== rmseStill, 'and changes its error', `${rmseStill} -> ${await text('rmse8')}`);
  await page.screenshot({ path: path.join(outDir, 'view_light_moved.png') });

  // Orbit (a drag in camera mode) and zoom (the wheel): the camera moves, so the G-buffer is made again.
  await page.selectOption('#dragMode', 'camera');
  const view = await page.$eval('#view', (c) => { const r = c.getBoundingClientRect(); return { x: r.x, y: r.y, w: r.width, h: r.height }; });
  const cameraBefore = await page.evaluate(() => JSON.stringify(window.penumbraView.state.camera));
  const gbuffersBefore = await page.evaluate(() => window.penumbraView.stats.gbufferFrames);
  n = await frames();
  // Left of the divider, which lies over the canvas's middle.
  await page.mouse.move(view.x + view.w * 0.25, view.y + view.h * 0.5);
  await page.mouse.down();
  await page.mouse.move(view.x + view.w * 0.25 + 40, view.y + view.h * 0.5 + 10, { steps: 4 });
  await page.mouse.up();
  await page.mouse.wheel(0, 200);
  await waitFrames(n, 'after orbiting and zooming');
  await page.waitForFunction((k) => window.penumbraView.stats.gbufferFrames > k, gbuffersBefore,
    { timeout: 30000 }).catch(() => {});
  const cameraAfter = await page.evaluate(() => JSON.stringify(window.penumbraView.state.camera));
  check(cameraAfter !== cameraBefore, 'orbiting and zooming move the camera');
  check(await page.evaluate((k) => window.penumbraView.stats.gbufferFrames > k, gbuffersBefore),
    'a moved camera makes the G-buffer again');

  // Another technique.
  n = await frames();
  await page.selectOption('#technique', 'pcss');
  await waitFrames(n, 'after switching to pcss');
  await page.waitForFunction(() => window.penumbraView.stats.lastHeader.techniqueCached === false ||
    document.getElementById('leftLabel').textContent === 'pcss', null, { timeout: 60000 }).catch(() => {});
  check((await text('leftLabel')) === 'pcss', 'switching the technique shows it');
  check((await text('message')) === '', 'pcss runs without a message', await text('message'));
  check((await page.$$('#params .param')).length > 3, 'its parameters are listed from the schema');
  const note = await page.$eval('#params .param small', (e) => e.textContent);
  check(/default/.test(note), 'with their type, range, unit and default', note);

  // A value outside the schema's range: the schema's message, and the server goes on.
  await page.fill('#param-map_size', '3');
  await page.dispatchEvent('#param-map_size', 'change');
  await page.waitForFunction(() => document.getElementById('message').textContent !== '', null, { timeout: 30000 })
    .catch(() => {});
  const refused = await text('message');
  check(/map_size/.test(refused) && /expected/.test(refused), 'a bad parameter value gets the schema\'s message', refused);
  n = await frames();
  await page.fill('#param-map_size', '');
  await page.dispatchEvent('#param-map_size', 'change');
  await waitFrames(n, 'after the value is cleared');
  check((await text('message')) === '', 'clearing it renders again');

  // The divider.
  const divider = await page.$eval('#divider', (e) => { const r = e.getBoundingClientRect(); return { x: r.x + r.width / 2, y: r.y + r.height / 2 }; });
  await page.mouse.move(divider.x, divider.y);
  await page.mouse.down();
  await page.mouse.move(box.x + box.w * 0.25, divider.y, { steps: 5 });
  await page.mouse.up();
  const split = await page.evaluate(() => window.penumbraView.split);
  check(Math.abs(split - 0.25) < 0.03, 'the split divider moves', String(split));
  await page.screenshot({ path: path.join(outDir, 'view_split.png') });

  // Shaded and error displays.
  for (const display of ['shaded', 'error']) {
    n = await frames();
    await page.check(`input[name=display][value=${display}]`);
    await waitFrames(n, `the ${display} display`);
    // A frame asked for before the click may arrive first: wait for one of this display.
    await page.waitForFunction((d) => window.penumbraView.stats.lastHeader.display === d, display,
      { timeout: 30000 }).catch(() => {});
    const header = await page.evaluate(() => window.penumbraView.stats.lastHeader);
    const technique = header.images.find((i) => i.side === 'technique');
    check(header.display === display && technique && technique.channels === 3,
      `the ${display} display arrives in colour`);
  }
  await page.screenshot({ path: path.join(outDir, 'view_error.png'), fullPage: true });

  check(errors.length === 0, 'no script errors', errors.join('; '));
  check(badRequests === 1, 'the only refused request is the bad parameter value', String(badRequests));
  check(foreign.length === 0, 'nothing is fetched from outside the server', foreign.join(', '));
  await context.close();
} catch (e) {
  check(false, 'the test ran to its end', String(e));
} finally {
  await browser.close();
}

// A scene with several lights: the light selector, and a polygon light's own shape.
{
  const several = await startView(['--scene', 'concave', '--width', '128', '--height', '128', '--port', '0',
    '--technique', 'hard', '--reference-spp', '2', '--max-seconds', '120', '--threads', '2']);
  const address = several.url;
  const again = await chromium.launch({ executablePath, args: ['--no-sandbox', '--disable-gpu'] });
  try {
    const page = await again.newPage({ viewport: { width: 1100, height: 800 } });
    await page.goto(address);
    await page.waitForFunction(() => window.penumbraView.stats.frames > 0, null, { timeout: 60000 });
    const lights = await page.$$eval('#light option', (o) => o.map((x) => x.textContent));
    check(lights.length === 5 && await page.isVisible('#light'), 'a scene with 5 lights offers all 5', lights.join(', '));
    const shapes = await page.$$eval('#shape option', (o) => o.map((x) => x.value));
    check(shapes.includes('polygon'), 'a polygon light keeps its own shape among the choices', shapes.join(', '));
    const before = await page.evaluate(() => window.penumbraView.stats.frames);
    await page.selectOption('#light', '3');
    await page.waitForFunction((k) => window.penumbraView.stats.frames > k, before, { timeout: 60000 });
    check((await page.$eval('#shape', (e) => e.value)) === 'rect' &&
      (await page.evaluate(() => window.penumbraView.state.light.index)) === 3, 'choosing light 3 (a rect) uses it');
    await page.screenshot({ path: path.join(outDir, 'view_lights.png'), fullPage: true });
  } catch (e) {
    check(false, 'the several-lights part ran to its end', String(e));
  } finally {
    await again.close();
  }
  several.process.kill('SIGTERM');
  check((await several.exited).code === 0 && /stopped \(SIGTERM\)/.test(several.output()), 'SIGTERM stops the server cleanly',
    several.output().trim().split('\n').pop());
}

server.process.kill('SIGINT');
const end = await server.exited;
check(end.code === 0 && /stopped \(Ctrl-C\)/.test(server.output()), 'Ctrl-C stops the server cleanly',
  `exit ${end.code} ${end.signal ?? ''}: ${server.output().trim().split('\n').pop()}`);

process.exit(summary(`screenshots in ${outDir}`));
