// The export buttons: each says what it writes before it is pressed; files are named after the population (or
// "population" when the file names share nothing), an interpolation by its two poses and t, a rig by its options;
// where two meshes are shown the OBJ holds both, named for what they are, and the Stages view's OBJ each stage's
// parts as groups. The drop overlay names every format the header does.
// Run: npm run build && node --test tests/e2e/exports.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, asPayload, tubePopulation, dropAndFit, summary, text, frames, openFitted, setMode, exportObj, relativeRms } from './helpers.mjs';

const session = pageSession();

const fitted = (path, opts) => openFitted(session, path, opts);

test('every export button says what it writes before it is pressed', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const ids = ['export-json', 'export-obj', 'export-gltf', 'pose-export-obj', 'pose-export-glb', 'pose-export-frames'];
  const titles = await page.evaluate((list) => list.map((id) => document.getElementById(id)?.title ?? null), ids);
  titles.forEach((t, k) => assert.ok(t && t.length > 10, `#${ids[k]} has a tooltip: ${t}`));
  assert.equal(new Set(titles).size, ids.length, 'each says its own');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the exports are named after the population, and the drop overlay names every format the header does', async () => {
  const { page, context, log } = await session.open('#ex=arm');
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const [json] = await Promise.all([page.waitForEvent('download'), page.click('#export-json')]);
  assert.equal(json.suggestedFilename(), 'posemfa-arm-model.json');
  const files = tubePopulation({ poses: 4 }).files;
  const c = await page.evaluate(() => window.posemfa.fitCount());
  await page.setInputFiles('[data-testid=file-input]', asPayload(files));
  await page.waitForFunction((x) => window.posemfa.fitCount() > x && document.body.dataset.state === 'fitted', c, { timeout: 120000 });
  const [obj] = await Promise.all([page.waitForEvent('download'), page.click('#export-obj')]);
  assert.equal(obj.suggestedFilename(), 'posemfa-tube-pose_tube1.obj');
  const overlay = await page.locator('#drop-overlay').textContent();
  for (const format of ['OBJ', 'PLY', 'glTF', 'FBX', 'USD', 'point cache', '.zip']) assert.ok(overlay.includes(format), `${format} in "${overlay}"`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('export names: an interpolation by its two poses and t, files sharing no name by "population", a rig by its options', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  // 1.obj, 2.obj, ...: the names share nothing but digits
  const files = tubePopulation({ poses: 4 }).files.map((f, k) => ({ name: `${k + 1}.obj`, text: f.text }));
  await dropAndFit(page, asPayload(files), { fitted: true });
  const saved = async (selector) => (await Promise.all([page.waitForEvent('download'), page.click(selector)]))[0].suggestedFilename();
  assert.equal(await saved('#export-json'), 'posemfa-population-model.json');
  // the Pose selector on another pose than the interpolation's: the name follows the interpolation
  await page.selectOption('#pose-select', '3');
  await page.check('#modes input[value=interp]', { force: true });
  await page.waitForFunction(() => window.posemfa.mode() === 'interp');
  await page.selectOption('#pose-a', '0');
  await page.selectOption('#pose-b', '2');
  await page.waitForFunction(() => /“1\.obj” → “3\.obj”/.test(document.getElementById('caption').textContent), null, { timeout: 30000 });
  assert.match(await saved('#export-obj'), /^posemfa-population-1-to-3-t0\.50-.+\.obj$/);
  await page.selectOption('#rig select[name=morphs]', 'residual');
  assert.match(await saved('#export-gltf'), /^posemfa-population-rig-.+-\d+bones.*-residual-morphs\.glb$/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('OBJ export: both meshes where two are shown, named for what they are; Stages: each stage\'s parts as groups', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  await setMode(page, 'recon');
  await page.waitForFunction(() => window.posemfa.shown().join() === 'original,reconstruction');
  assert.equal(await text(page, '#export-obj'), 'OBJ of the 2 shown meshes');
  const recon = await exportObj(page);
  assert.deepEqual(recon.objects.map((o) => o.name), ['original', 'reconstruction']);
  assert.equal(recon.objects[0].v.length, s.vertices);
  assert.equal(recon.objects[1].v.length, s.vertices);
  const r = relativeRms(recon.objects[0].v, recon.objects[1].v);
  assert.ok(r > 0 && r < 0.03, `the reconstruction is its own mesh, close to the original: ${r}`);
  assert.match(recon.name, /original_reconstruction/);
  const faces = [...recon.text.matchAll(/^f /gm)].length;
  assert.ok(faces > 0 && faces % 2 === 0, `${faces} faces: each mesh its own triangles`);
  await setMode(page, 'stages');
  await page.waitForFunction(() => window.posemfa.shown().join() === 'coarse,refined,final');
  const st = await exportObj(page);
  assert.deepEqual(st.objects.map((o) => o.name), ['coarse', 'refined', 'final']);
  const groups = st.objects.map((o) => o.groups.length);
  assert.equal(groups[0], s.coarseParts);
  assert.equal(groups[2], s.parts);
  assert.ok(st.objects[2].groups.every((g) => /^final_part_\d+$/.test(g)), st.objects[2].groups.join());
  assert.deepEqual(log.errors, []);
  await context.close();
});
