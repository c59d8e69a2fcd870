// The Web Worker that owns the wasm instance and all state: the population, the fit in progress, the model.
// The page only sends messages and shows the replies. Protocol (every message has a `type`; `id` is the
// sender's number for the request and comes back in its replies):
//
//   page -> worker
//     { type: 'load', id, names: string[], files: ArrayBuffer[], fit? }  mesh files (OBJ, PLY, glTF + .bin,
//                                                                   point cache + base mesh): read by extension
//                                                                   and validated in Rust; with a .posemfa among
//                                                                   them, the model file is opened instead of
//                                                                   fitting (the others: its poses), and its
//                                                                   model comes as 'fitted' (summary.opened, params)
//     { type: 'generate', id, spec, fit? }                          a synthetic population (posemfa::synth)
//                                                                   fit: { id, params, fault? }: start fitting it
//                                                                   at once (as a 'fit' message would)
//     { type: 'fit', id, params, fault? }                           start fitting the current population (fault:
//                                                                   test-only, see fit() below)
//     { type: 'cancel' }                                            stop the fit, keep its best state so far
//     { type: 'query', id, method, args }                           a question (see QUERIES, POPULATION_QUERIES)
//   worker -> page
//     { type: 'ready', defaults, examples }                         wasm loaded; defaults: the fit parameters'
//                                                                   defaults; examples: the core's built-in
//                                                                   examples ({id, title, note, failsOnPurpose,
//                                                                   spec, params})
//     { type: 'loaded', id, population }                            population: names, nShapes, nVertices,
//                                                                   provenance (where the poses came from), faces,
//                                                                   positions (one Float32Array per pose, unit
//                                                                   box), truth ({partNames, partOfVertex,
//                                                                   colours} of a generated one, else null)
//     { type: 'load-error', id, problems }                          the previous population is kept
//     { type: 'progress', id, steps, run, trace, labels, colours, elapsedMs }   after every slice: the AECM
//                                                                   iterations made (one progress object each, with
//                                                                   its run; a slice ends where a run ends), the run
//                                                                   in progress (Fitter.stage, with done), the
//                                                                   run's log-likelihood
//                                                                   trace, labels and their colours
//     { type: 'fitted', id, cancelled, fitMs, model }               model: summary (with fitMs), labels,
//                                                                   coarseLabels, refinedLabels, colours {final,
//                                                                   coarse, refined; see modelMessage}, latent,
//                                                                   tree, refinedFromTree
//     { type: 'fitted', id, cancelled: true, kept: true, fitMs }    a cancelled fit of a population whose
//                                                                   finished model stays (no model sent)
//     { type: 'fit-error', id, message, problems }
//     { type: 'reply', id, result } | { type: 'reply', id, error, problems }   answer to a query
//     { type: 'crashed', message }                                  the wasm instance trapped: this worker stops
//     { type: 'fatal', message }                                    the wasm module could not be loaded
//   problems: [{ kind, file, line, message }] as the core throws them (src/wasm.rs); colours: a palette index
//   per part (Rust's part graph: neighbouring parts differ).
//   teaching mode (one AECM iteration per Step): 'teach-reset', 'teach-step', 'teach-run', 'teach-pause' and
//   the replies 'teach', see teach-worker.js
import init, * as wasm from './pkg/posemfa.js';
import { openModelZips } from './zip-models.js';
import wasmUrl from './pkg/posemfa_bg.wasm?url';
import { Teacher } from './teach-worker.js';
import { workerQueries } from './worker-queries.js';
import { FitMemory } from './fit-memory.js';

const SLICE_MS = 40; // one fitter.run(budget) call; the worker reads its messages between slices
const PALETTE_SIZE = 12; // colors.js PALETTE.length

let population = null; // wasm Population
let fitter = null; // wasm Fitter of the fit in progress
let model = null; // wasm FitModel of the last fit (final, or where a cancelled first fit stopped)
// While a new fit runs, the last model is parked (wasm ParkedModel: its per-vertex arrays wait in JS, so the new
// fit does not grow the instance around them, as wasm memory never shrinks) and `model` is null. liveModel()
// brings it back: when the new fit is cancelled and the model stays, or when the page asks it something meanwhile.
let parked = null;
let modelGeneration = 0; // bumped whenever the model is replaced (not when it is parked and restored)
let modelComplete = false; // `model` is a finished fit's: a cancelled new fit keeps it
const memory = new FitMemory(PALETTE_SIZE); // the finished fits' colours and merge tree (fit-memory.js)
let truth = null; // wasm Synthetic of a generated population (its ground truth), else null
let fitToken = 0; // bumped by every new fit and population: a fit whose token is stale was superseded
let cancelRequested = false;
let refiningFit = false; // the fit claimed last starts from a partition of the tree kept (Refine)

