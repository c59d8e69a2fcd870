// Shared by the page tests and scripts/bench-page.mjs: a tiny static server for dist/, a headless Chromium
// (Debian's, through playwright-core), and OBJ text of small generated articulated populations.
import assert from 'node:assert/strict';
import http from 'node:http';
import { readFile, stat } from 'node:fs/promises';
import { readFileSync, readdirSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { extname, join, normalize, resolve, sep } from 'node:path';
import { fileURLToPath } from 'node:url';
import { before, after } from 'node:test';
import { chromium } from 'playwright-core';

export const ROOT = resolve(fileURLToPath(new URL('../..', import.meta.url)));

const TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.wasm': 'application/wasm',
  '.json': 'application/json',
  '.svg': 'image/svg+xml',
  '.png': 'image/png',
};

/** Serves `dir` (default $POSEMFA_DIST, else dist/) on a free loopback port; returns { url, close, requests }. */
export async function serveStatic(dir = process.env.POSEMFA_DIST || join(ROOT, 'dist')) {
  const root = resolve(dir);
  await stat(join(root, 'index.html')).catch(() => {
    throw new Error(`${root}/index.html is missing: build the page first (npm run build)`);
  });
  const requests = [];
  const server = http.createServer(async (req, res) => {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    requests.push(path);
    const file = normalize(join(root, path.endsWith('/') ? `${path}index.html` : path));
    if (!file.startsWith(root + sep) && file !== root) {
      res.writeHead(403).end();
      return;
    }
    try {
      const body = await readFile(file);
      res.writeHead(200, { 'content-type': TYPES[extname(file)] ?? 'application/octet-stream', 'cache-control': 'no-store' });
      res.end(body);
    } catch {
      res.writeHead(404).end('not found');
    }
  });
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  const { port } = server.address();
  return { url: `http://127.0.0.1:${port}/`, requests, close: () => new Promise((ok) => server.close(ok)) };
}

// Flags for this closed network; none of them breaks WebGL2 (shared/TOOLCHAIN.md).
const CHROMIUM_ARGS = [
  '--no-sandbox', '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--no-first-run', '--disable-default-apps', '--disable-extensions', '--disable-quic',
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
];

/** Headless Chromium with a fresh profile (launchPersistentContext would keep one; launch makes a new one). */
export async function launch() {
  return chromium.launch({
    executablePath: process.env.POSEMFA_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: CHROMIUM_ARGS,
  });
}

/** A page at 1280x800 that records console errors, page errors, dialogs and requests leaving loopback. The
 * page gets `window.__viewImage()`: the pixels of the view's canvas as ImageData (for the pixel checks).
 * Dialogs are dismissed (a confirm answers "no") unless the test sets `log.acceptDialogs = true`; either way
 * their messages are in `log.dialogs`. */
export async function openPage(browser, url, { width = 1280, height = 800 } = {}) {
  const context = await browser.newContext({ viewport: { width, height } });
  await context.addInitScript(() => {
    window.__viewImage = () => {
      const src = document.querySelector('#view canvas');
      const c = document.createElement('canvas');
      c.width = src.width;
      c.height = src.height;
      const g = c.getContext('2d');
      g.drawImage(src, 0, 0);
      return g.getImageData(0, 0, c.width, c.height);
    };
  });
  const page = await context.newPage();
  const log = { errors: [], dialogs: [], external: [], acceptDialogs: false };
  page.on('pageerror', (e) => log.errors.push(String(e)));
  page.on('console', (m) => m.type() === 'error' && log.errors.push(m.text()));
  page.on('dialog', (d) => {
    log.dialogs.push(d.message());
    if (log.acceptDialogs) d.accept();
    else d.dismiss();
  });
  page.on('request', (r) => {
    const u = new URL(r.url());
    if (!['127.0.0.1', 'localhost'].includes(u.hostname) && !['data:', 'blob:'].includes(u.protocol)) log.external.push(r.url());
  });
  await page.goto(url);
  return { page, context, log };
}

/**
 * For a test file: starts the static server (dist/) and the browser before its tests and stops them after.
 * `open(path, opts)` opens a page (see openPage) at the server's address + `path`.
 */
export function pageSession() {
  const s = {};
  before(async () => {
    s.server = await serveStatic();
    s.browser = await launch();
  });
  after(async () => {
    await s.browser?.close();
    await s.server?.close();
  });
  return { open: (path = '', opts) => openPage(s.browser, `${s.server.url}${path}`, opts) };
}

