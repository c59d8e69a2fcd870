// The views: what the viewer shows in each mode (parts, stages, reconstruction, truth, latent, interpolation),
// with its caption and legend. Positions come from the population or from the worker (www/worker.js asks the
// Rust core); colours from colors.js. Nothing here computes a position. Every slot names its mesh (`what`,
// a Shown descriptor of src/export/shown.rs), so the OBJ export can ask the core for the same mesh.
import { state, update, subscribe } from '../state.js';
import { query, isTreeFit } from '../session.js';
import { errorColours, RAMP_CSS, PALETTE } from '../colors.js';
import { viewer } from './viewer-instance.js';
import { interpValues } from '../controls/interp-values.js';
import { poseReach } from './frame-reach.js';

const $ = (id) => document.getElementById(id);
const nParts = (n) => `${n} part${n === 1 ? '' : 's'}`;
// more parts than colours: neighbouring parts always differ (the core's part graph), others can share a colour
const partsShown = (n) => nParts(n) + (n > PALETTE.length ? `; ${PALETTE.length} colours, so parts that do not touch can share one` : '');

/** Colours of the parts now: the fitted model's, else the fit in progress', else grey. */
export function partColours() {
  if (state.model) return state.colours.final.vertexColours;
  return state.colours.live ?? state.colours.grey;
}

/** The part colours of the pose thumbnails: the same as the main view's, so the merge tree's partition when
 * the slider (controls/tree.js) shows one in the parts view, else the fitted parts'. */
export function thumbnailColours() {
  if (state.model && state.mode === 'parts' && state.treeParts !== null && state.colours.tree) return state.colours.tree;
  return partColours();
}

export const poseName = (i) => state.pop.names[i];

// `parts`: the fit stage whose parts colour the mesh (its OBJ export groups the faces by them), when fitted.
const single = (positions, name, what) => [{ positions, colours: partColours(), name, what, parts: 'final' }];
const pose = (p) => ({ kind: 'pose', pose: p });

// One builder per mode: (pose positions, pose) -> { slots, caption, legend? } (async when it asks the worker).
const VIEWS = {
  parts(P, pose) {
    const { model } = state;
    if (model && state.treeParts !== null && state.colours.tree) {
      // the merge tree's partition the slider asks for (controls/tree.js); its export groups by the fitted parts
      const slots = [{ positions: P, colours: state.colours.tree, name: `pose ${poseName(pose)}`, what: { kind: 'pose', pose } }];
      return { slots, caption: `Pose “${poseName(pose)}”, coloured by the merge tree's ${partsShown(state.treeParts)} (fitted: ${model.summary.parts})` };
    }
    // a cancelled fit's parts are where it stopped (said before the count, not inside the colours' clause); no
    // model and no fit (none yet, or the fit failed): grey, and the caption says so
    const stopped = model?.summary.cancelled ? ' where the cancelled fit stopped' : '';
    // a fit in progress has no parts before its first stage ends (the merge tree's start): grey until then
    const live = state.colours.live ? 'coloured by the parts of the fit in progress' : 'grey until the fit in progress has its first parts';
    const by = model ? `coloured by part${stopped} (${partsShown(model.summary.parts)})` : state.fitId ? live : 'not fitted (grey)';
    return { slots: single(P, `pose ${poseName(pose)}`, { kind: 'pose', pose }), caption: `Pose “${poseName(pose)}”, ${by}` };
  },
  // The three stages of what ran: the merge tree's start, the part rule's parts and the final AECM (the default
  // part rule), or Algorithm 1's coarse, refined and final parts (part rules distinct and threshold, the
  // refinement off, Step by step). The slots keep the stages' names (the OBJ export's objects and groups).
  stages(P, p) {
    const s = state.model.summary;
    const c = state.colours;
    const tree = isTreeFit(state.model);
    const [first, second] = tree ? ['start', 'after the part rule'] : ['coarse', 'refined'];
    const labels = [`${first} (${nParts(s.coarseParts)})`, `${second} (${nParts(s.refinedParts)})`, `final (${nParts(s.parts)})`];
    return {
      slots: [
        { positions: P, colours: c.coarse.vertexColours, name: 'coarse', what: pose(p), parts: 'coarse', label: labels[0] },
        { positions: P, colours: c.refined.vertexColours, name: 'refined', what: pose(p), parts: 'refined', label: labels[1] },
        { positions: P, colours: c.final.vertexColours, name: 'final', what: pose(p), parts: 'final', label: labels[2] },
      ],
      caption: `${tree ? 'Merge-tree fit' : 'Algorithm 1'} on pose “${poseName(p)}”: ${first} (${s.coarseParts} parts) | ${second} (${s.refinedParts}) | final (${s.parts})`,
    };
  },
  async recon(P, p) {
    const [recon, errors] = await Promise.all([query('reconstruct', p), query('vertexErrors', p)]);
    let max = 0;
    for (const e of errors) max = Math.max(max, e);
    const [maxOriginal] = await query('originalLengths', [max]);
    return {
      slots: [
        { positions: P, colours: partColours(), name: 'original', what: pose(p), parts: 'final', label: 'original' },
        { positions: recon, colours: errorColours(errors, max), name: 'reconstruction', what: { kind: 'reconstruction', pose: p }, parts: 'final', label: 'reconstruction (error)' },
      ],
      caption: `Pose “${poseName(p)}”: original (parts) | reconstruction from the latent shape, coloured by per-vertex error`,
      legend: `${max.toExponential(2)} unit box (${maxOriginal.toExponential(2)} original)`,
    };
  },
  truth(P, p) {
    return {
      slots: [
        { positions: P, colours: state.colours.truth, name: 'ground truth', what: pose(p), label: 'ground truth' },
        { positions: P, colours: state.colours.final.vertexColours, name: 'final', what: pose(p), parts: 'final', label: 'fitted' },
      ],
      caption: `Pose “${poseName(p)}”: ground truth of the generator (${nParts(state.pop.truth.partNames.length)}) | fitted (${nParts(state.model.summary.parts)})`,
    };
  },
  // The latent shape (eq 21) keeps every part in its own frame, centred on the origin: drawn as it is, the parts
  // lie on top of each other. By default each part is placed where it is in the pose shown (its R and b).
  async latent(P, p) {
    const how = $('latent-place').value;
    const name = `“${poseName(p)}”`;
    if (how === 'frames') {
      return {
        slots: single(state.model.latent, 'latent-own-frames', { kind: 'latent' }),
        caption: `The latent shape (eq 21) as the model keeps it: every part in its own frame, centred on the origin, so the ${state.model.summary.parts} parts lie on top of each other and the largest hides the rest`,
      };
    }
    if (how === 'moved') {
      return {
        slots: single(await query('latentPlaced', p), `latent-moved-pose-${p + 1}`, { kind: 'latent-moved', pose: p }),
        caption: `The latent shape (eq 21), every part moved by its b of pose ${name} but not turned: where the parts sit, each still facing its own frame's way`,
      };
    }
    return {
      slots: single(await query('reconstruct', p), `latent-posed-pose-${p + 1}`, { kind: 'reconstruction', pose: p }),
      caption: `The latent shape (eq 21), every part turned by its R and moved by its b of pose ${name} (eq 22 without the residual): the parts as the model places them; pick a pose below`,
    };
  },
  async interp() {
    const { a, b, t, side, opts } = interpValues();
    const linear = { kind: 'linear', from: a, to: b, t };
    const head = `“${poseName(a)}” → “${poseName(b)}” at t = ${t.toFixed(2)}`;
    if (!state.model) return { slots: single(await query('linearInterpolate', a, b, t), 'linear', linear), caption: `${head}: linear vertex blending` };
    const slots = single(await query('interpolate', a, b, t, opts), 'part-wise', { kind: 'interpolation', from: a, to: b, t, options: opts });
    if (side) {
      slots[0].label = 'part-wise';
      slots.push({ positions: await query('linearInterpolate', a, b, t), colours: partColours(), name: 'linear', what: linear, parts: 'final', label: 'linear blending' });
    }
    return { slots, caption: `${head}: part-wise (${opts.skin === 'smooth' ? 'smooth joints' : 'rigid parts'})${side ? ' | linear vertex blending' : ''}` };
  },
};

