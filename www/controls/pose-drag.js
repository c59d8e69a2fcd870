// Pose mode's drag (issue 28; www/controls/pose.js installs it): a part of the mesh turned about its joint by the
// pointer. The core turns it (the poser's turn, through the worker's pose queries); this file reads the pointer.
import { state, update } from '../state.js';
import { query } from '../session.js';
import { viewer } from '../views/viewer-instance.js';

const $ = (id) => document.getElementById(id);

// Drag: pointer down on a part (capture phase, before the orbit controls) selects it; moving turns it about the
// view direction through its joint, by the angle the pointer sweeps around the joint on the screen, scaled by
// how far out the pointer is against the reach of what turns (the part and the parts it carries, on the
// screen): held at its far end or beyond, the part follows the pointer; held near its joint, a move turns it
// by the distance moved over that reach (a trackball's gain), not by the large angle a short move sweeps there
// (issue 55: 70 px near the horse's neck turned its head 138°). Within NEAR pixels of the joint the angle is
// not read (it jumps there). The pose before the drag goes on the undo stack at its first turn (a click that
// turns nothing adds no undo step). While dragging, the parts that turn are shown in their colours and the rest
// greyed, and the joint is marked (pose.js poseView, views/joint-marker.js).
const NEAR = 8;
const SWEPT = 1e-6; // radians: less is rounding
const MIN_REACH = 60; // pixels: a part small on the screen still turns by at most 1 radian per 60 px

// How far the vertices that `bone`'s turn moves reach from the joint on the screen (pixels): the largest
// distance over (a sample of) them. `positions`: the pose shown (flat xyz), `moves(v)`: whether vertex v turns.
function reachOnScreen(positions, moves, pivot) {
  const n = positions.length / 3;
  const step = Math.max(1, Math.floor(n / 4000));
  let far = 0;
  for (let v = 0; v < n; v += step) {
    if (!moves(v)) continue;
    const p = viewer.screenPoint(0, [positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]]);
    far = Math.max(far, viewer.screenDistance(p, pivot));
  }
  return Math.max(far, MIN_REACH);
}
/** Installs the drag on the view. `pose`: pose mode's state (pose.js: skeleton, bone, dragging); `remember`
 * puts the pose on the undo stack, `turn(bone, angle)` turns a part (queued), `showAngle` shows the part's angle,
 * `highlight(bone, joint)` shows what is dragged (bone -1: nothing). */
export function installPoseDrag(pose, { remember, turn, showAngle, highlight }) {
  const view = $('view');
  let drag = null;
  let busy = false;
  let pending = 0;
  view.addEventListener('pointerdown', (e) => {
    if (state.mode !== 'pose' || !pose.skeleton || e.button !== 0) return;
    const hit = viewer.pick(e.clientX, e.clientY);
    if (!hit) return;
    e.stopPropagation();
    e.preventDefault();
    const bone = pose.skeleton.boneOfVertex[hit.vertex];
    update({ hoverPart: null }); // the hover box goes while a part is dragged (it would cover what moves)
    const mine = { bone, slot: hit.slot, joint: null, pivot: null, last: null, lastR: 0, x: e.clientX, y: e.clientY, reach: MIN_REACH, remembered: false };
    drag = mine;
    pose.dragging = bone;
    pose.bone = bone;
    $('pose-part').value = String(bone);
    showAngle();
    query('poseJoint', bone).then((j) => {
      if (drag !== mine) return;
      mine.joint = j;
      mine.pivot = viewer.screenPoint(hit.slot, j);
      mine.last = viewer.angleAround(mine.pivot, e.clientX, e.clientY, NEAR);
      mine.lastR = viewer.screenDistance({ x: e.clientX, y: e.clientY }, mine.pivot);
      const sk = pose.skeleton;
      const inTree = (b) => { for (; b >= 0; b = sk.parent[b]) if (b === bone) return true; return false; };
      const turns = sk.order.map((_, b) => inTree(b));
      mine.reach = reachOnScreen(pose.positions, (v) => turns[sk.boneOfVertex[v]], mine.pivot);
      pose.dragReach = mine.reach;
      highlight(bone, j);
    }, (err) => {
      // no joint to turn about (the model changed under the press): the drag turns nothing, and says why
      if (drag === mine) drag = null;
      $('pose-status').textContent = err.message ?? String(err);
    });
  }, { capture: true });
  window.addEventListener('pointermove', async (e) => {
    if (!drag?.pivot) return;
    // the joint where the view shows it now: the camera may have moved since the press (a glide of the orbit
    // controls, a new frame), and an angle swept around where the joint was is not one swept around the joint
    const pivot = viewer.screenPoint(drag.slot, drag.joint);
    if (viewer.screenDistance(pivot, drag.pivot) > 1e-3) {
      drag.pivot = pivot;
      drag.last = viewer.angleAround(pivot, drag.x, drag.y, NEAR);
      drag.lastR = viewer.screenDistance({ x: drag.x, y: drag.y }, pivot);
    }
    drag.x = e.clientX;
    drag.y = e.clientY;
    const now = viewer.angleAround(drag.pivot, e.clientX, e.clientY, NEAR);
    const r = viewer.screenDistance({ x: e.clientX, y: e.clientY }, drag.pivot);
    if (now === null) {
      drag.last = null;
      return;
    }
    if (drag.last !== null) {
      let d = now - drag.last;
      if (d > Math.PI) d -= 2 * Math.PI;
      if (d < -Math.PI) d += 2 * Math.PI;
      // the gain: the angle swept, times how far out the pointer is against the reach of what turns (at most 1)
      pending += d * Math.min(1, (r + drag.lastR) / 2 / drag.reach);
    }
    drag.last = now;
    drag.lastR = r;
    // (a move straight at or away from the joint sweeps nothing but rounding)
    if (busy || Math.abs(pending) < SWEPT) return;
    busy = true;
    const mine = drag;
    try {
      if (!mine.remembered) {
        mine.remembered = true;
        await remember();
      }
      // what the pointer swept while a turn was on its way is turned next, also after the pointer stops
      while (Math.abs(pending) >= SWEPT) {
        const angle = pending;
        pending = 0;
        await turn(mine.bone, angle);
      }
    } finally {
      busy = false;
    }
  });
  window.addEventListener('pointerup', () => {
    if (drag) highlight(-1, null);
    drag = null;
    pose.dragging = -1;
  });
}