/** Waits until document.body.dataset.state is one of `states`; returns it. */
export async function waitState(page, states, timeout = 60000) {
  const list = [].concat(states);
  await page.waitForFunction((l) => l.includes(document.body.dataset.state), list, { timeout, polling: 20 });
  return page.evaluate(() => document.body.dataset.state);
}

// ---------------------------------------------------------------- generated populations (OBJ text)

// Small seeded PRNG (mulberry32): the same population on every run.
function rng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/**
 * An articulated tube: `segments` rigid pieces of length 1 along x in a chain, each hinged on its parent about
 * z (and a little about y), posed `poses` times at random angles. Closed at both ends. Returns
 * { files: [{ name, text }], partOf: part index of every vertex }.
 */
export function tubePopulation({ segments = 3, poses = 8, ringsPerSegment = 16, around = 16, radius = 0.16, seed = 7, maxDeg = 70 } = {}) {
  const random = rng(seed);
  const rest = [];
  const partOf = [];
  const rings = segments * ringsPerSegment + 1;
  for (let r = 0; r < rings; r++) {
    const x = r / ringsPerSegment;
    for (let k = 0; k < around; k++) {
      const a = (2 * Math.PI * k) / around;
      rest.push([x, radius * Math.cos(a), radius * Math.sin(a)]);
      partOf.push(Math.min(Math.floor(r / ringsPerSegment), segments - 1));
    }
  }
  rest.push([-0.04, 0, 0]); // end caps' centres
  partOf.push(0);
  rest.push([segments + 0.04, 0, 0]);
  partOf.push(segments - 1);
  const faces = [];
  for (let r = 0; r + 1 < rings; r++) {
    for (let k = 0; k < around; k++) {
      const a = r * around + k;
      const b = r * around + ((k + 1) % around);
      const c = a + around;
      const d = b + around;
      faces.push([a, c, b], [b, c, d]);
    }
  }
  const c0 = rings * around;
  const c1 = c0 + 1;
  for (let k = 0; k < around; k++) {
    faces.push([c0, k, (k + 1) % around]);
    const last = (rings - 1) * around;
    faces.push([c1, last + ((k + 1) % around), last + k]);
  }
  const files = [];
  for (let p = 0; p < poses; p++) {
    // Chain of rotations: segment s turns by angle[s] about z (and tilt[s] about y) at its joint x = s.
    const transforms = [{ R: [[1, 0, 0], [0, 1, 0], [0, 0, 1]], t: [0, 0, 0] }];
    for (let s = 1; s < segments; s++) {
      const az = ((random() * 2 - 1) * maxDeg * Math.PI) / 180;
      const ay = ((random() * 2 - 1) * maxDeg * 0.3 * Math.PI) / 180;
      const Rz = [[Math.cos(az), -Math.sin(az), 0], [Math.sin(az), Math.cos(az), 0], [0, 0, 1]];
      const Ry = [[Math.cos(ay), 0, Math.sin(ay)], [0, 1, 0], [-Math.sin(ay), 0, Math.cos(ay)]];
      const local = mul(Rz, Ry);
      const parent = transforms[s - 1];
      const R = mul(parent.R, local);
      const joint = apply(parent, [s, 0, 0]); // the joint moves with the parent
      // x -> R (x - j) + joint(world)
      const t = sub(joint, mulv(R, [s, 0, 0]));
      transforms.push({ R, t });
    }
    const lines = [`# articulated tube, ${segments} parts, pose ${p + 1} of ${poses}`];
    rest.forEach((v, i) => {
      const w = apply(transforms[partOf[i]], v);
      lines.push(`v ${w.map((c) => c.toFixed(6)).join(' ')}`);
    });
    for (const f of faces) lines.push(`f ${f[0] + 1} ${f[1] + 1} ${f[2] + 1}`);
    files.push({ name: `tube${p + 1}.obj`, text: lines.join('\n') + '\n' });
  }
  return { files, partOf, nVertices: rest.length };
}

function mul(A, B) {
  return A.map((row) => [0, 1, 2].map((j) => row[0] * B[0][j] + row[1] * B[1][j] + row[2] * B[2][j]));
}
function mulv(A, v) {
  return A.map((row) => row[0] * v[0] + row[1] * v[1] + row[2] * v[2]);
}
function sub(a, b) {
  return a.map((x, i) => x - b[i]);
}
function apply({ R, t }, v) {
  return mulv(R, v).map((x, i) => x + t[i]);
}

