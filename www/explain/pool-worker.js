// One worker of the article's shared pool (www/explain/pool.js is the page side). It owns one wasm instance and
// any number of *sessions*, one per figure, each with its own population, fit and model. A session speaks the
// same protocol as www/worker.js (so that mount() works on it unchanged): 'generate' (with 'fit'), 'fit',
// 'query', the teaching messages 'teach-reset' / 'teach-step' / 'teach-run' / 'teach-pause', and answers
// 'loaded', 'progress', 'fitted', 'teach', 'reply', 'load-error', 'fit-error'. Every message in and out carries
// the session's number: { session, msg }. Pool messages:
//
//   page -> worker   { session, msg: { type: 'close' } }   frees the session
//   worker -> page   { type: 'pool-ready', defaults, examples }  once, when the wasm instance is up
//                    'teach' messages also carry `flips`: how many rotation steps of that iteration needed the
//                    handedness fix of eq 31 (wasm handednessFlips(), read around the step; null when the
//                    build has no such counter)
//                    { type: 'pool-fatal', message }            the wasm module failed to load
//
// Fits of different sessions run in slices (SLICE_MS) and yield to the event loop between slices, so sessions on
// one worker take turns and a 'teach-pause' or a query is read within one slice.
import init, * as wasm from '../pkg/posemfa.js';
import wasmUrl from '../pkg/posemfa_bg.wasm?url';
import { Teacher } from '../teach-worker.js';
import { poseQueries } from '../pose-queries.js';

const SLICE_MS = 25;
const PALETTE_SIZE = 12; // colors.js PALETTE.length
// The problems of an error thrown by the core (src/wasm.rs: {kind, file, line, message}).
const problemsOf = (e) => e?.problems ?? [{ kind: 'internal', file: null, line: null, message: String(e?.message ?? e) }];

// The core's count of rotation steps that needed eq 31, where the build has it (wasm handednessFlips()).
// Looked up by name, so that this file builds with or without the binding.
const binding = (name) => wasm[name];
const flipsSoFar = () => (typeof binding('handednessFlips') === 'function' ? binding('handednessFlips')() : null);

const channel = new MessageChannel();
const waiting = [];
channel.port1.onmessage = () => waiting.shift()?.();
const yieldToEvents = () => new Promise((resolve) => { waiting.push(resolve); channel.port2.postMessage(0); });

class Session {
  constructor(id) {
    this.id = id;
    this.population = null;
    this.synth = null;
    this.model = null;
    this.fitter = null;
    this.cancel = false;
    this.token = 0;
    this.teacher = new Teacher({
      wasm,
      post: (msg, transfer) => this.post(msg, transfer),
      claim: () => this.claim(),
      finish: (f, id, t0) => this.finish(f, id, t0),
      release: (f) => f.free(), // (this.finish does not free the fitter; the Teacher calls this once after it)
      yieldToEvents,
      paletteSize: PALETTE_SIZE,
    });
    this.queue = Promise.resolve();
  }

  post(msg, transfer = []) {
    if (msg.type === 'teach') {
      // Rotation steps that needed the handedness fix (eq 31) during this one iteration: the counter of the
      // instance read around it (steps run one at a time, so the difference is this step's alone).
      // (null when this build of the core does not count them)
      const now = flipsSoFar();
      msg.flips = now === null ? null : msg.kind === 'step' ? now - (this.flipsMark ?? now) : 0;
      this.flipsMark = now;
    }
    self.postMessage({ session: this.id, msg }, transfer);
  }

  free() {
    this.cancel = true;
    this.token++;
    this.teacher.drop();
    this.model?.free();
    this.population?.free();
    this.synth?.free();
    this.model = this.population = this.synth = null;
  }

  generate({ id, spec, fit }) {
    let synth;
    try {
      synth = new wasm.Synthetic(spec);
    } catch (e) {
      this.post({ type: 'load-error', id, problems: problemsOf(e) });
      return;
    }
    this.free();
    this.synth = synth;
    this.population = synth.population();
    const pop = this.population;
    const positions = [];
    for (let i = 0; i < pop.nShapes; i++) positions.push(pop.positions(i));
    const population = {
      names: pop.names(),
      nShapes: pop.nShapes,
      nVertices: pop.nVertices,
      faces: pop.faces(),
      positions,
      truth: { partNames: synth.partNames(), partOfVertex: synth.partOfVertex() },
    };
    population.truth.colours = pop.partColours(population.truth.partOfVertex, PALETTE_SIZE);
    this.post({ type: 'loaded', id, population }, [population.faces.buffer, ...positions.map((a) => a.buffer)]);
    if (fit) this.queue = this.queue.then(() => this.fit(fit));
  }

  // Stops this session's fit in progress and waits until it has let go; false if superseded meanwhile.
  async claim() {
    const token = ++this.token;
    if (this.fitter) {
      this.cancel = true;
      while (this.fitter) await yieldToEvents();
    }
    return token === this.token;
  }

