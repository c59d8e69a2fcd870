// The wasm boundary, through the Node build of the bindings (pkg-node/, built with the page): errors cross as
// data ({kind, file, line, message} and `problems`), objects passed in refuse unknown fields naming them,
// everything that comes out is camelCase, the OBJ of a shown mesh comes back in the original units, and a file
// of an extension the core does not read is refused by name.
// Run: npm run build && node --test tests/e2e/boundary.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { ROOT, tubePopulation } from './helpers.mjs';

const w = createRequire(import.meta.url)(join(ROOT, 'pkg-node', 'posemfa.js'));
const bytes = (text) => new TextEncoder().encode(text);
const thrown = (f) => {
  try {
    f();
  } catch (e) {
    return e;
  }
  throw new Error('no error was thrown');
};

// Every key of a plain value (recursively), to check the casing.
function keys(v, out = new Set()) {
  if (Array.isArray(v)) v.forEach((x) => keys(x, out));
  else if (v && typeof v === 'object' && !ArrayBuffer.isView(v)) {
    for (const [k, x] of Object.entries(v)) {
      out.add(k);
      keys(x, out);
    }
  }
  return out;
}
const notCamel = (v) => [...keys(v)].filter((k) => /_/.test(k));

function fitted() {
  const tube = tubePopulation({ segments: 3, poses: 5, seed: 4 });
  // moved and scaled away from the unit box, so that the original units matter
  const files = tube.files.map((f) => ({ name: f.name, text: f.text.replace(/^v (\S+) (\S+) (\S+)$/gm, (_, x, y, z) => `v ${+x * 30 + 5} ${+y * 30 - 2} ${+z * 30 + 0.5}`) }));
  const pop = new w.Population(files.map((f) => f.name), files.map((f) => bytes(f.text)));
  const fitter = new w.Fitter(pop, { ...w.defaultParams(), parts: 3 });
  while (!fitter.isDone()) fitter.run(1000);
  return { files, pop, model: fitter.result() };
}

test('a file of an extension the core does not read is refused by name with what it reads; .mtl files are ignored', () => {
  const tri = (x) => bytes(`v ${x} 0 0\nv 1 0 0\nv 0 1 0.5\nf 1 2 3\n`);
  const e = thrown(() => new w.Population(['a.obj', 'scene.blend', 'b.obj'], [tri(0), bytes('BLENDER-v300\0\0\0binary'), tri(0.2)]));
  assert.equal(e.problems.length, 1, JSON.stringify(e.problems));
  const [p] = e.problems;
  assert.deepEqual([p.kind, p.file, p.line], ['population', 'scene.blend', null]);
  assert.equal(p.message, 'posemfa reads .obj, .ply, .glb/.gltf, .fbx, .usd/.usda/.usdc/.usdz, .pc2/.mdd with a base mesh; not .blend: export the poses as one of these (e.g. glTF from Blender), or leave the file out');
  const pop = new w.Population(['a.obj', 'a.mtl', 'b.obj'], [tri(0), bytes('newmtl skin\n'), tri(0.2)]);
  assert.equal(pop.nShapes, 2);
  assert.equal(pop.source, '2 OBJ files');
});

test('OBJ problems cross as data: every file, its line, kind and message', () => {
  const e = thrown(() => new w.Population(['a.obj', 'b.obj', 'c.obj'], [
    bytes('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n'),
    bytes('v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n'),
    bytes('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n'),
  ]));
  assert.ok(e instanceof Error);
  assert.equal(e.problems.length, 2, JSON.stringify(e.problems));
  const [b, c] = e.problems;
  assert.deepEqual([b.kind, b.file, b.line], ['obj', 'b.obj', 2]);
  assert.deepEqual([c.kind, c.file, c.line], ['obj', 'c.obj', 4]);
  assert.ok(!b.message.includes('b.obj') && b.message.length > 5, b.message);
  assert.deepEqual([e.kind, e.file, e.line], ['obj', 'b.obj', 2]);
  assert.equal(e.message.split('\n').length, 2);
  assert.match(e.message, /^file b\.obj, line 2: /);
});

