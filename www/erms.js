// E_RMS (Kavan et al. 2010: 1000 x the RMS error per coordinate over the bounding-box diagonal) as the page
// writes it: three decimals, or two significant digits below 0.01, so that a small error is not read as "0.000".
export const ERMS_UNIT = 'RMS error per coordinate, in thousandths of the bounding-box diagonal';

export const eRmsText = (v) => (v === 0 || Math.abs(v) >= 0.01 ? v.toFixed(3) : v.toPrecision(2));

/** A share of the diagonal in per cent: two decimals, or two significant digits below 0.01 %. */
export const percentText = (f) => {
  const p = 100 * f;
  return p === 0 || Math.abs(p) >= 0.01 ? p.toFixed(2) : p.toPrecision(2);
};
