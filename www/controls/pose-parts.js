// Pose mode's parts as a person reads them: the Part list's names (where a part is in the skeleton,
// how much of the mesh it is, its colour), what a drag shows (the parts that turn in their colours, the rest
// greyed, the joint marked), and the rows of the hover box (a bounded list: a character's 399 frames would run
// off the view). Nothing here is computed but colours and counts of the core's skeleton.
import * as THREE from 'three';
import { viewer } from '../views/viewer-instance.js';

const GREY = [0.8, 0.81, 0.83];
const DIM = 0.75; // how far the parts that do not turn go toward grey while a part is dragged

/** Whether bone b is `bone` or carried by it (its subtree: what a turn of `bone` moves). */
export function inSubtree(skeleton, bone, b) {
  for (; b >= 0; b = skeleton.parent[b]) if (b === bone) return true;
  return false;
}

/** The Part list's short name of bone k: "part 7 · on part 3 · 4 %" (the root: "part 1 · root · 40 %"). */
export function partShort(skeleton, k) {
  const n = skeleton.boneOfVertex.length;
  let own = 0;
  for (let v = 0; v < n; v++) if (skeleton.boneOfVertex[v] === k) own++;
  const p = skeleton.parent[k];
  return `${skeleton.names[k]} · ${p < 0 ? 'root' : `on ${skeleton.names[p]}`} · ${own / n < 0.01 ? '<1' : Math.round((100 * own) / n)} %`;
}

/** The line under the Part list for bone k: "part 7: on part 3, carries 2 parts, 4 % of the mesh"; the root's says
 * it turns the whole body. */
export function partLabel(skeleton, k) {
  const n = skeleton.boneOfVertex.length;
  let own = 0;
  for (let v = 0; v < n; v++) if (skeleton.boneOfVertex[v] === k) own++;
  const share = `${own / n < 0.01 ? '<1' : Math.round((100 * own) / n)} % of the mesh`;
  const below = skeleton.order.filter((b) => b !== k && inSubtree(skeleton, k, b)).length;
  const carries = below ? `, carries ${below} part${below === 1 ? '' : 's'}` : ', an end part';
  const p = skeleton.parent[k];
  if (p < 0) return `${skeleton.names[k]}: the root (turns the whole body), ${share}`;
  return `${skeleton.names[k]}: on ${skeleton.names[p]}${carries}, ${share}`;
}

/** The colours of pose mode while `bone` is dragged: the vertices it turns (its subtree's) keep theirs, the rest
 * go toward grey. */
export function draggedColours(colours, skeleton, bone) {
  const turns = skeleton.order.map((_, b) => inSubtree(skeleton, bone, b));
  const out = Float32Array.from(colours);
  const n = skeleton.boneOfVertex.length;
  for (let v = 0; v < n; v++) {
    if (turns[skeleton.boneOfVertex[v]]) continue;
    for (let c = 0; c < 3; c++) out[3 * v + c] = colours[3 * v + c] * (1 - DIM) + GREY[c] * DIM;
  }
  return out;
}

let marker = null;
/** A ring-and-dot mark on the joint being dragged, drawn over the mesh (null: none). `point`: xyz in the shown
 * mesh's coordinates (slot 0). */
export function markJoint(point) {
  if (!marker) {
    const on = { depthTest: false, transparent: true };
    marker = new THREE.Group();
    marker.add(new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0x111111, ...on })));
    const ring = new THREE.Mesh(new THREE.RingGeometry(1.8, 2.4, 32), new THREE.MeshBasicMaterial({ color: 0xffffff, side: THREE.DoubleSide, ...on }));
    marker.add(ring);
    marker.renderOrder = 10;
    marker.traverse((o) => { o.renderOrder = 10; });
    viewer.scene.add(marker);
  }
  const slot = viewer.slots[0];
  marker.visible = !!(point && slot);
  if (marker.visible) {
    marker.position.set(point[0], point[1], point[2]).add(slot.mesh.position);
    marker.scale.setScalar(0.018 * (slot.mesh.geometry.boundingSphere?.radius ?? 1));
    marker.quaternion.copy(viewer.camera.quaternion); // the ring faces the camera
  }
  viewer.requestRender();
}

/** Whether the joint mark is shown, and where on the screen (client pixels), for the tests. */
export const jointMark = () => (marker?.visible ? viewer.screenPoint(0, marker.position.clone().sub(viewer.slots[0].mesh.position).toArray()) : null);

/** The rows a hover box lists of `n` values (`key(i)`: the value of row i): all of them up to MAX_ROWS, else the
 * TOP largest (in pose order), with { more: how many are left out }. */
export const MAX_ROWS = 12;
const TOP = 6;
export function boundedRows(n, key) {
  const all = Array.from({ length: n }, (_, i) => i);
  if (n <= MAX_ROWS) return { rows: all, more: 0 };
  const top = all.sort((a, b) => key(b) - key(a)).slice(0, TOP).sort((a, b) => a - b);
  return { rows: top, more: n - TOP };
}

/** Median and largest of the values (for the summary line over a bounded list). */
export function spread(values) {
  const s = Array.from(values).sort((a, b) => a - b);
  return { median: s[Math.floor(s.length / 2)] ?? 0, max: s[s.length - 1] ?? 0 };
}
