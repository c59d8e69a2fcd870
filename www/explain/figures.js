// The article's live figures. Each is a few mount() views (www/mount.js) whose worker is a channel of the shared
// pool (www/explain/pool.js), on its own small generated population. A figure shows and asks; every number it
// shows comes from the core (fits, queries, single AECM steps). Live parts (runs, animations) go only while the
// figure is in view (explain.js calls setVisible).
import { mount } from '../mount.js';
import { Chart } from './chart.js';
import { PALETTE, PALETTE_RGB, hexToRgb, paletteColours, gammaColours, errorColours } from '../colors.js';

const GREY = [0.8, 0.81, 0.84];
const LITERAL = '#d1495b';
const EXACT = '#2f6fb3';

// The figures' populations: small, so that each fits in a few hundred ms in the browser.
const QUAD = { preset: 'quadruped', vertices: 1100, poses: 6, seed: 0, jointBand: 0.01, maxAngleDeg: 60 };
const SNAKE = { preset: 'snake', vertices: 800, poses: 8, seed: 0, jointBand: 0.01, maxAngleDeg: 45 };
const ARM = { preset: 'arm', vertices: 600, poses: 6, seed: 0, jointBand: 0.01 };
const BLOB = { preset: 'blob', vertices: 800, poses: 6, seed: 0 };
const SYNTH = { refineThreshold: 2e-6 }; // as the app's examples (src/synth/presets.rs)

let nextId = 100000;

/** Per-vertex colours: the chosen part in its colour, the rest grey. */
function highlight(labels, part, colour) {
  const out = new Float32Array(labels.length * 3);
  labels.forEach((l, v) => out.set(l === part ? colour : GREY, 3 * v));
  return out;
}

const fmtE = (x) => (x === 0 ? '0' : x < 1e-3 ? x.toExponential(1) : x.toFixed(3));

/** Iterations where the log-likelihood fell (by more than rounding). */
export function drops(values) {
  const out = [];
  for (let i = 1; i < values.length; i++) {
    if (values[i - 1] - values[i] > 1e-9 * Math.max(1, Math.abs(values[i]))) out.push(i);
  }
  return out;
}

class Figure {
  constructor({ el, index, pool }) {
    Object.assign(this, { el, index, pool });
    this.name = el.dataset.figure;
    this.visible = false;
    this.views = [];
    this.statusEl = el.querySelector('.fig-status');
    this.setState('loading');
    for (const b of el.querySelectorAll('[data-act]')) b.addEventListener('click', () => this.act(b.dataset.act));
  }

  $(sel) {
    return this.el.querySelector(sel);
  }

  out(name, text) {
    for (const o of this.el.querySelectorAll(`[data-out="${name}"]`)) o.textContent = text;
  }

  /** Visible figures get the pool first, then the others in the article's order. */
  priority() {
    return (this.visible ? 0 : 1000) + this.index;
  }

  setState(s, note = '') {
    if ((s === 'fitted' || s === 'stepping') && this.readyAt === undefined) this.readyAt = performance.now();
    this.state = s;
    this.el.dataset.state = s;
    if (this.statusEl) {
      const text = { loading: 'Waiting for its turn…', fitting: 'Fitting…', error: `Error: ${note}` }[s] ?? note;
      this.statusEl.textContent = text;
    }
  }

  /**
   * A mount() view in `el` on a pool channel; made when the pool gives the figure its turn. `spec` may be a
   * function of the pool's info ({defaults, examples}), to build on a built-in example's spec.
   */
  view(el, spec, params, extra = {}) {
    const v = { el, spec, params, handle: null, pop: null, model: null };
    v.channel = this.pool.channel(() => this.priority(), () => this.prepare());
    v.make = () => {
      if (v.handle) return;
      // spec read when the pool says 'ready' (by then a spec given as a function has been resolved)
      v.handle = mount(el, { get spec() { return v.spec; }, params, worker: v.channel, ...extra });
      v.handle.on((m) => this.message(v, m));
      v.handle.viewer.renderer.domElement.addEventListener('click', (e) => this.click(v, e));
    };
    this.views.push(v);
    // The first figure makes its view at once (its WebGL set-up overlaps the workers' start).
    if (this.index === 0) v.make();
    return v;
  }

  /** Makes the figure's views (WebGL contexts) if not yet made: when its turn comes, or when it is in view. */
  prepare() {
    for (const v of this.views) {
      if (typeof v.spec === 'function' && this.pool.info) v.spec = v.spec(this.pool.info);
      v.make();
    }
  }

  message(v, m) {
    if (m.type === 'loaded') {
      v.pop = m.population;
      v.model = null;
      if (!this.live()) this.setState('fitting');
    } else if (m.type === 'fitted') {
      v.model = m.model;
      if (this.views.every((w) => w.model)) {
        this.onFitted(v, m);
        this.refreshState();
        if (this.visible) this.resume();
      }
    } else if (m.type === 'teach') {
      this.onTeach(v, m);
    } else if (['fit-error', 'load-error', 'fatal'].includes(m.type)) {
      this.stopLive?.();
      this.setState('error', m.message ?? m.problems?.map((p) => p.message).join('; '));
    }
  }

  /** Regenerates the population and fits it again (Reset). */
  regenerate() {
    this.pause();
    for (const v of this.views) {
      if (!v.handle) continue;
      v.model = null;
      v.handle.post({ type: 'generate', id: nextId++, spec: v.spec, fit: { id: nextId++, params: v.params } });
    }
    this.setState('fitting');
  }

