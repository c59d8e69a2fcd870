// Linked views: click a vertex to see its part, its responsibilities (eq 12) and its reconstruction error;
// hover a part to see its rotation angle in every pose. The numbers come from the worker.
import { state, update, subscribe } from '../state.js';
import { query } from '../session.js';
import { viewer } from './viewer-instance.js';
import { poseName } from './render.js';
import { restPose, boneOfPart, poseSkeleton } from '../controls/pose.js';
import { boundedRows, spread } from '../controls/pose-parts.js';

const infoPick = document.createElement('div');
const infoHover = document.createElement('div');

function swatch(part) {
  const s = document.createElement('span');
  s.className = 'swatch';
  s.style.background = state.colours.final?.partColour[part] ?? '#ccc';
  return s;
}

function bar(fraction, width = 80) {
  const b = document.createElement('span');
  b.className = 'bar';
  b.style.width = `${Math.max(1, Math.round(fraction * width))}px`;
  return b;
}

function row(...cells) {
  const tr = document.createElement('tr');
  for (const c of cells) {
    const td = document.createElement('td');
    td.append(c);
    tr.append(td);
  }
  return tr;
}

// The parts inspected are the fit's; while the merge tree's slider shows another count, the box says so.
const ofFit = () => (state.treeParts !== null && state.model && state.mode === 'parts'
  ? ` of the fit's ${state.model.summary.parts} (the view shows the merge tree's ${state.treeParts})` : '');

async function showPick() {
  const hit = state.pick;
  if (!hit || !state.model) {
    infoPick.replaceChildren();
    return;
  }
  const v = hit.vertex;
  const part = state.model.labels[v];
  const { gen, pose } = state;
  let resp;
  let errors;
  let original;
  try {
    [resp, errors] = await Promise.all([query('responsibilities', v), query('vertexErrors', pose)]);
    [original] = await query('originalLengths', [errors[v]]);
  } catch (e) {
    infoPick.textContent = e.message;
    return;
  }
  if (gen !== state.gen || state.pick !== hit) return;
  const head = document.createElement('div');
  head.append(`Vertex ${v} (${state.shown[hit.slot]?.name ?? ''}): part ${part + 1}${ofFit()} `, swatch(part));
  const err = document.createElement('div');
  err.textContent = `error in pose “${poseName(pose)}”: ${errors[v].toExponential(2)} unit box = ${original.toExponential(2)} original`;
  const order = [...resp.keys()].sort((a, b) => resp[b] - resp[a]).slice(0, 5);
  const table = document.createElement('table');
  table.append(row('P(part | vertex), eq 12', '', ''));
  for (const k of order) table.append(row(Object.assign(swatch(k), { title: `part ${k + 1}` }), `part ${k + 1}`, resp[k].toFixed(4)));
  // The part (its colour, the exports' label) is the fit's label: the part rule labels every vertex by rigid
  // motion and keeps each part one connected piece of the mesh, so near a border it can differ from the part
  // that eq 12's densities alone favour. Said, not hidden.
  const why = document.createElement('div');
  why.className = 'note';
  why.dataset.testid = 'pick-why';
  why.textContent = order[0] === part
    ? `part ${part + 1} is also the most likely by eq 12`
    : `part ${part + 1} is the fit's label (its colour, and the exports'): the part rule labels by rigid motion and keeps every part one connected piece; eq 12's densities alone favour part ${order[0] + 1}`;
  infoPick.replaceChildren(head, err, table, why);
}

// The hover box's table: one row per pose, at most MAX_ROWS of them (a character's 399 frames would run off the
// view and cover the mesh): past that a summary line and the largest few (pose-parts.js boundedRows).
function anglesTable(n, columns, key) {
  const table = document.createElement('table');
  const { rows, more } = boundedRows(n, key);
  if (columns.length > 1) table.append(row('', ...columns.map((c) => c.title)));
  for (const i of rows) table.append(row(poseName(i), ...columns.flatMap((c) => (c.bar ? [bar(c.values[i] / 180), `${c.values[i].toFixed(1)}°`] : [`${c.values[i].toFixed(1)}°`]))));
  if (!more) return [table];
  const s = spread(columns[0].values);
  const summary = document.createElement('div');
  summary.dataset.testid = 'hover-summary';
  summary.textContent = `${n} poses: median ${s.median.toFixed(1)}°, largest ${s.max.toFixed(1)}°${columns.length > 1 ? ` (${columns[0].title})` : ''}; the ${rows.length} largest, in pose order (${more} more not listed):`;
  return [summary, table];
}

