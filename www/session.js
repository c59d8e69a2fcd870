// What the page asks of the worker, and what it keeps of the answers: populations (files or generated), fits
// (with live progress), questions about the model (cached per model), and a restarted worker given the work
// again. Every change goes to the page state (state.js); the views and controls react to it.
import { startWorker, worker as firstWorker } from './worker-client.js';
import { WorkerClient, MAX_RESTARTS } from './protocol.js';
import { state, update, subscribe } from './state.js';
import { paletteColours } from './colors.js';
import { checkedParams, fillParams, resetForNewPopulation } from './controls/form.js';
import { showProblems, note } from './problems.js';
import { fetchSource } from './fetch-source.js';
import { ask } from './ask.js';

const GREY = 0.78;
const LIVE_MS = 250; // the mesh is recoloured at most this often while a fit runs

const readyHandlers = [];
/** fn(readyMessage) when the first worker is ready ({ defaults, examples, features }). */
export const onReady = (fn) => readyHandlers.push(fn);

export const client = new WorkerClient({
  start: startWorker,
  first: firstWorker,
  onReady: (m) => readyHandlers.forEach((f) => f(m)),
  onFatal: (message) => {
    showProblems([{ file: null, line: null, message }], 'The page cannot run');
    update({ phase: 'error' });
  },
  onRestart: ({ message }) => restartWork(message),
  onGiveUp: ({ message, restarts }) => giveUp(message, restarts),
});

// Test-only fault injection (the page tests open the page with ?faultInjection=1, which adds
// window.posemfa.injectFault): while armed, every fit asks the worker to make the wasm instance trap first.
const fault = { kind: null, times: 0 };
export const faultInjection = new URLSearchParams(location.search).get('faultInjection') === '1';
/** Arms (kind 'panic', for `times` fits; Infinity: every one) or disarms (null) the fault. */
export function injectFault(kind, times = Infinity) {
  Object.assign(fault, { kind, times: kind ? times : 0 });
}
function takeFault() {
  if (!faultInjection || !fault.kind || fault.times <= 0) return null;
  fault.times--;
  return fault.kind;
}

// A key naming the work in hand (population and fit parameters): the restart cap counts per key.
export const jobKey = (source, params) => JSON.stringify([source?.label, source?.spec ?? source?.names, source?.animation, params]);

/** The state to return to when a load fails: whatever was there before. */
export const restingState = () => (state.fitId ? 'fitting' : state.model ? 'fitted' : state.pop ? 'idle' : 'error');

/**
 * A generated population (an example's, or any generator spec), fitted at once with the form's parameters
 * (opts.fit false: not fitted, e.g. for a teaching link).
 */
export function generate(spec, example = null, params = null, { fit = true } = {}) {
  if (params) fillParams({ ...state.baseParams, ...params });
  const label = example ? `example “${example.title}”` : `generated ${spec.preset}, seed ${spec.seed ?? 0}`;
  startLoad({ label, example, spec }, [], { fit });
}

/** An example: its population generated and fitted with its own parameters (shown in the form). */
export function runExample(ex, params = {}, opts = {}) {
  document.getElementById('example').value = ex.id;
  update({ baseParams: { ...state.defaults, ...ex.params } });
  fillParams({ ...state.baseParams, ...params });
  generate(ex.spec, ex, null, opts);
}

/**
 * Opens `url` (a link's src=URL): fetched with its progress and a Cancel over the view (#fetch-status), then
 * opened as a drop of its files is. Resolves to null when the files went to the worker, else to what went wrong
 * (the fetch failed or was cancelled: said over the view and in the problems box; what was loaded stays).
 */
