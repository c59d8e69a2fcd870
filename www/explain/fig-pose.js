// The article's figure of what the fit is for: the poses the population spans. The fitted rig's
// training poses, as every joint's rotation relative to the bind pose (log map), give principal modes; two
// sliders move along the first two (0 = the mean pose), "Random pose" draws within the training range. Every pose
// comes from the core (src/export/pose_glb.rs, the worker's pose queries).
import { Figure, QUAD, SYNTH } from './figure.js';
import { paletteColours } from '../colors.js';

export class PoseSpace extends Figure {
  constructor(ctx) {
    super(ctx);
    this.v = this.view(this.$('.fig-view'), QUAD, { ...SYNTH });
    this.c = [0, 0];
    this.inputs = [0, 1].map((m) => this.control(`m${m + 1}`, (x) => {
      this.c[m] = x;
      this.draw();
    }));
    this.busy = false;
    this.again = false;
  }

  async onFitted() {
    try {
      const r = await this.v.handle.query('poseStart', {});
      this.sk = r.skeleton;
      this.inputs.forEach((input, m) => {
        const [lo, hi] = this.sk.range[m] ?? [0, 0];
        input.disabled = m >= this.sk.nModes;
        input.min = String(Math.min(lo, 0));
        input.max = String(Math.max(hi, 0));
        input.step = String((hi - lo) / 100 || 0.01);
        input.value = '0';
      });
      this.c = [0, 0];
      this.refreshState();
    } catch (e) {
      this.setState('error', e.message);
      return;
    }
    await this.draw(true);
  }

  async draw(frame = false) {
    if (!this.sk) return;
    if (this.busy) {
      this.again = true;
      return;
    }
    this.busy = true;
    try {
      const r = await this.v.handle.query('poseModes', this.c.slice(0, this.sk.nModes));
      const colours = paletteColours(this.v.model.labels, this.v.model.colours.final).vertexColours;
      this.v.handle.viewer.show([{ positions: r.positions, colours }], { frame });
      this.out('c1', this.c[0].toFixed(2));
      this.out('c2', this.c[1].toFixed(2));
    } catch (e) {
      this.setState('error', e.message);
    } finally {
      this.busy = false;
      if (this.again) {
        this.again = false;
        this.draw();
      }
    }
  }

  fittedNote() {
    if (!this.sk) return '';
    const total = this.sk.sd.reduce((a, s) => a + s * s, 0);
    const two = this.sk.sd.slice(0, 2).reduce((a, s) => a + s * s, 0);
    return `${this.sk.order.length} bones; ${this.sk.nModes} modes from ${this.sk.coords.length} poses; the first two carry ${(100 * two / total).toFixed(0)} % of the variance.`;
  }

  async act(a) {
    if (a === 'random' && this.sk) {
      const c = Array.from(await this.v.handle.query('poseRandom', Math.floor(Math.random() * 2 ** 31)));
      this.c = [c[0] ?? 0, c[1] ?? 0];
      this.inputs.forEach((input, m) => { input.value = String(this.c[m]); });
      this.draw();
    } else if (a === 'mean') {
      this.c = [0, 0];
      this.inputs.forEach((input) => { input.value = '0'; });
      this.draw();
    } else if (a === 'reset') {
      this.sk = null;
      this.regenerate();
    }
  }
}
