// The framing camera's axes (www/view-axes.js viewAxes): across the thinnest side, from the side the shape reaches
// out to (the Hand example's thumb in front of its palm). Pure functions: no browser.
// Run: node --test tests/e2e/view-axes.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { viewAxes } from '../../www/view-axes.js';

// A slab 2 x 1 x 0.1 (thin along z) as a grid of points, and a finger of `length` along `dir` from its middle.
function slab(finger = null) {
  const xyz = [];
  for (let i = 0; i <= 20; i++) for (let j = 0; j <= 10; j++) for (const z of [-0.05, 0.05]) xyz.push(i / 10 - 1, j / 10 - 0.5, z);
  if (finger) for (let t = 1; t <= 20; t++) xyz.push(...finger.map((d) => (d * t) / 20));
  return Float32Array.from(xyz);
}

test('a flat shape is seen across its thinnest side, from +z when nothing sticks out', () => {
  assert.deepEqual(viewAxes(slab()), { view: 2, up: 1, right: 0, side: 1 });
});

test('a finger reaching out to -z puts the camera on that side; one to +z keeps it on +z', () => {
  assert.equal(viewAxes(slab([0.3, 0, -0.4])).side, -1);
  assert.equal(viewAxes(slab([0.3, 0, 0.4])).side, 1);
  // a small bump on -z is not enough to turn the view round
  assert.equal(viewAxes(slab([0, 0, -0.06])).side, 1);
});

test('with y the thinnest side, z is up', () => {
  const flat = slab();
  const swapped = Float32Array.from(flat, (_, k) => flat[k - (k % 3) + [0, 2, 1][k % 3]]);
  assert.deepEqual(viewAxes(swapped), { view: 1, up: 2, right: 0, side: 1 });
});

test('no points: the default axes', () => {
  assert.deepEqual(viewAxes(new Float32Array(0)), { view: 2, up: 1, right: 0, side: 1 });
});
