// Pose mode: make a pose of one's own from the fitted rig. Click a part and drag to turn it (and the
// parts it carries) about its joint, around the view direction; or pick the part in the list and turn it with the
// buttons (keyboard). The angle from the rest pose is shown; Undo and Reset. The pose space: sliders along the
// principal modes of the training poses' joint rotations (0 = the mean pose), "Random pose" within the training
// range. Export the posed mesh (OBJ) and the pose (.glb with a one-frame clip). "Add frames": frames of the same
// mesh solved onto the rig (the bones with the weights fixed) and played. Everything is computed by the core
// (src/export/pose_glb.rs, through the worker's pose queries); this file only shows and asks (the drag:
// pose-drag.js; the files of what is shown: pose-export.js).
import { state, subscribe } from '../state.js';
import { query } from '../session.js';
import { viewer } from '../views/viewer-instance.js';
import { renderView, registerView } from '../views/render.js';
import { showProblems } from '../problems.js';
import { eRmsText, ERMS_UNIT } from '../erms.js';
import { download, populationStem } from '../download.js';
import { describePoseShown, exportPoseObj, exportPoseGlb } from './pose-export.js';
import { installPoseDrag } from './pose-drag.js';
import { partLabel, partShort, draggedColours, markJoint, jointMark } from './pose-parts.js';

const $ = (id) => document.getElementById(id);
const STEP = (10 * Math.PI) / 180; // a button press: 10 degrees

// What pose mode shows: the skeleton of the poser, the current mesh and angles, the undo stack, added frames.
// whole: what the last action made of the whole pose ('random', 'mean', 'modes', 'rest', 'training': training
// pose `training` as the rig makes it), null after a part was turned (the caption then names that part)
const pose = { gen: -1, starting: null, skeleton: null, positions: null, angles: null, bone: -1, dragging: -1, highlight: -1, whole: null, training: 0, undo: [], frames: null, frame: 0, playing: false };

// the pose space's modes come largest first (the core's PCA of the training poses); the first few get a slider
const MODE_SLIDERS = 6;

/** The rest pose of pose mode: the training pose the rig is bound in (every bone's motion the identity), as
 * the core chose it (skeleton.bindPose: the rig export's default, the file named "reference", else the first
 * pose, so the .glb export is bound in the same pose); the mesh is that pose as the rig rebuilds it (its rigid
 * reconstruction, eq 22, with the fitted weights' bind positions: src/articulate/rig.rs). */
export const restPose = () => pose.skeleton?.bindPose ?? 0;
const restName = () => `“${state.pop.names[restPose()]}”`;

/** The mesh pose mode shows (for views/render.js), or null before the poser is ready. */
export async function poseView() {
  await ensureStarted();
  const frames = frameShown() >= 0;
  const positions = frames ? pose.frames.positions[pose.frame] : pose.positions;
  const name = frames ? `frame ${pose.frames.names[pose.frame]}` : 'posed';
  const caption = frames
    ? `Added ${frameWords()} (${pose.frame + 1} of ${pose.frames.names.length}) solved onto the rig: E_RMS ${eRmsText(pose.frames.eRms[pose.frame])} (${ERMS_UNIT})`
    : pose.whole || pose.bone >= 0
      ? `Pose mode: ${madeWords()} (drag a part to turn it about its joint)`
      : `Pose mode: ${madeWords()}; drag a part to turn it about its joint (one too thin to grab: choose it in the Part list, then ↺ / ↻)`;
  // while a part is dragged, what turns keeps its colours and the rest is greyed (pose-parts.js)
  const colours = !frames && pose.highlight >= 0
    ? draggedColours(state.colours.final.vertexColours, pose.skeleton, pose.highlight)
    : state.colours.final.vertexColours;
  // stay: a part turned, the rest of the mesh stays where it is on the screen (not centred on the new box)
  return { slots: [{ positions, colours, name }], caption, stay: true };
}

