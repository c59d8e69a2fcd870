// The part-count curve: the core's part rule (model::distinct) merges the cheapest pair of adjacent
// parts while its score is below the distinct ratio; each decision is one point {parts, score, variance, merged}.
// Drawn as score (log scale, whole decades) against the part count: filled dots were merged, the hollow one is
// the pair that was not, which is why the fit stopped where it did; the dashed line is the distinct ratio the
// scores were compared with. JS only draws what the core decided. The canvas's dataset says what it wrote (points,
// axisLo, axisHi, ratio, note, clipped: the page tests read them).
import { clearedCanvas } from '../plot.js';

const SUPERSCRIPT = { '-': '⁻', 0: '⁰', 1: '¹', 2: '²', 3: '³', 4: '⁴', 5: '⁵', 6: '⁶', 7: '⁷', 8: '⁸', 9: '⁹' };

/** A power of ten as one reads it: 10^k written out from 0.001 to 10000, beyond that 10 with a superscript. */
export function decade(k) {
  if (k >= 0 && k <= 4) return String(10 ** k);
  if (k < 0 && k >= -3) return (10 ** k).toFixed(-k);
  return `10${String(k).split('').map((c) => SUPERSCRIPT[c]).join('')}`;
}

/** ratio: the distinct ratio the fit compared the scores with (the line; none when unknown). applied: false when
 * the fit's parts were given to it (a Refine): the rule judged them, but changed nothing. */
export function drawPartCurve(canvas, curve, { ratio = null, applied = true } = {}) {
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
  // the last decision is the pair not merged, unless the merges went down to one part
  const merges = curve.filter((p) => p.merged).length;
  const kept = stop.merged ? stop.parts - 1 : stop.parts;
  const next = stop.merged ? 'no pair left' : Number.isFinite(stop.score) ? `the next pair scored ${stop.score.toFixed(1)}` : 'no pair left';
  // the core keeps the decisions of the part rule's last round only (a fit can run it again after a refit): the
  // title says so, so that its count is not read as the whole rule's (the Stages view's start to "after")
  const title = applied
    ? `part rule, last round: ${merges} merge${merges === 1 ? '' : 's'}, ${curve[0].parts} → ${kept} part${kept === 1 ? '' : 's'}`
    : `part rule on the refined parts, not applied: ${merges} merge${merges === 1 ? '' : 's'} would make ${curve[0].parts} → ${kept}`;
  canvas.dataset.title = title;
  // the title and what the next pair scored, on as many lines as the width takes (words kept whole)
  const lines = [];
  for (const word of `${title} (${next})`.split(' ')) {
    const last = lines.length ? `${lines[lines.length - 1]} ${word}` : word;
    if (lines.length && g.measureText(last).width + 4 <= w) lines[lines.length - 1] = last;
    else lines.push(word);
  }
  lines.forEach((t, i) => label(t, 4, 12 + 13 * i));
  let top = 20 + 13 * (lines.length - 1);
  canvas.dataset.clipped = String(clipped);
  const pts = curve.filter((p) => Number.isFinite(p.score) && p.score > 0);
  Object.assign(canvas.dataset, { points: String(pts.length), axisLo: '', axisHi: '', ratio: '', note: '' });
  if (pts.length === 0) return;
  const line = Number.isFinite(ratio) && ratio > 0 ? Math.log10(ratio) : null;
  const ys = pts.map((p) => Math.log10(p.score)).concat(line ?? []);
  // the axis spans whole decades, so that its two labels are the powers of ten at its ends
  const lo = Math.floor(Math.min(...ys));
  const hi = Math.max(Math.ceil(Math.max(...ys)), lo + 1);
  const xs = curve.map((p) => p.parts);
  const x0 = Math.min(...xs) - 0.5;
  const x1 = Math.max(...xs) + 0.5;
  const loText = decade(lo);
  const hiText = decade(hi);
  // the y axis's title: what the score is and its unit (a ratio: the rise in squared error a shared motion
  // costs, in multiples of a typical part's own)
  const yTitle = 'pair score (× part error)';
  const titleRoom = 0;
  // (the y axis's title over it, left, the x axis's under it, right)
  label(`↑ ${yTitle}`, 2, top + 2);
  top += 12;
  const left = titleRoom + Math.max(g.measureText(loText).width, g.measureText(hiText).width) + 6;
  const right = w - 6;
  // (under the axis: the x axis's title, and under it a one-decision chart's note)
  const bottom = pts.length === 1 ? h - 27 : h - 14;
  const x = (n) => left + ((right - left) * (n - x0)) / (x1 - x0);
  const y = (v) => bottom - ((bottom - top) * (v - lo)) / (hi - lo);
  g.strokeStyle = style.color;
  g.globalAlpha = 0.3;
  g.beginPath();
  g.moveTo(left, bottom);
  g.lineTo(right, bottom);
  g.stroke();
  g.globalAlpha = 1;
  label(hiText, titleRoom + 2, top + 4);
  label(loText, titleRoom + 2, bottom);
  const xTitle = 'parts before each merge →';
  Object.assign(canvas.dataset, { axisLo: loText, axisHi: hiText, ratio: line === null ? '' : String(ratio), yTitle, xTitle });
  label(xTitle, w - g.measureText(xTitle).width - 2, bottom + 12);
  if (line !== null) {
    // the distinct ratio: a pair scoring below it is merged
    g.save();
    g.setLineDash([4, 3]);
    g.globalAlpha = 0.6;
    g.beginPath();
    g.moveTo(left, y(line));
    g.lineTo(right, y(line));
    g.stroke();
    g.restore();
    const t = `merged below ${ratio}`;
    label(t, right - g.measureText(t).width, y(line) - 3);
  }
  for (const p of pts) {
    g.beginPath();
    g.arc(x(p.parts), y(Math.log10(p.score)), 3, 0, 2 * Math.PI);
    if (p.merged) g.fill();
    else {
      g.strokeStyle = '#c0392b';
      g.stroke();
    }
  }
  if (pts.length === 1) {
    // one decision only: the caption under the axis says what the lone dot is
    const p = pts[0];
    canvas.dataset.note = `one decision${line !== null ? `, ${p.merged ? 'below' : 'above'} the line` : ''}: ${p.merged ? 'merged' : 'not merged'}`;
    label(canvas.dataset.note, left, h - 2);
  }
  canvas.dataset.clipped = String(clipped);
}
