// Mesh formats on the page: files written by Blender (tests/fixtures/blender: a shape-key .glb, a skinned .glb
// split at every face corner, FBX with shape-key animation and with an armature), USD point caches written by
// usd-core (tests/fixtures/usd), PLY (ASCII and binary) and a .pc2 point cache with its base mesh, picked through
// the file input, are read by the core (mesh::load), fitted, and the population panel says where the poses came
// from; a damaged .glb is refused with its name and what to do, and the population and model shown are kept; a
// glTF with two animations that move the mesh offers the other one.
// Run: npm run build && node --test tests/e2e/formats.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { pageSession, waitState, tubePopulation, dropAndFit, afterNextFit, ROOT, summary } from './helpers.mjs';

const session = pageSession();
const fixture = (name) => ({ name, buffer: readFileSync(join(ROOT, 'tests/fixtures/blender', name)) });
const counters = (page) => page.evaluate(() => [window.posemfa.fitCount(), window.posemfa.loadErrorCount()]);
const shownSource = (page) => page.locator('[data-testid=pop-source]').innerText();

async function fresh() {
  const p = await session.open('');
  await waitState(p.page, ['fitted', 'idle', 'error'], 60000);
  return p;
}

// Picks binary files ({ name, buffer }) and waits until their fit has ended (throws if they were refused).
async function fitBinary(page, files, { parts = 4 } = {}) {
  await page.fill('#params input[name=parts]', String(parts));
  const [fits, errs] = await counters(page);
  await page.setInputFiles('[data-testid=file-input]', files.map((f) => ({ name: f.name, mimeType: 'application/octet-stream', buffer: f.buffer })));
  await page.waitForFunction(([f, l]) => window.posemfa.fitCount() > f || window.posemfa.loadErrorCount() > l, [fits, errs], { timeout: 120000, polling: 50 });
  const errors = await page.locator('[data-testid=errors]').innerText();
  assert.equal(await page.evaluate((l) => window.posemfa.loadErrorCount() > l, errs), false, `refused: ${errors}`);
  return page.evaluate(() => document.body.dataset.state);
}

// OBJ text (v / f lines, as tubePopulation writes) -> positions and 0-based triangles.
function parseObj(text) {
  const v = [];
  const f = [];
  for (const line of text.split('\n')) {
    const w = line.trim().split(/\s+/);
    if (w[0] === 'v') v.push(w.slice(1, 4).map(Number));
    if (w[0] === 'f') f.push(w.slice(1, 4).map((s) => parseInt(s, 10) - 1));
  }
  return { v, f };
}

function plyAscii({ v, f }) {
  const head = `ply\nformat ascii 1.0\ncomment tube\nelement vertex ${v.length}\nproperty float x\nproperty float y\nproperty float z\n` +
    `element face ${f.length}\nproperty list uchar int vertex_indices\nend_header\n`;
  return Buffer.from(head + v.map((p) => p.join(' ')).join('\n') + '\n' + f.map((t) => `3 ${t.join(' ')}`).join('\n') + '\n');
}

function plyBinaryBigEndian({ v, f }) {
  const head = Buffer.from(`ply\nformat binary_big_endian 1.0\nelement vertex ${v.length}\nproperty double x\nproperty double y\n` +
    `property double z\nelement face ${f.length}\nproperty list uchar uint vertex_indices\nend_header\n`);
  const body = Buffer.alloc(v.length * 24 + f.length * 13);
  let at = 0;
  for (const p of v) for (const c of p) at = body.writeDoubleBE(c, at);
  for (const t of f) {
    at = body.writeUInt8(3, at);
    for (const i of t) at = body.writeUInt32BE(i, at);
  }
  return Buffer.concat([head, body]);
}

// PointCache2: header, then every frame's points as float32 little endian.
function pc2(frames) {
  const points = frames[0].length;
  const b = Buffer.alloc(32 + frames.length * points * 12);
  b.write('POINTCACHE2\0', 0, 'latin1');
  b.writeInt32LE(1, 12);
  b.writeInt32LE(points, 16);
  b.writeFloatLE(0, 20);
  b.writeFloatLE(1, 24);
  b.writeInt32LE(frames.length, 28);
  let at = 32;
  for (const fr of frames) for (const p of fr) for (const c of p) at = b.writeFloatLE(c, at);
  return b;
}

