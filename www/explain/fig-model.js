// The article's figures of sections 1 and 2: registered poses (vertices in correspondence), and the model of
// eq 2-4 (one part's motion: pick a part and a pose).
import { Figure, PoseFigure, Ticker, GREY, QUAD, SNAKE, SYNTH } from './figure.js';
import { hexToRgb, paletteColours, errorColours } from '../colors.js';

const FULL_SCALE = 180; // degrees: the rotation-angle bars' full width

/** Per-vertex colours: the chosen part in its colour, the rest grey. */
function highlight(labels, part, colour) {
  const out = new Float32Array(labels.length * 3);
  labels.forEach((l, v) => out.set(l === part ? colour : GREY, 3 * v));
  return out;
}

// ------------------------------------------------------------------ 1. the problem: registered poses

export class Poses extends Figure {
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
    return `${this.statusNote ?? ''} A first, coarse fit of this population: ${s.parts} parts in ${Math.round(s.fitMs)} ms.`;
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
    this.refreshState(); // the status names the poses shown
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

  act(a) {
    if (a === 'next') this.shift(4);
    else if (a === 'reset') {
      this.first = 0;
      this.regenerate();
    }
  }
}

// ------------------------------------------------------------------ 2. the model: one part's motion

export class Model extends PoseFigure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), SNAKE, { ...SYNTH, parts: 6 });
    this.part = 0;
    this.partSel = this.$('[data-ctl=part]');
    this.partSel.addEventListener('change', () => {
      this.partPicked = true;
      this.choosePart(Number(this.partSel.value));
    });
    this.posesEvery(1200);
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
    this.refreshState(); // the status names the part shown
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

  // One fixed scale for every part: the full width is 180°, the largest angle a rotation can have, so a part
  // that barely turns gets short bars (not bars scaled to its own largest angle).
  drawBars() {
    const box = this.$('[data-out=angles]');
    if (!this.angles) return;
    const scale = document.createElement('div');
    scale.className = 'bars-title';
    scale.textContent = `Rotation of part ${this.part + 1} relative to pose 1; bar width: angle, full width = ${FULL_SCALE}°`;
    box.replaceChildren(scale, ...Array.from(this.angles, (a, i) => {
      const bar = document.createElement('div');
      bar.className = `bar${i === this.pose ? ' current' : ''}`;
      bar.innerHTML = `<span class="lbl">pose ${i + 1}</span><span class="fill" style="width:${(100 * Math.min(a, FULL_SCALE)) / FULL_SCALE}%;background:${this.partColour[this.part]}"></span><span class="val">${a.toFixed(1)}°</span>`;
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
}