export async function openUrl(url) {
  const box = document.getElementById('fetch-status');
  const text = document.getElementById('fetch-text');
  const button = document.getElementById('fetch-cancel');
  const abort = new AbortController();
  box.hidden = false;
  box.dataset.state = 'fetching';
  button.textContent = 'Cancel';
  button.onclick = () => abort.abort();
  text.textContent = `Fetching ${url}…`;
  const said = (message, state) => {
    box.dataset.state = state;
    text.textContent = message;
    button.textContent = 'Close';
    button.onclick = () => { box.hidden = true; };
  };
  let got;
  try {
    got = await fetchSource(url, {
      signal: abort.signal,
      onProgress: (n, total) => {
        text.textContent = `Fetching ${url}: ${(n / 1e6).toFixed(1)}${total ? ` of ${(total / 1e6).toFixed(1)}` : ''} MB`;
      },
    });
  } catch (e) {
    if (abort.signal.aborted) {
      const text = `Cancelled: ${url} was not opened${state.pop ? '; what was shown stays' : ''}.`;
      said(text, 'cancelled');
      return text;
    }
    const problems = e.problems ?? [{ file: url, line: null, message: String(e.message ?? e) }];
    const text = `Cannot open ${url}: ${problems[0].message}.`;
    said(text, 'error');
    showProblems(problems, `Cannot open ${url}`);
    update({ loadErrorCount: state.loadErrorCount + 1, phase: restingState() });
    return text;
  }
  box.hidden = true;
  loadFiles(got, { url });
  return null;
}

/** Files from the picker or a drop ({ files, ignored, problems }, see drop.js), fitted at once (a model file:
 * opened without fitting). `url`: the address they were fetched from (openUrl), kept in the link. */
export async function loadFiles(got, { url = null } = {}) {
  const { files, ignored, problems } = await got;
  const notes = ignored.length ? [{ file: null, line: null, message: `ignored (not a mesh, point cache, glTF buffer or .zip): ${ignored.join(', ')}` }] : [];
  if (problems.length || files.length === 0) {
    // nothing to open: one problem, naming what was ignored (not a second one for it)
    const none = ignored.length ? `; ignored: ${ignored.join(', ')}` : '';
    if (!files.length) problems.push({ file: null, line: null, message: `no mesh file (.obj, .ply, .glb, .gltf, .pc2 / .mdd with its base mesh, .fbx, .usd / .usda / .usdc / .usdz) nor model file (.posemfa) in what was dropped or picked${none}` });
    showProblems(files.length ? [...problems, ...notes] : problems);
    update({ loadErrorCount: state.loadErrorCount + 1, phase: restingState() });
    return;
  }
  const label = files.length === 1 ? files[0].name : `${files.length} files`;
  // the page keeps the files' bytes (copies go to the worker): a restarted worker gets them again. Fitted with
  // the defaults of the hidden parameters, the part count and the literal Λ step (seed, tolerance... as typed);
  // the form and settings show them once the core has accepted the files (onLoaded): a refused drop keeps
  // everything as it was
  startLoad({ label, url, names: files.map((f) => f.name), bytes: files.map((f) => f.bytes) }, notes, { fresh: !url });
}

/** The same files read again with another of their glTF's animations (the Population panel's list), fitted with
 * the form's parameters; a refusal keeps what is loaded. */
export function readAnimation(name) {
  if (!state.source?.bytes) return;
  startLoad({ ...state.source, animation: name }, []);
}

/** Whether `model`'s parts came from the merge tree, as the core says (summary.partsFrom): the default part rule
 * with the refinement on; Algorithm 1 otherwise, and always in Step by step. The Stages view and the Parts line
 * name the stages after it. */
export const isTreeFit = (model) => model?.summary?.partsFrom === 'merge tree';

