// Where the camera looks from, read off the shape alone (no three.js: unit-tested in Node,
// tests/e2e/view-axes.test.mjs).

/** The view axes for a mesh of flat xyz `reference`: the camera looks across the thinnest side of its box (a
 * horse from its flank; `view`), with `up` the next axis up (y, or z when y is the thinnest) and `right` the third.
 * `side` (+1 / -1): it looks from +view unless the shape reaches out much farther the other way from its mean
 * (more than 1.5 times as far): then from there, so that what sticks out is in front (the hand's thumb before
 * the palm, not behind it). */
export function viewAxes(reference) {
  const n = reference.length / 3;
  if (!n) return { view: 2, up: 1, right: 0, side: 1 };
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  const mean = [0, 0, 0];
  for (let k = 0; k < reference.length; k++) {
    const c = k % 3;
    lo[c] = Math.min(lo[c], reference[k]);
    hi[c] = Math.max(hi[c], reference[k]);
    mean[c] += reference[k] / n;
  }
  const size = hi.map((h, c) => h - lo[c]);
  const view = size.indexOf(Math.min(...size));
  const up = view === 1 ? 2 : 1;
  const side = mean[view] - lo[view] > 1.5 * (hi[view] - mean[view]) ? -1 : 1;
  return { view, up, right: 3 - view - up, side };
}