/** Files for page.setInputFiles. */
export const asPayload = (files) => files.map((f) => ({ name: f.name, mimeType: 'text/plain', buffer: Buffer.from(f.text) }));

/**
 * Counts, on the view's canvas, the pixels of each palette colour (exact within `tol` per channel; use the
 * page's "Flat colours" mode so that shading does not change them). Returns { [hex]: pixels }.
 */
export async function paletteCounts(page, tol = 3) {
  return page.evaluate((tol) => {
    const { data } = window.__viewImage();
    const pal = window.posemfa.palette.map((h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16)));
    const counts = Object.fromEntries(window.posemfa.palette.map((h) => [h, 0]));
    for (let p = 0; p < data.length; p += 4) {
      for (let k = 0; k < pal.length; k++) {
        const q = pal[k];
        if (Math.abs(data[p] - q[0]) <= tol && Math.abs(data[p + 1] - q[1]) <= tol && Math.abs(data[p + 2] - q[2]) <= tol) {
          counts[window.posemfa.palette[k]]++;
          break;
        }
      }
    }
    return counts;
  }, tol);
}

/** A hash-like fingerprint of the view's canvas pixels (to tell whether the picture changed). */
export async function canvasFingerprint(page) {
  return page.evaluate(() => {
    const { data } = window.__viewImage();
    let h = 2166136261;
    for (let i = 0; i < data.length; i++) h = Math.imul(h ^ data[i], 16777619);
    return h >>> 0;
  });
}

/** Opens the Pose view and waits until its rig is ready (pose mode). */
export async function enterPoseMode(page) {
  await page.click('[data-testid=mode-pose]');
  await page.waitForFunction(() => window.posemfa.pose?.ready(), null, { timeout: 120000, polling: 50 });
  // the view framed for pose mode: a place on the screen measured now (a joint, a vertex) is where a press lands
  let last = null;
  for (let i = 0; i < 100; i++) {
    const now = await page.evaluate(async () => JSON.stringify([window.posemfa.camera(), await window.posemfa.pose.jointOnScreen(0), window.posemfa.pose.screenOf(0)]));
    if (now === last) return;
    last = now;
    await page.waitForTimeout(150);
  }
  throw new Error('pose mode: the view kept moving for 15 s');
}

// Moves the merge tree's parts slider to `n` as an input event does, waits until the page shows that count and
// returns the slider's dataset.
export async function moveTreeSlider(page, n) {
  await page.evaluate((v) => {
    const s = document.getElementById('tree-slider');
    s.value = String(v);
    s.dispatchEvent(new Event('input'));
  }, n);
  await page.waitForFunction((v) => document.getElementById('tree-slider').dataset.count === String(v), n);
  return page.evaluate(() => ({ ...document.getElementById('tree-slider').dataset }));
}

/** Runs `action` (async) and waits until the fit it starts has ended (the page's fit count goes up); with
 * `fitted`, until the page is fitted again too. */
export async function afterNextFit(page, action, { fitted = false, timeout = 120000 } = {}) {
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await action();
  await page.waitForFunction(([f, want]) => window.posemfa.fitCount() > f && (!want || document.body.dataset.state === 'fitted'), [fits, fitted], { timeout });
}

/** Drops `files` (a setInputFiles payload: asPayload(...) or { name, mimeType, buffer } entries) through the
 * page's file input and waits for the fit that follows (afterNextFit). */
export const dropAndFit = (page, files, opts) => afterNextFit(page, () => page.setInputFiles('[data-testid=file-input]', files), opts);

/** Opens `path` in `session` (a pageSession) with Cancel pressed as soon as the page's first fit runs, and waits
 * for that fit to end: on a population large enough that Cancel lands in the fit's first run (e.g.
 * '?preset=quadruped&vertices=20000&poses=10'), the page keeps and shows where the fit stopped. */
export async function openCancelledFirstFit(session, path) {
  const opened = await session.open(path);
  const { page } = opened;
  await page.addInitScript(() => document.addEventListener('DOMContentLoaded', () => {
    const seen = new MutationObserver(() => {
      if (document.body.dataset.state !== 'fitting') return;
      seen.disconnect();
      document.getElementById('cancel').click();
    });
    seen.observe(document.body, { attributes: true, attributeFilter: ['data-state'] });
  }));
  await page.reload();
  await page.waitForFunction(() => window.posemfa?.fitCount() > 0, null, { timeout: 120000 });
  return opened;
}