test('what the article shows is measured by the core: placed latent shape, distances to the linear blend, position along the body', () => {
  const { pop, model } = fitted();
  const hyp = (a, b, v) => Math.hypot(a[3 * v] - b[3 * v], a[3 * v + 1] - b[3 * v + 1], a[3 * v + 2] - b[3 * v + 2]);
  // the latent shape with each part moved by its translation in pose 2 (the JSON export's b^i)
  const json = JSON.parse(model.toJson());
  const latent = model.latent();
  const placed = model.latentPlaced(2);
  const labels = model.labels();
  let worst = 0;
  for (let v = 0; v < labels.length; v++) {
    const b = json.parts[labels[v]].translations[2];
    for (let a = 0; a < 3; a++) worst = Math.max(worst, Math.abs(placed[3 * v + a] - (latent[3 * v + a] + b[a])));
  }
  assert.ok(worst < 1e-6, `largest difference ${worst}`);
  assert.match(thrown(() => model.latentPlaced(99)).message, /no pose 99/);
  // per vertex |interpolation - linear blend| at t, for the options asked
  for (const [t, opts] of [[0.4, {}], [1, { root: 'paper', tree: 'breadth-first', exactEnds: false, residual: false }]]) {
    const d = model.distancesToLinear(0, 3, t, opts);
    const a = model.interpolate(0, 3, t, opts);
    const lin = model.linearInterpolate(0, 3, t);
    assert.equal(d.length, labels.length);
    let off = 0;
    for (let v = 0; v < d.length; v++) off = Math.max(off, Math.abs(d[v] - hyp(a, lin, v)));
    assert.ok(off < 1e-5, `t ${t}: ${off}`);
    assert.ok(Math.max(...d) > 1e-4, `t ${t}: the interpolation differs from the blend somewhere`);
  }
  // at t = 1 the blend is pose 4: the largest distance is the articulation report's end error
  const end = model.articulationReport(0, 3, 1).methods[0].endpointError[1];
  assert.ok(Math.abs(Math.max(...model.distancesToLinear(0, 3, 1, {})) - end) < 1e-5 * Math.max(1, end), `report ${end}`);
  assert.match(thrown(() => model.distancesToLinear(0, 3, 0.5, { skinn: 'rigid' })).message, /skinn/);
  // 0 at one end of the longest side of the box, 1 at the other
  const along = pop.alongLongestAxis(0);
  assert.equal(along.length, labels.length);
  assert.equal(Math.min(...along), 0);
  assert.equal(Math.max(...along), 1);
  assert.match(thrown(() => pop.alongLongestAxis(9)).message, /no shape 9/);
});

test('the articulation a view asks for is let go when a fit starts or its model is freed, and rebuilt the same when asked again', () => {
  const a = fitted();
  const { model: b } = fitted();
  const fitB = () => {
    const f = new w.Fitter(a.pop, { ...w.defaultParams(), targetParts: 2 });
    while (!f.isDone()) f.run(1000);
    const m = f.result();
    f.free();
    return m;
  };
  const first = a.model.interpolate(0, 1, 0.5, {});
  // another model's articulation replaces A's in the cache; A's comes back the same, not B's
  const other = fitB();
  const twoParts = other.interpolate(0, 1, 0.5, {});
  assert.ok(first.some((x, k) => Math.abs(x - twoParts[k]) > 1e-4), 'the 2-part model interpolates otherwise');
  assert.deepEqual(a.model.interpolate(0, 1, 0.5, {}), first);
  // a new fit lets go of it; asked again during or after that fit, it is rebuilt
  const f = new w.Fitter(a.pop, { ...w.defaultParams(), parts: 3 });
  assert.deepEqual(a.model.interpolate(0, 1, 0.5, {}), first);
  f.free();
  // the model whose articulation is cached is freed: the next model builds its own
  a.model.free();
  assert.deepEqual(other.interpolate(0, 1, 0.5, {}), twoParts);
  assert.equal(b.interpolate(0, 1, 0.5, {}).length, first.length);
  other.free();
  b.free();
});