const post = (msg, transfer = []) => self.postMessage(msg, transfer);

// A trap of the wasm instance (a Rust panic aborts; an allocation that fails aborts) or the engine running out
// of memory: the instance cannot be trusted any more. The worker says so once and stops; the page starts a new
// worker and gives it the population again (main.js, onWorkerCrash).
const isCrash = (e) => e instanceof WebAssembly.RuntimeError
  || (e instanceof RangeError && /memory|allocat/i.test(String(e.message)));
let dead = false;
function crashed(e) {
  if (!dead) post({ type: 'crashed', message: String(e.message ?? e) });
  dead = true;
  self.close();
}

// Yields to the event loop without the 4 ms clamp of nested timers: a message posted to ourselves is queued
// behind any message the page already sent (a 'cancel').
const channel = new MessageChannel();
const pending = [];
channel.port1.onmessage = () => pending.shift()?.();
const yieldToEvents = () => new Promise((resolve) => { pending.push(resolve); channel.port2.postMessage(0); });

// The problems of an error thrown by the core: it carries them as data ({kind, file, line, message}; see
// src/wasm.rs). Anything else (a JS error of this file) is one problem of its own.
const problemsOf = (e) => e?.problems ?? [{ kind: 'internal', file: null, line: null, message: String(e?.message ?? e) }];

const coloursOf = (labels) => memory.colours(population, labels);
const coloursLike = (labels, like, likeColours) => memory.coloursLike(population, labels, like, likeColours);

function describe(pop, truth = null) {
  const positions = [];
  for (let i = 0; i < pop.nShapes; i++) positions.push(pop.positions(i));
  return {
    names: pop.names(),
    nShapes: pop.nShapes,
    nVertices: pop.nVertices,
    provenance: pop.source,
    clips: pop.clips, // a glTF's animations that move the mesh, {names, read}, or null
    faces: pop.faces(),
    positions,
    truth,
  };
}

function replacePopulation(pop, synth = null) {
  stopFit();
  teacher.drop();
  fitToken++;
  dropModel();
  modelComplete = false;
  population?.free();
  population = pop;
  memory.forget();
  truth?.free();
  truth = synth;
}

function sendPopulation(id, truth) {
  if (truth) truth.colours = coloursOf(truth.partOfVertex);
  const p = describe(population, truth);
  post({ type: 'loaded', id, population: p }, [p.faces.buffer, ...p.positions.map((a) => a.buffer)]);
}

// A model file (.posemfa) among the files: opened without fitting (src/model_file.rs), with the other files as the
// poses it was fitted to if any (checked to be its mesh). The population goes to the page as a load's does, then
// the model as a finished fit's does (under the fit's id when the load asked for a fit).
const isModelFile = (name) => /\.posemfa$/i.test(name);

function openModel(data) {
  const { id, names, files } = data;
  let opened;
  try {
    opened = wasm.openModel(names, files.map((b) => new Uint8Array(b)), data.animation ?? undefined);
  } catch (e) {
    return loadFailed(id, e);
  }
  replacePopulation(opened.population);
  sendPopulation(id, null);
  model = opened.model;
  memory.keepTree(model, false);
  const msg = modelMessage(model);
  Object.assign(msg.summary, { fitMs: 0, cancelled: false, opened: names.find(isModelFile) });
  msg.params = opened.params;
  modelComplete = !!msg.summary.complete;
  post({ type: 'fitted', id: data.fit?.id ?? id, cancelled: false, fitMs: 0, model: msg });
}

const loadFailed = (id, e) => (isCrash(e) ? crashed(e) : post({ type: 'load-error', id, problems: problemsOf(e) }));

