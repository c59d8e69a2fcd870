// Worker side of the teaching mode (www/teach.js is the page side): one wasm Fitter driven by the page's
// Step / Run / Pause / Reset. One Step = one `fitter.step()` = one AECM iteration (Algorithm 1 moves from
// stage to stage inside it). Messages (see worker.js for the rest of the protocol):
//
//   page -> worker
//     { type: 'teach-reset', id, params }  a new teaching fit of the current population (iteration 0);
//                                          supersedes any fit in progress
//     { type: 'teach-step', id, count }    exactly `count` AECM iterations (default 1; fewer when the fit
//                                          ends first), one 'teach' message after them (starts a fit with
//                                          `params` first if there is none: { type: 'teach-step', id, params })
//     { type: 'teach-run', id }            iterations one by one (paced: RUN_MS each at least), a 'teach'
//                                          message after each, until paused or done
//     { type: 'teach-pause' }              stops a run after the iteration in progress
//   worker -> page
//     { type: 'teach', id, kind, steps, step, stage, running, trace, labels, gamma, parts, vertices, colours }
//        kind: 'reset' | 'step' | 'paused'; steps: the progress objects of the iterations just made (empty
//        unless kind is 'step'), step: the last of them (or null); stage: where the
//        pipeline is now; trace: the current AECM run's log-likelihoods; labels: per vertex (all vertices);
//        gamma: responsibilities [j * parts + k] of the run's vertices (`vertices`: their ids during the
//        refinement, else null); colours: a palette index per component of the run (neighbours differ)
//     then, once the pipeline is done, the usual { type: 'fitted', id, ... } (worker.js)

// Run paces itself to at most one iteration per RUN_MS, so that the plot, the counter and the colours can be
// followed (an unpaced run fits the quadruped in a fraction of a second).
const RUN_MS = 30;
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

export class Teacher {
  /**
   * wasm: the bindings; post(msg, transfer); claim(): async, stops any other fit and resolves to true
   * when this one may start; finish(fitter, id, t0): posts the model of a finished fitter (and frees the
   * fitter); release(fitter): frees a fitter unless that was done already.
   */
  constructor({ wasm, post, claim, finish, release, yieldToEvents, paletteSize }) {
    Object.assign(this, { wasm, post, claim, finish, release, yieldToEvents, paletteSize });
    this.fitter = null;
    this.id = null;
    this.running = false;
  }

  /** Frees the teaching fit (a new population, or a normal fit, replaces it). */
  drop() {
    this.running = false;
    this.fitter?.free();
    this.fitter = null;
    this.id = null;
  }

  async reset(population, { id, params }) {
    this.drop();
    if (!population) throw new Error('no population loaded');
    if (!(await this.claim())) return false;
    // (the core picks the pipeline a lesson shows: Algorithm 1, whatever the page's part rule)
    this.fitter = this.wasm.Fitter.forTeaching(population, params);
    this.id = id;
    this.t0 = performance.now();
    this.report('reset', []);
    return true;
  }

  // After a step (or a reset): what the page shows.
  report(kind, steps) {
    const f = this.fitter;
    const trace = f.currentTrace();
    const labels = f.currentLabels();
    const r = f.currentResponsibilities();
    const colours = f.currentColours(this.paletteSize);
    const msg = { type: 'teach', id: this.id, kind, steps, step: steps[steps.length - 1] ?? null, stage: f.stage(), running: this.running, trace, labels, parts: r.parts ?? 0, gamma: r.gamma ?? null, vertices: r.vertices ?? null, colours };
    const transfer = [trace.buffer, labels.buffer, colours.buffer];
    if (msg.gamma) transfer.push(msg.gamma.buffer);
    if (msg.vertices) transfer.push(msg.vertices.buffer);
    this.post(msg, transfer);
  }

  // `count` iterations (fewer when the pipeline is done first), then one report; when the pipeline is done,
  // its model goes to the page and the teaching fit ends.
  stepOnce(count = 1) {
    const f = this.fitter;
    const steps = [];
    while (steps.length < count && !f.isDone()) steps.push(f.step());
    const done = f.isDone();
    if (done) this.running = false;
    this.report('step', steps);
    if (done) {
      const id = this.id;
      this.fitter = null;
      this.id = null;
      try {
        this.finish(f, id, this.t0);
      } finally {
        this.release(f);
      }
    }
  }

  async step(population, { id, params, count = 1 }) {
    if (this.running) return;
    if (!this.fitter && !(await this.reset(population, { id, params }))) return;
    this.stepOnce(Math.max(1, Math.floor(count)));
  }

  async run(population, { id, params }) {
    if (this.running) return;
    if (!this.fitter && !(await this.reset(population, { id, params }))) return;
    this.running = true;
    const f = this.fitter;
    while (this.running && this.fitter === f) {
      const t0 = performance.now();
      this.stepOnce();
      const rest = RUN_MS - (performance.now() - t0);
      await (rest > 1 ? sleep(rest) : this.yieldToEvents()); // a 'teach-pause' (or a new fit) is read here
    }
    if (this.fitter === f) this.report('paused', []);
  }

  pause() {
    this.running = false;
  }
}