/** The bone of part `part` (the rig's joint named after it: src/export/gltf.rs names it "part k+1"), or -1. */
export const boneOfPart = (part) => pose.skeleton?.names.indexOf(`part ${part + 1}`) ?? -1;
/** The skeleton of pose mode (null before it is ready). */
export const poseSkeleton = () => (pose.skeleton && pose.gen === state.gen ? pose.skeleton : null);

// The added frame the view shows (while frames play or are paused on one), else -1: the pose made is shown.
const frameShown = () => (pose.frames && pose.showFrames ? pose.frame : -1);
const frameWords = () => `frame “${pose.frames.names[pose.frame]}”`;

// The pose made, in words (the caption's and the posed mesh's OBJ header's).
function madeWords() {
  if (pose.whole) return wholePose();
  if (pose.bone >= 0) return `${pose.skeleton.names[pose.bone]} turned ${pose.angles[pose.bone].toFixed(1)}° from the rest pose ${restName()} at its joint`;
  return `the rest pose, the rig's bind pose (${restName()} rebuilt from its parts)`;
}

// What the Pose view's exports write (www/controls/pose-export.js): the frame shown, else the pose made.
describePoseShown(() => {
  if (!pose.skeleton || pose.gen !== state.gen) return null;
  const f = frameShown();
  return f >= 0
    ? { frame: f, name: pose.frames.names[f], header: `frame ${pose.frames.names[f]} solved onto the rig (posemfa pose mode): E_RMS ${eRmsText(pose.frames.eRms[f])} (${ERMS_UNIT})` }
    : { frame: -1, name: 'pose', header: `a pose made in posemfa pose mode: ${madeWords()}` };
});

// The caption's words for a pose made of all the parts at once (pose.whole).
function wholePose() {
  const n = pose.skeleton.order.length;
  return {
    random: `a random pose of all ${n} part${n === 1 ? '' : 's'}, within the training poses' range`,
    mean: 'the mean pose of the training poses',
    modes: 'a pose from the pose-space sliders (0 = the mean pose)',
    rest: `the rest pose, the rig's bind pose (${restName()} rebuilt from its parts)`,
    training: `training pose “${state.pop.names[pose.training]}” as the rig makes it (its bones solved onto the rig)`,
  }[pose.whole];
}

async function ensureStarted() {
  if (pose.gen === state.gen && pose.skeleton) return;
  if (pose.starting && pose.startGen === state.gen) return pose.starting;
  pose.startGen = state.gen;
  $('pose-status').textContent = 'building the rig…';
  pose.starting = (async () => {
    const r = await query('poseStart', {});
    pose.gen = state.gen;
    pose.skeleton = r.skeleton;
    pose.trainingAngles = r.trainingAngles;
    pose.positions = r.positions;
    pose.angles = r.angles;
    pose.bone = -1;
    pose.whole = null;
    pose.undo = [];
    pose.frames = null;
    pose.showFrames = false;
    fillControls();
    setModeSliders(r.coords); // the rest pose's coordinates (0 would be the mean pose, not the one shown)
    const n = r.skeleton.nModes;
    const sliders = Math.min(n, MODE_SLIDERS);
    $('pose-status').textContent = `${r.skeleton.order.length} bones, ${n} pose-space direction${n === 1 ? '' : 's'}: the main directions of the training poses' joint rotations (0: their mean pose; ±: their spread, one standard deviation)${n > sliders ? `; sliders for the ${sliders} largest` : ''}`;
    document.body.dataset.pose = 'ready';
  })();
  try {
    await pose.starting;
  } finally {
    pose.starting = null;
  }
}

