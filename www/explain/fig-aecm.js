// The article's figures of sections 3 and 4: responsibilities (eq 6-12) of a clicked vertex while AECM runs, and
// AECM itself (eq 13-19, 31) with Step / Run / Pause / Reset, the log-likelihood plot and the cycle in progress.
import { Stepping } from './stepping.js';
import { Chart } from './chart.js';
import { QUAD, SYNTH, EXACT, drops } from './figure.js';
import { PALETTE, paletteColours, gammaColours } from '../colors.js';

// ------------------------------------------------------------------ 3. responsibilities

export class Responsibilities extends Stepping {
  constructor(ctx) {
    super(ctx);
    const params = { ...SYNTH, parts: 8, refine: false };
    this.setup([[this.view(this.$('.fig-view'), QUAD, params), params]], 260);
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

export class Aecm extends Stepping {
  constructor(ctx) {
    super(ctx);
    // The quadruped's thin leg pieces with 10 parts to start: several rotation steps need eq 31.
    const params = { ...SYNTH, parts: 10, refine: false };
    this.setup([[this.view(this.$('.fig-view'), QUAD, params), params]], 420);
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
