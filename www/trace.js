// A log-likelihood trace, read the same way by the app's result panel and the article's figures.

/** Iterations where the log-likelihood fell (by more than rounding). */
export function drops(values) {
  const out = [];
  for (let i = 1; i < values.length; i++) {
    if (values[i - 1] - values[i] > 1e-9 * Math.max(1, Math.abs(values[i]))) out.push(i);
  }
  return out;
}
