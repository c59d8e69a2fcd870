// The camera follows the poses: framed on one pose, a standing pose of a crouching animal had its head and feet cut off
// until "Reset camera", and an interpolation 3 -> 8 a hoof. The view frames (viewer.frame) at least the largest
// extent of any training pose along each axis (each mesh shown is centred on its own box, so a box that holds
// every pose's extent holds every pose), computed once per population; a mesh shown that still outgrows the
// frame (a pose made by hand, an interpolation beyond the poses) frames again, unless the person has moved the
// camera. Poses that fit do not move the camera: no jump on every slider move.
import * as THREE from 'three';

/** The largest extent along x, y and z of any of `poses` (flat xyz arrays). */
export function poseReach(poses) {
  const most = new THREE.Vector3();
  for (const p of poses) {
    const lo = [Infinity, Infinity, Infinity];
    const hi = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < p.length; i += 3) {
      for (let c = 0; c < 3; c++) {
        const x = p[i + c];
        if (x < lo[c]) lo[c] = x;
        if (x > hi[c]) hi[c] = x;
      }
    }
    if (lo[0] <= hi[0]) most.max(new THREE.Vector3(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
  }
  return most;
}

/** Whether the meshes shown now reach past what the camera was last framed for (viewer.framedSize). */
export function outgrows(viewer) {
  if (!viewer.framedSize) return false;
  const box = new THREE.Box3();
  for (const s of viewer.slots) box.expandByObject(s.mesh);
  if (box.isEmpty()) return false;
  const size = box.getSize(new THREE.Vector3());
  return ['x', 'y', 'z'].some((c) => size[c] > viewer.framedSize[c] * 1.002 + 1e-9);
}
