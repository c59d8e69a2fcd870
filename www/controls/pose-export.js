// The Pose view's files of what it shows: the posed mesh (OBJ; the Pose panel's "Posed mesh (OBJ)" and the
// toolbar's "OBJ of the shown mesh") and the pose (.glb, the rig with the pose as a one-frame clip). While added
// frames play or are paused on one, that is the frame on screen (solved onto the rig); otherwise the pose made.
// The core writes both (the poser: src/export/pose_glb.rs, through the worker's pose queries). The poser's OBJ
// has no part groups: its mesh is the rig's, which no shown-mesh descriptor of the toolbar's export names.
import { query } from '../session.js';
import { download, safeName, populationStem } from '../download.js';

// pose.js says what the view shows: { frame (index, -1 for the pose made), name (for the file's name), header }
let shown = () => null;

/** Called by pose.js with a function returning what the Pose view shows (above), or null before its rig. */
export const describePoseShown = (f) => {
  shown = f;
};

function what() {
  const s = shown();
  if (!s) throw new Error('the Pose view is still building its rig: export when the pose is shown');
  return s;
}

const fileName = (s, ext) => `posemfa-${populationStem()}-${s.frame >= 0 ? `frame-${safeName(s.name)}` : 'pose'}.${ext}`;

/** Downloads the OBJ of the mesh the Pose view shows (original units, the population's faces). */
export async function exportPoseObj() {
  const s = what();
  const text = s.frame >= 0 ? await query('poseFrameObj', s.frame, s.header) : await query('poseObj', s.header);
  download(fileName(s, 'obj'), text, 'model/obj');
}

/** Downloads the rig .glb with the pose the Pose view shows as its one-frame clip "pose". */
export async function exportPoseGlb() {
  const s = what();
  download(fileName(s, 'glb'), s.frame >= 0 ? await query('poseFrameGlb', s.frame) : await query('poseGlb'), 'model/gltf-binary');
}