test('a model parked while a new fit runs comes back the same: labels, latent shape, tree, JSON, views', () => {
  const a = fitted();
  const before = {
    labels: a.model.labels(), latent: a.model.latent(), coarse: a.model.coarseLabels(), refined: a.model.refinedLabels(),
    tree: a.model.treeCuts().counts(), json: a.model.toJson(), pose: a.model.reconstruct(1), mid: a.model.interpolate(0, 1, 0.5, {}),
  };
  const fewest = before.tree.fewest;
  const treeLabels = a.model.treeCuts().labels(fewest);
  const parked = a.model.park();
  assert.throws(() => a.model.labels(), 'the parked FitModel object is spent');
  // a new fit of the same population runs meanwhile and is dropped (as a cancelled refit)
  const f = new w.Fitter(a.pop, { ...w.defaultParams(), targetParts: 2 });
  while (!f.isDone()) f.run(1000);
  f.result().free();
  f.free();
  const m = parked.restore();
  assert.throws(() => parked.restore(), 'the ParkedModel object is spent');
  assert.deepEqual(m.labels(), before.labels);
  assert.deepEqual(m.latent(), before.latent);
  assert.deepEqual(m.coarseLabels(), before.coarse);
  assert.deepEqual(m.refinedLabels(), before.refined);
  assert.deepEqual(m.treeCuts().counts(), before.tree);
  assert.deepEqual(m.treeCuts().labels(fewest), treeLabels);
  assert.equal(m.toJson(), before.json);
  assert.deepEqual(m.reconstruct(1), before.pose);
  assert.deepEqual(m.interpolate(0, 1, 0.5, {}), before.mid);
  m.free();
  a.pop.free();
});

test('misspelled fields of parameters, generator specs, options and mesh descriptors are errors naming the field', () => {
  const { pop, model } = fitted();
  const cases = [
    [() => new w.Fitter(pop, { partz: 3 }), 'partz'],
    [() => new w.Synthetic({ preset: 'arm', vertexes: 500 }), 'vertexes'],
    [() => model.interpolate(0, 1, 0.5, { skinn: 'smooth' }), 'skinn'],
    [() => model.objText({ kind: 'pose', pose: 1, poze: 2 }, ''), 'poze'],
  ];
  for (const [f, field] of cases) {
    const e = thrown(f);
    assert.ok(e.message.includes(field), `${field}: ${e.message}`);
    assert.ok(['params', 'request'].includes(e.kind), `${field}: kind ${e.kind}`);
    assert.equal(e.problems[0].message, e.message);
  }
  assert.equal(thrown(() => new w.Fitter(pop, { ...w.defaultParams(), tol: -1 })).kind, 'params');
  assert.equal(thrown(() => model.reconstruct(99)).kind, 'request');
});

test('what comes out is camelCase: summary, examples, articulation report, ground truth, progress and stages', () => {
  const { files, pop, model } = fitted();
  const s = model.summary();
  assert.deepEqual(notCamel(s), []);
  // one unit-box length in the original units: the ratio of a distance in the file to the same in the unit box
  const unit = pop.positions(0);
  const orig = [...files[0].text.matchAll(/^v (\S+) (\S+) (\S+)$/gm)].map((m) => m.slice(1, 4).map(Number));
  const last = orig.length - 1;
  const ratio = Math.hypot(...orig[last].map((c, k) => c - orig[0][k])) / Math.hypot(...[0, 1, 2].map((k) => unit[3 * last + k] - unit[k]));
  const [perUnit] = pop.originalLengths([1]);
  assert.ok(Math.abs(perUnit / ratio - 1) < 1e-5, `one unit: ${perUnit} original, from the vertices ${ratio}`);
  assert.ok(Math.abs(s.rmseOriginal / (s.rmse * perUnit) - 1) < 1e-12, `rmse ${s.rmse}, original ${s.rmseOriginal}`);
  const r = model.articulationReport(0, 3, 0.5);
  assert.deepEqual(notCamel(r), []);
  assert.equal(typeof r.methods[0].volumeChange, 'number');
  assert.equal(typeof r.methods[0].stretch.boundaryP99, 'number');
  assert.deepEqual(notCamel(w.examples()), []);
  assert.deepEqual(notCamel(w.defaultParams()), []);
  const synth = new w.Synthetic({ preset: 'arm', vertices: 800, poses: 5 });
  const sp = synth.population();
  const f = new w.Fitter(sp, { ...w.defaultParams(), parts: 3 });
  while (!f.isDone()) f.run(1000);
  const g = synth.groundTruth(f.result());
  // a teaching fit's progress objects and stages, step by step through Algorithm 1 (the refinement's subParts)
  const t = new w.Fitter(sp, { ...w.defaultParams(), parts: 3, partRule: 'distinct' });
  const seen = [t.stage()];
  while (!t.isDone()) seen.push(t.step(), t.stage(), t.currentResponsibilities());
  assert.deepEqual(notCamel(seen), []);
  assert.ok(seen.some((x) => x.kind === 'refine' && x.subParts >= 1), 'the refinement was seen with its subParts');
  assert.deepEqual(notCamel(f.result().kernelLimit(1)), []);
  assert.deepEqual(Object.keys(g).sort(), ['ari', 'rotationErrorDeg', 'rotationErrorDegMax', 'rotationErrorsDeg', 'tied', 'trueParts']);
  assert.equal(g.trueParts, 3);
  assert.deepEqual(g.tied, []); // the arm ties no parts (the limit example's pairs: examples.test.mjs)
});