  live() {
    return false;
  }

  refreshState() {
    if (this.state === 'error') return;
    if (this.live()) this.setState('stepping', 'Running.');
    else if (this.views.length && this.views.every((v) => v.model)) this.setState('fitted', this.fittedNote?.() ?? '');
  }

  setVisible(on) {
    if (on === this.visible) return;
    this.visible = on;
    if (on) this.prepare();
    if (on) this.resume();
    else this.pause();
  }

  // Defaults: no live part.
  resume() {}
  pause() {}
  onFitted() {}
  onTeach() {}
  click() {}
  act(a) {
    if (a === 'reset') this.regenerate();
  }

  logLikelihood() {
    return Array.from(this.views[0]?.model?.summary.logLikelihood ?? []);
  }

  contract() {
    return { name: this.name, state: this.state, logLikelihood: this.logLikelihood() };
  }

  detail() {
    return { visible: this.visible, readyAt: this.readyAt, fitMs: this.views.map((v) => v.model?.summary.fitMs ?? null) };
  }
}

/** An animation that runs while the figure is in view: `tick()` every `ms`. */
class Ticker {
  constructor(ms, tick) {
    Object.assign(this, { ms, tick, timer: null });
  }

  start() {
    if (this.timer) return;
    this.timer = setInterval(() => this.tick(), this.ms);
  }

  stop() {
    clearInterval(this.timer);
    this.timer = null;
  }

  get on() {
    return this.timer !== null;
  }
}

/**
 * AECM step by step on one view, paced by the page: one 'teach-step' at a time, the next `pace` ms after the
 * previous answer, while `running` and the figure is in view. Calls onStep(step, msg) and onDone(model).
 */
class Stepper {
  constructor(fig, v, params, pace) {
    Object.assign(this, { fig, v, params, pace });
    this.id = null;
    this.running = false;
    this.waiting = false;
    this.done = false;
    this.values = [];
    this.iteration = 0;
    this.started = false;
    this.timer = null;
  }

  reset() {
    this.id = nextId++;
    this.values = [];
    this.iteration = 0;
    this.done = false;
    this.waiting = false;
    this.started = true;
    clearTimeout(this.timer);
    this.v.handle.post({ type: 'teach-reset', id: this.id, params: this.params });
  }

  stepOnce() {
    if (this.waiting || this.done) return;
    if (this.id === null) this.reset();
    this.waiting = true;
    this.v.handle.post({ type: 'teach-step', id: this.id, params: this.params });
  }

  run() {
    if (this.done) this.reset();
    this.running = true;
    this.stepOnce();
  }

  pause() {
    this.running = false;
    clearTimeout(this.timer);
  }

  /** A 'teach' message; true if it was this stepper's step. */
  onTeach(m) {
    if (m.id !== this.id) return false;
    if (m.kind !== 'step') return false;
    this.waiting = false;
    this.values.push(m.step.logLikelihood);
    this.iteration = m.step.totalIterations;
    if (m.stage?.kind === 'done') {
      this.done = true;
      this.running = false;
    }
    if (this.running && this.fig.visible && !this.done) {
      clearTimeout(this.timer);
      this.timer = setTimeout(() => this.running && this.fig.visible && this.stepOnce(), this.pace);
    }
    return true;
  }
}

// ------------------------------------------------------------------ 1. the problem: registered poses

class Poses extends Figure {
  constructor(ctx) {
    super(ctx);
    this.first = 0;
    // Only the poses matter here: a coarse fit (no refinement) is enough for the caption, and quick.
    this.v = this.view(this.$('.fig-view'), QUAD, { ...SYNTH, parts: 8, refine: false });
    this.ticker = new Ticker(2500, () => this.shift(1));
  }

  draw(frame = false) {
    const { pop } = this.v;
    const colours = this.colour;
    if (!colours) return;
    const shown = [0, 1, 2, 3].map((k) => (this.first + k) % pop.nShapes);
    this.v.handle.viewer.show(shown.map((i) => ({ positions: pop.positions[i], colours })), { frame });
    this.statusNote = `Poses ${shown.map((i) => i + 1).join(', ')} of ${pop.nShapes}.`;
  }

  fittedNote() {
    const s = this.v.model.summary;
    return `${this.statusNote} A first, coarse fit of this population: ${s.parts} parts in ${Math.round(s.fitMs)} ms.`;
  }

  // Every vertex coloured by where it lies along the body's longest side in pose 1 (the core measures it): a
  // vertex keeps its colour in every pose, which is what "in correspondence" means.
  async onFitted() {
    this.colour = null;
    try {
      this.colour = errorColours(await this.v.handle.query('alongLongestAxis', 0), 1);
    } catch (e) {
      this.setState('error', e.message);
      return;
    }
    this.draw(true);
  }

  shift(d) {
    if (!this.v.model) return;
    this.first = (this.first + d) % this.v.pop.nShapes;
    this.draw();
    this.refreshState();
  }

  resume() {
    if (this.v.model) this.ticker.start();
  }

  pause() {
    this.ticker.stop();
  }

  act(a) {
    if (a === 'next') this.shift(4);
    else if (a === 'reset') {
      this.first = 0;
      this.regenerate();
    }
  }
}

// ------------------------------------------------------------------ 2. the model: one part's motion

