// Wires the page to the worker: sends what a person asks for, shows what comes back. Nothing here fits or
// parses; the worker (and the Rust core in it) does. Test contract: document.body.dataset.state, the
// data-testid elements of index.html, and window.posemfa (see the end of this file).
import { worker as firstWorker, startWorker } from './worker-client.js'; // first: wasm loads while three.js evaluates
import { installUrlState } from './urlstate.js'; // second: an embedded page hides its controls at once
import { Viewer } from './viewer.js';
import { Plot } from './plot.js';
import { filesFromDataTransfer, filesFromList } from './drop.js';
import { labelColours, errorColours, RAMP_CSS, PALETTE } from './colors.js';
import { installTeaching } from './teach.js';
import { installPresets, accuracyText } from './presets.js';

const $ = (id) => document.getElementById(id);

// The built-in population: the first of the core's examples (posemfa::synth::presets), fitted at load. The
// URL may choose another example (?example=arm) or a population of its own (?preset=snake&vertices=3000&
// poses=12&seed=4, fitted with the default parameters).
const url = new URLSearchParams(location.search);
const URL_SPEC = url.has('preset')
  ? { preset: url.get('preset'), vertices: Number(url.get('vertices')) || 2500, poses: Number(url.get('poses')) || 8, seed: Number(url.get('seed')) || 0 }
  : null;
// Without the examples binding (older core): a small quadruped.
const FALLBACK_SPEC = { preset: 'quadruped', vertices: 2500, poses: 8, seed: 1 };
const GREY = 0.78;
const LIVE_MS = 250;

const app = {
  state: 'loading',
  defaults: null,
  features: {},
  pop: null, // { names, nShapes, nVertices, faces, positions: Float32Array[], normalization, truth, source }
  model: null, // { summary, labels, coarseLabels, refinedLabels, latent, interpolate, gltf, trace }
  gen: 0, // bumped whenever the population or the model changes: stale answers are dropped
  colours: {}, // cached colourings: final, coarse, refined, live, grey
  pose: 0,
  mode: 'parts',
  fitId: null,
  loadId: null,
  liveShown: 0,
  fitCount: 0, // fits ended (finished, cancelled or failed)
  restartCount: 0, // workers replaced after a crash
  workerReady: false,
  source: null, // what the current population came from: { names, bytes } or { spec }, and a label
  reload: null, // set while a restarted worker starts: { source, message }
  loadErrorCount: 0, // drops or picks refused (the previous population kept)
  cache: new Map(), // `${gen}:${method}:${args}` -> query result
  pick: null, // { slot, vertex }
  hoverPart: null,
  shown: [], // what the viewer shows: [{ positions, colours, name }]
  interp: { playing: false, last: 0, dir: 1, busy: false },
};

// ------------------------------------------------------------------ worker and its protocol (see worker.js)
let worker = firstWorker; // replaced by a fresh one when it crashes (see onWorkerCrash)
let nextId = 1;
const waiting = new Map();
function send(msg, transfer = []) {
  const id = nextId++;
  worker.postMessage({ ...msg, id }, transfer);
  return id;
}
// Answers kept for the model's lifetime (small, asked again and again); interpolations are not kept.
const CACHED = new Set(['reconstruct', 'vertexErrors', 'responsibilities', 'rotationAngles']);
function query(method, ...args) {
  const key = `${app.gen}:${method}:${JSON.stringify(args)}`;
  if (app.cache.has(key)) return Promise.resolve(app.cache.get(key));
  return new Promise((resolve, reject) => {
    const id = send({ type: 'query', method, args });
    waiting.set(id, { resolve, reject, key, gen: app.gen, method });
  });
}

function onWorkerMessage({ data: m }) {
  if (m.type === 'crashed') return onWorkerCrash(m.message);
  if (m.type === 'ready') app.workerReady = true;
  if (m.type === 'ready' && app.reload) return reloadAfterCrash();
  if (extensions.some((x) => x.onMessage(m))) return; // presets, URL state, teaching mode (see the end)
  switch (m.type) {
    case 'ready': return onReady(m);
    case 'fatal': showProblems([{ file: null, line: null, reason: m.message }], 'The page cannot run'); return setState('error');
    case 'loaded': if (m.id === app.loadId) onLoaded(m.population); return;
    case 'load-error': if (m.id === app.loadId) onLoadError(m.problems); return;
    case 'progress': if (m.id === app.fitId) onProgress(m); return;
    case 'fitted': if (m.id === app.fitId) onFitted(m); return;
    case 'fit-error': if (m.id === app.fitId) onFitError(m.message); return;
    case 'reply': {
      const w = waiting.get(m.id);
      if (!w) return;
      waiting.delete(m.id);
      if (m.error !== undefined) return w.reject(new Error(m.error));
      if (w.gen === app.gen && CACHED.has(w.method)) app.cache.set(w.key, m.result);
      return w.resolve(m.result);
    }
  }
}
function onWorkerError(e) {
  if (app.workerReady) return onWorkerCrash(e.message || String(e));
  showProblems([{ file: null, line: null, reason: `the worker failed: ${e.message || e}` }], 'The page cannot run');
  setState('error');
}
// Events of a worker that was replaced are ignored.
function wire(w) {
  w.onmessage = (e) => w === worker && onWorkerMessage(e);
  w.onerror = (e) => w === worker && onWorkerError(e);
}
wire(worker);

