// The live log-likelihood plot: the trace of the AECM run in progress (one point per iteration), drawn on a
// 2D canvas with its range written on the axis.

const fmt = (v, more = 0) => (Math.abs(v) >= 1e5 || (Math.abs(v) < 1e-2 && v !== 0) ? v.toExponential(3 + more) : v.toFixed(2 + more));

/** The axis's min and max as text, with as many more digits as it takes for two different values to read
 * differently (a converging run rises by far less than its size: 5.582e+5 to 5.582e+5). */
export function rangeText(lo, hi) {
  for (let more = 0; more < 12; more++) {
    const [a, b] = [fmt(lo, more), fmt(hi, more)];
    if (a !== b || lo === hi) return [a, b];
  }
  return [fmt(lo, 12), fmt(hi, 12)];
}

/** The canvas sized to its box at the device's pixel ratio, cleared, with the page's font and colour set:
 *  { g, w, h, style } (w, h in CSS pixels), or null while it has no size. Shared by every 2D plot of the page and article. */
export function clearedCanvas(c) {
  const dpr = window.devicePixelRatio || 1;
  const w = c.clientWidth;
  const h = c.clientHeight;
  if (!w || !h) return null;
  c.width = Math.round(w * dpr);
  c.height = Math.round(h * dpr);
  const g = c.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, w, h);
  const style = getComputedStyle(c);
  g.font = `11px ${style.fontFamily}`;
  g.fillStyle = style.color;
  return { g, w, h, style };
}

export class Plot {
  constructor(canvas) {
    this.canvas = canvas;
    this.values = [];
    this.title = '';
    new ResizeObserver(() => this.draw()).observe(canvas);
  }

  /** `runs` (optional): indices where AECM runs start; each run is then drawn to its own scale (the
   *  teaching mode's steps span runs on different vertex sets, whose log-likelihoods do not compare). */
  set(values, title, runs = null) {
    this.values = Array.from(values).filter(Number.isFinite);
    this.title = title;
    this.runs = runs && runs.length > 1 ? runs : null;
    this.draw();
  }

  draw() {
    const surface = clearedCanvas(this.canvas);
    if (!surface) return;
    const { g, w, h, style } = surface;
    const v = this.values;
    const left = 4;
    const right = w - 4;
    // the title on as many lines as it needs (words are never cut); the max label beside its last line when it
    // fits there, else on a line of its own: the two never overlap
    const titleLines = wrap(g, this.title.split(' '), ' ', right - left);
    titleLines.forEach((t, i) => g.fillText(t, left, 12 * (i + 1)));
    Object.assign(this.canvas.dataset, { title: this.title, min: '', max: '', runs: '0' });
    if (v.length === 0) {
      g.fillText('log-likelihood: no iteration yet', left, h / 2);
      return;
    }
    const shown = this.runs ? v.slice(this.runs[this.runs.length - 1]) : v; // labels: the current run's range
    const lo = Math.min(...shown);
    const hi = Math.max(...shown);
    const span = hi - lo || Math.abs(hi) || 1;
    const [loText, hiText] = rangeText(lo, hi);
    const maxText = `max ${hiText}`;
    // what was written, for the page tests
    Object.assign(this.canvas.dataset, { min: loText, max: hiText, runs: String(this.runs?.length ?? 1) });
    const last = titleLines[titleLines.length - 1] ?? '';
    const beside = g.measureText(last).width + 8 + g.measureText(maxText).width <= right - left;
    const maxLine = beside ? Math.max(titleLines.length, 1) : titleLines.length + 1;
    // the footer's parts (min, iterations, runs) on as many lines as they need, from the bottom up
    const footer = wrap(g, [`min ${loText}`, `${v.length} iteration${v.length === 1 ? '' : 's'}`, ...(this.runs ? [`${this.runs.length} runs, each to its own scale`] : [])], ' · ', right - left);
    const top = 12 * maxLine + 6;
    const bottom = h - 2 - 12 * footer.length;
    const x = (i) => left + ((right - left) * i) / Math.max(v.length - 1, 1);
    const y = (val) => bottom - ((bottom - top) * (val - lo)) / span;
    g.strokeStyle = style.borderColor || '#999';
    g.beginPath();
    g.moveTo(left, bottom + 0.5);
    g.lineTo(right, bottom + 0.5);
    g.stroke();
    g.strokeStyle = style.getPropertyValue('--accent') || '#4363d8';
    g.lineWidth = 1.5;
    g.beginPath();
    if (this.runs) {
      // one polyline per run, each scaled to its own range, a tick where a run starts
      this.runs.forEach((start, r) => {
        const seg = v.slice(start, this.runs[r + 1] ?? v.length);
        const a = Math.min(...seg);
        const s = Math.max(...seg) - a || 1;
        seg.forEach((val, i) => {
          // a run of one iteration has no range: its point halfway up, drawn as a dot below
          const yy = seg.length === 1 ? (top + bottom) / 2 : bottom - ((bottom - top) * (val - a)) / s;
          if (i) g.lineTo(x(start + i), yy);
          else g.moveTo(x(start), yy);
        });
        g.moveTo(x(start), bottom);
        g.lineTo(x(start), bottom - 4);
      });
    } else {
      v.forEach((val, i) => (i ? g.lineTo(x(i), y(val)) : g.moveTo(x(i), y(val))));
    }
    g.stroke();
    // runs of one iteration: a dot each (a line needs two points)
    for (const [r, start] of (this.runs ?? []).entries()) {
      if ((this.runs[r + 1] ?? v.length) - start !== 1) continue;
      g.beginPath();
      g.arc(Math.min(x(start), right - 2.5), (top + bottom) / 2, 2.5, 0, 2 * Math.PI);
      g.fillStyle = g.strokeStyle;
      g.fill();
      g.fillStyle = style.color;
    }
    if (v.length === 1) {
      // one iteration: a dot, not an empty plot (a line needs two points)
      g.beginPath();
      g.arc(x(0) + 2, y(v[0]), 2.5, 0, 2 * Math.PI);
      g.fillStyle = g.strokeStyle;
      g.fill();
      g.fillStyle = style.color;
    }
    g.fillText(maxText, right - g.measureText(maxText).width, 12 * maxLine);
    footer.forEach((t, i) => g.fillText(t, left, h - 2 - 12 * (footer.length - 1 - i)));
  }
}

// Greedy line breaking of `parts` joined by `sep` into lines no wider than `width` (a part wider than that has a
// line of its own).
function wrap(g, parts, sep, width) {
  const lines = [];
  for (const p of parts) {
    const next = lines.length ? `${lines[lines.length - 1]}${sep}${p}` : p;
    if (lines.length && g.measureText(next).width <= width) lines[lines.length - 1] = next;
    else lines.push(p);
  }
  return lines.filter((l) => l !== '');
}