// Loading and fitting go in one message: the worker starts the fit as soon as the population is in. With a
// form field the core refuses (shown at the field), the population is loaded and not fitted. fresh: files
// opened or dropped, fitted with the defaults of a new population (loadFiles), which the form shows once the
// population is in.
async function startLoad(source, notes, { fit: fitting = true, fresh = false } = {}) {
  const params = fitting ? await checkedParams(fresh ? { fresh: state.defaults } : {}) : null;
  const fit = params ? { id: client.id(), params, fault: takeFault() } : undefined;
  const job = jobKey(source, fit?.params);
  let req;
  if (source.spec) {
    req = client.request({ type: 'generate', spec: source.spec, fit }, { job });
  } else {
    const files = source.bytes.map((b) => b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength));
    req = client.request({ type: 'load', names: source.names, files, fit, animation: source.animation }, { transfer: files, job });
  }
  update({ loading: { id: req.id, source, fit, notes, fresh }, phase: 'loading' });
  const fitDone = fit ? client.expect(fit.id, { onEvent: onProgress }) : null;
  fitDone?.catch(() => {}); // settled below once the population is in
  req.done.then(
    (m) => {
      if (state.loading?.id !== req.id) return;
      onLoaded(m.population, fit?.id ?? null);
      if (fit) watchFit(fit.id, fitDone);
    },
    (e) => {
      if (fit) client.forget(fit.id);
      if (state.loading?.id !== req.id || e.kind === 'crashed') return;
      update({ loading: null, loadErrorCount: state.loadErrorCount + 1 });
      showProblems(e.problems);
      update({ phase: restingState() });
    },
  );
}

function onLoaded(pop, fitId) {
  const { source, notes, fresh } = state.loading;
  if (fresh) {
    update({ baseParams: state.defaults }); // hidden parameters back to the defaults
    resetForNewPopulation(state.defaults); // and the part count and the literal Λ step (seed, tolerance... stay)
  }
  const colours = { grey: new Float32Array(pop.nVertices * 3).fill(GREY) };
  if (pop.truth) colours.truth = paletteColours(pop.truth.partOfVertex, pop.truth.colours).vertexColours;
  pop.source = source.label;
  showProblems(notes);
  loadNotes = fitId === null ? [] : notes;
  update({
    // a step-by-step fit of the last population went with it (the worker dropped it): its panel starts again
    loading: null, source, pop, model: null, fitId, gen: state.gen + 1, colours, pose: 0, pick: null, keptAfter: null, treeParts: null, teach: null,
    hoverPart: null, lastStep: null, mode: !pop.truth && state.mode === 'truth' ? 'parts' : state.mode,
    phase: fitId === null ? 'idle' : 'fitting',
  });
  liveLabels = null;
}

/** A fit of the population shown, with the form's parameters; with `startLabels` (one part per vertex), from
 * that partition with exactly its number of parts (the merge tree's Refine). A step-by-step fit in hand (paused
 * or running) is dropped by it: asked first, as Step / Run / Reset ask before they drop a finished fit
 * (teach.js); a dismissed question changes nothing. */
export async function startFit({ startLabels = null } = {}) {
  if (!state.pop) return;
  const teaching = state.teach !== null && state.fitId === state.teach.id;
  // asked in the page, under the Fit button (teach.js asks the same way before a finished fit is dropped)
  if (teaching) {
    const at = state.teach.iteration;
    const yes = await ask(document.getElementById('fit').parentElement, `Fit starts a new fit and drops the step-by-step fit at iteration ${at}. Drop it?`, {
      yes: 'Drop it and fit', no: 'Keep the step-by-step fit', kept: `Kept the step-by-step fit at iteration ${at}: no new fit was started.`,
    });
    if (!yes || !(state.teach !== null && state.fitId === state.teach.id)) return;
  }
  // the last fit's failure goes as a new one is asked for (a field refused now is said under the form)
  showProblems([]);
  const checked = await checkedParams({ vertices: state.pop.nVertices });
  if (!checked || !state.pop) return; // the form says which field, and what it allows
  const params = startLabels ? { ...checked, startLabels: Array.from(startLabels) } : checked;
  // (the job's key names a start by its count of parts, not by its labels)
  const job = jobKey(state.source, startLabels ? { ...checked, startParts: new Set(startLabels).size } : checked);
  const { id, done } = client.request({ type: 'fit', params, fault: takeFault() }, { onEvent: onProgress, job });
  // a step-by-step fit (paused, running or finished) gives way to the new fit: its panel starts again
  update({ fitId: id, lastStep: null, keptAfter: null, teach: null, phase: 'fitting' });
  liveLabels = null;
  loadNotes = [];
  watchFit(id, done);
}