function fillControls() {
  const sel = $('pose-part');
  // listed by name, numbers in order ("part 2" before "part 10"), not in the skeleton's parent-first order
  const byName = pose.skeleton.order.slice().sort((a, b) => pose.skeleton.names[a].localeCompare(pose.skeleton.names[b], undefined, { numeric: true }));
  // each named where it is (on which part, what it carries, its share of the mesh) in its colour
  const colour = (k) => state.colours.final?.partColour?.[Number(pose.skeleton.names[k].replace(/\D+/g, '')) - 1];
  sel.replaceChildren(...byName.map((k) => {
    const o = Object.assign(document.createElement('option'), { value: String(k), textContent: `■ ${partShort(pose.skeleton, k)}`, title: partLabel(pose.skeleton, k) });
    if (colour(k)) o.style.color = colour(k);
    return o;
  }));
  const box = $('pose-modes');
  // The modes are the principal components of the training poses' joint rotations (src/articulate/pose.rs
  // PoseSpace: every non-root joint's rotation from the rest pose, relative to its parent, as axis x angle);
  // sd: the training poses' standard deviation along each, the joints' rotations together (radians). The
  // status line says so (ensureStarted).
  box.replaceChildren();
  const shown = Math.min(pose.skeleton.nModes, MODE_SLIDERS);
  for (let m = 0; m < shown; m++) {
    const [lo, hi] = pose.skeleton.range[m];
    const pad = 0.25 * (hi - lo);
    const label = document.createElement('label');
    const input = Object.assign(document.createElement('input'), { type: 'range', min: String(lo - pad), max: String(hi + pad), step: String((hi - lo) / 200 || 0.001), value: '0' });
    input.dataset.mode = String(m);
    input.dataset.testid = `pose-mode-${m}`;
    const spread = (pose.skeleton.sd[m] * 180 / Math.PI).toFixed(1);
    input.setAttribute('aria-label', `pose-space direction ${m + 1}`);
    input.addEventListener('input', () => applyModes());
    label.title = `pose-space direction ${m + 1}: the training poses spread ±${spread}° along it (one standard deviation of their joint rotations)`;
    label.append(`direction ${m + 1} (±${spread}°) `, input);
    box.append(label);
  }
  showAngle();
}

function modeValues() {
  return [...document.querySelectorAll('#pose-modes input')].map((i) => Number(i.value));
}

function setModeSliders(coeffs) {
  for (const i of document.querySelectorAll('#pose-modes input')) i.value = String(coeffs[Number(i.dataset.mode)] ?? 0);
}

// The part's angle, read against the training poses': a pose made past them is the rig's guess, not learnt.
function showAngle() {
  const k = Number($('pose-part').value);
  const [a, most] = [pose.angles?.[k], pose.trainingAngles?.[k]];
  const beyond = a !== undefined && most !== undefined && a > most + 0.05;
  const against = most === undefined ? '' : beyond ? ` (beyond the training poses, which turn it at most ${most.toFixed(1)}°)` : ` (training poses: up to ${most.toFixed(1)}°)`;
  // what the angle is of: the turn at the part's joint, relative to the part that carries it (the root: its own)
  const p = pose.skeleton?.parent[k];
  const at = p === undefined ? '' : p < 0 ? ' (the root: its own turn)' : ` at its joint, relative to ${pose.skeleton.names[p]}`;
  $('pose-angle').textContent = a !== undefined && k >= 0 ? `${a.toFixed(1)}°${at}${against}` : '–';
  $('pose-angle').classList.toggle('beyond', beyond);
  $('pose-part-about').textContent = pose.skeleton && k >= 0 ? partLabel(pose.skeleton, k) : '';
  $('pose-undo').disabled = pose.undo.length === 0;
}

// A pose shown: its positions and angles; `sliders`: the pose-space sliders follow it (its coordinates along the
// modes; not when the sliders themselves made it)
function took(r, { sliders = true } = {}) {
  if (sliders) query('poseVector').then((v) => setModeSliders(v.coords), (e) => { $('pose-status').textContent = e.message; });
  pose.positions = r.positions;
  pose.angles = r.angles;
  pose.showFrames = false;
  if (pose.playing) playFrames(); // a pose made while frames play: pause them, show the pose
  showAngle();
  renderView();
}

// the undo stack keeps what the caption said of each pose with its bones (pose.whole)
async function remember() {
  const { whole, training } = pose;
  pose.undo.push({ bones: await query('poseBones'), whole, training });
  if (pose.undo.length > 100) pose.undo.shift();
}