test('a shape-key .glb written by Blender loads, fits and says where its poses came from; a damaged .glb is refused and the model kept', async () => {
  const { page, context } = await fresh();
  assert.equal(await fitBinary(page, [fixture('quadruped-shapekeys.glb')]), 'fitted');
  const s = await summary(page);
  assert.equal(s.shapes, 6);
  assert.equal(s.vertices, 1198);
  const source = await shownSource(page);
  assert.match(source, /^Poses: 6 frames of animation .* \(sampled at its keyframes, 24 fps\) of mesh .* in quadruped-shapekeys\.glb; 1198 vertices$/);

  const bytes = readFileSync(join(ROOT, 'tests/fixtures/blender/quadruped-shapekeys.glb'));
  const [fits, errs] = await counters(page);
  await page.setInputFiles('[data-testid=file-input]', [{ name: 'cut.glb', mimeType: 'application/octet-stream', buffer: bytes.subarray(0, 4000) }]);
  await page.waitForFunction((l) => window.posemfa.loadErrorCount() > l, errs);
  const errors = await page.locator('[data-testid=errors]').innerText();
  assert.match(errors, /cut\.glb/);
  assert.match(errors, /cut or damaged: export it again/);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  assert.deepEqual(await summary(page), s);
  assert.equal(await shownSource(page), source);
  assert.equal((await counters(page))[0], fits);
  await context.close();
});

test('a skinned .glb split at every face corner by Blender welds back to the mesh and fits', async () => {
  const { page, context } = await fresh();
  assert.equal(await fitBinary(page, [fixture('quadruped-skinned-seams.glb')]), 'fitted');
  const s = await summary(page);
  assert.equal(s.vertices, 1198);
  assert.ok(s.shapes >= 2, `${s.shapes} poses`);
  assert.match(await shownSource(page), /frames of animation .* in quadruped-skinned-seams\.glb; 7176 vertices welded to 1198 \(seams split by the exporter\)/);
  await context.close();
});

test('FBX files written by Blender (shape-key animation, skinned character) are read and fitted', async () => {
  const { page, context } = await fresh();
  assert.equal(await fitBinary(page, [fixture('quadruped-shapekeys.fbx')]), 'fitted');
  let s = await summary(page);
  assert.deepEqual([s.shapes, s.vertices], [6, 1198]);
  assert.match(await shownSource(page), /^Poses: 6 frames of posed in quadruped-shapekeys\.fbx \(animation 'Scene', 24 fps, .*5 blend shapes\); Y up, centimetres \(UnitScaleFactor 1\) turned to metres; 1198 vertices$/);
  assert.equal(await fitBinary(page, [fixture('quadruped-skinned.fbx')]), 'fitted');
  s = await summary(page);
  assert.deepEqual([s.shapes, s.vertices], [121, 1198]);
  assert.match(await shownSource(page), /^Poses: 121 frames of mesh in quadruped-skinned\.fbx \(animation 'Scene', 24 fps, .*skinned by 18 bones\)/);
  await context.close();
});

test('USD point caches written by usd-core (.usda, .usdc, .usdz) are read and fitted', async () => {
  const { page, context } = await fresh();
  for (const ext of ['usda', 'usdc', 'usdz']) {
    const name = `arm-pointcache.${ext}`;
    const buffer = readFileSync(join(ROOT, 'tests/fixtures/usd', name));
    assert.equal(await fitBinary(page, [{ name, buffer }], { parts: 3 }), 'fitted', name);
    const s = await summary(page);
    assert.deepEqual([s.shapes, s.vertices], [5, 408], name);
    assert.equal(await shownSource(page), `Poses: 5 frames of Body in ${name} (time-sampled points of /World/Character/Body, one per time sample, times 1 to 5 at 24 per second); upAxis Z turned to Y up, metersPerUnit 0.01 turned to metres; 408 vertices`);
  }
  await context.close();
});

test('PLY files (ASCII and big-endian binary) and a .pc2 with its base mesh give the tube population', async () => {
  const { page, context } = await fresh();
  const tube = tubePopulation({ segments: 3, poses: 5, seed: 9 });
  const meshes = tube.files.map((f) => parseObj(f.text));
  const plies = tube.files.map((f, i) => ({
    name: f.name.replace(/\.obj$/, '.ply'),
    buffer: i % 2 ? plyBinaryBigEndian(meshes[i]) : plyAscii(meshes[i]),
  }));
  assert.equal(await fitBinary(page, plies, { parts: 3 }), 'fitted');
  const fromPly = await summary(page);
  assert.equal(fromPly.shapes, 5);
  assert.equal(fromPly.vertices, tube.nVertices);
  assert.equal(fromPly.parts, 3);
  assert.equal(await shownSource(page), 'Poses: 5 PLY files');

  const cache = pc2(meshes.map((m) => m.v));
  const base = { name: 'rest.obj', buffer: Buffer.from(tube.files[0].text) };
  assert.equal(await fitBinary(page, [{ name: 'walk.pc2', buffer: cache }, base], { parts: 3 }), 'fitted');
  const fromCache = await summary(page);
  assert.equal(fromCache.shapes, 5);
  assert.equal(fromCache.parts, 3);
  assert.match(await shownSource(page), /^Poses: 5 frames of the point cache walk\.pc2 .*faces from rest\.obj$/);

  // a cache whose vertex count differs from its base mesh: both named, the cache's population kept
  const [, errs] = await counters(page);
  const other = { name: 'small.obj', buffer: Buffer.from('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n') };
  await page.setInputFiles('[data-testid=file-input]', [{ name: 'walk.pc2', mimeType: 'application/octet-stream', buffer: cache }, { ...other, mimeType: 'text/plain' }]);
  await page.waitForFunction((l) => window.posemfa.loadErrorCount() > l, errs);
  const errors = await page.locator('[data-testid=errors]').innerText();
  assert.match(errors, new RegExp(`walk\\.pc2.*${tube.nVertices} vertices per frame but the base mesh small\\.obj has 3`));
  assert.deepEqual(await summary(page), fromCache);
  await context.close();
});