class Model extends Figure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), SNAKE, { ...SYNTH, parts: 6 });
    this.part = 0;
    this.pose = 0;
    this.touched = false;
    this.partSel = this.$('[data-ctl=part]');
    this.poseIn = this.$('[data-ctl=pose]');
    this.partSel.addEventListener('change', () => {
      this.partPicked = true;
      this.choosePart(Number(this.partSel.value));
    });
    this.poseIn.addEventListener('input', () => {
      this.touched = true;
      this.ticker.stop();
      this.pose = Number(this.poseIn.value);
      this.draw();
    });
    this.ticker = new Ticker(1200, () => {
      this.pose = (this.pose + 1) % this.v.pop.nShapes;
      this.poseIn.value = String(this.pose);
      this.draw();
    });
  }

  async onFitted() {
    const { model, pop } = this.v;
    const { partColour } = paletteColours(model.labels, model.colours.final);
    this.partColour = partColour;
    this.partSel.replaceChildren(...partColour.map((c, k) => Object.assign(document.createElement('option'), { value: String(k), textContent: `part ${k + 1}` })));
    this.poseIn.max = String(pop.nShapes - 1);
    this.choosePart(this.part < partColour.length ? this.part : 0, true);
    if (this.partPicked) return;
    // start on the part that turns the most (its largest rotation angle over the poses, from the core)
    let best = 0;
    let bestAngle = -1;
    for (let k = 0; k < partColour.length; k++) {
      const a = Math.max(...(await this.v.handle.query('rotationAngles', k, 0).catch(() => [0])));
      if (a > bestAngle) {
        bestAngle = a;
        best = k;
      }
    }
    if (!this.partPicked && this.v.model === model) this.choosePart(best);
  }

  async choosePart(k, frame = false) {
    this.part = k;
    this.partSel.value = String(k);
    this.draw(frame);
    try {
      const angles = await this.v.handle.query('rotationAngles', k, 0);
      this.angles = angles;
      this.drawBars();
    } catch (e) {
      this.setState('error', e.message);
    }
  }

  draw(frame = false) {
    const { model, pop } = this.v;
    if (!model) return;
    const colour = hexToRgb(this.partColour[this.part]);
    const c = highlight(model.labels, this.part, colour);
    this.v.handle.viewer.show([{ positions: pop.positions[0], colours: c }, { positions: pop.positions[this.pose], colours: c }], { frame });
    this.out('pose', String(this.pose + 1));
    this.drawBars();
  }

  drawBars() {
    const box = this.$('[data-out=angles]');
    if (!this.angles) return;
    const max = Math.max(...this.angles, 1);
    box.replaceChildren(...Array.from(this.angles, (a, i) => {
      const bar = document.createElement('div');
      bar.className = `bar${i === this.pose ? ' current' : ''}`;
      bar.innerHTML = `<span class="lbl">pose ${i + 1}</span><span class="fill" style="width:${(100 * a) / max}%;background:${this.partColour[this.part]}"></span><span class="val">${a.toFixed(1)}°</span>`;
      return bar;
    }));
  }

  fittedNote() {
    const s = this.v.model.summary;
    return `${s.parts} parts; showing part ${this.part + 1}.`;
  }

  click(v, e) {
    const hit = v.handle.viewer.pick(e.clientX, e.clientY);
    if (hit && v.model) {
      this.partPicked = true;
      this.choosePart(v.model.labels[hit.vertex]);
    }
  }

  resume() {
    if (this.v.model && !this.touched) this.ticker.start();
  }

  pause() {
    this.ticker.stop();
  }

  act(a) {
    if (a === 'reset') {
      this.touched = false;
      this.pose = 0;
      this.poseIn.value = '0';
      this.regenerate();
    }
  }
}

// ------------------------------------------------------------------ teaching figures (AECM step by step)

class Stepping extends Figure {
  /** pace: ms between steps while running. */
  setup(v, params, pace) {
    this.v = v;
    this.stepper = new Stepper(this, v, params, pace);
    this.autoStarted = false;
  }

  live() {
    return this.stepper.running && this.visible;
  }

  message(v, m) {
    super.message(v, m);
    if (m.type === 'fitted' && m.id === this.stepper.id) {
      v.handle.caption.textContent = `${m.model.summary.parts} parts after ${this.stepper.iteration} iterations, one step at a time`;
      this.stepper.running = false;
      this.stepper.done = true;
      this.refreshState();
      this.buttons();
    }
  }

  onTeach(v, m) {
    if (this.stepper.onTeach(m)) {
      this.showStep(m);
      this.refreshState();
      this.buttons();
    } else if (m.kind === 'reset' && m.id === this.stepper.id) {
      this.showStep(m);
    }
  }

  resume() {
    if (!this.v.model) return;
    if (!this.autoStarted) {
      this.autoStarted = true;
      this.stepper.reset();
      this.stepper.run();
    } else if (this.resumeOnShow) {
      this.resumeOnShow = false;
      this.stepper.run();
    }
    this.refreshState();
    this.buttons();
  }

  pause() {
    if (this.stepper.running) this.resumeOnShow = true;
    this.stepper.pause();
    this.refreshState();
    this.buttons();
  }

  act(a) {
    if (!this.v.model && a !== 'reset') return;
    if (a === 'step') {
      this.stepper.pause();
      if (this.stepper.done) this.stepper.reset();
      this.stepper.stepOnce();
    } else if (a === 'run') {
      this.stepper.run();
    } else if (a === 'pause') {
      this.stepper.pause();
      this.resumeOnShow = false;
    } else if (a === 'reset') {
      this.stepper.pause();
      this.stepper.reset();
      this.autoStarted = true;
      if (this.visible) this.stepper.run();
    }
    this.refreshState();
    this.buttons();
  }