// The user's pose actions run one after another in the order they were asked for: a Random pose clicked just
// before Add frames must not land after the frames and hide them. A queued action must never call another
// queued one (it would wait for itself): inside them, call the plain functions (turnPart, not turn).
let queue = Promise.resolve();
const orReport = (f) => (...a) => {
  const run = queue.then(async () => {
    try {
      await f(...a);
    } catch (e) {
      $('pose-status').textContent = e.message ?? String(e);
      if (e.problems) showProblems(e.problems, 'Pose mode');
    }
  });
  queue = run;
  return run;
};

/** Shows training pose i as the rig makes it (its bones solved onto the rig): a thumbnail or the pose list
 * picked in the Pose view. */
export const showTrainingPose = orReport(async (i) => {
  await ensureStarted();
  await remember();
  pose.whole = 'training';
  pose.training = i;
  took(await query('poseTraining', i));
});

// The pose-space sliders follow the added frame shown (its coordinates along the modes, from the core; an
// answer for a frame no longer shown is dropped). Frames the core gave no bones for leave them where they are.
function followFrame() {
  const f = pose.frame;
  if (!pose.frames?.bonesKept) return;
  query('poseFrameVector', f).then((v) => frameShown() === f && setModeSliders(v.coords), (e) => { $('pose-status').textContent = e.message; });
}

// The view direction (camera -> scene): turns are about it, so a part turns in the plane of the screen.
function viewAxis() {
  const v = viewer.camera.getWorldDirection(new viewer.camera.position.constructor());
  return [v.x, v.y, v.z];
}

// Turns `bone` by `angle` about the view direction (inside a queued action; the drag queues it with `turn`).
async function turnPart(bone, angle) {
  pose.bone = bone;
  pose.whole = null;
  $('pose-part').value = String(bone);
  took(await query('poseTurn', bone, viewAxis(), angle));
}
const turn = orReport(turnPart);

// whole: what the caption calls the pose made (pose.whole): the sliders' own, or the mean or random pose they show
async function applyModes(whole = 'modes') {
  if (!pose.skeleton) return;
  pose.whole = whole;
  took(await query('poseModes', modeValues()), { sliders: false });
}

