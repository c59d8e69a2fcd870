// AECM step by step in the article's figures: a Stepper drives one view's teaching fit (one 'teach-step' at a
// time, paced by the page), and Stepping is a figure whose live part is one or more steppers (the eq 18 figure
// runs two side by side on the same start): they start when the figure is first in view, pause out of view
// and resume in view; Step / Run / Pause / Reset act on all of them.
import { Figure, newId } from './figure.js';

/**
 * AECM step by step on one view, paced by the page: one 'teach-step' at a time, the next `pace` ms after the
 * previous answer, while `running` and the figure is in view. The figure hands it its view's 'teach' and 'fitted'
 * messages (onTeach, onFitted).
 */
export class Stepper {
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
    this.id = newId();
    this.values = [];
    this.iteration = 0;
    this.done = false;
    this.waiting = false;
    this.started = true;
    clearTimeout(this.timer);
    this.label();
    this.v.handle.post({ type: 'teach-reset', id: this.id, params: this.params });
  }

  // The view's label follows the run: its iteration while stepping, its parts once done (never a finished
  // run's words over a new one).
  label(parts = null) {
    this.v.handle.caption.textContent = parts === null
      ? `Iteration ${this.iteration}, one step at a time`
      : `${parts} parts after ${this.iteration} iterations, one step at a time`;
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

  /** A 'fitted' message; true if it was this stepper's fit, now done (its view's caption says so). */
  onFitted(m) {
    if (m.type !== 'fitted' || m.id !== this.id) return false;
    this.label(m.model.summary.parts);
    this.running = false;
    this.done = true;
    return true;
  }

  /** A 'teach' message; true if it was this stepper's step. */
  onTeach(m) {
    if (m.id !== this.id) return false;
    if (m.kind !== 'step') return false;
    this.waiting = false;
    this.values.push(m.step.logLikelihood);
    this.iteration = m.step.totalIterations;
    if (m.stage?.kind !== 'done') this.label();
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

export class Stepping extends Figure {
  /** One stepper per [view, params]; pace: ms between steps while running. */
  setup(runs, pace) {
    this.steppers = runs.map(([v, params]) => new Stepper(this, v, params, pace));
    this.stepper = this.steppers[0];
    this.v = this.stepper.v;
    this.autoStarted = false;
  }

  ready() {
    return this.views.every((v) => v.model);
  }

  live() {
    return this.visible && this.steppers.some((s) => s.running);
  }

  message(v, m) {
    super.message(v, m);
    if (this.steppers.some((s) => s.onFitted(m))) {
      this.refreshState();
      this.buttons();
    }
  }

  onTeach(v, m) {
    const s = this.steppers.find((x) => x.v === v);
    if (s.onTeach(m)) {
      this.showStep(m, s);
      this.refreshState();
      this.buttons();
    } else if (m.kind === 'reset' && m.id === s.id) {
      this.showStep(m, s);
    }
  }

  resume() {
    if (!this.ready()) return;
    if (!this.autoStarted) {
      this.autoStarted = true;
      for (const s of this.steppers) {
        s.reset();
        s.run();
      }
    } else if (this.resumeOnShow) {
      this.resumeOnShow = false;
      for (const s of this.steppers) if (!s.done) s.run();
    }
    this.refreshState();
    this.buttons();
  }

  pause() {
    if (this.steppers.some((s) => s.running)) this.resumeOnShow = true;
    for (const s of this.steppers) s.pause();
    this.refreshState();
    this.buttons();
  }

  // Step and Run go on from where the runs are; once every run is done, they start over.
  act(a) {
    if (!this.ready() && a !== 'reset') return;
    const all = this.steppers;
    const over = all.every((s) => s.done);
    if (a === 'step') {
      for (const s of all) {
        s.pause();
        if (over) s.reset();
        if (!s.done) s.stepOnce();
      }
    } else if (a === 'run') {
      for (const s of all) if (over || !s.done) s.run();
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
    this.buttons();
  }

  buttons() {
    const b = (a) => this.$(`[data-act=${a}]`);
    const running = this.steppers.some((s) => s.running);
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

  /** What a step (or a reset) of stepper `s` shows. */
  showStep() {}
}
