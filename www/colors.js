// Colours of parts and errors. Which palette colour each part gets comes from the core with the labels (parts
// that share a mesh edge differ; posemfa::articulate::graph::colour_parts): paletteColours looks them up, for
// the app and the article alike.

// Well separated hues (after Kelly and Trubetskoy); no grey, white or black, which the background and the
// shading use.
export const PALETTE = [ // 12 colours: PALETTE_SIZE in worker.js
  '#e6194b', '#3cb44b', '#ffe119', '#4363d8', '#f58231', '#911eb4',
  '#42d4f4', '#f032e6', '#bfef45', '#fabed4', '#469990', '#9a6324',
];

export const hexToRgb = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);
export const PALETTE_RGB = PALETTE.map(hexToRgb);

/**
 * Per-vertex RGB (Float32Array, 3 per vertex) of part labels, given the palette index of every part (from the
 * core), and the CSS colour of every part.
 */
export function paletteColours(labels, partPalette) {
  const out = new Float32Array(labels.length * 3);
  labels.forEach((l, v) => out.set(PALETTE_RGB[partPalette[l] % PALETTE.length], 3 * v));
  return { vertexColours: out, partColour: Array.from(partPalette, (c) => PALETTE[c % PALETTE.length]) };
}

/**
 * Soft colours of responsibilities: row j (one per vertex of a run) gets the colours of its parts blended by
 * its γ (`gamma[j * parts + k]`), part k in palette colour `colourOf[k]` (from the core). Flat RGB per row.
 */
export function gammaColours(gamma, parts, colourOf) {
  const rows = gamma.length / parts;
  const out = new Float32Array(rows * 3);
  for (let j = 0; j < rows; j++) {
    for (let k = 0; k < parts; k++) {
      const w = gamma[j * parts + k];
      if (!w) continue;
      const c = PALETTE_RGB[colourOf[k] % PALETTE.length];
      for (let a = 0; a < 3; a++) out[3 * j + a] += w * c[a];
    }
  }
  return out;
}

// Error colour map: dark blue (0) -> teal -> yellow -> red (max), like the paper's Fig 4.
const RAMP = ['#2c3e91', '#2a9d8f', '#e9c46a', '#e63946'].map(hexToRgb);
export function rampColour(x) {
  const t = Math.min(Math.max(x, 0), 1) * (RAMP.length - 1);
  const i = Math.min(Math.floor(t), RAMP.length - 2);
  const f = t - i;
  return RAMP[i].map((c, k) => c + (RAMP[i + 1][k] - c) * f);
}
export const RAMP_CSS = `linear-gradient(to right, ${RAMP.map((c) => `rgb(${c.map((v) => Math.round(v * 255))})`).join(', ')})`;

/** Per-vertex RGB for errors, scaled so that `max` is red. */
export function errorColours(errors, max) {
  const out = new Float32Array(errors.length * 3);
  const m = max > 0 ? max : 1;
  errors.forEach((e, v) => out.set(rampColour(e / m), 3 * v));
  return out;
}