async function showHover() {
  const part = state.hoverPart;
  if (part === null || !state.model) {
    infoHover.replaceChildren();
    return;
  }
  // pose mode shows a pose made from the rig: the angles are from its rest pose (the rig's bind pose), as the
  // readout's are, and in the same two measures the core has: at the part's joint, relative to the part carrying
  // it (the readout's), and the whole part's own rotation (which includes the turns of the parts carrying it,
  // the body's too); elsewhere the part's rotation from the pose shown
  const posing = state.mode === 'pose';
  const sk = posing ? poseSkeleton() : null;
  const bone = sk ? boneOfPart(part) : -1;
  const { gen } = state;
  const pose = posing ? restPose() : state.pose;
  let angles;
  try {
    angles = bone >= 0 ? await query('poseTrainingAnglesOf', bone) : await query('rotationAngles', part, pose);
  } catch (e) {
    infoHover.textContent = e.message;
    return;
  }
  if (gen !== state.gen || state.hoverPart !== part) return;
  const head = document.createElement('div');
  if (bone >= 0) {
    const p = sk.parent[bone];
    head.append(swatch(part), ` part ${part + 1}, from the rest pose “${poseName(pose)}” (the rig's bind pose), in each training pose: `
      + (p >= 0 ? `at its joint (its turn relative to ${sk.names[p]}, as the readout), and the whole part (its own rotation: the turns of the parts carrying it included)` : 'the root: its own rotation, the whole body\'s turn'));
    const columns = p >= 0
      ? [{ title: 'at its joint', values: angles.joint, bar: true }, { title: 'whole part', values: angles.whole }]
      : [{ title: 'whole part', values: angles.whole, bar: true }];
    infoHover.replaceChildren(head, ...anglesTable(columns[0].values.length, columns, (i) => columns[0].values[i]));
    infoHover.dataset.measures = columns.map((c) => c.title).join('|');
    return;
  }
  head.append(swatch(part), posing
    ? ` part ${part + 1}: its own rotation from the rest pose (pose “${poseName(pose)}”, the rig's bind pose) in each training pose`
    : ` part ${part + 1}: rotation from pose “${poseName(pose)}”${ofFit()}`);
  infoHover.replaceChildren(head, ...anglesTable(angles.length, [{ title: 'rotation', values: angles, bar: true }], (i) => angles[i]));
  infoHover.dataset.measures = 'rotation';
}

/** Marks and inspects `hit` ({ slot, vertex }, or null: nothing); window.posemfa.inspect for the tests. */
export function pickVertex(hit) {
  if (hit) viewer.mark(hit.slot, hit.vertex);
  else viewer.mark(null);
  update({ pick: hit });
  showPick();
}

export function installInspect() {
  document.getElementById('info').append(infoPick, infoHover);
  const canvas = viewer.renderer.domElement;
  let down = null;
  canvas.addEventListener('pointerdown', (e) => { down = { x: e.clientX, y: e.clientY }; });
  canvas.addEventListener('pointerup', (e) => {
    if (!down || Math.hypot(e.clientX - down.x, e.clientY - down.y) > 4) return;
    down = null;
    const hit = viewer.pick(e.clientX, e.clientY);
    pickVertex(hit);
  });
  let hoverQueued = false;
  canvas.addEventListener('pointermove', (e) => {
    if (e.buttons || hoverQueued || !state.model) return;
    hoverQueued = true;
    requestAnimationFrame(() => {
      hoverQueued = false;
      const hit = viewer.pick(e.clientX, e.clientY);
      update({ hoverPart: hit ? state.model.labels[hit.vertex] : null });
    });
  });
  canvas.addEventListener('pointerleave', () => update({ hoverPart: null }));
  subscribe((s, changed) => {
    if (changed.has('hoverPart')) showHover();
    if (changed.has('pose') && s.pick) showPick();
    if (changed.has('pop')) showPick(); // pick was cleared
    // another partition shown (the merge tree's slider), or a new model (or none: a step-by-step run threw the
    // fit away), whose parts and errors are others: the boxes of the last one go (a new click or hover asks
    // again, and says which parts it names)
    if ((changed.has('treeParts') || changed.has('model')) && (s.pick || s.hoverPart !== null)) {
      pickVertex(null);
      update({ hoverPart: null });
    }
    // pose mode shows the rig's rest pose, not the pose the vertex was picked on
    if (changed.has('mode') && s.mode === 'pose' && s.pick) pickVertex(null);
    // into or out of pose mode: the hover box's angles are from another pose
    if (changed.has('mode') && s.hoverPart !== null) showHover();
  });
}