/** The OBJ files of `folder` in natural order, as { name, text } (for asPayload). */
export const objFiles = (folder) => readdirSync(folder).filter((f) => f.endsWith('.obj'))
  .sort((a, b) => a.localeCompare(b, 'en', { numeric: true }))
  .map((name) => ({ name, text: readFileSync(join(folder, name), 'utf8') }));

/** Builds the debug CLI if needed; returns its path. */
export function debugCli() {
  execFileSync('cargo', ['build', '--quiet', '--bin', 'posemfa'], { cwd: ROOT, stdio: 'inherit' });
  return join(ROOT, 'target', 'debug', 'posemfa');
}

/** From now on answers every question the page asks in itself (www/ask.js: Step / Run / Reset before they drop a
 * finished fit, Fit before it drops a step-by-step one) yes or no, as openPage's dialog handler does for the
 * browser's boxes; `askedQuestions(page)` lists the questions asked since. */
export async function answerQuestions(page, yes) {
  await page.evaluate((yes) => {
    window.__asked ??= [];
    window.__askObserver?.disconnect();
    const answer = () => {
      for (const box of document.querySelectorAll('[data-testid=ask][role=alertdialog]')) {
        if (box.dataset.answered) continue;
        box.dataset.answered = '1';
        window.__asked.push(box.getAttribute('aria-label'));
        box.querySelector(yes ? '[data-testid=ask-yes]' : '[data-testid=ask-no]').click();
      }
    };
    window.__askObserver = new MutationObserver(answer);
    window.__askObserver.observe(document.body, { childList: true, subtree: true });
    answer();
  }, yes);
}
export const askedQuestions = (page) => page.evaluate(() => window.__asked ?? []);

/** The page's summary of the fit shown (window.posemfa.summary()), or null. */
export const summary = (page) => page.evaluate(() => window.posemfa.summary());
/** The text of the element `sel`. */
export const text = (page, sel) => page.locator(sel).innerText();
/** Resolves after two animation frames: what was asked is on the screen. */
export const frames = (page) => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

/** A page of `session` opened at `path` (the part after #) with its fit finished (the page's errors are the
 * assertion's message when it failed) and drawn: { page, context, log }. */
export async function openFitted(session, path = '', opts) {
  const p = await session.open(path, opts);
  const state = await waitState(p.page, ['fitted', 'error'], 90000);
  assert.equal(state, 'fitted', await text(p.page, '[data-testid=errors]'));
  await frames(p.page);
  return p;
}

/** Shows view mode `m` (parts, stages, recon, latent, interp, pose) as a click on its button does. */
export async function setMode(page, m) {
  await page.check(`#modes input[value=${m}]`, { force: true });
  await page.waitForFunction((x) => window.posemfa.mode() === x, m);
}

// The OBJ the export button writes now: { text, objects: [{ name, v: [[x, y, z]...], groups: [names] }] }.
export async function exportObj(page) {
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-obj')]);
  const t = await readFile(await download.path(), 'utf8');
  const objects = [];
  let cur = null;
  for (const line of t.split('\n')) {
    if (line.startsWith('o ')) objects.push((cur = { name: line.slice(2), v: [], groups: [] }));
    else if (line.startsWith('v ')) {
      if (!cur) objects.push((cur = { name: null, v: [], groups: [] }));
      cur.v.push(line.slice(2).split(' ').map(Number));
    } else if (line.startsWith('g ')) cur.groups.push(line.slice(2));
  }
  return { text: t, name: download.suggestedFilename(), objects };
}

// RMS distance between two vertex lists, over the diagonal of the first one's bounding box.
export function relativeRms(a, b) {
  assert.equal(a.length, b.length);
  let s = 0;
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  a.forEach((p, i) => {
    for (let k = 0; k < 3; k++) {
      s += (p[k] - b[i][k]) ** 2;
      lo[k] = Math.min(lo[k], p[k]);
      hi[k] = Math.max(hi[k], p[k]);
    }
  });
  const diag = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  return Math.sqrt(s / a.length) / diag;
}

// Asserts that the page is fitted (its errors shown if not).
export async function untilFitted(page) {
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted', await text(page, '[data-testid=errors]'));
}

// Waits until the fit after `n` ended and the page is fitted.
export async function nextFit(page, n) {
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n, { timeout: 180000, polling: 50 });
  await untilFitted(page);
}
