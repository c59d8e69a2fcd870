// The page's entry: starts the worker, builds the pieces and wires them to the page state. Where things live:
//   state.js       the one page state; every change goes through update(patch)
//   protocol.js    the worker client (requests and their promises, restarts with a cap); worker.js the worker
//   session.js     loading, generating, fitting, questions about the model, a crashed worker's work redone
//   views/         render.js (what each view mode shows), inspect.js (click / hover), result.js (figures)
//   controls/      form.js (parameters, Fit, Cancel, examples), poses.js, interp.js, toolbar.js, exports.js
//   drop.js        file pickers and drops; presets.js, teach.js, urlstate.js: presets, teaching, the link
// Test contract: document.body.dataset.state, the data-testid elements of index.html, window.posemfa (below).
import './worker-client.js'; // first: the wasm module loads while three.js evaluates
import { installUrlState } from './urlstate.js'; // second: an embedded page hides its controls at once
import { state, update, subscribe } from './state.js';
import { faultInjection, injectFault, onReady, generate, runExample, loadFiles, openUrl, startFit, cancelFit, query } from './session.js';
import { viewer } from './views/viewer-instance.js';
import { installViews, renderView } from './views/render.js';
import { installInspect, pickVertex } from './views/inspect.js';
import { installResult } from './views/result.js';
import { installForm, fillParams, readParams, showExamples } from './controls/form.js';
import { installPoses } from './controls/poses.js';
import { installInterp } from './controls/interp.js';
import { installPose } from './controls/pose.js';
import { installTree, refine } from './controls/tree.js';
import { installToolbar } from './controls/toolbar.js';
import { installExports } from './controls/exports.js';
import { installDrop } from './drop.js';
import { installPresets } from './presets.js';
import { installTeaching, teach } from './teach.js';
import { note } from './problems.js';
import { PALETTE } from './colors.js';

const $ = (id) => document.getElementById(id);

// The test contract (README): read-only views of the page state.
window.posemfa = {
  /** Summary of the current model ({shapes, vertices, parts, rmse, iterations, fitMs, ...}) or null. */
  summary: () => (state.model ? { ...state.model.summary } : null),
  /** The palette, and the colour of every final part. */
  palette: PALETTE,
  partColours: () => state.colours.final?.partColour.slice() ?? null,
  /** Number of fits that have ended (finished, cancelled or failed) since the page opened. */
  fitCount: () => state.fitCount,
  /** Number of drops or picks refused with errors since the page opened. */
  loadErrorCount: () => state.loadErrorCount,
  /** Names of the meshes in the view, left to right (e.g. ['part-wise', 'linear']). */
  shown: () => state.shown.map((x) => x.name),
  /** Number of poses, and the view mode. */
  poses: () => state.pop?.nShapes ?? 0,
  mode: () => state.mode,
  /** Workers replaced after a crash since the page opened. */
  restartCount: () => state.restartCount,
  /** The fitted parts: the part of every vertex and the palette colour of every part (null before a fit). */
  fittedParts: () => (state.model ? { labels: Array.from(state.model.labels), colours: Array.from(state.model.colours.final) } : null),
  /** The Stages view's parts: for stage 'coarse', 'refined' or 'final', the part of every vertex and the palette
   * colour of every part (null before a fit). */
  stageParts: (stage) => {
    const m = state.model;
    const labels = m && { coarse: m.coarseLabels, refined: m.refinedLabels, final: m.labels }[stage];
    return labels ? { labels: Array.from(labels), colours: Array.from(m.colours[stage]) } : null;
  },
  /** The merge tree ({most, fewest, decided}, null without one) and the count its slider shows (null: the fit). */
  tree: () => (state.model?.tree ? { ...state.model.tree, shown: state.treeParts } : null),
  /** The merge tree's partition with n parts, as its slider shows it: { labels, colours } (a promise). */
  treePartition: (n) => query('treePartition', n).then(({ labels, colours }) => ({ labels: Array.from(labels), colours: Array.from(colours) })),
  /** Inspects vertex v of the first mesh shown, as a click on it does (the info box answers). */
  inspect: (v) => pickVertex({ slot: 0, vertex: v }),
};
if (faultInjection) {
  /** Page tests only (?faultInjection=1): the next `times` fits make the wasm instance trap (a Rust panic). */
  window.posemfa.injectFault = injectFault;
}

// body[data-state] (test contract), the marks scripts/bench-page.mjs reads, and the Cancel button.
// A teaching fit is 'fitting' while it runs and 'paused' between steps (nothing runs then).
subscribe((s, changed) => {
  if (!changed.has('phase') && !(changed.has('teach') && s.phase === 'teaching')) return;
  document.body.dataset.state = s.phase === 'teaching' ? (s.teach?.running ? 'fitting' : 'paused') : s.phase;
  document.body.dataset.teaching = s.phase === 'teaching' ? '1' : '';
  if (changed.has('phase')) performance.mark(`posemfa:${s.phase}`); // times since navigation
  $('cancel').disabled = s.phase !== 'fitting';
});

const urlState = installUrlState({
  viewer, readParams, fillParams, renderView, runExample, generate, openUrl, note, refine, teach: (count) => teach('teach-step', { count }),
});
installPoses(); // before the views: a new population's pose lists are filled before its first picture
installViews();
installResult();
installInspect();
installForm({ startFit, cancelFit, runExample, check: (base, fields, vertices) => query('formParams', base, fields, vertices) });
installInterp();
installPose();
installTree();
installToolbar();
installExports();
installDrop(loadFiles);
installPresets(runExample);
installTeaching();

// The built-in population: the first of the core's examples (posemfa::synth::presets), fitted at load. The
// link may name another: #ex=ID (urlstate.js), ?example=ID, or a generated population of its own
// (?preset=snake&vertices=3000&poses=12&seed=4, fitted with the default parameters).
onReady(({ defaults, examples }) => {
  update({ defaults, baseParams: defaults, examples });
  fillParams(defaults);
  showExamples(examples);
  const url = new URLSearchParams(location.search);
  if (urlState.start()) return; // the link chose the population (and its parameters and view)
  if (url.has('preset')) {
    generate({ preset: url.get('preset'), vertices: Number(url.get('vertices')) || 2500, poses: Number(url.get('poses')) || 8, seed: Number(url.get('seed')) || 0 });
  } else {
    runExample(examples.find((e) => e.id === url.get('example')) ?? examples[0]);
  }
});

document.body.dataset.state = 'loading';
$('cancel').disabled = true;