test('the OBJ of a shown mesh is in the original units; neighbouring parts get different colours', () => {
  const { files, pop, model } = fitted();
  const verts = (t) => [...t.matchAll(/^v (\S+) (\S+) (\S+)$/gm)].map((m) => m.slice(1, 4).map(Number));
  const want = verts(files[2].text);
  // the population stores unit-box coordinates in f32 (half the memory of f64): back in original units a point is within half
  // an f32 step of the unit box (2^-25) times the population box's side, with a 2x margin
  const all = files.flatMap((f) => verts(f.text));
  const side = Math.max(...[0, 1, 2].map((k) => {
    const c = all.map((v) => v[k]);
    return Math.max(...c) - Math.min(...c);
  }));
  const tolerance = 2 ** -24 * side;
  for (const text of [pop.objText({ kind: 'pose', pose: 2 }, 'pose 3'), model.objText({ kind: 'pose', pose: 2 }, 'pose 3')]) {
    const got = verts(text);
    assert.equal(got.length, want.length);
    let worst = 0;
    got.forEach((v, i) => v.forEach((c, k) => { worst = Math.max(worst, Math.abs(c - want[i][k])); }));
    assert.ok(worst <= tolerance, `largest difference ${worst}, more than ${tolerance} (f32 in a box of side ${side})`);
    assert.ok(text.startsWith('# pose 3\n'));
  }
  // t = 0 of the linear blend and of the part-wise interpolation is the pose itself, in original units.
  const lin = verts(pop.objText({ kind: 'linear', from: 2, to: 4, t: 0 }, ''));
  assert.deepEqual(lin, verts(pop.objText({ kind: 'pose', pose: 2 }, '')));
  const rigid = verts(model.objText({ kind: 'interpolation', from: 2, to: 4, t: 0, options: { skin: 'rigid', residual: true } }, ''));
  // (the ends of the interpolation are exact on the stored pose: the same f32 rounding as above, and the skinning's)
  rigid.forEach((v, i) => v.forEach((c, k) => assert.ok(Math.abs(c - want[i][k]) <= 2 * tolerance + 1e-9 * side, `${c} against ${want[i][k]}`)));
  assert.equal(verts(model.objText({ kind: 'latent' }, '')).length, want.length);
  assert.match(thrown(() => pop.objText({ kind: 'latent' }, '')).message, /fitted model/);
  // The linear blend the page shows comes from the core too.
  assert.deepEqual(Array.from(pop.linearInterpolate(0, 1, 0.25)), Array.from(model.linearInterpolate(0, 1, 0.25)));

  const labels = model.labels();
  const colours = pop.partColours(labels, 12);
  const faces = pop.faces();
  let touching = 0;
  for (let f = 0; f < faces.length; f += 3) {
    for (let e = 0; e < 3; e++) {
      const a = labels[faces[f + e]];
      const b = labels[faces[f + ((e + 1) % 3)]];
      if (a !== b) {
        touching++;
        assert.notEqual(colours[a], colours[b], `parts ${a} and ${b} touch`);
      }
    }
  }
  assert.ok(touching > 0);
  assert.ok(Array.from(colours).every((c) => c < 12));
});
