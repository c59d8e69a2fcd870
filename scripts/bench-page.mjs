#!/usr/bin/env node
// Loads the BUILT page (dist/, `npm run build`) in headless Chromium and prints JSON:
//   { loadToFittedDefaultMs, fitMs, parts, rmse, runs: [...] }
// loadToFittedDefaultMs: navigation start -> the built-in population fitted (the page's own performance marks);
// fitMs, parts, rmse: the folder given on the command line (default ../shared/data/horse-poses), picked through
// the page's folder input and fitted; fitMs is the page's own timer (wall time in the worker).
// Figures are medians over --runs (default 3) fresh pages. Usage: node scripts/bench-page.mjs [FOLDER] [--runs N]
import { existsSync, statSync } from 'node:fs';
import { resolve } from 'node:path';
import { serveStatic, launch, openPage, waitState, ROOT } from '../tests/e2e/helpers.mjs';

const args = process.argv.slice(2);
let runs = 3;
const rest = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--runs') runs = Number(args[++i]);
  else rest.push(args[i]);
}
const folder = resolve(rest[0] ?? resolve(ROOT, '../shared/data/horse-poses'));
if (!existsSync(folder) || !statSync(folder).isDirectory()) {
  console.error(`bench-page: the folder ${folder} is absent; give a folder of OBJ files on the command line`);
  process.exit(2);
}

const median = (xs) => {
  const v = xs.filter((x) => typeof x === 'number').sort((a, b) => a - b);
  return v.length ? v[(v.length - 1) >> 1] : null;
};

const server = await serveStatic();
const browser = await launch();
const results = [];
try {
  for (let r = 0; r < runs; r++) {
    const { page, context, log } = await openPage(browser, server.url);
    const first = await waitState(page, ['fitted', 'idle', 'error'], 120000);
    const loadToFittedDefaultMs = first === 'fitted'
      ? await page.evaluate(() => performance.getEntriesByName('posemfa:fitted')[0].startTime)
      : null; // this build has no built-in population
    const before = await page.evaluate(() => [window.posemfa.fitCount(), window.posemfa.loadErrorCount()]);
    await page.setInputFiles('#folder-input', folder);
    await page.waitForFunction(([f, l]) => window.posemfa.fitCount() > f || window.posemfa.loadErrorCount() > l, before, { timeout: 300000, polling: 20 });
    const state = await page.evaluate(() => document.body.dataset.state);
    if (state !== 'fitted') throw new Error(`the folder was not fitted: ${await page.locator('[data-testid=errors]').innerText()}`);
    const s = await page.evaluate(() => window.posemfa.summary());
    if (log.errors.length || log.external.length) throw new Error(`page errors ${log.errors} / external requests ${log.external}`);
    results.push({ loadToFittedDefaultMs, fitMs: s.fitMs, parts: s.parts, rmse: s.rmse, shapes: s.shapes, vertices: s.vertices });
    await context.close();
  }
} finally {
  await browser.close();
  await server.close();
}

const round = (x) => (typeof x === 'number' ? Math.round(x) : x);
console.log(JSON.stringify({
  loadToFittedDefaultMs: round(median(results.map((r) => r.loadToFittedDefaultMs))),
  fitMs: round(median(results.map((r) => r.fitMs))),
  parts: median(results.map((r) => r.parts)),
  rmse: median(results.map((r) => r.rmse)),
  folder,
  runs: results.map((r) => ({ ...r, loadToFittedDefaultMs: round(r.loadToFittedDefaultMs), fitMs: round(r.fitMs) })),
}, null, 2));
