// The rig from the page is the CLI's rig: a generated quadruped dropped on the built page and fitted
// with "Parts in the end" = 9, exported from the export panel (fitted weights, 4 influences); the E_RMS the page
// shows equals (within 1 %) what `posemfa rig-report --bones 9 --weights fitted` computes natively for the same files (the
// same fit and rig, in wasm and natively), and the downloaded .glb, measured by `posemfa rig-report --glb`, gives
// the page's figure; the Bones field's affine bones are the CLI's --bone-affine. Runs the CLI (debug build, built
// here if needed).
// Run: npm run build && node --test tests/e2e/rig.test.mjs
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, readdirSync, rmSync, copyFileSync, existsSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { pageSession, waitState, asPayload, ROOT } from './helpers.mjs';

const session = pageSession();
let dir;
let bin;

const posemfa = (...args) => execFileSync(bin, args, { cwd: ROOT, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });

before(() => {
  execFileSync('cargo', ['build', '--quiet', '--bin', 'posemfa'], { cwd: ROOT, stdio: 'inherit' });
  bin = path.join(ROOT, 'target', 'debug', 'posemfa');
  dir = mkdtempSync(path.join(tmpdir(), 'posemfa-rig-'));
  posemfa('generate', 'quadruped', '--vertices', '1500', '--poses', '6', '--seed', '4', '--out', path.join(dir, 'pop'));
});

after(() => {
  if (dir) rmSync(dir, { recursive: true, force: true });
});

test('the export panel writes the rig the CLI writes: same part count, same E_RMS, and the file measures what the page shows', async () => {
  const pop = path.join(dir, 'pop');
  const names = readdirSync(pop).filter((f) => f.endsWith('.obj')).sort((a, b) => a.localeCompare(b, 'en', { numeric: true }));
  const files = names.map((name) => ({ name, text: readFileSync(path.join(pop, name), 'utf8') }));
  const { page, context, log } = await session.open();
  await waitState(page, ['fitted', 'idle', 'error'], 60000);
  // new files start from "Parts in the end" on auto (fit-lifecycle.test.mjs): the count is asked for once they are in
  let fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.setInputFiles('[data-testid=file-input]', asPayload(files));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 120000, polling: 20 });
  await page.fill('#params input[name=targetParts]', '9');
  fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 120000, polling: 20 });
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted', await page.locator('[data-testid=errors]').innerText());
  assert.equal((await page.evaluate(() => window.posemfa.summary())).parts, 9);

  await page.selectOption('#rig select[name=weights]', 'fitted');
  await page.fill('#rig input[name=influences]', '4');
  const [download] = await Promise.all([page.waitForEvent('download', { timeout: 120000 }), page.click('#export-gltf')]);
  const glb = path.join(dir, 'page.glb');
  copyFileSync(await download.path(), glb);
  const shown = await page.evaluate(() => ({ ...document.querySelector('[data-testid=rig-erms]').dataset }));
  const pageErms = Number(shown.erms);
  assert.equal(Number(shown.bones), 9);
  assert.ok(pageErms > 0, JSON.stringify(shown));
  // the figure with its unit: E_RMS is 1000 x RMS error / bounding-box diagonal (Kavan et al. 2010)
  // beside the fit's own figure in the same measure (the result's E_RMS), which fitted weights beat
  const own = (await page.evaluate(() => window.posemfa.summary())).eRms;
  assert.ok(own > pageErms, `fit ${own}, rig ${pageErms}`);
  assert.match(await page.locator('[data-testid=rig-erms]').innerText(),
    new RegExp(`^${pageErms.toFixed(3).replace('.', '\\.')} \\(RMS error per coordinate, in thousandths of the bounding-box diagonal; 9 bones, at most 4 bones per vertex; max error [0-9.]+ % of the diagonal; the fit's rigid parts alone: ${own.toFixed(3).replace('.', '\\.')}; 1 clip: “training poses”, one key per pose\\)$`));
  assert.ok((await page.locator('#rmse').innerText()).endsWith(`; E_RMS ${own.toFixed(3)} (the rig's measure: RMS error per coordinate, in thousandths of the bounding-box diagonal)`));

  const cli = JSON.parse(posemfa('rig-report', pop, '--bones', '9', '--weights', 'fitted', '--influences', '4'));
  assert.equal(cli.bones, 9);
  // the fits agree to rounding, not bit for bit (wasm and native: measured 0.35 % apart in E_RMS)
  assert.ok(Math.abs(pageErms - cli.e_rms) <= 1e-2 * cli.e_rms, `page ${pageErms}, CLI ${cli.e_rms}`);
  const file = JSON.parse(posemfa('rig-report', pop, '--glb', glb));
  assert.ok(Math.abs(file.e_rms - pageErms) <= 1e-9 * pageErms, `file ${file.e_rms}, page ${pageErms}`);
  // affine bones (the Bones field): the CLI's --bone-affine rig, below the rigid bones' figure
  await page.selectOption('#rig select[name=bones]', 'affine');
  const [affineFile] = await Promise.all([page.waitForEvent('download', { timeout: 120000 }), page.click('#export-gltf')]);
  assert.match(affineFile.suggestedFilename(), /-affine-bones\.glb$/);
  await page.waitForFunction(() => document.querySelector('[data-testid=rig-erms]').dataset.erms);
  const affine = Number(await page.evaluate(() => document.querySelector('[data-testid=rig-erms]').dataset.erms));
  assert.match(await page.locator('[data-testid=rig-erms]').innerText(), /at most 4 bones per vertex, affine bones;/);
  const cliAffine = JSON.parse(posemfa('rig-report', pop, '--bones', '9', '--weights', 'fitted', '--bone-affine'));
  assert.ok(Math.abs(affine - cliAffine.e_rms) <= 1e-2 * cliAffine.e_rms, `page ${affine}, CLI ${cliAffine.e_rms}`);
  assert.ok(affine < pageErms, `affine ${affine}, rigid bones ${pageErms}`);
  // the field applies to fitted weights with free joints only
  await page.selectOption('#rig select[name=joints]', 'fixed');
  assert.equal(await page.locator('#rig select[name=bones]').isDisabled(), true);
  await page.selectOption('#rig select[name=joints]', 'free');
  await page.selectOption('#rig select[name=bones]', 'rigid');
  // rigid weights play the fit's own reconstructions: the rig's figure is the result's (f32 storage only)
  await page.selectOption('#rig select[name=weights]', 'rigid');
  await Promise.all([page.waitForEvent('download', { timeout: 120000 }), page.click('#export-gltf')]);
  const rigid = Number(await page.evaluate(() => document.querySelector('[data-testid=rig-erms]').dataset.erms));
  assert.ok(Math.abs(rigid - own) <= 1e-3 * own, `rigid rig ${rigid}, fit ${own}`);
  // options change: the figure shown is cleared until the next export
  await page.selectOption('#rig select[name=joints]', 'fixed');
  assert.equal(await page.locator('[data-testid=rig-erms]').innerText(), '–');
  assert.deepEqual(log.errors, []);
  await context.close();
});

