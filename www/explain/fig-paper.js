// The article's figures of section 5, where the printed paper goes wrong: the literal eq 18 beside the exact Λ
// step on the same start (both log-likelihood traces, drops marked), and Algorithm 2 as printed beside the
// corrected one, with the end poses each misses.
import { Figure, Ticker, QUAD, SNAKE, SYNTH, LITERAL, EXACT, drops, fmtE } from './figure.js';
import { Stepping } from './stepping.js';
import { Chart } from './chart.js';
import { paletteColours, errorColours } from '../colors.js';

const SIDES = ['literal', 'exact'];

// ------------------------------------------------------------------ 5. eq 18 against the exact step

export class Eq18 extends Stepping {
  constructor(ctx) {
    super(ctx);
    const base = { ...SYNTH, parts: 6, refine: false, maxIter: 60 };
    const params = { literal: { ...base, lambdaRule: 'paper-eq18' }, exact: { ...base, lambdaRule: 'exact' } };
    this.setup(SIDES.map((side) => [this.view(this.$(`[data-view=${side}]`), QUAD, params[side]), params[side]]), 150);
    this.chart = new Chart(this.$('[data-out=plot]'));
  }

  trace(side) {
    const s = this.steppers[SIDES.indexOf(side)];
    return s.started ? s.values.slice() : Array.from(s.v.model?.summary.logLikelihood ?? []);
  }

  draw() {
    const series = SIDES.map((side) => {
      const values = this.trace(side);
      return { values, colour: side === 'literal' ? LITERAL : EXACT, markers: drops(values) };
    });
    this.chart.set(series);
    for (const side of SIDES) {
      const t = this.trace(side);
      const d = drops(t);
      const worst = d.length ? Math.max(...d.map((i) => t[i - 1] - t[i])) : 0;
      this.out(side, t.length ? `${t.length} iterations, ${d.length} drop${d.length === 1 ? '' : 's'}${d.length ? ` (largest ${worst.toFixed(1)} nats)` : ''}` : '–');
    }
  }

  onFitted() {
    this.draw();
  }

  showStep(m, s) {
    const { v } = s;
    if (m.labels && m.colours?.length && v.pop) v.handle.viewer.show([{ positions: v.pop.positions[0], colours: paletteColours(m.labels, m.colours).vertexColours }]);
    this.draw();
    this.refreshState();
  }

  fittedNote() {
    return this.steppers.some((s) => s.started) ? 'Same start, two Λ rules.' : 'Both fitted; the live run starts in view.';
  }

  logLikelihood() {
    return this.trace('exact');
  }

  contract() {
    return { name: this.name, state: this.state, literal: this.trace('literal'), exact: this.trace('exact') };
  }

  detail() {
    const [literal, exact] = this.steppers;
    return { visible: this.visible, readyAt: this.readyAt, literal: literal.values.length, exact: exact.values.length, running: this.steppers.some((s) => s.running) };
  }
}

// ------------------------------------------------------------------ 5b. Algorithm 2's missed end poses

const PRINTED = { root: 'paper', tree: 'breadth-first', exactEnds: false, residual: false };

export class Ends extends Figure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), SNAKE, { ...SYNTH, parts: 6 });
    this.t = 1;
    this.tIn = this.control('t', (t) => {
      this.t = t;
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
}