// Play the added frames: one frame per half second, looping, until Pause.
function playFrames() {
  if (!pose.frames) return;
  if (pose.playing) {
    pose.playing = false;
    $('pose-play').textContent = 'Play frames';
    return;
  }
  pose.playing = true;
  pose.showFrames = true;
  $('pose-play').textContent = 'Pause';
  let last = 0;
  const tick = (now) => {
    if (!pose.playing) return;
    if (now - last > 500) {
      last = now;
      pose.frame = (pose.frame + 1) % pose.frames.names.length;
      document.body.dataset.poseFrame = String(pose.frame);
      followFrame();
      renderView();
    }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}

export function installPose() {
  registerView('pose', poseView, { pending: 'Pose mode: building the rig… (the mesh shown is still the last view\'s)' });
  installPoseDrag(pose, {
    remember, turn, showAngle,
    highlight: (bone, joint) => {
      pose.highlight = bone;
      markJoint(bone >= 0 ? joint : null);
      renderView();
    },
  });
  $('pose-part').addEventListener('change', () => {
    pose.bone = Number($('pose-part').value);
    pose.whole = null;
    showAngle();
    renderView();
  });
  $('pose-minus').addEventListener('click', orReport(async () => {
    await remember();
    await turnPart(Number($('pose-part').value), -STEP);
  }));
  $('pose-plus').addEventListener('click', orReport(async () => {
    await remember();
    await turnPart(Number($('pose-part').value), STEP);
  }));
  $('pose-undo').addEventListener('click', orReport(async () => {
    const last = pose.undo.pop();
    if (!last) return;
    const r = await query('poseSetBones', Array.from(last.bones));
    pose.whole = last.whole;
    pose.training = last.training;
    took(r);
  }));
  $('pose-reset').addEventListener('click', orReport(async () => {
    await remember();
    pose.whole = 'rest';
    took(await query('poseReset'));
  }));
  $('pose-mean').addEventListener('click', orReport(async () => {
    await remember();
    setModeSliders([]);
    await applyModes('mean');
  }));
  $('pose-random').addEventListener('click', orReport(async () => {
    await remember();
    const c = await query('poseRandom', Math.floor(Math.random() * 2 ** 31));
    setModeSliders(Array.from(c));
    pose.whole = 'random';
    took(await query('poseModes', Array.from(c)), { sliders: false });
  }));
  $('pose-export-obj').addEventListener('click', orReport(exportPoseObj));
  $('pose-export-glb').addEventListener('click', orReport(exportPoseGlb));
  $('pose-frames').addEventListener('change', orReport(async (e) => {
    const files = [...e.target.files];
    if (!files.length) return;
    $('pose-status').textContent = `solving ${files.length} files onto the rig…`;
    const bytes = await Promise.all(files.map((f) => f.arrayBuffer()));
    const r = await query('poseAddFrames', files.map((f) => f.name), bytes);
    pose.frames = r;
    pose.frame = 0;
    showProblems([]); // an earlier refusal of frames is answered
    const mean = r.eRmsAll; // over all the frames, from the core
    $('pose-status').textContent = `${r.names.length} frames solved onto the rig: E_RMS ${eRmsText(mean)}`;
    $('pose-status').dataset.erms = String(mean);
    $('pose-play').disabled = false;
    $('pose-export-frames').disabled = false;
    document.body.dataset.poseFrames = String(r.names.length);
    playFrames();
  }));
  $('pose-play').addEventListener('click', playFrames);
  $('pose-export-frames').addEventListener('click', () => pose.frames && download(`posemfa-${populationStem()}-frames.glb`, pose.frames.glb, 'model/gltf-binary'));
  subscribe((s, changed) => {
    if (changed.has('mode')) {
      $('pose-panel').hidden = s.mode !== 'pose';
      if (s.mode !== 'pose' && pose.playing) playFrames();
    }
    if (changed.has('gen')) {
      pose.skeleton = null;
      pose.frames = null;
      pose.playing = false;
      document.body.dataset.pose = '';
    }
  });
  // the test contract (window.posemfa.pose): what pose mode shows, and its questions to the core
  window.posemfa = Object.assign(window.posemfa ?? {}, {
    pose: {
      ready: () => !!pose.skeleton && pose.gen === state.gen,
      skeleton: () => pose.skeleton,
      positions: () => pose.positions && Array.from(pose.positions),
      angles: () => pose.angles && Array.from(pose.angles),
      turn: (bone, axis, angle) => query('poseTurn', bone, axis, angle).then((r) => { took(r); return Array.from(r.positions); }),
      joint: (bone) => query('poseJoint', bone).then((j) => Array.from(j)),
      // where a bone's joint is on the screen (client pixels; the drag turns about it)
      jointOnScreen: (bone) => query('poseJoint', bone).then((j) => viewer.screenPoint(0, j)),
      touches: (bone) => query('poseTouches', bone).then((t) => Array.from(t)),
      selected: () => pose.bone,
      // the part a press on the mesh holds (-1: none; a press beside the mesh holds none)
      dragging: () => pose.dragging ?? -1,
      // what a drag shows: the bone highlighted (-1: none), the joint's mark on the screen (null: none), and the
      // reach on the screen (pixels) that the drag's gain is measured against
      // where vertex v of the mesh shown is on the screen (client pixels)
      screenOf: (v) => viewer.screenPoint(0, Array.from(state.shown[0].positions.slice(3 * v, 3 * v + 3))),
      highlighted: () => ({ bone: pose.highlight ?? -1, mark: jointMark(), reach: pose.dragReach ?? null }),
      modes: (c) => query('poseModes', c).then((r) => { took(r); return Array.from(r.positions); }),
      training: (i) => query('poseTraining', i).then((r) => { took(r); return Array.from(r.positions); }),
      vector: () => query('poseVector'),
      frameVector: (f) => query('poseFrameVector', f),
      // the positions the view shows (the made pose or the frame shown)
      shownPositions: () => state.shown[0] && Array.from(state.shown[0].positions),
      frames: () => pose.frames && { names: pose.frames.names, eRms: Array.from(pose.frames.eRms), frame: pose.frame },
    },
  });
}
