// The merge tree's slider: the default part rule records every merge of the fitted parts
// (posemfa::parts::merge_tree), so every part count has its partition at once. Moving the slider shows that
// count's parts (asked of the core: labels and colours, the fitted parts' colours kept where a part is the same);
// "Refine N parts" fits from that partition with exactly N parts (the form's "Parts in the end"); the slider
// keeps that tree after it (every count, and the part rule's own, stay in reach; the link says `cut=N`).
import { state, update, subscribe } from '../state.js';
import { query, startFit } from '../session.js';
import { paletteColours } from '../colors.js';
import { renderView } from '../views/render.js';
import { setTargetParts } from './form.js';

const $ = (id) => document.getElementById(id);
const parts = (n) => `${n} part${n === 1 ? '' : 's'}`;
let token = 0;
// the slider at the fit's own count; a Refine's fit came from the tree's partition shown around it
const fitCaption = (n) => `${parts(n)} (the fit${state.model?.refinedFromTree ? ', refined from this count of the tree' : ''})`;
// The count Refine wrote into the form's "Parts in the end" (null: none). Refine fits through the form, so the
// field keeps that count for every later fit: a line under it says so while the field still holds it.
let refined = null;

function showRefineNote() {
  const field = $('params').elements.targetParts;
  const holds = refined !== null && field.value.trim() === String(refined);
  if (!holds) refined = null;
  $('refine-note').hidden = !holds;
  $('refine-note').textContent = holds
    ? `Refine fits with “Parts in the end” set to ${refined}, and the field keeps it: later fits too make exactly ${parts(refined)}, each its own (not this partition: Refine again from the slider for that), until it is auto (empty) again.`
    : '';
}

/** Shows the tree's partition with n parts in the parts view. */
async function show(n) {
  const tree = state.model?.tree;
  if (!tree) return;
  const mine = ++token;
  const fit = state.model.summary.parts;
  const t0 = performance.now();
  const slider = $('tree-slider');
  // for the tests: how long the move took until the view had the partition (its draw asked for: `ms`) and until
  // the frame that shows it was drawn (`drawnMs`: the viewer draws in the next animation frame, and a callback
  // asked for after its own runs after it; the frame rate is the renderer's), and the count shown
  const shownAt = (labels) => {
    const ready = performance.now() - t0;
    requestAnimationFrame(() => {
      if (mine !== token) return;
      slider.dataset.ms = ready.toFixed(1);
      slider.dataset.drawnMs = (performance.now() - t0).toFixed(1);
      slider.dataset.parts = String(new Set(labels).size);
      slider.dataset.count = String(n);
    });
  };
  if (n === fit) {
    // the fit's own parts (the tree's cut at that count can differ: the fit was refitted after the cut)
    update({ treeParts: null });
    $('tree-count').textContent = fitCaption(n);
    $('tree-refine').disabled = true;
    $('tree-refine').textContent = `Refine ${parts(n)}`;
    await renderView();
    shownAt(state.model.labels);
    return;
  }
  const { labels, colours } = await query('treePartition', n);
  if (mine !== token) return;
  const shown = paletteColours(labels, colours);
  update({ colours: { ...state.colours, tree: shown.vertexColours }, treeParts: n });
  const rule = n === tree.decided ? ', the part rule’s count' : n > fit ? ' (finer than the fit)' : '';
  // the partition is shown in the Parts view: from another view the slider goes there, and says so
  const from = document.querySelector(`#modes input[value="${state.mode}"]`)?.parentElement.textContent.trim();
  const moved = state.mode !== 'parts' ? `, shown in the Parts view (from ${from ?? state.mode})` : '';
  $('tree-count').textContent = `${parts(n)} of the merge tree${rule}${moved}`;
  $('tree-refine').disabled = n === state.model.summary.parts;
  $('tree-refine').textContent = `Refine ${parts(n)}`;
  if (state.mode !== 'parts') update({ mode: 'parts' });
  await renderView();
  shownAt(labels);
}

/** Refine: the fit from the merge tree's partition with n parts, with exactly that count (the form's "Parts in
 * the end" is set to it, and says so under the field). The tree stays the slider's (the worker keeps it:
 * fit-memory.js), so another count can be chosen and refined after. False when the tree cannot give it. */
export async function refine(n) {
  const mine = token;
  const tree = state.model?.tree;
  if (!tree || n < tree.fewest || n > tree.most) return false;
  let labels;
  try {
    ({ labels } = await query('treePartition', n));
  } catch (e) {
    $('tree-count').textContent = `cannot refine ${parts(n)}: ${e.message}`;
    return false;
  }
  if (mine !== token) return false; // a new model came meanwhile: its tree is another
  setTargetParts(n);
  refined = n;
  showRefineNote();
  startFit({ startLabels: labels });
  return true;
}

export function installTree() {
  const slider = $('tree-slider');
  slider.addEventListener('input', () => {
    delete slider.dataset.count; // set again once the count asked for is shown
    show(Number(slider.value));
  });
  $('tree-refine').addEventListener('click', () => refine(Number(slider.value)));
  // the field typed into, or filled in code (Defaults, an example, new files: a new model or population follows)
  $('params').addEventListener('input', showRefineNote);
  $('reset-params').addEventListener('click', showRefineNote); // after the form's own listener has filled it
  subscribe((s, changed) => {
    if (changed.has('model') || changed.has('pop')) showRefineNote();
    if (!changed.has('model')) return;
    const tree = s.model?.tree;
    $('tree').hidden = !tree;
    token++;
    if (!tree) return;
    slider.min = String(tree.fewest);
    slider.max = String(tree.most);
    slider.value = String(s.model.summary.parts);
    $('tree-count').textContent = fitCaption(s.model.summary.parts);
    $('tree-refine').disabled = true;
    $('tree-refine').textContent = `Refine ${parts(Number(slider.value))}`;
    if (s.treeParts !== null) update({ treeParts: null });
  });
}