function load(data) {
  try {
    data = openModelZips(wasm, data);
  } catch (e) {
    return loadFailed(data.id, e);
  }
  const { id, names, files } = data;
  if (names.some(isModelFile)) return openModel(data);
  let pop;
  try {
    // animation: a glTF's clip to read (the page's Animation list), else the core's choice
    pop = new wasm.Population(names, files.map((b) => new Uint8Array(b)), data.animation ?? undefined);
  } catch (e) {
    return loadFailed(id, e);
  }
  replacePopulation(pop);
  sendPopulation(id, null);
  if (data.fit) fit(data.fit);
}

function generate(data) {
  const { id, spec } = data;
  let synth;
  try {
    synth = new wasm.Synthetic(spec);
  } catch (e) {
    return loadFailed(id, e);
  }
  const groundTruth = { partNames: synth.partNames(), partOfVertex: synth.partOfVertex() };
  replacePopulation(synth.population(), synth);
  sendPopulation(id, groundTruth);
  if (data.fit) fit(data.fit);
}

function stopFit() {
  if (fitter) cancelRequested = true;
}

function modelMessage(m) {
  const summary = m.summary();
  if (truth) summary.groundTruth = truth.groundTruth(m); // posemfa::metrics::GroundTruthAccuracy
  const labels = m.labels();
  const coarseLabels = m.coarseLabels();
  const refinedLabels = m.refinedLabels();
  // the Stages view's panels side by side: a part that is the same in the next stage keeps that stage's colour
  // (final <- refined <- coarse), so what changed between two panels shows by eye
  const final = memory.finalColours(population, labels, summary.complete);
  const refined = coloursLike(refinedLabels, labels, final);
  const coarse = coloursLike(coarseLabels, refinedLabels, refined);
  return {
    summary, labels, coarseLabels, refinedLabels,
    colours: { final, coarse, refined },
    tree: memory.treeCounts(), // {most, fewest, decided} of the merge tree the slider shows, or null
    refinedFromTree: memory.parents, // the model was fitted from a partition of that tree (Refine)
    latent: m.latent(),
  };
}

const fitError = (id, e) => post({ type: 'fit-error', id, message: String(e?.message ?? e), problems: problemsOf(e) });

// fault: test-only fault injection (the page sends it only when opened with ?faultInjection=1): the core is
// asked to trap before the fit starts (wasm.faultInjection, src/wasm.rs).
async function fit({ id, params, fault = null }) {
  if (!population) {
    fitError(id, new Error('no population loaded'));
    return;
  }
  teacher.drop();
  // a Refine (a fit from a partition of the merge tree shown) keeps that tree for the slider
  const refining = !!params.startLabels;
  if (!(await claimFit({ refining }))) return;
  const t0 = performance.now();
  let f;
  try {
    if (fault) wasm.faultInjection(fault);
    f = new wasm.Fitter(population, params);
  } catch (e) {
    if (isCrash(e)) return crashed(e);
    fitError(id, e);
    return;
  }
  fitter = f;
  cancelRequested = false;
  const token = fitToken;
  try {
    while (!f.isDone() && !cancelRequested) {
      const steps = f.run(SLICE_MS);
      const trace = f.currentTrace();
      const labels = f.currentLabels();
      const colours = coloursOf(labels);
      // which of the pipeline's runs is in progress (Stage, src/parts/hierarchy/result.rs); done: none any more,
      // the last one finished
      const run = { ...f.stage(), done: f.isDone() };
      post({ type: 'progress', id, steps, run, trace, labels, colours, elapsedMs: performance.now() - t0 }, [trace.buffer, labels.buffer, colours.buffer]);
      await yieldToEvents();
    }
    if (token !== fitToken) return; // a new fit or population superseded this one: it keeps nothing
    finishFit(f, id, t0);
  } catch (e) {
    if (isCrash(e)) return crashed(e);
    fitError(id, e);
  } finally {
    if (!dead) release(f);
    if (fitter === f) fitter = null;
  }
}

// Stops the fit in progress, if any, and waits until its loop has let go (it keeps nothing: it was
// superseded); then parks the last model for the new fit. False when another fit or population superseded
// this request meanwhile.
async function claimFit({ refining = false } = {}) {
  const token = ++fitToken;
  if (fitter) {
    cancelRequested = true;
    while (fitter) await yieldToEvents();
  }
  if (token !== fitToken) return false;
  if (model) {
    parked = model.park(); // spends `model`
    model = null;
  }
  if (!refining) memory.releaseTree(); // a Refine keeps the tree it starts from (fit-memory.js)
  refiningFit = refining;
  return true;
}