export const cancelFit = () => client.post({ type: 'cancel' });

// The notes of the drop whose fit is running (files ignored), until that fit ends or another starts.
let loadNotes = [];

/** Follows the fit `id` to its end (done: its promise from the protocol): the model, or the failure. */
export function watchFit(id, done) {
  done.then(
    (m) => state.fitId === id && onFitted(m),
    (e) => {
      if (state.fitId !== id || e.kind === 'crashed') return;
      // no model: the failed fit's live parts go too (the view is grey, as its caption says)
      // a model kept: the Fit panel shows its figures again, not the failed run's (result.js)
      update({ fitId: null, fitCount: state.fitCount + 1, ...(state.model ? { keptAfter: 'failure' } : { colours: { ...state.colours, live: null } }) });
      // the drop's own notes (files ignored) stay beside the failure of the fit it started
      showProblems([...e.problems, ...loadNotes], state.model ? 'The fit failed; the previous model is kept' : 'The fit failed');
      loadNotes = [];
      update({ phase: state.model ? 'fitted' : 'error' });
    },
  );
}

// Progress arrives after every slice of the fit (and each teaching step); it is shown once per frame.
const progressHandlers = [];
/** fn(progress) once per animation frame while a fit runs: the latest steps, trace, labels, elapsedMs. */
export const onFitProgress = (fn) => progressHandlers.push(fn);
let pendingProgress = null;
let liveLabels = null;
let liveShown = 0;
function onProgress(m) {
  update({ lastStep: m.steps[m.steps.length - 1] ?? state.lastStep });
  // a run that ended is shown before the next run's steps join it: a slow frame must not skip a run's name
  if (pendingProgress?.steps.some((s) => s.runFinished)) showProgress();
  if (!pendingProgress) requestAnimationFrame(showProgress);
  pendingProgress = { ...m, steps: [...(pendingProgress?.steps ?? []), ...m.steps] };
}
function showProgress() {
  const m = pendingProgress;
  pendingProgress = null;
  if (!m || m.id !== state.fitId) return;
  progressHandlers.forEach((f) => f(m));
  // A software-rendered frame costs tens of ms that the fit (sharing the CPU) would otherwise lose.
  const now = performance.now();
  if (now - liveShown >= LIVE_MS && !sameLabels(m.labels, liveLabels)) {
    liveShown = now;
    liveLabels = m.labels;
    update({ colours: { ...state.colours, live: paletteColours(m.labels, m.colours).vertexColours } });
  }
}
const sameLabels = (a, b) => !!a && !!b && a.length === b.length && a.every((x, i) => x === b[i]);

function onFitted({ model, kept: keptModel }) {
  loadNotes = [];
  // the last slice's progress, if its frame has not come yet, is shown first: every run is named before 'done'
  if (pendingProgress) showProgress();
  if (keptModel) {
    // a new fit cancelled: the finished model stays shown (result.js says the new fit was cancelled)
    kept = null;
    update({ fitId: null, fitCount: state.fitCount + 1, keptAfter: 'cancel', phase: 'fitted' });
    return;
  }
  const colours = {
    ...state.colours,
    final: paletteColours(model.labels, model.colours.final),
    coarse: paletteColours(model.coarseLabels, model.colours.coarse),
    refined: paletteColours(model.refinedLabels, model.colours.refined),
  };
  kept = null;
  if (model.summary.opened) {
    // a model file: the form shows the parameters it was fitted with (Fit again fits with them)
    update({ baseParams: { ...state.defaults, ...model.params } });
    fillParams(state.baseParams);
    if (!model.summary.hasData) {
      note(`${model.summary.opened} was saved without its poses: the poses shown are the model's reconstructions, and the reconstruction error, the responsibilities, the rig and pose mode need the poses. Drop the model file together with the pose files it was fitted to to see them.`);
    }
  }
  // the new model's own parts (not a merge tree cut the slider showed for the one before)
  update({ fitId: null, fitCount: state.fitCount + 1, model, gen: state.gen + 1, colours, treeParts: null, keptAfter: null, phase: 'fitted' });
}

