#!/usr/bin/env node
// Opening a model file in the BUILT page (dist/, `npm run build`) against fitting the same poses, in headless
// Chromium, side by side in one run. For each folder of OBJ poses: the CLI (target/release/posemfa, built when
// missing) fits it and saves its model file with the poses (and without); then, on fresh pages, the folder is
// picked and fitted, and the model file is picked and opened. Prints JSON per folder, medians over --runs:
//   fitMs          pick of the folder -> parts shown (the 'fitted' state and the next frame), the fit included
//   openMs         pick of the model file -> parts shown (no fit)
//   openBareMs     the same for the model file saved without its poses
//   bytes, bareBytes, rawBytes (f32 points + u32 triangles), parts (the two must agree)
// Usage: node scripts/bench-model-page.mjs FOLDER... [--runs N]   (default ../shared/data/horse-gallop)
import { existsSync, mkdtempSync, readFileSync, readdirSync, statSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { join, resolve, basename } from 'node:path';
import { tmpdir } from 'node:os';
import { serveStatic, launch, openPage, waitState, ROOT } from '../tests/e2e/helpers.mjs';

const args = process.argv.slice(2);
let runs = 3;
const folders = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--runs') runs = Number(args[++i]);
  else folders.push(resolve(args[i]));
}
if (!folders.length) folders.push(resolve(ROOT, '../shared/data/horse-gallop'));
for (const f of folders) {
  if (!existsSync(f) || !statSync(f).isDirectory()) {
    console.error(`bench-model-page: the folder ${f} is absent; give folders of OBJ poses on the command line`);
    process.exit(2);
  }
}

const cli = join(ROOT, 'target/release/posemfa');
if (!existsSync(cli)) execFileSync('cargo', ['build', '--release', '--quiet', '--bin', 'posemfa'], { cwd: ROOT, stdio: 'inherit' });
const median = (xs) => {
  const v = xs.filter((x) => typeof x === 'number').sort((a, b) => a - b);
  return v.length ? v[(v.length - 1) >> 1] : null;
};

// From the input's change event (the pick) to the first frame after the page reached 'fitted'.
async function timePick(page, pick) {
  await page.evaluate(() => {
    window.__picked = null;
    for (const id of ['file-input', 'folder-input']) {
      document.getElementById(id).addEventListener('change', () => { window.__picked = performance.now(); }, { capture: true, once: true });
    }
  });
  const before = await page.evaluate(() => [window.posemfa.fitCount(), window.posemfa.loadErrorCount()]);
  await pick();
  await page.waitForFunction(([f, l]) => window.posemfa.fitCount() > f || window.posemfa.loadErrorCount() > l, before, { timeout: 300000, polling: 5 });
  const state = await page.evaluate(() => document.body.dataset.state);
  if (state !== 'fitted') throw new Error(`not opened: ${await page.locator('[data-testid=errors]').innerText()}`);
  const ms = await page.evaluate(() => new Promise((ok) => requestAnimationFrame(() => {
    const marks = performance.getEntriesByName('posemfa:fitted');
    ok(marks[marks.length - 1].startTime - window.__picked);
  })));
  return { ms, summary: await page.evaluate(() => window.posemfa.summary()) };
}

const server = await serveStatic();
const browser = await launch();
const out = [];
try {
  for (const folder of folders) {
    const dir = mkdtempSync(join(tmpdir(), 'posemfa-bench-model-'));
    const file = join(dir, `${basename(folder)}.posemfa`);
    const bare = join(dir, `${basename(folder)}-bare.posemfa`);
    execFileSync(cli, ['fit', folder, '--quiet', '--save', file]);
    execFileSync(cli, ['fit', '--model', file, '--quiet', '--save', bare, '--without-poses']);
    const objs = readdirSync(folder).filter((n) => n.endsWith('.obj'));
    const payload = (path) => [{ name: basename(path), mimeType: 'application/octet-stream', buffer: readFileSync(path) }];
    const rows = [];
    for (let r = 0; r < runs; r++) {
      const { page, context, log } = await openPage(browser, server.url);
      await waitState(page, ['fitted', 'idle', 'error'], 120000);
      const fit = await timePick(page, () => page.setInputFiles('#folder-input', folder));
      const open = await timePick(page, () => page.setInputFiles('#file-input', payload(file)));
      const openBare = await timePick(page, () => page.setInputFiles('#file-input', payload(bare)));
      if (fit.summary.parts !== open.summary.parts) throw new Error(`parts differ: fitted ${fit.summary.parts}, opened ${open.summary.parts}`);
      if (log.errors.length) throw new Error(`page errors: ${log.errors}`);
      rows.push({ fitMs: fit.ms, pageFitMs: fit.summary.fitMs, openMs: open.ms, openBareMs: openBare.ms, parts: open.summary.parts, shapes: open.summary.shapes, vertices: open.summary.vertices });
      await context.close();
    }
    const first = rows[0];
    const triangles = readFileSync(join(folder, objs[0]), 'utf8').split('\n').filter((l) => l.startsWith('f ')).length;
    out.push({
      folder,
      shapes: first.shapes,
      vertices: first.vertices,
      parts: first.parts,
      fitMs: Math.round(median(rows.map((x) => x.fitMs))),
      pageFitMs: Math.round(median(rows.map((x) => x.pageFitMs))),
      openMs: Math.round(median(rows.map((x) => x.openMs))),
      openBareMs: Math.round(median(rows.map((x) => x.openBareMs))),
      runs: rows.map((x) => [Math.round(x.fitMs), Math.round(x.openMs), Math.round(x.openBareMs)]),
      bytes: statSync(file).size,
      bareBytes: statSync(bare).size,
      rawBytes: first.shapes * first.vertices * 12 + triangles * 12,
    });
  }
} finally {
  await browser.close();
  await server.close();
}
console.log(JSON.stringify(out, null, 1));
