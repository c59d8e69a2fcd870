// The article's figure scaffolding, shared by every figure module (www/explain/fig-*.js): a figure's mount()
// views on the shared worker pool (www/explain/pool.js), its state (data-state: loading | fitting | fitted |
// stepping | error) and status line, visibility (live parts run only in view: article.js calls setVisible),
// Reset, its entry in the test contract, and the small pieces several figures use: animations (Ticker), inputs
// (control), a pose at a time (PoseFigure), the figures' populations. A figure shows and asks; every number it
// shows comes from the core (fits, queries, single AECM steps).
import { mount } from '../mount.js';

export const GREY = [0.8, 0.81, 0.84];
export const LITERAL = '#d1495b';
export const EXACT = '#2f6fb3';

// The figures' populations: small, so that each fits in a few hundred ms in the browser.
export const QUAD = { preset: 'quadruped', vertices: 1100, poses: 6, seed: 0, jointBand: 0.01, maxAngleDeg: 60 };
export const SNAKE = { preset: 'snake', vertices: 800, poses: 8, seed: 0, jointBand: 0.01, maxAngleDeg: 45 };
export const ARM = { preset: 'arm', vertices: 600, poses: 6, seed: 0, jointBand: 0.01 };
export const BLOB = { preset: 'blob', vertices: 800, poses: 6, seed: 0 };
export const SYNTH = {}; // the default parameters, as the app's examples (src/synth/presets.rs)

// Request ids of the figures' own messages (mount() numbers its own from 1000).
let nextId = 100000;
export const newId = () => nextId++;

export const fmtE = (x) => (x === 0 ? '0' : x < 1e-3 ? x.toExponential(1) : x.toFixed(3));

// Iterations where the log-likelihood fell: the app's result panel reads traces the same way.
export { drops } from '../trace.js';

export class Figure {
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

  /**
   * The figure's input `[data-ctl=name]`: moving it stops the figure's animation, marks the figure touched (its
   * animation then stays off until Reset) and calls set(value as a number).
   */
  control(name, set) {
    const input = this.$(`[data-ctl=${name}]`);
    input.addEventListener('input', () => {
      this.touched = true;
      this.ticker?.stop();
      set(Number(input.value));
    });
    return input;
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
      this.setState('error', m.message ?? m.problems?.map((p) => p.message).join('; '));
    }
  }

  /** Regenerates the population and fits it again (Reset). */
  regenerate() {
    this.pause();
    for (const v of this.views) {
      if (!v.handle) continue;
      v.model = null;
      v.handle.post({ type: 'generate', id: newId(), spec: v.spec, fit: { id: newId(), params: v.params } });
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

  // Defaults: no live part but the figure's animation (this.ticker), if it has one.
  resume() {}
  pause() {
    this.ticker?.stop();
  }
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
export class Ticker {
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

/**
 * A figure with one view that shows a pose at a time: the slider `[data-ctl=pose]`, and while in view an
 * animation through the poses (every `ms`) until the reader moves the slider. Subclasses draw(); call
 * posesEvery(ms) in the constructor after making the view `this.v`.
 */
export class PoseFigure extends Figure {
  posesEvery(ms) {
    this.pose = 0;
    this.touched = false;
    this.poseIn = this.control('pose', (p) => {
      this.pose = p;
      this.draw();
    });
    this.ticker = new Ticker(ms, () => {
      this.pose = (this.pose + 1) % this.v.pop.nShapes;
      this.poseIn.value = String(this.pose);
      this.draw();
    });
  }

  resume() {
    if (this.v.model && !this.touched) this.ticker.start();
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