// The worker's wasm instance trapped or ran out of memory (it says 'crashed'), or the worker died: a fresh
// worker takes its place and gets the population the page had (its files or its generator spec), fitted again
// with the parameters in the form. Unanswered questions are refused; the page keeps showing what it had.
function onWorkerCrash(message) {
  worker.terminate();
  app.workerReady = false;
  app.restartCount++;
  for (const w of waiting.values()) w.reject(new Error('the worker was restarted'));
  waiting.clear();
  if (app.fitId) app.fitCount++;
  app.fitId = null;
  app.loadId = null;
  app.reload = { source: app.source, message };
  worker = startWorker();
  wire(worker);
  showProblems([{ file: null, line: null, reason: `the worker stopped (${message}); a new one is starting${app.source ? ' and gets the population again' : ''}` }], 'The worker was restarted');
}

function reloadAfterCrash() {
  const { source, message } = app.reload;
  app.reload = null;
  const notes = [{ file: null, line: null, reason: `the worker stopped (${message}) and was restarted; the population was loaded again and is being fitted again` }];
  if (!source) {
    showProblems([{ file: null, line: null, reason: `the worker stopped (${message}) and was restarted` }], 'The worker was restarted');
    setState(restingState());
    return;
  }
  app.pendingFit = fitRequest();
  app.pendingSource = source.label;
  app.pendingExample = source.example ?? null;
  app.pendingSpec = source.spec ?? null;
  app.pendingNotes = notes;
  if (source.spec) {
    app.loadId = send({ type: 'generate', spec: source.spec, fit: app.pendingFit });
  } else {
    const buffers = source.bytes.map((b) => b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength));
    app.loadId = send({ type: 'load', names: source.names, files: buffers, fit: app.pendingFit }, buffers);
  }
  app.pendingSourceData = source;
  setState('loading');
}

// ------------------------------------------------------------------ state
function setState(s) {
  app.state = s;
  // The test contract allows loading | idle | fitting | fitted | error: a teaching fit in progress is
  // 'fitting', told apart by data-teaching.
  document.body.dataset.state = s === 'teaching' ? 'fitting' : s;
  document.body.dataset.teaching = s === 'teaching' ? '1' : '';
  performance.mark(`posemfa:${s}`); // times since navigation, for scripts/bench-page.mjs
  $('cancel').disabled = s !== 'fitting';
  const fitted = !!app.model;
  $('export-json').disabled = !fitted;
  $('export-obj').disabled = !app.pop;
  $('export-gltf').disabled = !(fitted && app.model.gltf);
}
// The state to return to when a load fails: whatever was there before.
const restingState = () => (app.fitId ? 'fitting' : app.model ? 'fitted' : app.pop ? 'idle' : 'error');

// ------------------------------------------------------------------ loading
function onReady({ defaults, features, examples }) {
  app.defaults = defaults;
  app.baseParams = defaults; // parameters the form does not show come from here
  app.features = features;
  app.examples = examples ?? [];
  fillParams(defaults);
  document.querySelector('.generate').hidden = !app.examples.length;
  $('example').replaceChildren(...app.examples.map((e) => Object.assign(document.createElement('option'), { value: e.id, textContent: e.title })));
  if (urlState.start()) {
    // the state in location.hash chose the population (and its parameters and view)
  } else if (URL_SPEC && features.synth) {
    generate(URL_SPEC);
  } else if (app.examples.length) {
    runExample(app.examples.find((e) => e.id === url.get('example')) ?? app.examples[0]);
  } else if (features.synth) {
    generate(FALLBACK_SPEC);
  } else {
    $('pop-info').textContent = 'No population yet: open or drop OBJ files (same vertices and faces, different poses).';
    $('caption').textContent = 'Open or drop OBJ files of one mesh in several poses to see its parts here.';
    setState('idle');
  }
}

// An example: its population generated and fitted with its own parameters (shown in the form).
function runExample(ex, params = {}) {
  $('example').value = ex.id;
  app.baseParams = { ...app.defaults, ...ex.params };
  fillParams({ ...app.baseParams, ...params });
  generate(ex.spec, ex);
}

// Loading and fitting go in one message: the worker starts the fit as soon as the population is in.
function fitRequest() {
  const params = readParams();
  return { id: nextId++, params };
}