  buttons() {
    const b = (a) => this.$(`[data-act=${a}]`);
    const running = this.stepper.running;
    if (b('run')) b('run').disabled = running;
    if (b('step')) b('step').disabled = running;
    if (b('pause')) b('pause').disabled = !running;
  }

  logLikelihood() {
    return this.stepper.started ? this.stepper.values.slice() : super.logLikelihood();
  }

  detail() {
    return { visible: this.visible, readyAt: this.readyAt, running: this.stepper.running, iteration: this.stepper.iteration, steps: this.stepper.values.length, done: this.stepper.done };
  }

  showStep() {}
}

// ------------------------------------------------------------------ 3. responsibilities

class Responsibilities extends Stepping {
  constructor(ctx) {
    super(ctx);
    this.setup(this.view(this.$('.fig-view'), QUAD, { ...SYNTH, parts: 8, refine: false }), { ...SYNTH, parts: 8, refine: false }, 260);
    this.vertex = null;
    this.gamma = null;
    const canvas = this.$('.fig-view');
    canvas.addEventListener('keydown', (e) => {
      if (e.key === 'Enter' && this.gamma) {
        e.preventDefault();
        this.pickUncertain();
      }
    });
  }

  showStep(m) {
    if (!m.gamma || !m.parts || !this.v.pop) return;
    // the core's palette index per component (neighbours differ), kept for the whole run so that colours do
    // not jump between steps
    const key = `${this.stepper.id}:${m.parts}`;
    if (key !== this.colourKey && m.colours?.length === m.parts) {
      this.colourKey = key;
      this.colourOf = Array.from(m.colours);
    }
    if (!this.colourOf) return;
    this.gamma = { values: m.gamma, parts: m.parts };
    this.v.handle.viewer.show([{ positions: this.v.pop.positions[0], colours: gammaColours(m.gamma, m.parts, this.colourOf) }]);
    this.out('iteration', String(this.stepper.iteration));
    this.drawGamma();
  }

  // The vertex whose largest responsibility is smallest: one on a boundary between parts.
  pickUncertain() {
    const { values, parts } = this.gamma;
    let best = 0;
    let bestMax = 2;
    for (let j = 0; j < values.length / parts; j++) {
      let mx = 0;
      for (let k = 0; k < parts; k++) mx = Math.max(mx, values[j * parts + k]);
      if (mx < bestMax) {
        bestMax = mx;
        best = j;
      }
    }
    this.choose(best);
  }

  choose(vertex) {
    this.vertex = vertex;
    this.v.handle.viewer.mark(0, vertex);
    this.drawGamma();
  }

  click(v, e) {
    const hit = v.handle.viewer.pick(e.clientX, e.clientY);
    if (hit) this.choose(hit.vertex);
  }

  drawGamma() {
    const box = this.$('[data-out=gamma]');
    if (this.vertex === null || !this.gamma) {
      box.textContent = 'Click a vertex to see its responsibilities.';
      return;
    }
    const { values, parts } = this.gamma;
    const row = Array.from({ length: parts }, (_, k) => values[this.vertex * parts + k]);
    box.replaceChildren(
      Object.assign(document.createElement('p'), { className: 'bars-title', textContent: `Vertex ${this.vertex}, iteration ${this.stepper.iteration}: γ over the ${parts} parts` }),
      ...row.map((g, k) => {
        const bar = document.createElement('div');
        bar.className = 'bar';
        bar.innerHTML = `<span class="lbl">part ${k + 1}</span><span class="fill" style="width:${100 * g}%;background:${PALETTE[this.colourOf[k]]}"></span><span class="val">${g < 1e-3 && g > 0 ? g.toExponential(1) : g.toFixed(3)}</span>`;
        return bar;
      }),
    );
  }

  fittedNote() {
    return this.stepper.started ? `Iteration ${this.stepper.iteration}${this.stepper.done ? ': converged.' : ', paused.'}` : 'Fitted; the live run starts in view.';
  }
}

// ------------------------------------------------------------------ 4. AECM: Step / Run / Reset

class Aecm extends Stepping {
  constructor(ctx) {
    super(ctx);
    // The quadruped's thin leg pieces with 10 parts to start: several rotation steps need eq 31.
    const params = { ...SYNTH, parts: 10, refine: false };
    this.setup(this.view(this.$('.fig-view'), QUAD, params), params, 420);
    this.chart = new Chart(this.$('[data-out=plot]'));
    this.cycleTimers = [];
    this.flips = [];
  }

  showStep(m) {
    const s = this.stepper;
    if (m.kind === 'reset') this.flips = [];
    if (m.kind === 'step' && m.flips != null) this.flips.push(m.flips);
    const marked = this.flips.flatMap((f, i) => (f > 0 ? [i] : []));
    this.chart.set([{ values: s.values, colour: EXACT, markers: marked, markerColour: '#e9a23b' }]);
    this.out('iteration', String(s.iteration));
    this.out('ll', s.values.length ? s.values[s.values.length - 1].toFixed(2) : '–');
    if (this.flips.length) {
      const total = this.flips.reduce((a, b) => a + b, 0);
      const last = this.flips[this.flips.length - 1];
      this.out('flips', `Rotation steps that needed the handedness fix: ${last} in the last iteration, ${total} in ${this.flips.length} iteration${this.flips.length === 1 ? '' : 's'}.`);
    }
    if (m.labels && m.colours?.length && this.v.pop) this.v.handle.viewer.show([{ positions: this.v.pop.positions[0], colours: paletteColours(m.labels, m.colours).vertexColours }]);
    if (m.kind === 'step') this.flashCycles();
  }

