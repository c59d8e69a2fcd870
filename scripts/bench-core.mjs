// The benchmark itself, shared by Node and the browser (no Node imports here): fits one population with the
// wasm module `wasm` (the glue of www/pkg or pkg-node) and returns the figures `posemfa bench` prints natively.
//   input: { label, names, files } (OBJ bytes) or { label, synth: spec } (a generated population)

const median = (xs) => [...xs].sort((a, b) => a - b)[(xs.length - 1) >> 1];

// refits: that many more fits after the timed ones, in the same instance, as the page fits again: the last
// model parked while the next fit runs (www/worker.js, claimFit), then freed; the memory after each
// (peak_memory_bytes_refits, in bytes: linear memory only grows). interpolate: after the first fit and after
// each refit, the view the page's Interpolation tab shows (poses 1 -> 2 at t = 0.5), and the memory after it
// (peak_memory_bytes_view, peak_memory_bytes_refit_views). rig: 'rigid' | 'smooth' | 'fitted' | 'pose': after
// the first fit (and its view), the rig the page exports with those weights, or pose mode's poser, and the
// memory after it (peak_memory_bytes_rig).
export function benchOne(wasm, input, { repeat = 3, seed = 0, kernelMs = 200, refits = 0, interpolate = false, rig = null } = {}) {
  const t0 = performance.now();
  let pop;
  let truth = null;
  if (input.synth) {
    truth = new wasm.Synthetic(input.synth);
    pop = truth.population();
  } else {
    pop = new wasm.Population(input.names, input.files);
  }
  const loadMs = performance.now() - t0;
  // linear memory only grows: its size after loading, and after the first fit (before the kernel limits, which
  // lay the data out again), is the peak of each
  const memoryAfterLoad = wasm.memoryBytes();
  let memoryAfterFit = null;
  let memoryAfterView = null;
  let memoryAfterRig = null;
  const runs = [];
  const fractions = [];
  let summary;
  let kernel;
  let groundTruth = null;
  for (let r = 0; r < repeat; r++) {
    const t = performance.now();
    const fitter = new wasm.Fitter(pop, { seed });
    while (!fitter.isDone()) fitter.run(1e9);
    const model = fitter.result();
    runs.push(performance.now() - t);
    // as the page's worker does (finishFit): the fitter freed, then the model's summary (its diagnosis)
    fitter.free();
    summary = model.summary();
    if (memoryAfterFit === null) {
      memoryAfterFit = wasm.memoryBytes();
      if (interpolate) {
        model.interpolate(0, 1, 0.5, {});
        memoryAfterView = wasm.memoryBytes();
      }
      if (rig === 'pose') model.poser({}).free();
      else if (rig) model.rig({ weights: rig });
      if (rig) memoryAfterRig = wasm.memoryBytes();
    }
    // the kernels right after each fit, so that each fraction compares two measurements of the same moment
    // (kernelMs 0: none, so that the memory figures after the fits are the fits' own)
    kernel = kernelMs > 0 ? model.kernelLimit(kernelMs) : null;
    if (kernel) fractions.push(kernel.fraction);
    if (truth && r === repeat - 1) groundTruth = truth.groundTruth(model);
    model.free();
  }
  const memoryRefits = [];
  const memoryRefitViews = [];
  let kept = null;
  for (let r = 0; r < refits; r++) {
    const parked = kept?.park();
    const fitter = new wasm.Fitter(pop, { seed });
    while (!fitter.isDone()) fitter.run(1e9);
    const model = fitter.result();
    fitter.free();
    parked?.free();
    model.summary();
    kept = model;
    memoryRefits.push(wasm.memoryBytes());
    if (interpolate) {
      model.interpolate(0, 1, 0.5, {});
      memoryRefitViews.push(wasm.memoryBytes());
    }
  }
  kept?.free();
  const stages = summary.stageStats.map((s, i) => ({
    stage: s.name, ms: s.ms, iterations: s.iterations, aecm_runs: s.aecmRuns, estep_ms: s.estepMs,
    estep_gflop: s.estepFlops / 1e9, estep_gflop_f32: s.estepFlopsF32 / 1e9,
    estep_gflops_per_s: s.estepMs > 0 ? s.estepFlops / s.estepMs / 1e6 : 0,
    estep_fraction_of_limit: kernel?.stageFractions[i] ?? null,
  }));
  const out = {
    input: input.label, shapes: pop.nShapes, vertices: pop.nVertices,
    load_ms: loadMs, fit_ms_median: median(runs), fit_ms_all: runs,
    parts: summary.parts, rmse: summary.rmse, iterations: stages.reduce((a, s) => a + s.iterations, 0),
    stages,
    kernel_limit_f64: kernel?.f64 ?? null, kernel_limit_f32: kernel?.f32 ?? null,
    estep_fraction_of_limit: kernel ? median(fractions) : null, estep_fraction_of_limit_all: fractions,
    peak_memory_bytes: wasm.memoryBytes(),
    peak_memory_bytes_load: memoryAfterLoad, peak_memory_bytes_fit: memoryAfterFit,
    peak_memory_bytes_refits: memoryRefits,
    peak_memory_bytes_view: memoryAfterView, peak_memory_bytes_refit_views: memoryRefitViews,
    peak_memory_bytes_rig: memoryAfterRig,
    ground_truth: groundTruth,
  };
  pop.free();
  if (truth) truth.free();
  return out;
}

/** `synth:PRESET[:VERTICES[:POSES[:SEED]]]` as a generator spec, or null. */
export function synthSpec(arg) {
  if (!arg.startsWith('synth:')) return null;
  const [preset, vertices, poses, seed] = arg.slice(6).split(':');
  const spec = { preset };
  if (vertices) spec.vertices = Number(vertices);
  if (poses) spec.poses = Number(poses);
  if (seed) spec.seed = Number(seed);
  return spec;
}
