// Pose mode's drag (www/controls/pose.js installs it): a part of the mesh turned about its joint by the
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
// (read as a swept angle, 70 px near the horse's neck turned its head 138°). Within NEAR pixels of the joint the angle is
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
    console.log('PD', state.mode, !!pose.skeleton, e.button, JSON.stringify(viewer.pick(e.clientX, e.clientY)));
    if (state.mode !== 'pose' || !pose.skeleton || e.button !== 0) return;
    const hit = viewer.pick(e.clientX, e.clientY);
    if (!hit) return;
    e.stopPropagation();
    e.preventDefault();
    const bone = pose.skeleton.boneOfVertex[hit.vertex];
    update({ hoverPart: null }); // the hover box goes while a part is dragged (it would cover what moves)
    // x, y: the pointer's last place measured against the joint. The moves that come before the worker has said
    // where the joint is wait in `early` and are measured when it has, also after a release: a quick drag on a
    // busy machine is not lost.
    const mine = { bone, slot: hit.slot, joint: null, pivot: null, last: null, lastR: 0, x: e.clientX, y: e.clientY,
      early: [], released: false, reach: MIN_REACH, remembered: false };
    drag = mine;
    pose.dragging = bone;
    pose.bone = bone;
    $('pose-part').value = String(bone);
    showAngle();
    query('poseJoint', bone).then((j) => {
      if (drag !== mine && !mine.released) return;
      mine.joint = j;
      mine.pivot = viewer.screenPoint(hit.slot, j);
      mine.last = viewer.angleAround(mine.pivot, e.clientX, e.clientY, NEAR);
      mine.lastR = viewer.screenDistance({ x: e.clientX, y: e.clientY }, mine.pivot);
      const sk = pose.skeleton;
      const inTree = (b) => { for (; b >= 0; b = sk.parent[b]) if (b === bone) return true; return false; };
      const turns = sk.order.map((_, b) => inTree(b));
      mine.reach = reachOnScreen(pose.positions, (v) => turns[sk.boneOfVertex[v]], mine.pivot);
      pose.dragReach = mine.reach;
      if (!mine.released) highlight(bone, j);
      for (const [x, y] of mine.early) moveTo(mine, x, y);
      mine.early = [];
    }, (err) => {
      // no joint to turn about (the model changed under the press): the drag turns nothing, and says why
      if (drag === mine) drag = null;
      $('pose-status').textContent = err.message ?? String(err);
    });
  }, { capture: true });
  window.addEventListener('pointermove', (e) => {
    if (!drag) return;
    if (drag.pivot) moveTo(drag, e.clientX, e.clientY);
    else drag.early.push([e.clientX, e.clientY]);
  });
  // The pointer of the drag `g` at (x, y) on the screen: the angle swept around the joint since its last place
  // is turned.
  async function moveTo(g, x, y) {
    // the joint where the view shows it now: the camera may have moved since the press (a glide of the orbit
    // controls, a new frame), and an angle swept around where the joint was is not one swept around the joint
    const pivot = viewer.screenPoint(g.slot, g.joint);
    if (viewer.screenDistance(pivot, g.pivot) > 1e-3) {
      g.pivot = pivot;
      g.last = viewer.angleAround(pivot, g.x, g.y, NEAR);
      g.lastR = viewer.screenDistance({ x: g.x, y: g.y }, pivot);
    }
    g.x = x;
    g.y = y;
    const now = viewer.angleAround(g.pivot, x, y, NEAR);
    const r = viewer.screenDistance({ x, y }, g.pivot);
    if (now === null) {
      g.last = null;
      return;
    }
    if (g.last !== null) {
      let d = now - g.last;
      if (d > Math.PI) d -= 2 * Math.PI;
      if (d < -Math.PI) d += 2 * Math.PI;
      // the gain: the angle swept, times how far out the pointer is against the reach of what turns (at most 1)
      pending += d * Math.min(1, (r + g.lastR) / 2 / g.reach);
    }
    g.last = now;
    g.lastR = r;
    // (a move straight at or away from the joint sweeps nothing but rounding)
    if (busy || Math.abs(pending) < SWEPT) return;
    busy = true;
    try {
      if (!g.remembered) {
        g.remembered = true;
        await remember();
      }
      // what the pointer swept while a turn was on its way is turned next, also after the pointer stops
      while (Math.abs(pending) >= SWEPT) {
        const angle = pending;
        pending = 0;
        await turn(g.bone, angle);
      }
    } finally {
      busy = false;
    }
  }
  window.addEventListener('pointerup', () => {
    if (drag) {
      drag.released = true;
      highlight(-1, null);
    }
    drag = null;
    pose.dragging = -1;
  });
}
