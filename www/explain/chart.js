// A small line chart for the article's figures: several series on one 2D canvas with shared axes, optional
// markers (e.g. the iterations where a log-likelihood fell). Draws only what it is given.

import { clearedCanvas } from '../plot.js';

const fmt = (v) => (Math.abs(v) >= 1e5 || (Math.abs(v) < 1e-2 && v !== 0) ? v.toExponential(2) : v.toFixed(2));

export class Chart {
  /** opts: { xLabel, yLabel, x: (i) => x value of point i (default i + 1) } */
  constructor(canvas, opts = {}) {
    this.canvas = canvas;
    this.opts = opts;
    this.series = [];
    new ResizeObserver(() => this.draw()).observe(canvas);
  }

  /** series: [{ values, colour, label, markers: [indices], xs: [x per point] }] */
  set(series) {
    this.series = series;
    this.draw();
  }

  draw() {
    const surface = clearedCanvas(this.canvas);
    if (!surface) return;
    const { g, w, h, style } = surface;
    const pts = this.series.flatMap((s) => s.values.map((v, i) => [s.xs ? s.xs[i] : i + 1, v])).filter(([x, y]) => Number.isFinite(x) && Number.isFinite(y));
    const { xLabel = 'iteration', yLabel = 'log-likelihood' } = this.opts;
    g.fillText(yLabel, 4, 11);
    if (!pts.length) {
      g.fillText('no points yet', 4, h / 2);
      return;
    }
    let [x0, x1] = [Math.min(...pts.map((p) => p[0])), Math.max(...pts.map((p) => p[0]))];
    let [y0, y1] = [Math.min(...pts.map((p) => p[1])), Math.max(...pts.map((p) => p[1]))];
    if (x1 === x0) x1 = x0 + 1;
    if (y1 === y0) {
      y1 += Math.abs(y1) * 1e-3 || 1;
      y0 -= Math.abs(y0) * 1e-3 || 1;
    }
    const left = 6;
    const right = w - 6;
    const top = 18;
    const bottom = h - 16;
    const X = (x) => left + ((right - left) * (x - x0)) / (x1 - x0);
    const Y = (y) => bottom - ((bottom - top) * (y - y0)) / (y1 - y0);
    g.strokeStyle = '#9aa1ad';
    g.lineWidth = 1;
    g.beginPath();
    g.moveTo(left, bottom + 0.5);
    g.lineTo(right, bottom + 0.5);
    g.stroke();
    if (y0 < 0 && y1 > 0) {
      g.setLineDash([3, 3]);
      g.beginPath();
      g.moveTo(left, Y(0));
      g.lineTo(right, Y(0));
      g.stroke();
      g.setLineDash([]);
    }
    for (const s of this.series) {
      g.strokeStyle = s.colour;
      g.lineWidth = 1.8;
      g.beginPath();
      s.values.forEach((v, i) => {
        const x = X(s.xs ? s.xs[i] : i + 1);
        if (i) g.lineTo(x, Y(v));
        else g.moveTo(x, Y(v));
      });
      g.stroke();
      g.fillStyle = s.markerColour ?? '#d62828';
      for (const i of s.markers ?? []) {
        g.beginPath();
        g.arc(X(s.xs ? s.xs[i] : i + 1), Y(s.values[i]), 3.2, 0, 2 * Math.PI);
        g.fill();
      }
    }
    g.fillStyle = style.color;
    const hi = `max ${fmt(y1)}`;
    g.fillText(hi, right - g.measureText(hi).width, 11);
    g.fillText(`min ${fmt(y0)}`, left, h - 3);
    const xl = `${xLabel} ${fmt(x0).replace(/\.00$/, '')}–${fmt(x1).replace(/\.00$/, '')}`;
    g.fillText(xl, right - g.measureText(xl).width, h - 3);
  }
}