// The last model, restored first if it is parked (null when there is none).
function liveModel() {
  if (parked) {
    model = parked.restore(); // spends `parked`
    parked = null;
  }
  return model;
}

function dropModel() {
  model?.free();
  parked?.free();
  model = null;
  parked = null;
  modelGeneration++;
}

// Frees a fitter once, whoever lets go of it first (finishFit, or the loop that ran it when finishFit did not).
const released = new WeakSet();
function release(f) {
  if (released.has(f)) return;
  released.add(f);
  f.free();
}

// The model of a finished (or cancelled) fitter becomes the worker's model and goes to the page. A cancelled
// fit of a population that already has a finished model leaves that model in place (where the new fit stopped
// is no better than a finished fit): the page is told so ({ kept: true }, no model). Frees the fitter, before
// the model's summary: its diagnosis then reuses the fitter's memory instead of growing the instance (wasm
// memory never shrinks: on the generated 42 k x 11 this is 63.6 -> 59.1 bytes per vertex-pose at the peak).
function finishFit(f, id, t0) {
  const cancelled = !f.isDone();
  const m = cancelled && (model || parked) && modelComplete ? null : f.result();
  release(f);
  const fitMs = performance.now() - t0;
  if (!m) {
    memory.restoreTree(liveModel());
    post({ type: 'fitted', id, cancelled, kept: true, fitMs });
    return;
  }
  dropModel();
  model = m;
  memory.keepTree(m, refiningFit);
  const msg = modelMessage(m);
  msg.summary.fitMs = fitMs;
  msg.summary.cancelled = cancelled;
  modelComplete = !!msg.summary.complete;
  post({ type: 'fitted', id, cancelled, fitMs, model: msg });
}

const teacher = new Teacher({ wasm, post, claim: claimFit, finish: finishFit, release, yieldToEvents, paletteSize: PALETTE_SIZE });
let teachQueue = Promise.resolve();

// Teaching messages: errors end the teaching fit and are reported like a fit's.
async function teach(data) {
  try {
    if (data.type === 'teach-reset') await teacher.reset(population, data);
    else if (data.type === 'teach-step') await teacher.step(population, data);
    else if (data.type === 'teach-run') await teacher.run(population, data);
  } catch (e) {
    if (isCrash(e)) return crashed(e);
    teacher.drop();
    fitError(data.id, e);
  }
}

// The questions (www/worker-queries.js): about the model, the population, or neither.
const { POPULATION_QUERIES, QUERIES, FREE_QUERIES } = workerQueries({
  wasm, model: () => model, population: () => population, memory, generation: () => modelGeneration,
});

function query({ id, method, args }) {
  try {
    const q = FREE_QUERIES[method] ?? POPULATION_QUERIES[method] ?? QUERIES[method];
    if (!q) throw new Error(`unknown query ${method}`);
    if (!population && !FREE_QUERIES[method]) throw new Error('no population loaded');
    if (!FREE_QUERIES[method]) liveModel();
    if (!model && !POPULATION_QUERIES[method] && !FREE_QUERIES[method]) throw new Error('no fitted model yet');
    const result = q(...(args ?? []));
    post({ type: 'reply', id, result }, ArrayBuffer.isView(result) ? [result.buffer] : []);
  } catch (e) {
    if (isCrash(e)) return crashed(e);
    post({ type: 'reply', id, error: String(e?.message ?? e), problems: problemsOf(e) });
  }
}

const ready = init({ module_or_path: wasmUrl }).then(
  () => post({
    type: 'ready',
    defaults: wasm.defaultParams(),
    examples: wasm.examples(),
  }),
  (e) => post({ type: 'fatal', message: `the wasm module failed to load: ${e.message ?? e}` }),
);

self.onmessage = async ({ data }) => {
  if (dead) return;
  if (data.type === 'cancel') {
    cancelRequested = true;
    return;
  }
  if (data.type === 'teach-pause' || data.type === 'teach-reset') teacher.pause(); // a run stops at once
  if (data.type === 'teach-pause') return;
  await ready;
  if (data.type === 'load') load(data);
  else if (data.type === 'generate') generate(data);
  else if (data.type === 'fit') fit(data);
  else if (data.type === 'query') query(data);
  else if (data.type.startsWith('teach-')) teachQueue = teachQueue.then(() => teach(data)); // one at a time, in order
};

export {};