  // Marks cycle 1, cycle 2, then the likelihood, in the order one iteration computes them.
  flashCycles() {
    for (const t of this.cycleTimers) clearTimeout(t);
    const items = [...this.el.closest('section').querySelectorAll('[data-cycle]')];
    const pace = Math.min(this.stepper.pace / 3, 150);
    items.forEach((li, i) => {
      this.cycleTimers.push(setTimeout(() => items.forEach((x, k) => x.classList.toggle('current', k === i)), i * pace));
    });
  }

  fittedNote() {
    const s = this.stepper;
    if (!s.started) return 'Fitted; the live run starts in view.';
    const d = drops(s.values).length;
    return `${s.iteration} iterations${s.done ? ', converged' : ''}; the log-likelihood fell ${d} times.`;
  }

  detail() {
    return { ...super.detail(), flips: this.flips.slice() };
  }
}

// ------------------------------------------------------------------ 5. eq 18 against the exact step

class Eq18 extends Figure {
  constructor(ctx) {
    super(ctx);
    const base = { ...SYNTH, parts: 6, refine: false, maxIter: 60 };
    this.params = { literal: { ...base, lambdaRule: 'paper-eq18' }, exact: { ...base, lambdaRule: 'exact' } };
    this.sides = {};
    for (const side of ['literal', 'exact']) {
      const v = this.view(this.$(`[data-view=${side}]`), QUAD, this.params[side]);
      v.side = side;
      this.sides[side] = { v, stepper: new Stepper(this, v, this.params[side], 150) };
    }
    this.chart = new Chart(this.$('[data-out=plot]'));
    this.autoStarted = false;
  }

  steppers() {
    return Object.values(this.sides).map((s) => s.stepper);
  }

  live() {
    return this.visible && this.steppers().some((s) => s.running);
  }

  trace(side) {
    const s = this.sides[side];
    return s.stepper.started ? s.stepper.values.slice() : Array.from(s.v.model?.summary.logLikelihood ?? []);
  }

  draw() {
    const series = ['literal', 'exact'].map((side) => {
      const values = this.trace(side);
      return { values, colour: side === 'literal' ? LITERAL : EXACT, markers: drops(values) };
    });
    this.chart.set(series);
    for (const side of ['literal', 'exact']) {
      const t = this.trace(side);
      const d = drops(t);
      const worst = d.length ? Math.max(...d.map((i) => t[i - 1] - t[i])) : 0;
      this.out(side, t.length ? `${t.length} iterations, ${d.length} drop${d.length === 1 ? '' : 's'}${d.length ? ` (largest ${worst.toFixed(1)} nats)` : ''}` : '–');
    }
  }

  onFitted() {
    this.draw();
  }

  message(v, m) {
    super.message(v, m);
    const st = this.sides[v.side].stepper;
    if (m.type === 'fitted' && m.id === st.id) {
      v.handle.caption.textContent = `${m.model.summary.parts} parts after ${st.iteration} iterations, one step at a time`;
      st.running = false;
      st.done = true;
      this.refreshState();
    }
  }

  onTeach(v, m) {
    const st = this.sides[v.side].stepper;
    if (st.onTeach(m) || (m.kind === 'reset' && m.id === st.id)) {
      if (m.labels && m.colours?.length && v.pop) v.handle.viewer.show([{ positions: v.pop.positions[0], colours: paletteColours(m.labels, m.colours).vertexColours }]);
      this.draw();
      this.refreshState();
    }
  }

  fittedNote() {
    return this.steppers().some((s) => s.started) ? 'Same start, two Λ rules.' : 'Both fitted; the live run starts in view.';
  }

  startBoth() {
    for (const s of this.steppers()) {
      s.reset();
      s.run();
    }
  }

  resume() {
    if (!this.views.every((v) => v.model)) return;
    if (!this.autoStarted) {
      this.autoStarted = true;
      this.startBoth();
    } else if (this.resumeOnShow) {
      this.resumeOnShow = false;
      for (const s of this.steppers()) if (!s.done) s.run();
    }
    this.refreshState();
  }

  pause() {
    if (this.steppers().some((s) => s.running)) this.resumeOnShow = true;
    for (const s of this.steppers()) s.pause();
    this.refreshState();
  }

  act(a) {
    if (!this.views.every((v) => v.model)) return;
    const all = this.steppers();
    if (a === 'step') {
      for (const s of all) {
        s.pause();
        if (!s.done) s.stepOnce();
      }
    } else if (a === 'run') {
      for (const s of all) if (!s.done) s.run();
    } else if (a === 'pause') {
      for (const s of all) s.pause();
      this.resumeOnShow = false;
    } else if (a === 'reset') {
      this.autoStarted = true;
      for (const s of all) {
        s.pause();
        s.reset();
        if (this.visible) s.run();
      }
    }
    this.refreshState();
  }

  contract() {
    return { name: this.name, state: this.state, literal: this.trace('literal'), exact: this.trace('exact') };
  }

