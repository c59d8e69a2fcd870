// The article's figures of sections 8 and 9: part-wise interpolation (Algorithm 2, Figs 5-6) against linear
// blending with the volume along t; and the method's limits (two limbs that never move apart, a smoothly bent
// blob).
import { Figure, Ticker, ARM, SYNTH, EXACT, LITERAL } from './figure.js';
import { Chart } from './chart.js';
import { paletteColours } from '../colors.js';
import { tiedText } from '../ground-truth.js';
import { thresholdText } from './article-threshold.js';

// ------------------------------------------------------------------ 8. interpolation against linear blending

export class Interpolation extends Figure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), ARM, { ...SYNTH, parts: 3 });
    this.t = 0;
    this.dir = 1;
    this.tIn = this.control('t', (t) => {
      this.t = t;
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
      this.refreshState(); // the status gives the largest volume changes, known only now
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

export class Limit extends Figure {
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
    if (this.name === 'blob') {
      const d = s.diagnosis;
      return `${s.parts} part${s.parts === 1 ? '' : 's'}, RMSE ${s.rmse.toExponential(2)} (unit box): ${d.undecided ? 'too few parts for a verdict' : d.articulated ? 'articulated' : 'not articulated'}, rigid parts explain ${(100 * Math.max(d.explained, 0)).toFixed(1)} % of the motion (articulated shapes: ${thresholdText(this.pool.info?.minExplained)} and more, the verdict's threshold).`;
    }
    const { partNames } = this.v.pop.truth;
    // the tied legs as the core measured them (posemfa::metrics::TiedParts), in the app's words
    const tied = tiedText(s.groundTruth);
    return `${partNames.length} true part${partNames.length === 1 ? '' : 's'}, ${s.parts} fitted (adjusted Rand index ${s.groundTruth.ari.toFixed(3)}).${tied ? ` ${tied}` : ''}`;
  }
}