  async fit({ id, params }) {
    if (!this.population) {
      this.post({ type: 'fit-error', id, message: 'no population loaded' });
      return;
    }
    this.teacher.drop();
    if (!(await this.claim())) return;
    const token = this.token;
    const t0 = performance.now();
    let f;
    try {
      f = new wasm.Fitter(this.population, { ...params, partRule: 'distinct' }); // the article explains Algorithm 1
    } catch (e) {
      this.post({ type: 'fit-error', id, message: String(e.message ?? e) });
      return;
    }
    this.fitter = f;
    this.cancel = false;
    try {
      while (!f.isDone() && !this.cancel) {
        const steps = f.run(SLICE_MS);
        const trace = f.currentTrace();
        const labels = f.currentLabels();
        const colours = this.population.partColours(labels, PALETTE_SIZE);
        this.post({ type: 'progress', id, steps, trace, labels, colours, elapsedMs: performance.now() - t0 }, [trace.buffer, labels.buffer, colours.buffer]);
        await yieldToEvents();
      }
      if (token === this.token && !this.cancel) this.finish(f, id, t0);
    } catch (e) {
      this.post({ type: 'fit-error', id, message: String(e.message ?? e) });
    } finally {
      f.free();
      if (this.fitter === f) this.fitter = null;
    }
  }

  finish(f, id, t0) {
    const m = f.result();
    this.model?.free();
    this.model = m;
    const summary = m.summary();
    summary.fitMs = performance.now() - t0;
    if (this.synth) summary.groundTruth = this.synth.groundTruth(m);
    const model = {
      summary,
      labels: m.labels(),
      coarseLabels: m.coarseLabels(),
      refinedLabels: m.refinedLabels(),
      latent: m.latent(),
    };
    const colours = (labels) => this.population.partColours(labels, PALETTE_SIZE);
    model.colours = { final: colours(model.labels), coarse: colours(model.coarseLabels), refined: colours(model.refinedLabels) };
    this.post({ type: 'fitted', id, cancelled: false, fitMs: summary.fitMs, model });
  }

  query({ id, method, args }) {
    const Q = {
      reconstruct: (i) => this.model.reconstruct(i),
      vertexErrors: (i) => this.model.vertexErrors(i),
      responsibilities: (v) => this.model.responsibilities(v),
      rotationAngles: (part, ref) => this.model.rotationAngles(part, ref),
      interpolate: (i, j, t, opts) => this.model.interpolate(i, j, t, opts ?? {}),
      linearInterpolate: (i, j, t) => this.model.linearInterpolate(i, j, t),
      articulationReport: (i, j, t) => this.model.articulationReport(i, j, t),
      distancesToLinear: (i, j, t, opts) => this.model.distancesToLinear(i, j, t, opts ?? {}),
      latentPlaced: (i) => this.model.latentPlaced(i),
      alongLongestAxis: (i) => this.population.alongLongestAxis(i),
      ...(this.poseQ ??= poseQueries(() => this.model)), // the pose-space figure (fig-pose.js)
    };
    try {
      if (!Q[method]) throw new Error(`unknown query ${method}`);
      if (!this.model) throw new Error('no fitted model yet');
      const result = Q[method](...(args ?? []));
      this.post({ type: 'reply', id, result }, ArrayBuffer.isView(result) ? [result.buffer] : []);
    } catch (e) {
      this.post({ type: 'reply', id, error: String(e.message ?? e) });
    }
  }

  async teach(data) {
    this.flipsMark = flipsSoFar(); // nothing before this message counts (other sessions' work)
    try {
      if (data.type === 'teach-reset') await this.teacher.reset(this.population, data);
      else if (data.type === 'teach-step') await this.teacher.step(this.population, data);
      else if (data.type === 'teach-run') await this.teacher.run(this.population, data);
    } catch (e) {
      this.teacher.drop();
      this.post({ type: 'fit-error', id: data.id, message: String(e.message ?? e) });
    }
  }

  onMessage(m) {
    if (m.type === 'cancel') {
      this.cancel = true;
      return;
    }
    if (m.type === 'teach-pause' || m.type === 'teach-reset') this.teacher.pause();
    if (m.type === 'teach-pause') return;
    if (m.type === 'generate') this.generate(m);
    else if (m.type === 'fit') this.queue = this.queue.then(() => this.fit(m));
    else if (m.type === 'query') this.query(m);
    else if (m.type.startsWith('teach-')) this.queue = this.queue.then(() => this.teach(m));
  }
}

const sessions = new Map();

const ready = init({ module_or_path: wasmUrl }).then(
  () => self.postMessage({ type: 'pool-ready', defaults: wasm.defaultParams(), examples: wasm.examples(), minExplained: wasm.minExplained() }),
  (e) => self.postMessage({ type: 'pool-fatal', message: `the wasm module failed to load: ${e.message ?? e}` }),
);

self.onmessage = async ({ data: { session, msg } }) => {
  if (msg.type === 'close') {
    sessions.get(session)?.free();
    sessions.delete(session);
    return;
  }
  await ready;
  let s = sessions.get(session);
  if (!s) sessions.set(session, (s = new Session(session)));
  try {
    s.onMessage(msg);
  } catch (e) {
    s.post({ type: 'fit-error', id: msg.id, message: String(e.message ?? e) });
  }
};