function generate(spec, example = null, params = null) {
  if (params) fillParams({ ...app.baseParams, ...params });
  app.pendingSpec = spec;
  app.pendingFit = fitRequest();
  app.loadId = send({ type: 'generate', spec, fit: app.pendingFit });
  app.pendingSource = example ? `example “${example.title}”` : `generated ${spec.preset}, seed ${spec.seed ?? 0}`;
  app.pendingExample = example;
  app.pendingSourceData = { spec, example, label: app.pendingSource };
  setState('loading');
}

async function loadFiles(got) {
  const { files, ignored, problems } = await got;
  const notes = ignored.length ? [{ file: null, line: null, reason: `ignored (not .obj or .zip): ${ignored.join(', ')}` }] : [];
  if (problems.length || files.length === 0) {
    if (!files.length) problems.push({ file: null, line: null, reason: 'no .obj file in what was dropped or picked' });
    showProblems([...problems, ...notes]);
    app.loadErrorCount++;
    setState(restingState());
    return;
  }
  app.pendingNotes = notes;
  app.pendingSource = files.length === 1 ? files[0].name : `${files.length} files`;
  app.pendingExample = null;
  app.pendingSpec = null;
  app.baseParams = app.defaults; // the form's values stay; hidden ones back to the defaults
  const buffers = files.map((f) => f.bytes.buffer.slice(f.bytes.byteOffset, f.bytes.byteOffset + f.bytes.byteLength));
  // the page keeps the files' bytes (the copies go to the worker): a restarted worker gets them again
  app.pendingSourceData = { names: files.map((f) => f.name), bytes: files.map((f) => f.bytes), label: app.pendingSource };
  app.pendingFit = fitRequest();
  app.loadId = send({ type: 'load', names: files.map((f) => f.name), files: buffers, fit: app.pendingFit }, buffers);
  setState('loading');
}

function onLoadError(problems) {
  app.loadId = null;
  app.loadErrorCount++;
  showProblems(problems);
  setState(restingState());
}

function onLoaded(pop) {
  app.loadId = null;
  app.source = app.pendingSourceData ?? null;
  pop.source = app.pendingSource;
  app.pop = pop;
  app.model = null;
  app.fitId = null;
  app.gen++;
  app.cache.clear();
  app.colours = { grey: new Float32Array(pop.nVertices * 3).fill(GREY) };
  app.liveLabels = null;
  app.pose = 0;
  app.pick = null;
  viewer.mark(null);
  showProblems(app.pendingNotes || []);
  app.pendingNotes = null;
  const tris = pop.faces.length / 3;
  $('pop-info').textContent = `${pop.nShapes} poses × ${pop.nVertices} vertices, ${tris} triangles (${pop.source})`;
  if (pop.truth) {
    $('pop-info').textContent += `. Ground truth: ${pop.truth.partNames.length} parts.`;
    app.colours.truth = labelColours(pop.truth.partOfVertex, pop.faces).vertexColours;
  }
  const ex = app.pendingExample;
  $('example-note').hidden = !ex;
  $('example-note').classList.toggle('fails', !!ex?.failsOnPurpose);
  $('example-note').textContent = ex ? `${ex.failsOnPurpose ? 'Fails on purpose. ' : ''}${ex.note}` : '';
  document.querySelector('#modes input[value=truth]').parentElement.hidden = !pop.truth;
  if (!pop.truth && app.mode === 'truth') {
    app.mode = 'parts';
    document.querySelector('#modes input[value=parts]').checked = true;
  }
  $('names').replaceChildren(...pop.names.map((n) => Object.assign(document.createElement('li'), { textContent: n })));
  fillPoseLists();
  showResult();
  updateInterpNote();
  viewer.setTopology(pop.faces, pop.positions[0]);
  renderView({ frame: true });
  fitStarted(app.pendingFit.id); // the worker started it right after the load
}

// Lists problems (file, line, reason), each as text. `heading` defaults to the one for a refused input.
function showProblems(problems, heading) {
  const box = $('errors');
  if (!problems.length) return box.replaceChildren();
  const head = document.createElement('strong');
  const serious = problems.some((p) => p.file !== null || p.line !== null || !/^ignored/.test(p.reason));
  head.textContent = heading ?? (serious
    ? `${problems.length} problem${problems.length > 1 ? 's' : ''}${app.pop ? '; the previous population is kept' : ''}`
    : 'Note');
  const list = document.createElement('ul');
  for (const p of problems) {
    const li = document.createElement('li');
    if (p.file !== null && p.file !== undefined) {
      const f = document.createElement('span');
      f.className = 'file';
      f.textContent = p.file; // file names are text, never HTML
      li.append(f, p.line ? `, line ${p.line}: ` : ': ');
    }
    li.append(p.reason);
    list.append(li);
  }
  box.replaceChildren(head, list);
}

// ------------------------------------------------------------------ fitting
function fillParams(p) {
  const f = $('params').elements;
  f.parts.value = p.parts;
  f.seed.value = p.seed;
  f.tol.value = p.tol;
  f.varianceFloor.value = p.varianceFloor;
  f.paperLambda.checked = p.lambdaRule === 'paper-eq18';
  f.refine.checked = p.refine;
}

