// The article's figures of sections 6 and 7: the hierarchy of Algorithm 1 (Fig 2) replayed one AECM iteration
// at a time, then its coarse / refined / final parts; reconstruction with error colours and the latent shape
// (eq 20-22, Figs 3-4).
import { PoseFigure, Ticker, GREY, QUAD, SYNTH } from './figure.js';
import { Stepping } from './stepping.js';
import { PALETTE, PALETTE_RGB, paletteColours, errorColours } from '../colors.js';

// ------------------------------------------------------------------ 6. the hierarchy (Algorithm 1, Fig 2)

const STAGE_TEXT = {
  coarse: () => 'coarse AECM on all vertices',
  refine: (st) => `refining coarse part ${st.part + 1} of ${st.of} with m_k = ${st.subParts} (the rest grey)`,
  final: () => 'final AECM on all vertices, from the refined labels',
  done: () => 'done',
};

export class Hierarchy extends Stepping {
  constructor(ctx) {
    super(ctx);
    const params = { ...SYNTH, parts: 5 };
    this.setup([[this.view(this.$('.fig-view'), QUAD, params), params]], 70);
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

export class Reconstruction extends PoseFigure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), QUAD, { ...SYNTH, parts: 8 });
    this.posesEvery(2200);
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
}