// ------------------------------------------------------------------ questions about the model
// Answers kept for the model's lifetime (small, asked again and again); interpolations are not kept.
const CACHED = new Set(['reconstruct', 'vertexErrors', 'responsibilities', 'rotationAngles']);
const cache = new Map(); // `${gen}:${method}:${args}` -> answer

/** Asks the worker about the model: query('reconstruct', pose) etc. (QUERIES in worker.js). */
export function query(method, ...args) {
  const key = `${state.gen}:${method}:${JSON.stringify(args)}`;
  if (cache.has(key)) return Promise.resolve(cache.get(key));
  const gen = state.gen;
  return client.request({ type: 'query', method, args }).done.then((m) => {
    if (gen === state.gen && CACHED.has(method)) cache.set(key, m.result);
    return m.result;
  });
}
subscribe((s, changed) => changed.has('gen') && cache.clear());

// ------------------------------------------------------------------ faults
// What the page showed before the first of a run of restarts: shown again if the worker keeps crashing.
let kept = null;

// A fresh worker gets the population the page had (its files or its generator spec), fitted again with the
// parameters in the form. Unanswered questions were refused.
function restartWork(message) {
  if (!kept && state.pop) kept = { pop: state.pop, source: state.source, model: state.model, colours: state.colours };
  update({ restartCount: client.restartCount });
  const source = state.loading?.source ?? state.source;
  const fresh = !!state.loading?.fresh; // files not yet accepted: still fitted (and shown) as a new population
  const wasFitting = state.fitId !== null || state.loading !== null;
  update({ fitId: null, loading: null, teach: null, fitCount: state.fitCount + (wasFitting ? 1 : 0) });
  if (!source) {
    showProblems([{ file: null, line: null, message: `the worker stopped (${message}) and was restarted` }], 'The worker was restarted');
    update({ phase: restingState() });
    return;
  }
  startLoad(source, [{ file: null, line: null, message: `the worker stopped (${message}) and was restarted; the population was loaded again and is being fitted again` }], { fresh });
  showProblems([{ file: null, line: null, message: `the worker stopped (${message}); a new one is starting and gets the population again` }], 'The worker was restarted');
}

// The same work crashed the worker again after MAX_RESTARTS restarts: the page shows again what it had
// before the first restart (its model's summary, colours and views stay; questions to the worker need a new
// population or fit) and waits for the next request (a new worker starts with it).
function giveUp(message, restarts) {
  const wasFitting = state.fitId !== null || state.loading !== null;
  update({ fitId: null, loading: null, teach: null, fitCount: state.fitCount + (wasFitting ? 1 : 0) });
  if (kept) update({ ...kept, gen: state.gen + 1, pick: null, hoverPart: null, pose: Math.min(state.pose, kept.pop.nShapes - 1) });
  kept = null;
  showProblems([{ file: null, line: null, message: `the worker stopped again (${message}) after ${restarts} restart${restarts === 1 ? '' : 's'} with this population and these parameters (at most ${MAX_RESTARTS}): it was not restarted. ${state.model ? 'The last model is still shown; its' : 'Its'} questions (reconstruction, interpolation, exports) need a new fit: change the parameters, open other files or choose an example.` }], 'The worker keeps crashing');
  update({ phase: restingState() });
}

export { note };