function readParams() {
  const f = $('params').elements;
  return {
    ...app.baseParams,
    parts: Number(f.parts.value),
    seed: Number(f.seed.value),
    tol: Number(f.tol.value),
    varianceFloor: Number(f.varianceFloor.value),
    lambdaRule: f.paperLambda.checked ? 'paper-eq18' : 'exact',
    refine: f.refine.checked,
  };
}

function startFit() {
  if (!app.pop) return;
  showProblems([]);
  fitStarted(send({ type: 'fit', params: readParams() }));
}

function fitStarted(id) {
  app.fitId = id;
  app.lastStep = null;
  $('stage').textContent = 'starting';
  $('iteration').textContent = '–';
  $('elapsed').textContent = '–';
  $('loglik').textContent = '–';
  plot.set([], '');
  setState('fitting');
}

function stageText(s) {
  if (!s) return '–';
  if (s.kind === 'refine') return `refining part ${s.part + 1} of ${s.of} (${s.subParts} sub-parts)`;
  return { coarse: 'coarse', final: 'final', done: 'done' }[s.kind] ?? s.kind;
}

// Progress arrives after every slice of the fit; the page shows the latest once per animation frame, so a
// slow frame (software WebGL) never queues work behind it.
let pendingProgress = null;
function onProgress(m) {
  app.lastStep = m.steps[m.steps.length - 1] ?? app.lastStep;
  if (!pendingProgress) requestAnimationFrame(showProgress);
  pendingProgress = { ...m, steps: [...(pendingProgress?.steps ?? []), ...m.steps] };
}

function showProgress() {
  const m = pendingProgress;
  pendingProgress = null;
  if (!m || m.id !== app.fitId) return;
  const last = m.steps[m.steps.length - 1];
  if (last) {
    $('stage').textContent = stageText(last.stage);
    $('iteration').textContent = `${last.iteration} (total ${last.totalIterations})`;
    $('loglik').textContent = last.logLikelihood.toFixed(2);
    plot.set(m.trace, `${stageText(last.stage)}: log-likelihood`);
  }
  $('elapsed').textContent = `${(m.elapsedMs / 1000).toFixed(2)} s`;
  // The mesh is recoloured at most every LIVE_MS: a software-rendered frame costs tens of ms that the fit
  // (sharing the CPU) would otherwise lose.
  const now = performance.now();
  if (now - app.liveShown >= LIVE_MS && !sameLabels(m.labels, app.liveLabels)) {
    app.liveShown = now;
    app.liveLabels = m.labels;
    app.colours.live = labelColours(m.labels, app.pop.faces).vertexColours;
    if (!app.model) renderView();
  }
}

const sameLabels = (a, b) => !!a && !!b && a.length === b.length && a.every((x, i) => x === b[i]);

function onFitted({ cancelled, fitMs, model }) {
  app.fitId = null;
  app.fitCount++;
  app.model = model;
  app.gen++;
  app.cache.clear();
  const faces = app.pop.faces;
  app.colours.final = labelColours(model.labels, faces);
  app.colours.coarse = labelColours(model.coarseLabels, faces);
  app.colours.refined = labelColours(model.refinedLabels, faces);
  $('stage').textContent = cancelled ? 'cancelled: best state so far' : 'done';
  if (app.lastStep) $('iteration').textContent = `${app.lastStep.iteration} (total ${app.lastStep.totalIterations})`;
  $('elapsed').textContent = `${(fitMs / 1000).toFixed(2)} s`;
  plot.set(model.summary.logLikelihood ?? [], `${cancelled ? 'best model so far' : 'final stage'}: log-likelihood`);
  showResult();
  updateInterpNote();
  setState('fitted');
  renderView({ frame: false });
  setTimeout(drawThumbnails, 0);
}

function onFitError(message) {
  app.fitId = null;
  app.fitCount++;
  showProblems([{ file: null, line: null, reason: message }], app.model ? 'The fit failed; the previous model is kept' : 'The fit failed');
  setState(app.model ? 'fitted' : 'error');
}

function showResult() {
  const s = app.model?.summary;
  $('parts-count').textContent = s ? s.parts : '–';
  $('stage-parts').textContent = s ? `(coarse ${s.coarseParts}, refined ${s.refinedParts}${s.cancelled ? ', cancelled' : ''})` : '';
  $('rmse').textContent = s ? `${s.rmse.toExponential(3)} (unit box) = ${(s.rmse / app.pop.normalization[3]).toExponential(3)} original units` : '–';
  $('iterations').textContent = s ? `${s.iterations} in the final stage${s.converged ? ', converged' : ''}` : '–';
  $('fit-time').textContent = s ? `${Math.round(s.fitMs)} ms` : '–';
  $('truth-acc').textContent = accuracyText(s?.groundTruth);
  $('truth-acc').classList.toggle('good', s?.groundTruth?.ari >= 0.95);
}

