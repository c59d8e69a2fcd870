#!/usr/bin/env node
// Writes the README's pictures from the BUILT page (dist/, `npm run build`), in headless Chromium:
//   docs/img/page-horse.png  the app after a drop of a real population (default ../shared/data/horse-poses),
//                            fitted with the default parameters, parts view
//   docs/img/article.png     explain.html, its first figure once fitted
// Usage: node scripts/screenshots.mjs [FOLDER] [--out DIR] [--width PX]
// The meshes of ../shared/data are for research use only: the pictures show them at screen resolution and are
// the only thing taken from them; the meshes themselves are never committed.
import { existsSync, mkdirSync, statSync } from 'node:fs';
import { resolve, join } from 'node:path';
import { serveStatic, launch, openPage, waitState, ROOT } from '../tests/e2e/helpers.mjs';

const args = process.argv.slice(2);
let out = join(ROOT, 'docs/img');
let width = 900;
const rest = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--out') out = resolve(args[++i]);
  else if (args[i] === '--width') width = Number(args[++i]);
  else if (args[i].startsWith('--')) {
    console.error(`screenshots: unknown option ${args[i]} (options: --out DIR, --width PX)`);
    process.exit(2);
  } else rest.push(args[i]);
}
if (!Number.isInteger(width) || width < 400) {
  console.error('screenshots: --width takes a whole number of pixels, at least 400');
  process.exit(2);
}
const folder = resolve(rest[0] ?? resolve(ROOT, '../shared/data/horse-poses'));
if (!existsSync(folder) || !statSync(folder).isDirectory()) {
  console.error(`screenshots: the folder ${folder} is absent. The page picture needs a real population: give a ` +
    'folder of OBJ files (one per pose) on the command line, e.g. ../shared/data/horse-poses.');
  process.exit(2);
}
mkdirSync(out, { recursive: true });

const server = await serveStatic();
const browser = await launch();
const written = [];
try {
  // The app: wait for the built-in example, then pick the folder as a user would and wait for its fit.
  {
    const { page, context, log } = await openPage(browser, server.url, { width, height: Math.round(width * 0.8) });
    await waitState(page, ['fitted', 'idle', 'error'], 120000);
    const before = await page.evaluate(() => window.posemfa.fitCount());
    await page.setInputFiles('#folder-input', folder);
    await page.waitForFunction((f) => window.posemfa.fitCount() > f || document.body.dataset.state === 'error', before,
      { timeout: 300000, polling: 50 });
    const state = await page.evaluate(() => document.body.dataset.state);
    if (state !== 'fitted') throw new Error(`the folder was not fitted: ${await page.locator('[data-testid=errors]').innerText()}`);
    await page.check('#modes input[value=parts]', { force: true });
    await page.waitForTimeout(500); // one more frame of the view after the mode change
    const s = await page.evaluate(() => window.posemfa.summary());
    if (log.errors.length) throw new Error(`page errors: ${log.errors.join(' | ')}`);
    const file = join(out, 'page-horse.png');
    await page.screenshot({ path: file });
    written.push({ file, shapes: s.shapes, vertices: s.vertices, parts: s.parts, rmse: s.rmse });
    await context.close();
  }
  // The article: its first figure, fitted.
  {
    const { page, context, log } = await openPage(browser, `${server.url}explain.html`, { width, height: 900 });
    const first = await page.evaluate(() => document.querySelector('[data-figure]')?.dataset.figure);
    if (!first) throw new Error('explain.html has no [data-figure] element');
    await page.waitForFunction((n) => ['fitted', 'stepping'].includes(document.querySelector(`[data-figure=${n}]`).dataset.state),
      first, { timeout: 60000, polling: 50 });
    await page.waitForFunction(() => document.body.dataset.typeset === 'done', null, { timeout: 20000 });
    const fig = page.locator(`[data-figure=${first}]`);
    await fig.scrollIntoViewIfNeeded();
    await page.waitForTimeout(500);
    if (log.errors.length) throw new Error(`page errors: ${log.errors.join(' | ')}`);
    const file = join(out, 'article.png');
    await fig.screenshot({ path: file });
    written.push({ file, figure: first });
    await context.close();
  }
} finally {
  await browser.close();
  await server.close();
}
for (const w of written) {
  console.log(JSON.stringify({ ...w, bytes: statSync(w.file).size }));
}