// What the caption says while a mode's view is being built, when that takes a while (pose mode builds the rig
// first): the meshes of the mode before stay until the new view is ready, and the caption must not name them.
const PENDING = {};
const PENDING_MS = 60;

/** Adds a view mode built elsewhere (controls/pose.js adds `pose`), so that render.js imports none of them;
 * pending: the caption while a slow build runs. */
export function registerView(mode, build, { pending = null } = {}) {
  VIEWS[mode] = build;
  if (pending) PENDING[mode] = pending;
}

let renderToken = 0;
let reached = { pop: null, size: null };
const reach = (pop) => {
  if (reached.pop !== pop) reached = { pop, size: poseReach(pop.positions) };
  return reached.size;
};

/** Builds the slots of the current mode (some need answers from the worker) and shows them. */
export async function renderView({ frame = false } = {}) {
  if (!state.pop) return;
  const token = ++renderToken;
  const { pop, model, pose, mode } = state;
  const needModel = (!model && mode !== 'parts' && mode !== 'interp') || (mode === 'truth' && !pop.truth);
  let view;
  const pending = !needModel && PENDING[mode]
    ? setTimeout(() => token === renderToken && ($('caption').textContent = PENDING[mode]), PENDING_MS)
    : null;
  try {
    view = await VIEWS[needModel ? 'parts' : mode](pop.positions[pose], pose);
  } catch (e) {
    if (token === renderToken && e.kind !== 'crashed') $('caption').textContent = e.message;
    return;
  } finally {
    clearTimeout(pending);
  }
  if (token !== renderToken) return;
  if (needModel) view.caption += ' (this view needs a fitted model)';
  const reframe = frame || view.slots.length !== state.shown.length;
  // every training pose's extent fits in the frame, so that another pose is not cut off (frame-reach.js); the
  // latent shape is no pose
  viewer.minSize = mode === 'latent' ? null : reach(pop);
  update({ shown: view.slots });
  viewer.show(view.slots, { frame: reframe, stay: !!view.stay });
  $('caption').textContent = view.caption;
  $('legend').hidden = !view.legend;
  if (view.legend) $('legend-hi').textContent = view.legend;
  if (state.pick && state.pick.slot < view.slots.length) viewer.mark(state.pick.slot, state.pick.vertex);
}

export function installViews() {
  // the test contract: how many of the shown meshes' vertices lie outside the view (the camera follows the poses)
  window.posemfa = Object.assign(window.posemfa ?? {}, {
    /** Where the camera is (to tell whether it moved). */
    camera: () => viewer.camera.position.toArray(),
    outOfView: () => {
      const r = viewer.renderer.domElement.getBoundingClientRect();
      let out = 0;
      state.shown.forEach((slot, k) => {
        const p = slot.positions;
        for (let i = 0; i < p.length; i += 3) {
          const q = viewer.screenPoint(k, [p[i], p[i + 1], p[i + 2]]);
          if (q.x < r.left || q.x > r.right || q.y < r.top || q.y > r.bottom) out++;
        }
      });
      return out;
    },
  });
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
    } else if (changed.has('fitId') && !s.model) {
      renderView(); // a fit started, or ended without a model (failed): the caption is not left at "in progress"
    }
  });
}