// ------------------------------------------------------------------ views
const viewer = new Viewer($('view'));
const plot = new Plot($('plot'));

function partColours() {
  if (app.model) return app.colours.final.vertexColours;
  return app.colours.live ?? app.colours.grey;
}

const poseName = (i) => app.pop.names[i];
let renderToken = 0;

// Builds the slots of the current mode (some need answers from the worker) and shows them.
async function renderView({ frame = false } = {}) {
  if (!app.pop) return;
  const token = ++renderToken;
  const { pop, model, pose } = app;
  const P = pop.positions[pose];
  let slots;
  let caption = '';
  let legend = null;
  const needModel = (!model && app.mode !== 'parts' && app.mode !== 'interp') || (app.mode === 'truth' && !pop.truth);
  if (app.mode === 'parts' || needModel) {
    slots = [{ positions: P, colours: partColours(), name: `pose ${poseName(pose)}` }];
    caption = `Pose “${poseName(pose)}”, coloured by ${model ? `part (${model.summary.parts} parts)` : app.fitId ? 'the parts of the fit in progress' : 'nothing yet'}`;
    if (needModel) caption += ' (this view needs a fitted model)';
  } else if (app.mode === 'stages') {
    const s = model.summary;
    slots = [
      { positions: P, colours: app.colours.coarse.vertexColours, name: 'coarse' },
      { positions: P, colours: app.colours.refined.vertexColours, name: 'refined' },
      { positions: P, colours: app.colours.final.vertexColours, name: 'final' },
    ];
    caption = `Algorithm 1 on pose “${poseName(pose)}”: coarse (${s.coarseParts} parts) | refined (${s.refinedParts}) | final (${s.parts})`;
  } else if (app.mode === 'recon') {
    const [recon, errors] = await Promise.all([query('reconstruct', pose), query('vertexErrors', pose)]);
    if (token !== renderToken) return;
    let max = 0;
    for (const e of errors) max = Math.max(max, e);
    slots = [
      { positions: P, colours: partColours(), name: 'original' },
      { positions: recon, colours: errorColours(errors, max), name: 'reconstruction' },
    ];
    caption = `Pose “${poseName(pose)}”: original (parts) | reconstruction from the latent shape, coloured by per-vertex error`;
    legend = max;
  } else if (app.mode === 'truth') {
    slots = [
      { positions: P, colours: app.colours.truth, name: 'ground truth' },
      { positions: P, colours: app.colours.final.vertexColours, name: 'final' },
    ];
    caption = `Pose “${poseName(pose)}”: ground truth of the generator (${pop.truth.partNames.length} parts) | fitted (${model.summary.parts} parts)`;
  } else if (app.mode === 'latent') {
    slots = [{ positions: model.latent, colours: partColours(), name: 'latent' }];
    caption = 'The latent reference shape (eq 21): every part in its own latent frame';
  } else if (app.mode === 'interp') {
    const { a, b, t, side, opts } = interpValues();
    const A = pop.positions[a];
    const B = pop.positions[b];
    const linear = new Float32Array(A.length);
    for (let k = 0; k < A.length; k++) linear[k] = A[k] + (B[k] - A[k]) * t;
    if (model?.interpolate) {
      const partwise = await query('interpolate', a, b, t, opts);
      if (token !== renderToken) return;
      slots = [{ positions: partwise, colours: partColours(), name: 'part-wise' }];
      if (side) slots.push({ positions: linear, colours: partColours(), name: 'linear' });
      caption = `“${poseName(a)}” → “${poseName(b)}” at t = ${t.toFixed(2)}: part-wise (${opts.skin === 'smooth' ? 'smooth joints' : 'rigid parts'})${side ? ' | linear vertex blending' : ''}`;
    } else {
      slots = [{ positions: linear, colours: partColours(), name: 'linear' }];
      caption = `“${poseName(a)}” → “${poseName(b)}” at t = ${t.toFixed(2)}: linear vertex blending`;
    }
  }
  if (token !== renderToken) return;
  const reframe = frame || slots.length !== app.shown.length;
  app.shown = slots;
  viewer.show(slots, { frame: reframe });
  $('caption').textContent = caption;
  $('legend').hidden = legend === null;
  if (legend !== null) {
    $('legend-hi').textContent = `${legend.toExponential(2)} unit box (${(legend / pop.normalization[3]).toExponential(2)} original)`;
  }
  if (app.pick && app.pick.slot < slots.length) viewer.mark(app.pick.slot, app.pick.vertex);
}

$('legend').querySelector('.ramp').style.background = RAMP_CSS;

for (const r of document.querySelectorAll('input[name=mode]')) {
  r.addEventListener('change', () => {
    app.mode = r.value;
    $('interp').hidden = app.mode !== 'interp';
    if (app.mode !== 'interp') stopPlay();
    renderView({ frame: true });
  });
}
$('flat').addEventListener('change', (e) => viewer.setFlat(e.target.checked));
$('reset-view').addEventListener('click', () => viewer.reset());

