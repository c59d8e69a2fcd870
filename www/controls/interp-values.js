// The interpolation asked for in the Interpolate controls, read from the page: poses a -> b at t, side by side
// or not, and the core's options. Its own module so that the views (views/render.js), the interpolation
// controls (interp.js) and the exports read it without importing each other (www/ has no import cycle:
// tests/e2e/house.test.mjs).
const $ = (id) => document.getElementById(id);

/** { a, b, t, side, opts: { skin, residual } } as the controls show them now. */
export function interpValues() {
  return {
    a: Number($('pose-a').value),
    b: Number($('pose-b').value),
    t: Number($('interp-t').value),
    side: $('side-by-side').checked,
    opts: { skin: $('interp-skin').value, residual: $('interp-residual').checked },
  };
}
