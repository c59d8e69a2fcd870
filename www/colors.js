// Colours of parts and errors. Which palette colour each part gets comes from the core with the labels (parts
// that share a mesh edge differ; posemfa::articulate::graph::colour_parts): paletteColours looks them up.
// (colourParts / labelColours below still colour in JS for the article's figures, www/explain/, until its pool
// worker sends the core's colouring as www/worker.js does.)

// Well separated hues (after Kelly and Trubetskoy); no grey, white or black, which the background and the
// shading use.
export const PALETTE = [ // 12 colours: PALETTE_SIZE in worker.js
  '#e6194b', '#3cb44b', '#ffe119', '#4363d8', '#f58231', '#911eb4',
  '#42d4f4', '#f032e6', '#bfef45', '#fabed4', '#469990', '#9a6324',
];

export const hexToRgb = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);
const PALETTE_RGB = PALETTE.map(hexToRgb);

/**
 * Per-vertex RGB (Float32Array, 3 per vertex) of part labels, given the palette index of every part (from the
 * core), and the CSS colour of every part.
 */
export function paletteColours(labels, partPalette) {
  const out = new Float32Array(labels.length * 3);
  labels.forEach((l, v) => out.set(PALETTE_RGB[partPalette[l] % PALETTE.length], 3 * v));
  return { vertexColours: out, partColour: Array.from(partPalette, (c) => PALETTE[c % PALETTE.length]) };
}

/** Sets of neighbouring parts, from every triangle edge whose two vertices lie in different parts. */
export function partAdjacency(labels, faces, nParts) {
  const adj = Array.from({ length: nParts }, () => new Set());
  for (let f = 0; f < faces.length; f += 3) {
    for (let e = 0; e < 3; e++) {
      const a = labels[faces[f + e]];
      const b = labels[faces[f + ((e + 1) % 3)]];
      if (a !== b) {
        adj[a].add(b);
        adj[b].add(a);
      }
    }
  }
  return adj;
}

/** Palette index of every part: never the colour of a neighbour (while the palette has one left). */
export function colourParts(labels, faces) {
  let nParts = 0;
  for (const l of labels) nParts = Math.max(nParts, l + 1);
  const adj = partAdjacency(labels, faces, nParts);
  const size = new Array(nParts).fill(0);
  for (const l of labels) size[l]++;
  // Most constrained first (Welsh-Powell), then the larger part.
  const order = [...Array(nParts).keys()].sort((a, b) => adj[b].size - adj[a].size || size[b] - size[a] || a - b);
  const colour = new Array(nParts).fill(-1);
  const used = new Array(PALETTE.length).fill(0);
  for (const p of order) {
    const taken = new Set([...adj[p]].map((q) => colour[q]));
    let best = -1;
    for (let c = 0; c < PALETTE.length; c++) {
      if (!taken.has(c) && (best < 0 || used[c] < used[best])) best = c;
    }
    if (best < 0) best = used.indexOf(Math.min(...used)); // more neighbours than colours
    colour[p] = best;
    used[best]++;
  }
  return colour;
}

/** Per-vertex RGB (Float32Array, 3 per vertex) for part labels. */
export function labelColours(labels, faces) {
  const colour = colourParts(labels, faces);
  const out = new Float32Array(labels.length * 3);
  labels.forEach((l, v) => out.set(PALETTE_RGB[colour[l]], 3 * v));
  return { vertexColours: out, partColour: colour.map((c) => PALETTE[c]) };
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