// ------------------------------------------------------------------ poses: list and thumbnail strip
function fillPoseLists() {
  const names = app.pop.names;
  const opts = () => names.map((n, i) => Object.assign(document.createElement('option'), { value: i, textContent: n }));
  $('pose-select').replaceChildren(...opts());
  $('pose-a').replaceChildren(...opts());
  $('pose-b').replaceChildren(...opts());
  $('pose-a').value = 0;
  $('pose-b').value = Math.min(1, names.length - 1);
  $('pose-strip').replaceChildren(...names.map((n, i) => {
    const b = document.createElement('button');
    b.type = 'button';
    b.title = n;
    b.setAttribute('aria-pressed', String(i === app.pose));
    b.setAttribute('aria-label', `pose ${n}`);
    const c = document.createElement('canvas');
    c.width = 160;
    c.height = 120;
    const label = document.createElement('span');
    label.textContent = n.split('/').pop(); // the file's own name; the full path is in the title
    b.append(c, label);
    b.addEventListener('click', () => choosePose(i));
    return b;
  }));
}

function choosePose(i) {
  app.pose = i;
  $('pose-select').value = i;
  [...$('pose-strip').children].forEach((b, k) => b.setAttribute('aria-pressed', String(k === i)));
  app.hoverPart = null;
  if (app.pick) showPick();
  renderView();
}
$('pose-select').addEventListener('change', (e) => choosePose(Number(e.target.value)));
// Arrow keys step through the strip.
$('pose-strip').addEventListener('keydown', (e) => {
  const step = { ArrowLeft: -1, ArrowRight: 1 }[e.key];
  if (!step || !app.pop) return;
  e.preventDefault();
  const i = (app.pose + step + app.pop.nShapes) % app.pop.nShapes;
  choosePose(i);
  $('pose-strip').children[i].focus();
});

let thumbsToken = 0;
function drawThumbnails() {
  const token = ++thumbsToken;
  const canvases = [...$('pose-strip').querySelectorAll('canvas')];
  const colours = partColours();
  let i = 0;
  const next = () => {
    if (token !== thumbsToken || i >= canvases.length || !app.pop) return;
    viewer.thumbnail(app.pop.positions[i], colours, canvases[i]);
    i++;
    setTimeout(next, 0);
  };
  next();
}

// ------------------------------------------------------------------ picking (click) and hovering
const canvas = viewer.renderer.domElement;
let down = null;
canvas.addEventListener('pointerdown', (e) => { down = { x: e.clientX, y: e.clientY }; });
canvas.addEventListener('pointerup', (e) => {
  if (!down || Math.hypot(e.clientX - down.x, e.clientY - down.y) > 4) return;
  down = null;
  const hit = viewer.pick(e.clientX, e.clientY);
  app.pick = hit;
  if (hit) viewer.mark(hit.slot, hit.vertex);
  else viewer.mark(null);
  showPick();
});

let hoverQueued = false;
canvas.addEventListener('pointermove', (e) => {
  if (e.buttons || hoverQueued || !app.model) return;
  hoverQueued = true;
  requestAnimationFrame(() => {
    hoverQueued = false;
    const hit = viewer.pick(e.clientX, e.clientY);
    const part = hit ? app.model.labels[hit.vertex] : null;
    if (part !== app.hoverPart) {
      app.hoverPart = part;
      showHover();
    }
  });
});
canvas.addEventListener('pointerleave', () => {
  app.hoverPart = null;
  showHover();
});

const infoPick = document.createElement('div');
const infoHover = document.createElement('div');
$('info').append(infoPick, infoHover);

function swatch(part) {
  const s = document.createElement('span');
  s.className = 'swatch';
  s.style.background = app.colours.final?.partColour[part] ?? '#ccc';
  return s;
}

function bar(fraction, width = 80) {
  const b = document.createElement('span');
  b.className = 'bar';
  b.style.width = `${Math.max(1, Math.round(fraction * width))}px`;
  return b;
}

function row(...cells) {
  const tr = document.createElement('tr');
  for (const c of cells) {
    const td = document.createElement('td');
    td.append(c);
    tr.append(td);
  }
  return tr;
}

async function showPick() {
  const hit = app.pick;
  if (!hit || !app.model) {
    infoPick.replaceChildren();
    return;
  }
  const v = hit.vertex;
  const part = app.model.labels[v];
  const gen = app.gen;
  const pose = app.pose;
  let resp;
  let errors;
  try {
    [resp, errors] = await Promise.all([query('responsibilities', v), query('vertexErrors', pose)]);
  } catch (e) {
    infoPick.textContent = e.message;
    return;
  }
  if (gen !== app.gen || app.pick !== hit) return;
  const s = app.pop.normalization[3];
  const head = document.createElement('div');
  head.append(`Vertex ${v} (${app.shown[hit.slot]?.name ?? ''}): part ${part} `, swatch(part));
  const err = document.createElement('div');
  err.textContent = `error in pose “${poseName(pose)}”: ${errors[v].toExponential(2)} unit box = ${(errors[v] / s).toExponential(2)} original`;
  const order = [...resp.keys()].sort((a, b) => resp[b] - resp[a]).slice(0, 5);
  const table = document.createElement('table');
  table.append(row('P(part | vertex)', '', ''));
  for (const k of order) table.append(row(Object.assign(swatch(k), { title: `part ${k}` }), `part ${k}`, resp[k].toFixed(4)));
  infoPick.replaceChildren(head, err, table);
}