// The page's own fit (auto part count, the core's default parameters after a drop) is the CLI's: the same parts
// at every stage and the same AECM iterations, RMSE and log-likelihood to rounding (wasm and native differ only
// in the last bits of exp / ln). Until k-means++ drew its vertex indices as u64 (rand sizes a usize range by
// the target: 32 bits in wasm), the page started from other vertices: horse-poses 32 parts in the page, 29 in
// the CLI. On a generated quadruped, and on ../shared/data/horse-poses when it is there.
async function pageFitEqualsCli(t, folder) {
  const names = readdirSync(folder).filter((f) => f.endsWith('.obj'));
  const cli = path.join(dir, 'cli.json');
  posemfa('fit', folder, '--quiet', '--json', cli);
  const want = JSON.parse(readFileSync(cli, 'utf8'));
  const { page, context, log } = await session.open();
  await waitState(page, ['fitted', 'idle', 'error'], 60000);
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.setInputFiles('[data-testid=file-input]', names.map((n) => path.join(folder, n)));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 300000, polling: 50 });
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted', await page.locator('[data-testid=errors]').innerText());
  const got = await page.evaluate(() => window.posemfa.summary());
  const stages = want.stages;
  assert.deepEqual([got.coarseParts, got.refinedParts, got.parts], [stages.coarse_parts, stages.refined_parts, stages.final_parts], 'parts per stage, page vs CLI');
  assert.equal(got.iterations, want.iterations);
  const close = (a, b) => Math.abs(a - b) <= 1e-9 * Math.abs(b);
  assert.ok(close(got.rmse, want.rmse), `RMSE page ${got.rmse}, CLI ${want.rmse}`);
  assert.ok(close(got.logLikelihood.at(-1), want.log_likelihood.at(-1)), `log-likelihood page ${got.logLikelihood.at(-1)}, CLI ${want.log_likelihood.at(-1)}`);
  assert.deepEqual(log.errors, []);
  await context.close();
  t.diagnostic(`${folder}: ${got.parts} parts, RMSE ${got.rmse}`);
}

test('the page fits a dropped folder as the CLI does (generated quadruped)', async (t) => {
  await pageFitEqualsCli(t, path.join(dir, 'pop'));
});

test('the page fits horse-poses as the CLI does (needs ../shared)', async (t) => {
  const horse = path.join(process.env.POSEMFA_SHARED ?? path.join(ROOT, '../shared'), 'data/horse-poses');
  if (!existsSync(horse)) {
    if (process.env.CI === 'true') assert.fail(`${horse} is absent, and CI=true`);
    t.skip(`${horse} is absent`);
    return;
  }
  await pageFitEqualsCli(t, horse);
});
