// The labels over the meshes shown side by side (www/viewer.js's setLabels / placeLabels): one label per mesh
// (HTML over the canvas, .pane-label), placed over its mesh at every frame, so that the panes say what they are
// where they are, also after the camera moved.
import * as THREE from 'three';

/** Sets the labels' texts (one per mesh; '' hides one). */
export function setLabels(viewer, texts) {
  viewer.labels ??= [];
  while (viewer.labels.length > texts.length) viewer.labels.pop().remove();
  while (viewer.labels.length < texts.length) {
    const el = document.createElement('div');
    el.className = 'pane-label';
    viewer.container.appendChild(el);
    viewer.labels.push(el);
  }
  texts.forEach((t, k) => {
    viewer.labels[k].textContent = t;
    viewer.labels[k].hidden = !t;
  });
}

/** Each label centred over the top of its mesh's box on the screen, kept inside the view. */
export function placeLabels(viewer) {
  if (!viewer.labels?.length) return;
  const w = viewer.container.clientWidth;
  const h = viewer.container.clientHeight;
  const { up } = viewer.axes;
  viewer.labels.forEach((el, k) => {
    const s = viewer.slots[k];
    if (!s || el.hidden) return;
    const box = new THREE.Box3().setFromObject(s.mesh);
    const top = box.getCenter(new THREE.Vector3()).setComponent(up, box.max.getComponent(up)).project(viewer.camera);
    const half = el.offsetWidth / 2;
    const x = Math.min(Math.max(((top.x + 1) / 2) * w, half + 2), w - half - 2);
    const y = Math.min(Math.max(((1 - top.y) / 2) * h, el.offsetHeight + 2), h - 2);
    el.style.left = `${x}px`;
    el.style.top = `${y}px`;
  });
}
