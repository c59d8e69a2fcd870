#!/usr/bin/env node
// The page's rig export against the native one on the same folder (default ../shared/data/horse-poses): the
// BUILT page (dist/, `npm run build`) in headless Chromium fits the folder (picked through its folder input, fit
// parameters at their defaults, "Parts in the end" from --bones), then exports the rig of the export panel (fitted
// weights, 4 influences, free joints, no morphs); natively `posemfa rig-report FOLDER --weights fitted` (release
// build) does the same. Compared: the core's own timers of building the rig (weights, bones), writing the .glb and
// measuring it (rig + write + evaluate), in wasm in the page's worker and natively; and the E_RMS of both.
// Runs alternate between the two; figures are medians over --runs (default 3).
// Usage: node scripts/bench-rig-page.mjs [FOLDER] [--runs N] [--bones N]
import { existsSync, statSync } from 'node:fs';
import { resolve } from 'node:path';
import { execFileSync } from 'node:child_process';
import { serveStatic, launch, openPage, waitState, ROOT } from '../tests/e2e/helpers.mjs';

const args = process.argv.slice(2);
let runs = 3;
let bones = null;
const rest = [];
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--runs') runs = Number(args[++i]);
  else if (args[i] === '--bones') bones = args[++i];
  else rest.push(args[i]);
}
const folder = resolve(rest[0] ?? resolve(ROOT, '../shared/data/horse-poses'));
if (!existsSync(folder) || !statSync(folder).isDirectory()) {
  console.error(`bench-rig-page: the folder ${folder} is absent; give a folder of OBJ files on the command line`);
  process.exit(2);
}
const median = (xs) => [...xs].sort((a, b) => a - b)[(xs.length - 1) >> 1];

execFileSync('cargo', ['build', '--release', '--quiet', '--bin', 'posemfa'], { cwd: ROOT, stdio: 'inherit' });
const bin = resolve(ROOT, 'target/release/posemfa');
const server = await serveStatic();
const browser = await launch();
const page_ = [];
const native = [];
try {
  for (let r = 0; r < runs; r++) {
    const { page, context, log } = await openPage(browser, server.url);
    await waitState(page, ['fitted', 'idle', 'error'], 120000);
    if (bones) await page.fill('#params input[name=targetParts]', String(bones));
    const fits = await page.evaluate(() => window.posemfa.fitCount());
    await page.setInputFiles('#folder-input', folder);
    await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 600000, polling: 50 });
    if (await page.evaluate(() => document.body.dataset.state) !== 'fitted') throw new Error(await page.locator('[data-testid=errors]').innerText());
    await page.selectOption('#rig select[name=weights]', 'fitted');
    await page.fill('#rig input[name=influences]', '4');
    const t0 = Date.now();
    await Promise.all([page.waitForEvent('download', { timeout: 600000 }), page.click('#export-gltf')]);
    const wallMs = Date.now() - t0;
    const d = await page.evaluate(() => ({ ...document.querySelector('[data-testid=rig-erms]').dataset }));
    if (log.errors.length) throw new Error(`page errors: ${log.errors}`);
    page_.push({ ms: Number(d.ms), wallMs, eRms: Number(d.erms), bones: Number(d.bones) });
    await context.close();
    const cli = ['rig-report', folder, '--weights', 'fitted', '--influences', '4', ...(bones ? ['--bones', String(bones)] : [])];
    const rep = JSON.parse(execFileSync(bin, cli, { encoding: 'utf8' }));
    const t = rep.timings_ms;
    native.push({ ms: t.rig + t.write + t.evaluate, articulateMs: t.articulate, eRms: rep.e_rms, bones: rep.bones });
    console.error(JSON.stringify({ run: r, page: page_.at(-1), native: native.at(-1) }));
  }
} finally {
  await browser.close();
  await server.close();
}
const pageMs = median(page_.map((x) => x.ms));
const nativeMs = median(native.map((x) => x.ms));
console.log(JSON.stringify({
  folder,
  pageRigMs: Math.round(pageMs),
  pageClickToDownloadMs: Math.round(median(page_.map((x) => x.wallMs))),
  nativeRigMs: Math.round(nativeMs),
  ratio: Number((pageMs / nativeMs).toFixed(2)),
  pageErms: page_[0].eRms,
  nativeErms: native[0].eRms,
  bones: [page_[0].bones, native[0].bones],
  runs: { page: page_, native },
}, null, 2));
