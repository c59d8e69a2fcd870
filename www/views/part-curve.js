// The part-count curve (issue 15): the core's part rule (model::distinct) merges the cheapest pair of adjacent
// parts while its score is below the distinct ratio; each decision is one point {parts, score, variance, merged}.
// Drawn as score (log scale) against the part count: filled dots were merged, the hollow one is the pair that was
// not, which is why the fit stopped where it did. JS only draws what the core decided.
import { clearedCanvas } from '../plot.js';

export function drawPartCurve(canvas, curve) {
  const surface = clearedCanvas(canvas);
  if (!surface || curve.length === 0) return;
  const { g, w, h, style } = surface;
  // every label is drawn whole: the title goes on two lines when one is too narrow; canvas.dataset.clipped
  // counts labels that still do not fit (the page tests read it)
  let clipped = 0;
  const label = (t, x, y) => {
    if (x < 0 || x + g.measureText(t).width > w + 0.5 || y > h) clipped++;
    g.fillText(t, x, y);
  };
  const stop = curve[curve.length - 1];
  const kept = stop.parts;
  const next = Number.isFinite(stop.score) ? `the next pair scored ${stop.score.toFixed(1)}` : 'no pair left';
  const title = `part rule: ${curve.length - 1} merges, ${curve[0].parts} → ${kept} parts`;
  let top = 20;
  if (g.measureText(`${title} (${next})`).width + 4 <= w) label(`${title} (${next})`, 4, 12);
  else {
    label(title, 4, 12);
    label(`(${next})`, 4, 25);
    top = 33;
  }
  canvas.dataset.clipped = String(clipped);
  const pts = curve.filter((p) => Number.isFinite(p.score) && p.score > 0);
  if (pts.length === 0) return;
  const ys = pts.map((p) => Math.log10(p.score));
  const lo = Math.min(...ys, -1);
  const hi = Math.max(...ys, 1);
  const xs = curve.map((p) => p.parts);
  const x0 = Math.min(...xs) - 0.5;
  const x1 = Math.max(...xs) + 0.5;
  const left = 32, right = w - 6, bottom = h - 14;
  const x = (n) => left + ((right - left) * (n - x0)) / (x1 - x0);
  const y = (v) => bottom - ((bottom - top) * (v - lo)) / (hi - lo || 1);
  g.strokeStyle = style.color;
  g.globalAlpha = 0.3;
  g.beginPath();
  g.moveTo(left, bottom);
  g.lineTo(right, bottom);
  g.stroke();
  g.globalAlpha = 1;
  label(`10^${hi.toFixed(0)}`, 0, top + 4);
  label(`10^${lo.toFixed(0)}`, 0, bottom);
  label('parts →', w - g.measureText('parts →').width - 2, h - 2);
  canvas.dataset.clipped = String(clipped);
  for (const p of pts) {
    g.beginPath();
    g.arc(x(p.parts), y(Math.log10(p.score)), 3, 0, 2 * Math.PI);
    if (p.merged) g.fill();
    else {
      g.strokeStyle = '#c0392b';
      g.stroke();
    }
  }
}
