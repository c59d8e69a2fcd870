// The three.js scene: up to three copies of the mesh side by side ("slots", e.g. original | reconstruction),
// per-vertex colours, orbit controls, vertex picking, and pose thumbnails. It renders on demand only, so the
// fit in the worker keeps the CPU.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { viewAxes } from './view-axes.js';
import { flatFacesMaterial, orderFaces } from './flat-faces.js';
import { outgrows } from './views/frame-reach.js';
import { setLabels, placeLabels } from './view-labels.js';

THREE.ColorManagement.enabled = false; // colours go to the screen as given: exact pixels for the tests

const BACKGROUND = 0xeef0f3;

export class Viewer {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    this.renderer.setClearColor(BACKGROUND);
    this.renderer.domElement.tabIndex = 0;
    this.renderer.domElement.setAttribute('aria-label', 'mesh view: drag to orbit, wheel to zoom, click a vertex; keys: arrows pan, Shift+arrows orbit, + and - zoom, 0 resets the camera');
    this.renderer.domElement.addEventListener('keydown', (e) => this.zoomKey(e));
    container.appendChild(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
    // Lights chosen so that lit colours never exceed the vertex colour (no clipping, hues kept).
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a8a, 1.6));
    const key = new THREE.DirectionalLight(0xffffff, 1.4);
    key.position.set(1, 1.5, 2);
    this.camera.add(key);
    this.scene.add(this.camera);

    this.lit = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide });
    this.flatMaterial = flatFacesMaterial(); // one colour per triangle (flat-faces.js)
    this.flat = false;
    this.faces = null;
    this.slots = [];
    this.axes = { view: 2, up: 1, right: 0, side: 1 };

    this.cameraListeners = [];
    this.makeControls();

    this.warmUp();
    this.raycaster = new THREE.Raycaster();
    this.needsRender = false;
    this.resizeObserver = new ResizeObserver(() => this.resize());
    this.resizeObserver.observe(container);
    this.resize();
  }

  /** Frees the WebGL context and removes the canvas (www/mount.js unmount()). */
  dispose() {
    this.disposed = true;
    this.resizeObserver.disconnect();
    this.controls.dispose();
    for (const s of this.slots) this.removeSlot(s);
    this.slots = [];
    this.thumbTarget?.dispose(); // the thumbnails' render target (thumbnail())
    this.renderer.dispose();
    this.renderer.forceContextLoss();
    this.renderer.domElement.remove();
    for (const el of this.labels ?? []) el.remove();
  }

  // Compiles the shaders of both materials now (software GL takes a while), while the worker loads the wasm,
  // rather than at the first frame of a mesh.
  warmUp() {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(9), 3));
    g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(9), 3));
    g.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(9), 3));
    const meshes = [new THREE.Mesh(g, this.lit), new THREE.Mesh(g, this.flatMaterial)];
    this.scene.add(...meshes);
    this.renderer.compile(this.scene, this.camera);
    this.scene.remove(...meshes);
    g.dispose();
  }

  resize() {
    const w = Math.max(this.container.clientWidth, 1);
    const h = Math.max(this.container.clientHeight, 1);
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    if (this.framed && !this.userMoved) this.frame(); // keep everything in view until the person moves the camera
    this.requestRender();
  }

  requestRender() {
    if (this.needsRender) return;
    this.needsRender = true;
    requestAnimationFrame(() => {
      this.needsRender = false;
      if (this.disposed) return;
      const moving = this.controls.update(); // true while damping still moves the camera
      this.renderer.render(this.scene, this.camera);
      this.placeLabels();
      if (moving) this.requestRender();
    });
  }

  /** New topology: faces of every slot from now on. `reference` (flat xyz) picks the view axes. */
  setTopology(faces, reference) {
    this.faces = faces;
    for (const s of this.slots) this.removeSlot(s);
    this.slots = [];
    this.axes = viewAxes(reference);
  }

  removeSlot(s) {
    this.scene.remove(s.mesh);
    s.mesh.geometry.dispose();
  }

  /** Shows the given meshes side by side: [{ positions, colours, label? }] (label: words over that mesh, when
   * several are shown). Frames the camera when asked. `stay`: the same meshes changed shape (a part turned in pose
   * mode): each keeps its place instead of being centred on its new box, so what did not move stays under the
   * pointer. */
  show(items, { frame = false, stay = false } = {}) {
    stay = stay && !frame && items.length === this.slots.length;
    while (this.slots.length > items.length) this.removeSlot(this.slots.pop());
    while (this.slots.length < items.length) {
      const geometry = new THREE.BufferGeometry();
      geometry.setIndex(new THREE.BufferAttribute(this.faces, 1)); // own attribute: disposing one geometry frees only its buffers
      const mesh = new THREE.Mesh(geometry, this.flat ? this.flatMaterial : this.lit);
      this.scene.add(mesh);
      this.slots.push({ mesh });
    }
    items.forEach((item, k) => {
      const g = this.slots[k].mesh.geometry;
      const pos = g.getAttribute('position');
      if (pos && pos.array.length === item.positions.length) {
        pos.array.set(item.positions);
        pos.needsUpdate = true;
      } else {
        g.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(item.positions), 3));
      }
      const col = g.getAttribute('color');
      if (col && col.array.length === item.colours.length) {
        col.array.set(item.colours);
        col.needsUpdate = true;
      } else {
        g.setAttribute('color', new THREE.BufferAttribute(Float32Array.from(item.colours), 3));
      }
      if (this.flat) orderFaces(g, this.faces);
      g.computeVertexNormals();
      g.computeBoundingBox();
      g.computeBoundingSphere();
    });
    this.setLabels(items.length > 1 ? items.map((item) => item.label ?? '') : []);
    if (frame) this.framed = false; // lay out for the framing direction, not for the camera being replaced
    if (!stay) this.layout();
    if (frame || (this.framed && !this.userMoved && outgrows(this))) this.frame(); // views/frame-reach.js
    this.requestRender();
  }

  // the panes' labels (view-labels.js)
  setLabels(texts) { setLabels(this, texts); }
  placeLabels() { placeLabels(this); }

  // Direction from the target to the camera when framing: across the view axis, a little from above.
  frameDirection() {
    const { view, up, side } = this.axes;
    return new THREE.Vector3().setComponent(view, side).setComponent(up, 0.2).normalize();
  }

  // +1 when the world's `right` axis points to the right of the screen, else -1.
  screenRightSign() {
    const { up, right } = this.axes;
    let r;
    if (this.framed) {
      this.camera.updateMatrixWorld();
      r = new THREE.Vector3().setFromMatrixColumn(this.camera.matrixWorld, 0);
    } else {
      r = new THREE.Vector3().crossVectors(this.frameDirection().negate(), new THREE.Vector3().setComponent(up, 1));
    }
    return r.getComponent(right) < 0 ? -1 : 1;
  }

  // Slots in a row, left to right on the screen, each centred on its own box.
  layout() {
    const { right } = this.axes;
    const sign = this.screenRightSign();
    const boxes = this.slots.map((s) => s.mesh.geometry.boundingBox);
    const widths = boxes.map((b) => b.max.getComponent(right) - b.min.getComponent(right));
    const gap = 0.15 * Math.max(...widths, 1e-6);
    const total = widths.reduce((a, b) => a + b, 0) + gap * (widths.length - 1);
    let x = -total / 2;
    this.slots.forEach((s, k) => {
      const c = boxes[k].getCenter(new THREE.Vector3());
      const offset = new THREE.Vector3().sub(c);
      offset.setComponent(right, sign * (x + widths[k] / 2) - c.getComponent(right));
      s.mesh.position.copy(offset);
      x += widths[k] + gap;
    });
  }

  /** Back to the framing view, slots laid out for it. */
  reset() {
    this.framed = false;
    this.layout();
    this.frame();
  }

  /** The view focused: + and - move the camera toward and away from its target (the wheel's zoom), 0 frames the
   * shapes again (Reset camera); the arrows are OrbitControls' (undamped). */
  zoomKey(e) {
    if (e.key.startsWith('Arrow')) {
      // a press moves at once: damped, its small step fell under OrbitControls' own threshold and stopped there
      this.controls.enableDamping = false;
      setTimeout(() => { this.controls.enableDamping = true; }); // after OrbitControls' listener has run
      return;
    }
    if (e.altKey || e.ctrlKey || e.metaKey) return;
    const step = { '+': 0.8, '=': 0.8, '-': 1.25, _: 1.25 }[e.key];
    if (e.key === '0') this.reset();
    else if (step) {
      this.camera.position.sub(this.controls.target).multiplyScalar(step).add(this.controls.target);
      this.userMoved = true;
      this.controls.update();
      this.requestRender();
      for (const f of this.cameraListeners) f();
    } else return;
    e.preventDefault();
  }

  /** OrbitControls orbit about the camera's up axis as it was when they were made: made anew when it changes. */
  makeControls() {
    this.controls?.dispose();
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.enableDamping = true;
    this.controls.listenToKeyEvents(this.renderer.domElement); // arrows pan, Shift / Ctrl + arrows orbit
    this.controls.keyRotateSpeed = 10; // a press turns 2π·10/height: about 5° on a 700-pixel view
    this.controls.addEventListener('change', () => {
      this.requestRender();
      for (const f of this.cameraListeners) f();
    });
    this.controls.addEventListener('start', () => { this.userMoved = true; });
  }

  /** Calls `f` whenever the user's camera moves (survives makeControls). */
  onCameraChange(f) {
    this.cameraListeners.push(f);
  }

  /** Camera looking across the thinnest axis at everything shown. */
  frame() {
    const box = new THREE.Box3();
    for (const s of this.slots) box.expandByObject(s.mesh);
    if (box.isEmpty()) return;
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    if (this.minSize) size.max(this.minSize); // every training pose fits (views/frame-reach.js)
    this.framedSize = size.clone();
    const { view, up, right } = this.axes;
    const halfW = size.getComponent(right) / 2;
    const halfH = size.getComponent(up) / 2;
    const fov = THREE.MathUtils.degToRad(this.camera.fov) / 2;
    const dist = 1.15 * Math.max(halfH / Math.tan(fov), halfW / (Math.tan(fov) * this.camera.aspect)) + size.getComponent(view) / 2;
    const dir = this.frameDirection();
    if (this.camera.up.getComponent(up) !== 1) {
      this.camera.up.set(0, 0, 0).setComponent(up, 1);
      this.makeControls();
    }
    this.camera.position.copy(centre).addScaledVector(dir, dist);
    this.camera.near = dist / 100;
    this.camera.far = dist * 10;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.framed = true;
    this.userMoved = false;
    this.requestRender();
  }

  /** A dot on vertex `vertex` of slot `slot` (null: none). */
  mark(slot, vertex) {
    if (!this.marker) {
      this.marker = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: 0x111111 }));
      this.scene.add(this.marker);
    }
    const s = this.slots[slot];
    this.marker.visible = !!s;
    if (s) {
      const g = s.mesh.geometry;
      this.marker.position.fromBufferAttribute(g.getAttribute('position'), vertex).add(s.mesh.position);
      this.marker.scale.setScalar(0.012 * g.boundingSphere.radius);
    }
    this.requestRender();
  }

  setFlat(flat) {
    this.flat = flat;
    for (const s of this.slots) {
      s.mesh.material = flat ? this.flatMaterial : this.lit;
      if (flat) orderFaces(s.mesh.geometry, this.faces);
    }
    this.requestRender();
  }

  /** Where point `p` (xyz in slot `slot`'s mesh coordinates) is on the screen: { x, y } in client pixels. */
  screenPoint(slot, p) {
    const r = this.renderer.domElement.getBoundingClientRect();
    const v = new THREE.Vector3(p[0], p[1], p[2]).add(this.slots[slot].mesh.position).project(this.camera);
    return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height };
  }

  /** The angle (radians, clockwise on the screen) of client point (x, y) around screen point `pivot`, or null
   * within `near` pixels of it (where the angle jumps). */
  angleAround(pivot, x, y, near) {
    return this.screenDistance(pivot, { x, y }) <= near ? null : Math.atan2(y - pivot.y, x - pivot.x);
  }

  /** Pixels between screen points a and b ({ x, y }). */
  screenDistance(a, b) {
    return Math.hypot(a.x - b.x, a.y - b.y);
  }

  /** The vertex under a screen point: { slot, vertex } or null (nearest corner of the hit triangle). */
  pick(clientX, clientY) {
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    const hit = this.raycaster.intersectObjects(this.slots.map((s) => s.mesh), false)[0];
    if (!hit) return null;
    const slot = this.slots.findIndex((s) => s.mesh === hit.object);
    const pos = hit.object.geometry.getAttribute('position');
    const local = hit.object.worldToLocal(hit.point.clone());
    let best = -1;
    let bestD = Infinity;
    for (const v of [hit.face.a, hit.face.b, hit.face.c]) {
      const d = local.distanceToSquared(new THREE.Vector3().fromBufferAttribute(pos, v));
      if (d < bestD) {
        bestD = d;
        best = v;
      }
    }
    return { slot, vertex: best };
  }

  /** A small picture of one mesh, drawn into `canvas` (a 2D canvas), from the current view direction. */
  thumbnail(positions, colours, canvas) {
    const w = canvas.width;
    const h = canvas.height;
    const geometry = new THREE.BufferGeometry();
    geometry.setIndex(new THREE.BufferAttribute(this.faces, 1)); // own attribute: disposing one geometry frees only its buffers
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    geometry.computeVertexNormals();
    geometry.computeBoundingSphere();
    const mesh = new THREE.Mesh(geometry, this.lit);
    const scene = new THREE.Scene();
    scene.add(mesh, new THREE.HemisphereLight(0xffffff, 0x8a8a8a, 1.6));
    const cam = new THREE.PerspectiveCamera(35, w / h, 0.01, 100);
    const key = new THREE.DirectionalLight(0xffffff, 1.4);
    key.position.set(1, 1.5, 2);
    cam.add(key);
    scene.add(cam);
    const { center, radius } = geometry.boundingSphere;
    const dir = this.camera.position.clone().sub(this.controls.target).normalize();
    cam.up.copy(this.camera.up);
    cam.position.copy(center).addScaledVector(dir, radius / Math.sin(THREE.MathUtils.degToRad(17.5)));
    cam.lookAt(center);
    // one multisampled target for every thumbnail of a size (a new one each time costs its allocation per call)
    if (!this.thumbTarget || this.thumbTarget.width !== w || this.thumbTarget.height !== h) {
      this.thumbTarget?.dispose();
      this.thumbTarget = new THREE.WebGLRenderTarget(w, h, { samples: 4 });
    }
    const target = this.thumbTarget;
    this.renderer.setRenderTarget(target);
    this.renderer.render(scene, cam);
    const pixels = new Uint8Array(w * h * 4);
    this.renderer.readRenderTargetPixels(target, 0, 0, w, h, pixels);
    this.renderer.setRenderTarget(null);
    geometry.dispose();
    const img = new ImageData(w, h);
    for (let y = 0; y < h; y++) img.data.set(pixels.subarray((h - 1 - y) * w * 4, (h - y) * w * 4), y * w * 4);
    canvas.getContext('2d').putImageData(img, 0, 0);
  }
}