  detail() {
    return { visible: this.visible, readyAt: this.readyAt, literal: this.sides.literal.stepper.values.length, exact: this.sides.exact.stepper.values.length, running: this.steppers().some((s) => s.running) };
  }
}

// ------------------------------------------------------------------ 5b. Algorithm 2's missed end poses

const PRINTED = { root: 'paper', tree: 'breadth-first', exactEnds: false, residual: false };

class Ends extends Figure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), SNAKE, { ...SYNTH, parts: 6 });
    this.t = 1;
    this.tIn = this.$('[data-ctl=t]');
    this.tIn.addEventListener('input', () => {
      this.ticker.stop();
      this.t = Number(this.tIn.value);
      this.draw();
    });
    this.ticker = new Ticker(60, () => {
      this.t = Math.min(1, this.t + 0.025);
      this.tIn.value = String(this.t);
      this.draw();
      if (this.t >= 1) this.ticker.stop();
    });
    this.seq = 0;
  }

  async onFitted() {
    const { pop } = this.v;
    this.i = 0;
    this.j = pop.nShapes - 1;
    this.out('from', String(this.i + 1));
    this.out('to', String(this.j + 1));
    try {
      const r = await this.v.handle.query('articulationReport', this.i, this.j, 0.5);
      const printed = r.methods.find((m) => m.name.startsWith('Algorithm 2 as printed'));
      const ours = r.methods[0];
      this.errors = { printed: printed.endpointError, ours: ours.endpointError };
      this.out('errors', `as printed ${fmtE(printed.endpointError[0])} / ${fmtE(printed.endpointError[1])}, corrected ${fmtE(ours.endpointError[0])} / ${fmtE(ours.endpointError[1])} (largest vertex distance at t = 0 / t = 1, unit box)`);
    } catch (e) {
      this.setState('error', e.message);
      return;
    }
    await this.draw(true);
  }

  async draw(frame = false) {
    const { model } = this.v;
    if (!model) return;
    const seq = ++this.seq;
    this.out('t', this.t.toFixed(2));
    // Colour: each vertex's distance (from the core) to the linear blend of the two training poses, which is
    // exactly the end pose at t = 0 and t = 1 (in between, both methods rightly differ from it).
    const q = (...args) => this.v.handle.query(...args);
    const [a, b, da, db] = await Promise.all([
      q('interpolate', this.i, this.j, this.t, PRINTED),
      q('interpolate', this.i, this.j, this.t, {}),
      q('distancesToLinear', this.i, this.j, this.t, PRINTED),
      q('distancesToLinear', this.i, this.j, this.t, {}),
    ]).catch((e) => {
      this.setState('error', e.message);
      return [];
    });
    if (seq !== this.seq || !a) return;
    const max = Math.max(...da, ...db, 1e-6);
    this.v.handle.viewer.show([{ positions: a, colours: errorColours(da, max) }, { positions: b, colours: errorColours(db, max) }], { frame });
  }

  fittedNote() {
    return `${this.v.model.summary.parts} parts.`;
  }

  act(a) {
    if (a === 'play') {
      this.t = 0;
      this.ticker.start();
    } else if (a === 'reset') {
      this.t = 1;
      this.tIn.value = '1';
      this.regenerate();
    }
  }

  pause() {
    this.ticker.stop();
  }
}

// ------------------------------------------------------------------ 6. the hierarchy (Algorithm 1, Fig 2)

const STAGE_TEXT = {
  coarse: () => 'coarse AECM on all vertices',
  refine: (st) => `refining coarse part ${st.part + 1} of ${st.of} with m_k = ${st.subParts} (the rest grey)`,
  final: () => 'final AECM on all vertices, from the refined labels',
  done: () => 'done',
};

class Hierarchy extends Stepping {
  constructor(ctx) {
    super(ctx);
    const params = { ...SYNTH, parts: 5 };
    this.setup(this.view(this.$('.fig-view'), QUAD, params), params, 70);
    this.stage = 'coarse';
    this.auto = true;
    this.ticker = new Ticker(1800, () => {
      const order = ['coarse', 'refined', 'final'];
      this.show(order[(order.indexOf(this.stage) + 1) % 3]);
    });
  }

  // The stages of the fitted model (Fig 2): coarse, refined, final labels.
  show(stage, frame = false) {
    const { model, pop } = this.v;
    if (!model) return;
    this.stage = stage;
    const labels = { coarse: model.coarseLabels, refined: model.refinedLabels, final: model.labels }[stage];
    const parts = new Set(labels).size;
    this.v.handle.viewer.show([{ positions: pop.positions[0], colours: paletteColours(labels, model.colours[stage]).vertexColours }], { frame });
    this.out('stage', `${stage}, ${parts} parts`);
    for (const b of this.el.querySelectorAll('[data-act]')) b.setAttribute('aria-pressed', String(b.dataset.act === stage));
  }

