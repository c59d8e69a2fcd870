// The views: what the viewer shows in each mode (parts, stages, reconstruction, truth, latent, interpolation),
// with its caption and legend. Positions come from the population or from the worker (www/worker.js asks the
// Rust core); colours from colors.js. Nothing here computes a position.
import { state, update, subscribe } from '../state.js';
import { query } from '../session.js';
import { errorColours, RAMP_CSS } from '../colors.js';
import { viewer } from './viewer-instance.js';
import { interpValues } from '../controls/interp.js';

const $ = (id) => document.getElementById(id);

/** Colours of the parts now: the fitted model's, else the fit in progress', else grey. */
export function partColours() {
  if (state.model) return state.colours.final.vertexColours;
  return state.colours.live ?? state.colours.grey;
}

export const poseName = (i) => state.pop.names[i];

const single = (positions, name) => [{ positions, colours: partColours(), name }];

// One builder per mode: (pose positions, pose) -> { slots, caption, legend? } (async when it asks the worker).
const VIEWS = {
  parts(P, pose) {
    const { model } = state;
    const by = model ? `part (${model.summary.parts} parts)` : state.fitId ? 'the parts of the fit in progress' : 'nothing yet';
    return { slots: single(P, `pose ${poseName(pose)}`), caption: `Pose “${poseName(pose)}”, coloured by ${by}` };
  },
  stages(P, pose) {
    const s = state.model.summary;
    const c = state.colours;
    return {
      slots: [
        { positions: P, colours: c.coarse.vertexColours, name: 'coarse' },
        { positions: P, colours: c.refined.vertexColours, name: 'refined' },
        { positions: P, colours: c.final.vertexColours, name: 'final' },
      ],
      caption: `Algorithm 1 on pose “${poseName(pose)}”: coarse (${s.coarseParts} parts) | refined (${s.refinedParts}) | final (${s.parts})`,
    };
  },
  async recon(P, pose) {
    const [recon, errors] = await Promise.all([query('reconstruct', pose), query('vertexErrors', pose)]);
    let max = 0;
    for (const e of errors) max = Math.max(max, e);
    return {
      slots: [
        { positions: P, colours: partColours(), name: 'original' },
        { positions: recon, colours: errorColours(errors, max), name: 'reconstruction' },
      ],
      caption: `Pose “${poseName(pose)}”: original (parts) | reconstruction from the latent shape, coloured by per-vertex error`,
      legend: max,
    };
  },
  truth(P, pose) {
    return {
      slots: [
        { positions: P, colours: state.colours.truth, name: 'ground truth' },
        { positions: P, colours: state.colours.final.vertexColours, name: 'final' },
      ],
      caption: `Pose “${poseName(pose)}”: ground truth of the generator (${state.pop.truth.partNames.length} parts) | fitted (${state.model.summary.parts} parts)`,
    };
  },
  latent() {
    return { slots: single(state.model.latent, 'latent'), caption: 'The latent reference shape (eq 21): every part in its own latent frame' };
  },
  async interp() {
    const { a, b, t, side, opts } = interpValues();
    const A = state.pop.positions[a];
    const B = state.pop.positions[b];
    const linear = new Float32Array(A.length);
    for (let k = 0; k < A.length; k++) linear[k] = A[k] + (B[k] - A[k]) * t;
    const head = `“${poseName(a)}” → “${poseName(b)}” at t = ${t.toFixed(2)}`;
    if (!state.model) return { slots: single(linear, 'linear'), caption: `${head}: linear vertex blending` };
    const slots = single(await query('interpolate', a, b, t, opts), 'part-wise');
    if (side) slots.push({ positions: linear, colours: partColours(), name: 'linear' });
    return { slots, caption: `${head}: part-wise (${opts.skin === 'smooth' ? 'smooth joints' : 'rigid parts'})${side ? ' | linear vertex blending' : ''}` };
  },
};

let renderToken = 0;

/** Builds the slots of the current mode (some need answers from the worker) and shows them. */
export async function renderView({ frame = false } = {}) {
  if (!state.pop) return;
  const token = ++renderToken;
  const { pop, model, pose, mode } = state;
  const needModel = (!model && mode !== 'parts' && mode !== 'interp') || (mode === 'truth' && !pop.truth);
  let view;
  try {
    view = await VIEWS[needModel ? 'parts' : mode](pop.positions[pose], pose);
  } catch (e) {
    if (token === renderToken && e.kind !== 'crashed') $('caption').textContent = e.message;
    return;
  }
  if (token !== renderToken) return;
  if (needModel) view.caption += ' (this view needs a fitted model)';
  const reframe = frame || view.slots.length !== state.shown.length;
  update({ shown: view.slots });
  viewer.show(view.slots, { frame: reframe });
  $('caption').textContent = view.caption;
  const legend = view.legend ?? null;
  $('legend').hidden = legend === null;
  if (legend !== null) {
    $('legend-hi').textContent = `${legend.toExponential(2)} unit box (${(legend / pop.normalization[3]).toExponential(2)} original)`;
  }
  if (state.pick && state.pick.slot < view.slots.length) viewer.mark(state.pick.slot, state.pick.vertex);
}

export function installViews() {
  $('legend').querySelector('.ramp').style.background = RAMP_CSS;
  subscribe((s, changed) => {
    if (changed.has('pop')) {
      viewer.mark(null);
      viewer.setTopology(s.pop.faces, s.pop.positions[0]);
      renderView({ frame: true });
    } else if (changed.has('model') && s.model) {
      renderView({ frame: false });
    } else if (changed.has('mode')) {
      renderView({ frame: true });
    } else if (changed.has('pose')) {
      renderView();
    } else if (changed.has('colours') && !s.model && s.phase === 'fitting') {
      renderView(); // the parts of the fit in progress
    }
  });
}
