// Pose mode's drag (issue 28; www/controls/pose.js installs it): a part of the mesh turned about its joint by the
// pointer. The core turns it (the poser's turn, through the worker's pose queries); this file reads the pointer.
import { state } from '../state.js';
import { query } from '../session.js';
import { viewer } from '../views/viewer-instance.js';

const $ = (id) => document.getElementById(id);

// Drag: pointer down on a part (capture phase, before the orbit controls) selects it; moving turns it about the
// view direction through its joint, by the angle the pointer sweeps around the joint on the screen: the part
// follows the pointer whichever way it goes. Within NEAR pixels of the joint the angle is not read (it jumps
// there). The pose before the drag goes on the undo stack at its first turn (a click that turns nothing adds
// no undo step).
const NEAR = 8;
const SWEPT = 1e-6; // radians: less is rounding
/** Installs the drag on the view. `pose`: pose mode's state (pose.js: skeleton, bone, dragging); `remember`
 * puts the pose on the undo stack, `turn(bone, angle)` turns a part (queued), `showAngle` shows the part's angle. */
export function installPoseDrag(pose, { remember, turn, showAngle }) {
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
    const mine = { bone, pivot: null, last: null, remembered: false };
    drag = mine;
    pose.dragging = bone;
    pose.bone = bone;
    $('pose-part').value = String(bone);
    showAngle();
    query('poseJoint', bone).then((j) => {
      if (drag !== mine) return;
      mine.pivot = viewer.screenPoint(hit.slot, j);
      mine.last = viewer.angleAround(mine.pivot, e.clientX, e.clientY, NEAR);
    }, (err) => {
      // no joint to turn about (the model changed under the press): the drag turns nothing, and says why
      if (drag === mine) drag = null;
      $('pose-status').textContent = err.message ?? String(err);
    });
  }, { capture: true });
  window.addEventListener('pointermove', async (e) => {
    if (!drag?.pivot) return;
    const now = viewer.angleAround(drag.pivot, e.clientX, e.clientY, NEAR);
    if (now === null) {
      drag.last = null;
      return;
    }
    if (drag.last !== null) {
      let d = now - drag.last;
      if (d > Math.PI) d -= 2 * Math.PI;
      if (d < -Math.PI) d += 2 * Math.PI;
      pending += d;
    }
    drag.last = now;
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
    drag = null;
    pose.dragging = -1;
  });
}