  // A step of the replay: the run in progress; during the refinement, the coarse part being split in the
  // colours of its sub-parts (argmax of γ), the rest grey.
  showStep(m) {
    const { pop } = this.v;
    if (!pop || !m.stage) return;
    const kind = m.stage.kind;
    this.out('stage', `replaying: ${STAGE_TEXT[kind](m.stage)}, iteration ${this.stepper.iteration}`);
    for (const b of this.el.querySelectorAll('[data-act]')) b.setAttribute('aria-pressed', 'false');
    let colours;
    if (!m.colours?.length) return; // none between the runs
    if (kind === 'refine' && m.vertices && m.gamma && m.parts) {
      colours = new Float32Array(pop.nVertices * 3);
      for (let v = 0; v < pop.nVertices; v++) colours.set(GREY, 3 * v);
      const K = m.parts;
      m.vertices.forEach((v, j) => {
        let best = 0;
        for (let k = 1; k < K; k++) if (m.gamma[j * K + k] > m.gamma[j * K + best]) best = k;
        colours.set(PALETTE_RGB[m.colours[best] % PALETTE.length], 3 * v);
      });
    } else if (m.labels && kind !== 'refine') {
      colours = paletteColours(m.labels, m.colours).vertexColours;
    }
    if (colours) this.v.handle.viewer.show([{ positions: pop.positions[0], colours }]);
  }

  message(v, m) {
    super.message(v, m);
    if (m.type === 'fitted' && m.id === this.stepper.id) {
      this.show('final');
      if (this.visible && this.auto) this.ticker.start();
    }
  }

  onFitted() {
    this.show('coarse', true);
  }

  fittedNote() {
    const s = this.v.model.summary;
    return `coarse ${s.coarseParts} → refined ${s.refinedParts} → final ${s.parts} parts; adjusted Rand index against the truth ${s.groundTruth?.ari.toFixed(3)}.`;
  }

  resume() {
    super.resume();
    if (this.v.model && this.auto && !this.stepper.running) this.ticker.start();
    else this.ticker.stop();
  }

  pause() {
    super.pause();
    this.ticker.stop();
  }

  act(a) {
    if (['coarse', 'refined', 'final'].includes(a)) {
      this.auto = false;
      this.ticker.stop();
      this.stepper.pause();
      this.resumeOnShow = false;
      this.refreshState();
      this.show(a);
    } else if (a === 'replay') {
      this.ticker.stop();
      super.act('reset');
    } else if (a === 'reset') {
      this.auto = true;
      this.ticker.stop();
      super.act('reset');
    }
  }

  buttons() {}
}

// ------------------------------------------------------------------ 7. reconstruction and latent shape

class Reconstruction extends Figure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), QUAD, { ...SYNTH, parts: 8 });
    this.pose = 0;
    this.poseIn = this.$('[data-ctl=pose]');
    this.poseIn.addEventListener('input', () => {
      this.touched = true;
      this.ticker.stop();
      this.pose = Number(this.poseIn.value);
      this.draw();
    });
    this.ticker = new Ticker(2200, () => {
      this.pose = (this.pose + 1) % this.v.pop.nShapes;
      this.poseIn.value = String(this.pose);
      this.draw();
    });
    this.seq = 0;
  }

  async onFitted() {
    this.placed = null;
    this.poseIn.max = String(this.v.pop.nShapes - 1);
    this.out('rmse', this.v.model.summary.rmse.toExponential(2));
    await this.draw(true);
  }

  async draw(frame = false) {
    const { model, pop } = this.v;
    if (!model) return;
    const seq = ++this.seq;
    const i = this.pose;
    let rec;
    let err;
    try {
      [rec, err] = await Promise.all([this.v.handle.query('reconstruct', i), this.v.handle.query('vertexErrors', i)]);
      // The latent shape drawn with every part moved to its place in pose 1 (its b^1) but not turned: the
      // parts of eq 21 are all centred on the origin, on top of each other.
      this.placed ??= await this.v.handle.query('latentPlaced', 0);
    } catch (e) {
      this.setState('error', e.message);
      return;
    }
    if (seq !== this.seq) return;
    const max = Math.max(...err, 1e-9);
    const parts = paletteColours(model.labels, model.colours.final).vertexColours;
    this.v.handle.viewer.show([
      { positions: pop.positions[i], colours: parts },
      { positions: rec, colours: errorColours(err, max) },
      { positions: this.placed, colours: parts },
    ], { frame });
    this.out('pose', String(i + 1));
    this.out('max', max.toExponential(1));
  }

  fittedNote() {
    return `${this.v.model.summary.parts} parts.`;
  }

  resume() {
    if (this.v.model && !this.touched) this.ticker.start();
  }

  pause() {
    this.ticker.stop();
  }

  act(a) {
    if (a === 'reset') {
      this.touched = false;
      this.pose = 0;
      this.poseIn.value = '0';
      this.regenerate();
    }
  }
}

// ------------------------------------------------------------------ 8. interpolation against linear blending