test('a refused drop keeps the fit settings as they were (form and hidden ones); an accepted population starts from the defaults', async () => {
  // the eq 18 example: its own hidden parameters (max_iter) and the literal Λ step, which Defaults shows again
  const { page, context, log } = await session.open('#ex=literal-eq18');
  await waitState(page, ['fitted', 'error'], 60000);
  assert.equal(await page.isChecked('#params [name=paperLambda]'), true);
  await page.fill('#params [name=targetParts]', '3');
  await page.fill('#params [name=tol]', '0.01');
  let [fits, errs] = await counters(page);
  await page.click('#fit');
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 120000 });
  assert.equal(await waitState(page, ['fitted', 'error']), 'fitted');
  const s = await summary(page);
  assert.equal(s.parts, 3);
  // a broken OBJ: refused by the core, the population, model and every setting kept
  [fits, errs] = await counters(page);
  await page.setInputFiles('[data-testid=file-input]', [{ name: 'broken.obj', mimeType: 'text/plain', buffer: Buffer.from('v 0 0\nf 1 2 3\n') }]);
  await page.waitForFunction((l) => window.posemfa.loadErrorCount() > l, errs);
  assert.match(await page.locator('[data-testid=errors]').innerText(), /broken\.obj/);
  assert.equal(await waitState(page, ['fitted']), 'fitted');
  assert.deepEqual(await summary(page), s);
  assert.equal(await page.inputValue('#params [name=targetParts]'), '3', '"Parts in the end" kept');
  assert.equal(await page.inputValue('#params [name=tol]'), '0.01');
  assert.equal(await page.isChecked('#params [name=paperLambda]'), true, 'the literal Λ step kept');
  // the hidden parameters are still the example's: Defaults fills the form from them (its literal Λ step)
  await page.click('#reset-params');
  assert.equal(await page.isChecked('#params [name=paperLambda]'), true, 'Defaults: the example\'s parameters, not the core\'s');
  assert.equal((await counters(page))[0], fits, 'no fit started');
  // accepted files: "Parts in the end" back to auto and the exact Λ step; the tolerance as typed
  await page.fill('#params [name=targetParts]', '3');
  await page.fill('#params [name=tol]', '0.01');
  const tube = tubePopulation({ segments: 4, poses: 6, seed: 5 });
  await page.setInputFiles('[data-testid=file-input]', tube.files.map((f) => ({ name: f.name, mimeType: 'text/plain', buffer: Buffer.from(f.text) })));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 120000 });
  assert.equal(await waitState(page, ['fitted', 'error']), 'fitted');
  assert.equal((await summary(page)).vertices, tube.nVertices);
  assert.equal(await page.inputValue('#params [name=targetParts]'), '');
  assert.equal(await page.isChecked('#params [name=paperLambda]'), false);
  assert.equal(await page.inputValue('#params [name=tol]'), '0.01');
  await page.click('#reset-params');
  assert.equal(await page.isChecked('#params [name=paperLambda]'), false, 'Defaults: the core\'s defaults now');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a glTF with two animations that move the mesh offers the other one, and reads it when chosen', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  assert.equal(await page.locator('#clip-row').isVisible(), false, 'no list for OBJ poses');
  const buffer = readFileSync(join(ROOT, 'tests/fixtures/blender/quadruped-skinned-seams.glb'));
  await dropAndFit(page, [{ name: 'quadruped-skinned-seams.glb', mimeType: 'model/gltf-binary', buffer }]);
  assert.equal(await page.locator('#clip-row').isVisible(), true);
  const options = await page.locator('#clip option').allTextContents();
  assert.deepEqual(options, ['interpolated', 'training poses']);
  assert.equal(await page.inputValue('#clip'), 'interpolated');
  assert.match(await page.textContent('#pop-source'), /frames of animation 'interpolated' .*of the 2 animations that move it/);
  await afterNextFit(page, () => page.selectOption('#clip', 'training poses'), { fitted: true });
  assert.match(await page.textContent('#pop-source'), /frames of animation 'training poses' /);
  assert.doesNotMatch(await page.textContent('#pop-source'), /animations that move it/);
  assert.equal(await page.inputValue('#clip'), 'training poses');
  assert.deepEqual(log.errors, []);
  await context.close();
});
