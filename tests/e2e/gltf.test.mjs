// The .glb written by `posemfa export-gltf`: the Khronos validator reports 0 errors (rigid, smooth and fitted
// weights, 8 influences, fixed joints with residual morph targets), three.js's GLTFLoader loads it, three.js
// plays the fitted rig with the E_RMS that `posemfa rig-report` prints, fixed joints keep bone lengths, morphs
// reproduce the poses, and playing the clip "training poses" reproduces every training
// pose's rigid reconstruction (from `posemfa interpolate --from I --to I --t 0 --no-residual`) within 1e-4
// of the unit box. Runs the CLI (debug build, built here if needed) on a generated quadruped.
// Run: node --test tests/e2e/gltf.test.mjs
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { validateFile } from '../../scripts/validate-gltf.mjs';

const root = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const POSES = 6;
let dir;
let bin;

function posemfa(...args) {
  return execFileSync(bin, args, { cwd: root, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
}

function readObj(file) {
  const v = [];
  for (const line of readFileSync(file, 'utf8').split('\n')) {
    if (line.startsWith('v ')) v.push(line.trim().split(/\s+/).slice(1).map(Number));
  }
  return v;
}

// Extent of a point set (largest bounding-box side): the unit box's scale in original units.
function extent(shapes) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (const s of shapes) for (const p of s) for (let d = 0; d < 3; d++) { lo[d] = Math.min(lo[d], p[d]); hi[d] = Math.max(hi[d], p[d]); }
  return Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
}

async function loadGlb(file) {
  const bytes = readFileSync(file);
  const ab = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
  return new Promise((resolve, reject) => new GLTFLoader().parse(ab, '', resolve, reject));
}

// three.js's skinning of vertex i, with the glTF's JOINTS_1 / WEIGHTS_1 too when present: three.js's own
// applyBoneTransform (and its shaders) take 4 influences and GLTFLoader renormalises those 4 to sum 1, so with 8
// three.js plays a different rig than the file's (E_RMS 6 % off on this population). The same sum runs here over
// three.js's bone matrices (bone world matrix x inverse bind matrix, between the bind matrix and its inverse).
function skin(mesh, i, v) {
  const g = mesh.geometry;
  const j1 = g.getAttribute('joints_1');
  if (!j1) {
    mesh.applyBoneTransform(i, v);
    return;
  }
  const sets = [[g.getAttribute('skinIndex'), g.getAttribute('skinWeight')], [j1, g.getAttribute('weights_1')]];
  // GLTFLoader renormalises the first four weights to sum 1 (normalizeSkinWeights); the file's eight sum to 1
  const sum = (w) => [0, 1, 2, 3].reduce((a, c) => a + w.getComponent(i, c), 0);
  const rest = sum(sets[1][1]);
  const first = sum(sets[0][1]);
  const scale = [first > 0 ? (1 - rest) / first : 0, 1];
  const base = v.clone().applyMatrix4(mesh.bindMatrix);
  const acc = new THREE.Vector3();
  const t = new THREE.Vector3();
  const m = new THREE.Matrix4();
  for (const [s, [joints, weights]] of sets.entries()) {
    for (let c = 0; c < 4; c++) {
      const w = scale[s] * weights.getComponent(i, c);
      if (!w) continue;
      const b = joints.getComponent(i, c);
      m.multiplyMatrices(mesh.skeleton.bones[b].matrixWorld, mesh.skeleton.boneInverses[b]);
      acc.addScaledVector(t.copy(base).applyMatrix4(m), w);
    }
  }
  v.copy(acc.applyMatrix4(mesh.bindMatrixInverse));
}

// Skinned vertex positions (world space) of the first SkinnedMesh at time `time` of clip `name` (morph targets
// applied), and the world positions of its bones.
function skinnedAt(gltf, name, time) {
  const clip = gltf.animations.find((a) => a.name === name);
  assert.ok(clip, `clip ${name} in ${gltf.animations.map((a) => a.name)}`);
  let mesh;
  gltf.scene.traverse((o) => { if (o.isSkinnedMesh && !mesh) mesh = o; });
  assert.ok(mesh, 'a SkinnedMesh');
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const action = mixer.clipAction(clip);
  action.setLoop(THREE.LoopOnce, 1); // at time = duration a looping action wraps to the first frame
  action.clampWhenFinished = true;
  action.play();
  mixer.setTime(time);
  gltf.scene.updateMatrixWorld(true);
  mesh.skeleton.update();
  const pos = mesh.geometry.getAttribute('position');
  const morphs = mesh.geometry.morphAttributes.position ?? [];
  const influences = mesh.morphTargetInfluences ?? [];
  const out = [];
  const v = new THREE.Vector3();
  const d = new THREE.Vector3();
  for (let i = 0; i < pos.count; i++) {
    v.fromBufferAttribute(pos, i);
    // glTF morph targets are relative displacements, applied before skinning (as three.js's shaders do)
    for (let t = 0; t < morphs.length; t++) {
      if (influences[t]) v.addScaledVector(d.fromBufferAttribute(morphs[t], i), influences[t]);
    }
    skin(mesh, i, v);
    v.applyMatrix4(mesh.matrixWorld);
    out.push([v.x, v.y, v.z]);
  }
  const bones = mesh.skeleton.bones.map((b) => {
    const w = new THREE.Vector3();
    b.getWorldPosition(w);
    return { parent: mesh.skeleton.bones.indexOf(b.parent), at: [w.x, w.y, w.z] };
  });
  mixer.stopAllAction();
  return { out, clip, mesh, bones };
}

function maxDistance(a, b) {
  assert.equal(a.length, b.length);
  let m = 0;
  for (let i = 0; i < a.length; i++) m = Math.max(m, Math.hypot(a[i][0] - b[i][0], a[i][1] - b[i][1], a[i][2] - b[i][2]));
  return m;
}

before(() => {
  execFileSync('cargo', ['build', '--quiet', '--bin', 'posemfa'], { cwd: root, stdio: 'inherit' });
  bin = path.join(root, 'target', 'debug', 'posemfa');
  dir = mkdtempSync(path.join(tmpdir(), 'posemfa-gltf-'));
  posemfa('generate', 'quadruped', '--vertices', '1500', '--poses', String(POSES), '--seed', '4', '--out', path.join(dir, 'pop'));
  posemfa('export-gltf', path.join(dir, 'pop'), '--out', path.join(dir, 'rigid.glb'));
  posemfa('export-gltf', path.join(dir, 'pop'), '--out', path.join(dir, 'smooth.glb'), '--weights', 'smooth');
  posemfa('export-gltf', path.join(dir, 'pop'), '--out', path.join(dir, 'fitted.glb'), '--weights', 'fitted');
  posemfa('export-gltf', path.join(dir, 'pop'), '--out', path.join(dir, 'fitted8.glb'), '--weights', 'fitted', '--influences', '8');
  posemfa('export-gltf', path.join(dir, 'pop'), '--out', path.join(dir, 'fixed-morphs.glb'), '--weights', 'fitted',
    '--joints', 'fixed', '--morphs', 'residual');
  posemfa('export-gltf', path.join(dir, 'pop'), '--out', path.join(dir, 'fitted-scale.glb'), '--weights', 'fitted',
    '--bone-scale');
  posemfa('export-gltf', path.join(dir, 'pop'), '--out', path.join(dir, 'fitted-affine.glb'), '--weights', 'fitted',
    '--bone-affine');
});

after(() => {
  if (dir) rmSync(dir, { recursive: true, force: true });
});

test('the Khronos validator reports 0 errors and 0 warnings (rigid, smooth, fitted weights; 8 influences; fixed joints and residual morphs; bone scale; affine bones)', async () => {
  for (const f of ['rigid.glb', 'smooth.glb', 'fitted.glb', 'fitted8.glb', 'fixed-morphs.glb', 'fitted-scale.glb', 'fitted-affine.glb']) {
    const r = await validateFile(path.join(dir, f));
    assert.equal(r.errors, 0, `${f}: ${JSON.stringify(r.messages)}`);
    assert.equal(r.warnings, 0, `${f}: ${JSON.stringify(r.messages)}`);
  }
});

test('a corrupted .glb is reported by the validator (the check can fail)', async () => {
  const bytes = readFileSync(path.join(dir, 'rigid.glb'));
  // overwrite the BIN chunk's first inverse-bind / position bytes with NaNs
  const bad = Buffer.from(bytes);
  const jsonLen = bad.readUInt32LE(12);
  const binStart = 20 + jsonLen + 8;
  for (let k = 0; k < 64; k += 4) bad.writeFloatLE(NaN, binStart + k);
  const file = path.join(dir, 'bad.glb');
  (await import('node:fs')).writeFileSync(file, bad);
  const r = await validateFile(file);
  assert.ok(r.errors > 0, JSON.stringify(r));
});

test('three.js loads it; the training clip reproduces every rigid reconstruction within 1e-4 (unit box)', async () => {
  const gltf = await loadGlb(path.join(dir, 'rigid.glb'));
  const names = gltf.animations.map((a) => a.name).sort();
  assert.deepEqual(names, ['interpolated', 'training poses']);
  const objs = readdirSync(path.join(dir, 'pop')).filter((f) => f.endsWith('.obj'));
  const originals = objs.map((f) => readObj(path.join(dir, 'pop', f)));
  const scale = extent(originals);
  for (let pose = 1; pose <= POSES; pose++) {
    const ref = path.join(dir, `rigid-${pose}.obj`);
    posemfa('interpolate', path.join(dir, 'pop'), '--from', String(pose), '--to', String(pose), '--t', '0', '--no-residual', '--out', ref);
    const want = readObj(ref);
    const { out, clip } = skinnedAt(gltf, 'training poses', pose - 1);
    assert.ok(Math.abs(clip.duration - (POSES - 1)) < 1e-6, `duration ${clip.duration}`);
    const err = maxDistance(out, want) / scale;
    assert.ok(err <= 1e-4, `pose ${pose}: max error ${err} (unit box)`);
  }
  // the interpolated clip passes through the training poses too (same keyframe times)
  const want = readObj(path.join(dir, 'rigid-3.obj'));
  const { out } = skinnedAt(gltf, 'interpolated', 2);
  assert.ok(maxDistance(out, want) / scale <= 1e-4);
  // and between keyframes it is somewhere else than either neighbour
  const mid = skinnedAt(gltf, 'interpolated', 2.5).out;
  assert.ok(maxDistance(mid, want) / scale > 1e-3);
});

test('smooth weights: up to 4 joints per vertex, bound in the first training shape', async () => {
  const gltf = await loadGlb(path.join(dir, 'smooth.glb'));
  let mesh;
  gltf.scene.traverse((o) => { if (o.isSkinnedMesh) mesh = o; });
  const w = mesh.geometry.getAttribute('skinWeight');
  let blended = 0;
  for (let i = 0; i < w.count; i++) {
    const ws = [w.getX(i), w.getY(i), w.getZ(i), w.getW(i)];
    assert.ok(Math.abs(ws.reduce((a, b) => a + b, 0) - 1) < 1e-5);
    if (ws.filter((x) => x > 0).length > 1) blended++;
  }
  assert.ok(blended > w.count * 0.05, `only ${blended} of ${w.count} vertices blend joints`);
  const objs = readdirSync(path.join(dir, 'pop')).filter((f) => f.endsWith('.obj'))
    .sort((a, b) => a.localeCompare(b, 'en', { numeric: true }));
  const first = readObj(path.join(dir, 'pop', objs[0]));
  const { out } = skinnedAt(gltf, 'training poses', 0);
  assert.ok(maxDistance(out, first) / extent([first]) <= 1e-4);
});

// E_RMS (Kavan et al. 2010) of a .glb's training clip as three.js plays it, against the population's OBJ files;
// d is the diagonal of the bind pose (the first file: the population has no reference.obj).
async function threeErms(file) {
  const gltf = await loadGlb(file);
  const objs = readdirSync(path.join(dir, 'pop')).filter((f) => f.endsWith('.obj'))
    .sort((a, b) => a.localeCompare(b, 'en', { numeric: true }));
  let sq = 0;
  let n = 0;
  let worst = 0;
  const rest = readObj(path.join(dir, 'pop', objs[0]));
  const lengths = [];
  for (let i = 0; i < objs.length; i++) {
    const want = readObj(path.join(dir, 'pop', objs[i]));
    const { out, bones } = skinnedAt(gltf, 'training poses', i);
    for (let v = 0; v < out.length; v++) {
      const e2 = (out[v][0] - want[v][0]) ** 2 + (out[v][1] - want[v][1]) ** 2 + (out[v][2] - want[v][2]) ** 2;
      sq += e2;
      worst = Math.max(worst, Math.sqrt(e2));
    }
    n += out.length;
    lengths.push(bones.map((b) => (b.parent < 0 ? 0 : Math.hypot(...b.at.map((c, d) => c - bones[b.parent].at[d])))));
  }
  const lo = [0, 1, 2].map((d) => Math.min(...rest.map((p) => p[d])));
  const hi = [0, 1, 2].map((d) => Math.max(...rest.map((p) => p[d])));
  const diag = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  let lengthChange = 0;
  for (let b = 0; b < lengths[0].length; b++) {
    const ls = lengths.map((f) => f[b]);
    lengthChange = Math.max(lengthChange, (Math.max(...ls) - Math.min(...ls)) / diag);
  }
  return { eRms: (1000 * Math.sqrt(sq / (3 * n))) / diag, maxOverDiag: worst / diag, lengthChange };
}

test('fitted weights: three.js plays the E_RMS that rig-report prints (within 1 %), below rigid weights', async () => {
  const report = (f) => JSON.parse(posemfa('rig-report', path.join(dir, 'pop'), '--glb', path.join(dir, f)));
  for (const f of ['rigid.glb', 'fitted.glb', 'fitted8.glb', 'fitted-scale.glb', 'fitted-affine.glb']) {
    const three = await threeErms(path.join(dir, f));
    const ours = report(f);
    assert.ok(Math.abs(three.eRms - ours.e_rms) <= 0.01 * ours.e_rms, `${f}: three.js ${three.eRms}, rig-report ${ours.e_rms}`);
  }
  const rigid = report('rigid.glb').e_rms;
  const fitted = report('fitted.glb').e_rms;
  assert.ok(fitted < 0.8 * rigid, `fitted ${fitted} vs rigid ${rigid}`);
  // scale channels: the skin's joints are the bones' leaf nodes, whose scale the clip animates
  const bytes = readFileSync(path.join(dir, 'fitted-scale.glb'));
  const scaled = JSON.parse(bytes.subarray(20, 20 + bytes.readUInt32LE(12)).toString());
  const paths = scaled.animations[0].channels.map((c) => c.target.path);
  assert.ok(paths.includes('scale'), `channels ${[...new Set(paths)]}`);
  assert.ok(report('fitted-scale.glb').e_rms <= fitted * 1.001, `bone scale ${report('fitted-scale.glb').e_rms} vs fitted ${fitted}`);
  // affine bones: two leaves per bone, the scale axes turning (rotation channels on both leaves)
  const affineBytes = readFileSync(path.join(dir, 'fitted-affine.glb'));
  const affine = JSON.parse(affineBytes.subarray(20, 20 + affineBytes.readUInt32LE(12)).toString());
  assert.equal(affine.skins[0].joints.every((j) => affine.nodes[j].name.endsWith(' skin')), true);
  assert.ok(report('fitted-affine.glb').e_rms <= report('fitted-scale.glb').e_rms * 1.02, `affine ${report('fitted-affine.glb').e_rms} vs bone scale ${report('fitted-scale.glb').e_rms}`);
});

test('fixed joints and residual morphs: in three.js every bone keeps its length and every pose is reproduced within 1e-5 of the diagonal', async () => {
  const fixed = await threeErms(path.join(dir, 'fixed-morphs.glb'));
  assert.ok(fixed.lengthChange <= 1e-5, `bone length changes by ${fixed.lengthChange} of the diagonal`);
  assert.ok(fixed.maxOverDiag <= 1e-5, `max error ${fixed.maxOverDiag} of the diagonal`);
  const free = await threeErms(path.join(dir, 'fitted.glb'));
  assert.ok(free.lengthChange > 1e-3, `free joints: lengths change by ${free.lengthChange} only`);
  assert.ok(free.maxOverDiag > 1e-3, `without morphs: max error ${free.maxOverDiag}`);
});

// The same functions through the wasm build for Node (pkg-node/, written by scripts/build-wasm.sh, which
// scripts/test.sh runs before these tests).
test('wasm: interpolate, keyframes, skinWeights, skeleton, rig', async (t) => {
  const pkg = path.join(root, 'pkg-node', 'posemfa.js');
  let wasm;
  try {
    wasm = (await import('node:module')).createRequire(import.meta.url)(pkg);
  } catch (e) {
    t.skip(`no wasm build for Node at ${pkg} (run npm run build:wasm): ${e.message}`);
    return;
  }
  assert.equal(typeof wasm.FitModel.prototype.rig, 'function', 'pkg-node is older than the articulation bindings: rebuild');
  const syn = new wasm.Synthetic({ preset: 'quadruped', vertices: 1200, poses: 4, seed: 3 });
  const pop = syn.population();
  const fitter = new wasm.Fitter(pop, {});
  while (!fitter.isDone()) fitter.run(1e9);
  const model = fitter.result();
  const nv = pop.nVertices;
  const close = (a, b, tol) => {
    assert.equal(a.length, b.length);
    let m = 0;
    for (let i = 0; i < a.length; i++) m = Math.max(m, Math.abs(a[i] - b[i]));
    assert.ok(m <= tol, `max difference ${m}`);
  };
  close(model.interpolate(0, 3, 0, {}), pop.positions(0), 1e-6);
  close(model.interpolate(0, 3, 1, undefined), pop.positions(3), 1e-6);
  close(model.interpolate(0, 3, 1, { residual: false }), model.reconstruct(3), 1e-6);
  close(model.interpolate(0, 3, 0, { skin: 'smooth', root: 'paper', exactEnds: true }), pop.positions(0), 1e-6);
  close(model.keyframes([0, 2, 1], 1, {}), pop.positions(2), 1e-6);
  const mid = model.interpolate(0, 3, 0.5, { skin: 'smooth' });
  assert.equal(mid.length, 3 * nv);
  assert.ok(mid.every(Number.isFinite));
  assert.throws(() => model.interpolate(0, 3, 0.5, { skin: 'rubber' }), /skin|variant/);
  assert.throws(() => model.interpolate(0, 9, 0.5, {}), /pose/);
  const w = model.skinWeights('smooth');
  const parts = model.nParts;
  assert.equal(w.length, nv * parts);
  for (let v = 0; v < nv; v++) {
    let s = 0;
    for (let k = 0; k < parts; k++) s += w[v * parts + k];
    assert.ok(Math.abs(s - 1) < 1e-5);
  }
  const sk = model.skeleton(0);
  assert.equal(sk.parents.length, parts);
  assert.equal(sk.parents[sk.root], -1);
  const report = model.articulationReport(0, 3, 0.5);
  assert.ok(report.methods.length >= 5);
  for (const weights of ['rigid', 'smooth']) {
    const { glb } = model.rig({ weights });
    const file = path.join(dir, `wasm-${weights}.glb`);
    (await import('node:fs')).writeFileSync(file, glb);
    const r = await validateFile(file);
    assert.equal(r.errors, 0, JSON.stringify(r.messages));
  }
});