class Interpolation extends Figure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), ARM, { ...SYNTH, parts: 3 });
    this.t = 0;
    this.dir = 1;
    this.tIn = this.$('[data-ctl=t]');
    this.tIn.addEventListener('input', () => {
      this.touched = true;
      this.ticker.stop();
      this.t = Number(this.tIn.value);
      this.draw();
    });
    this.ticker = new Ticker(70, () => {
      this.t += 0.02 * this.dir;
      if (this.t >= 1 || this.t <= 0) {
        this.t = Math.min(1, Math.max(0, this.t));
        this.dir = -this.dir;
      }
      this.tIn.value = String(this.t);
      this.draw();
    });
    this.chart = new Chart(this.$('[data-out=plot]'), { xLabel: 't', yLabel: 'volume change (%)' });
    this.seq = 0;
    this.busy = false;
  }

  async onFitted() {
    const { model } = this.v;
    // The pair of poses whose parts turn the most apart: the clearest bend.
    this.i = 0;
    this.j = 1;
    try {
      let best = -1;
      for (let k = 0; k < model.summary.parts; k++) {
        const angles = await this.v.handle.query('rotationAngles', k, 0);
        angles.forEach((a, j) => {
          if (a > best) {
            best = a;
            this.j = j;
          }
        });
      }
      this.out('from', String(this.i + 1));
      this.out('to', String(this.j + 1));
      const ts = Array.from({ length: 11 }, (_, k) => k / 10);
      const reports = [];
      for (const t of ts) reports.push(await this.v.handle.query('articulationReport', this.i, this.j, t));
      const ours = reports.map((r) => 100 * r.methods[0].volumeChange);
      const linear = reports.map((r) => 100 * r.methods.find((m) => m.name.startsWith('linear')).volumeChange);
      this.volume = { ts, ours, linear };
      this.chart.set([
        { values: ours, xs: ts, colour: EXACT },
        { values: linear, xs: ts, colour: LITERAL },
      ]);
    } catch (e) {
      this.setState('error', e.message);
      return;
    }
    await this.draw(true);
  }

  async draw(frame = false) {
    const { model, pop } = this.v;
    if (!model || this.busy) return;
    this.busy = true;
    const seq = ++this.seq;
    try {
      const [a, b] = await Promise.all([
        this.v.handle.query('interpolate', this.i, this.j, this.t, {}),
        this.v.handle.query('linearInterpolate', this.i, this.j, this.t),
      ]);
      if (seq !== this.seq) return;
      const colours = paletteColours(model.labels, model.colours.final).vertexColours;
      this.v.handle.viewer.show([{ positions: a, colours }, { positions: b, colours }], { frame });
      this.out('t', this.t.toFixed(2));
    } catch (e) {
      this.setState('error', e.message);
    } finally {
      this.busy = false;
    }
  }

  fittedNote() {
    if (!this.volume) return '';
    const m = (xs) => xs.reduce((a, b) => (Math.abs(b) > Math.abs(a) ? b : a), 0).toFixed(1);
    return `Largest volume change: part-wise ${m(this.volume.ours)} %, linear ${m(this.volume.linear)} %.`;
  }

  resume() {
    if (this.v.model && this.volume && !this.touched) this.ticker.start();
  }

  pause() {
    this.ticker.stop();
  }

  act(a) {
    if (a === 'play') {
      this.touched = false;
      this.ticker.start();
    } else if (a === 'reset') {
      this.t = 0;
      this.tIn.value = '0';
      this.volume = null;
      this.regenerate();
    }
  }
}

// ------------------------------------------------------------------ 9. limits

class Limit extends Figure {
  constructor(ctx, spec, params) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), spec, params);
  }

  onFitted() {
    const { model, pop } = this.v;
    // the blob: its most bent pose, plain and in the fit's parts; the tied legs: true parts and fitted ones
    const pose = this.name === 'blob' ? pop.nShapes - 1 : 0;
    const left = this.name === 'blob'
      ? new Float32Array(pop.nVertices * 3).fill(0.75)
      : paletteColours(pop.truth.partOfVertex, pop.truth.colours).vertexColours;
    this.v.handle.viewer.show([
      { positions: pop.positions[pose], colours: left },
      { positions: pop.positions[pose], colours: paletteColours(model.labels, model.colours.final).vertexColours },
    ], { frame: true });
  }

  fittedNote() {
    const s = this.v.model.summary;
    if (this.name === 'blob') return `${s.parts} parts, RMSE ${s.rmse.toExponential(2)} (unit box): the "parts" are slabs, and the error stays large.`;
    // For each piece of the front legs: the fitted part holding most of the left one's and of the right one's
    // vertices; the same part means the fit made the two legs one body.
    const { partNames, partOfVertex } = this.v.pop.truth;
    const labels = this.v.model.labels;
    const major = (name) => {
      const p = partNames.indexOf(name);
      const count = new Map();
      partOfVertex.forEach((t, v) => t === p && count.set(labels[v], (count.get(labels[v]) ?? 0) + 1));
      return [...count].sort((a, b) => b[1] - a[1])[0]?.[0];
    };
    const pieces = ['upper', 'lower', 'foot'].filter((seg) => partNames.includes(`front_left_${seg}`));
    const shared = pieces.filter((seg) => major(`front_left_${seg}`) === major(`front_right_${seg}`));
    return `${partNames.length} true parts, ${s.parts} fitted (adjusted Rand index ${s.groundTruth.ari.toFixed(3)}); of the front legs' ${pieces.length} pieces, ${shared.length} are one part shared by the left and the right leg.`;
  }
}

export const FIGURES = {
  poses: (ctx) => new Poses(ctx),
  model: (ctx) => new Model(ctx),
  responsibilities: (ctx) => new Responsibilities(ctx),
  aecm: (ctx) => new Aecm(ctx),
  eq18: (ctx) => new Eq18(ctx),
  ends: (ctx) => new Ends(ctx),
  hierarchy: (ctx) => new Hierarchy(ctx),
  reconstruction: (ctx) => new Reconstruction(ctx),
  interpolation: (ctx) => new Interpolation(ctx),
  // the app's "two limbs that never move apart" example (its tied front legs), on a smaller mesh
  tied: (ctx) => new Limit(ctx, ({ examples }) => ({ ...examples.find((e) => e.id === 'too-few-poses').spec, vertices: QUAD.vertices }), { ...SYNTH }),
  blob: (ctx) => new Limit(ctx, BLOB, { ...SYNTH, parts: 4 }),
};

