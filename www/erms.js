// E_RMS (Kavan et al. 2010: 1000 x the RMS error per coordinate over the bounding-box diagonal) as the page
// writes it: three decimals, or two significant digits below 0.01, so that a small error is not read as "0.000".
export const ERMS_UNIT = 'RMS error per coordinate, in thousandths of the bounding-box diagonal';

/** `v` with `decimals` decimals, or two significant digits when it is below 0.01 (and not 0). */
const figure = (v, decimals) => (v === 0 || Math.abs(v) >= 0.01 ? v.toFixed(decimals) : v.toPrecision(2));

export const eRmsText = (v) => figure(v, 3);

/** A share of the diagonal in per cent: two decimals, or two significant digits below 0.01 %. */
export const percentText = (f) => figure(100 * f, 2);