async function showHover() {
  const part = app.hoverPart;
  if (part === null || !app.model) {
    infoHover.replaceChildren();
    return;
  }
  const gen = app.gen;
  const pose = app.pose;
  let angles;
  try {
    angles = await query('rotationAngles', part, pose);
  } catch (e) {
    infoHover.textContent = e.message;
    return;
  }
  if (gen !== app.gen || app.hoverPart !== part) return;
  const head = document.createElement('div');
  head.append(swatch(part), ` part ${part}: rotation from pose “${poseName(pose)}”`);
  const table = document.createElement('table');
  angles.forEach((a, i) => table.append(row(poseName(i), bar(a / 180), `${a.toFixed(1)}°`)));
  infoHover.replaceChildren(head, table);
}

// ------------------------------------------------------------------ interpolation
function interpValues() {
  return {
    a: Number($('pose-a').value),
    b: Number($('pose-b').value),
    t: Number($('interp-t').value),
    side: $('side-by-side').checked,
    opts: { skin: $('interp-skin').value, residual: $('interp-residual').checked },
  };
}
function onInterpInput() {
  $('report').replaceChildren();
  $('interp-t-out').textContent = Number($('interp-t').value).toFixed(2);
  if (app.mode === 'interp') renderView();
}
for (const id of ['pose-a', 'pose-b', 'interp-t', 'interp-skin', 'interp-residual']) $(id).addEventListener('input', onInterpInput);
$('side-by-side').addEventListener('change', () => renderView({ frame: true }));

function updateInterpNote() {
  const partwise = !!app.model?.interpolate;
  for (const id of ['side-by-side', 'interp-skin', 'interp-residual', 'measure']) $(id).disabled = !partwise;
  $('interp-note').textContent = partwise
    ? ''
    : app.model
      ? 'Part-wise interpolation is not in this build (posemfa::articulate binding): showing linear vertex blending.'
      : 'Linear vertex blending until the fit ends; then the part-wise interpolation.';
  $('report').replaceChildren();
}

// The core's figures of every interpolation method at this t: volume change and edge stretch.
$('measure').addEventListener('click', async () => {
  const { a, b, t } = interpValues();
  $('report').textContent = 'measuring…';
  let r;
  try {
    r = await query('articulationReport', a, b, t);
  } catch (e) {
    $('report').textContent = e.message;
    return;
  }
  const pct = (x) => `${(100 * x).toFixed(1)} %`;
  const table = document.createElement('table');
  const head = document.createElement('tr');
  for (const h of ['method', 'volume change', 'edge stretch p99 (boundary)', 'largest stretch', 'error at t=0 / t=1']) {
    head.append(Object.assign(document.createElement('th'), { textContent: h }));
  }
  table.append(head);
  for (const m of r.methods) {
    const tr = document.createElement('tr');
    for (const c of [m.name, pct(m.volume_change), pct(m.stretch.boundary_p99), pct(m.stretch.all_max),
      m.endpoint_error.map((e) => e.toExponential(1)).join(' / ')]) {
      tr.append(Object.assign(document.createElement('td'), { textContent: c }));
    }
    table.append(tr);
  }
  const cap = document.createElement('div');
  cap.textContent = `“${poseName(a)}” → “${poseName(b)}” at t = ${t.toFixed(2)}; volume relative to (1-t)·V(from) + t·V(to); errors in unit-box units`;
  $('report').replaceChildren(cap, table);
});

function stopPlay() {
  app.interp.playing = false;
  $('play').textContent = 'Play';
}
$('play').addEventListener('click', () => {
  if (app.interp.playing) return stopPlay();
  app.interp.playing = true;
  app.interp.last = performance.now();
  $('play').textContent = 'Pause';
  const tick = async (now) => {
    if (!app.interp.playing) return;
    const slider = $('interp-t');
    let t = Number(slider.value) + (app.interp.dir * (now - app.interp.last)) / 2000;
    app.interp.last = now;
    if (t >= 1 || t <= 0) {
      app.interp.dir *= -1;
      t = Math.min(Math.max(t, 0), 1);
    }
    slider.value = t;
    $('interp-t-out').textContent = t.toFixed(2);
    await renderView();
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
});

// ------------------------------------------------------------------ exports
function download(name, data, type) {
  const url = URL.createObjectURL(new Blob([data], { type }));
  const a = Object.assign(document.createElement('a'), { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

// OBJ text of a unit-box mesh, written back in the population's original units: original = unit / scale + offset.
export function objText(positions, faces, normalization, comment) {
  const [ox, oy, oz, s] = normalization;
  const lines = [`# ${comment}`, `# posemfa, ${positions.length / 3} vertices, ${faces.length / 3} triangles`];
  const num = (x) => String(Number(x.toPrecision(9)));
  for (let k = 0; k < positions.length; k += 3) {
    lines.push(`v ${num(positions[k] / s + ox)} ${num(positions[k + 1] / s + oy)} ${num(positions[k + 2] / s + oz)}`);
  }
  for (let k = 0; k < faces.length; k += 3) lines.push(`f ${faces[k] + 1} ${faces[k + 1] + 1} ${faces[k + 2] + 1}`);
  return lines.join('\n') + '\n';
}

const safeName = (s) => s.replace(/\.obj$/i, '').replace(/[^A-Za-z0-9._-]+/g, '_');

$('export-json').addEventListener('click', async () => download('posemfa-model.json', await query('toJson'), 'application/json'));
$('export-obj').addEventListener('click', () => {
  const slot = app.shown[0];
  if (!slot) return;
  const what = app.mode === 'interp' ? `${slot.name} interpolation t=${interpValues().t}` : `${slot.name}`;
  const name = `posemfa-${safeName(poseName(app.pose))}-${safeName(what)}.obj`;
  download(name, objText(slot.positions, app.pop.faces, app.pop.normalization, what), 'model/obj');
});
$('export-gltf').addEventListener('click', async () => {
  const skin = $('interp-skin').value; // the skinning chosen for the interpolation
  download(`posemfa-model-${skin}.glb`, await query('toGlb', skin), 'model/gltf-binary');
});

// ------------------------------------------------------------------ opening files: picker, folder, drop
$('file-input').addEventListener('change', (e) => {
  loadFiles(filesFromList([...e.target.files])); // a copy: clearing the input empties its FileList
  e.target.value = '';
});
$('folder-input').addEventListener('change', (e) => {
  loadFiles(filesFromList([...e.target.files])); // a copy: clearing the input empties its FileList
  e.target.value = '';
});
let dragDepth = 0;
window.addEventListener('dragenter', (e) => {
  e.preventDefault();
  dragDepth++;
  $('drop-overlay').hidden = false;
});
window.addEventListener('dragleave', () => {
  if (--dragDepth <= 0) {
    dragDepth = 0;
    $('drop-overlay').hidden = true;
  }
});
window.addEventListener('dragover', (e) => e.preventDefault());
window.addEventListener('drop', (e) => {
  e.preventDefault();
  dragDepth = 0;
  $('drop-overlay').hidden = true;
  loadFiles(filesFromDataTransfer(e.dataTransfer));
});

$('params').addEventListener('submit', (e) => {
  e.preventDefault();
  startFit();
});
$('cancel').addEventListener('click', () => worker.postMessage({ type: 'cancel' }));
$('reset-params').addEventListener('click', () => app.baseParams && fillParams(app.baseParams));
$('generate').addEventListener('click', () => runExample(app.examples.find((e) => e.id === $('example').value)));

// ------------------------------------------------------------------ test contract
window.posemfa = {
  /** Summary of the current model ({shapes, vertices, parts, rmse, iterations, fitMs, ...}) or null. */
  summary: () => (app.model ? { ...app.model.summary } : null),
  /** The palette, and the colour of every final part. */
  palette: PALETTE,
  partColours: () => app.colours.final?.partColour.slice() ?? null,
  /** Number of fits that have ended (finished, cancelled or failed) since the page opened. */
  fitCount: () => app.fitCount,
  /** Number of drops or picks refused with errors since the page opened. */
  loadErrorCount: () => app.loadErrorCount,
  /** Names of the meshes in the view, left to right (e.g. ['part-wise', 'linear']). */
  shown: () => app.shown.map((x) => x.name),
  /** Number of poses, and the view mode. */
  poses: () => app.pop?.nShapes ?? 0,
  mode: () => app.mode,
  /** Workers replaced after a crash since the page opened. */
  restartCount: () => app.restartCount,
  /** Fault injection for the page tests: the worker reports a wasm trap as if the core had crashed. */
  crashWorkerForTest: () => worker.postMessage({ type: 'test-crash' }),
};

// Presets, URL state (location.hash) and the teaching mode: each sees the worker's messages first.
const urlState = installUrlState({
  app, viewer, readParams, renderView, runExample, generate,
  examples: () => app.examples ?? [],
  note: (text) => showProblems([{ file: null, line: null, reason: text }], 'Note'),
});
const extensions = [
  installPresets({ app, runExample }),
  urlState,
  installTeaching({ app, send, setState, plot, renderView, readParams, stageText }),
];

setState('loading');
updateInterpNote();
