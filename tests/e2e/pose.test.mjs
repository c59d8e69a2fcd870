// Pose mode on the built page: a generated quadruped dropped and fitted, then the Pose view. A mouse drag
// on the mesh turns the part under the pointer and only its subtree: every vertex with no weight on that subtree
// moves by less than 1e-6 of the bounding-box diagonal, and the part's joint stays in place (1e-4); the angle from
// the rest pose is shown and Undo brings the mesh back. The pose-space sliders at 0 give the mean pose vector, and
// each training pose's coordinates give that pose back. Frames of the same mesh added with "Add frames" are solved
// onto the rig and play. No console errors. Runs the CLI (debug build, built here if needed) for the files.
// Run: npm run build && node --test tests/e2e/pose.test.mjs
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { pageSession, waitState, asPayload, ROOT, enterPoseMode, objFiles, debugCli } from './helpers.mjs';

const session = pageSession();
let dir;

before(() => {
  const bin = debugCli();
  dir = mkdtempSync(path.join(tmpdir(), 'posemfa-pose-page-'));
  // the same mesh (the design and the vertex count make it), other poses (the seed draws the angles)
  execFileSync(bin, ['generate', 'quadruped', '--vertices', '1500', '--poses', '6', '--seed', '4', '--out', path.join(dir, 'pop')]);
  execFileSync(bin, ['generate', 'quadruped', '--vertices', '1500', '--poses', '4', '--seed', '11', '--out', path.join(dir, 'new')]);
});

after(() => {
  if (dir) rmSync(dir, { recursive: true, force: true });
});

const maxAbs = (a, b) => a.reduce((m, x, i) => Math.max(m, Math.abs(x - b[i])), 0);

test('pose mode: a drag turns only the subtree about its joint; sliders give the mean and the training poses; added frames play', async () => {
  const { page, log } = await session.open();
  await waitState(page, ['fitted', 'idle', 'error'], 60000);
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.setInputFiles('[data-testid=file-input]', asPayload(objFiles(path.join(dir, 'pop'))));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 120000, polling: 50 });
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');

  await enterPoseMode(page);
  const sk = await page.evaluate(() => window.posemfa.pose.skeleton());
  assert.ok(sk.order.length >= 3 && sk.nModes >= 1, JSON.stringify({ bones: sk.order.length, modes: sk.nModes }));
  const diag = sk.diagonal;

  // a real drag: press on the mesh, move, release; find a press point on a non-root part
  const box = await page.locator('#view canvas').boundingBox();
  let bone = -1;
  let start = null;
  let before = null;
  let joint = null;
  // (press points over the view's middle, row by row: the view frames every training pose, so the mesh is where
  // the poses' common frame puts it)
  for (const [fx, fy] of Array.from({ length: 72 }, (_, i) => [0.3 + 0.05 * (i % 9), 0.35 + 0.05 * Math.floor(i / 9)])) {
    const x = box.x + fx * box.width;
    const y = box.y + fy * box.height;
    before = await page.evaluate(() => window.posemfa.pose.positions());
    await page.mouse.move(x, y);
    await page.mouse.down();
    await page.waitForTimeout(100);
    const picked = await page.evaluate(() => window.posemfa.pose.selected());
    if (picked >= 0 && sk.parent[picked] >= 0) {
      bone = picked;
      start = { x, y };
      joint = await page.evaluate((b) => window.posemfa.pose.joint(b), bone);
      break;
    }
    await page.mouse.up();
  }
  assert.ok(bone >= 0, 'a press on some non-root part of the mesh');
  const angleBefore = (await page.evaluate(() => window.posemfa.pose.angles()))[bone];
  // the drag turns the part by the angle swept around its joint on the screen: move across the line from the
  // joint to the press point
  const pivot = await page.evaluate((b) => window.posemfa.pose.jointOnScreen(b), bone);
  const [rx, ry] = [start.x - pivot.x, start.y - pivot.y];
  const across = Math.hypot(rx, ry) > 1 ? [-ry / Math.hypot(rx, ry), rx / Math.hypot(rx, ry)] : [1, 0];
  for (let s = 1; s <= 8; s++) {
    await page.mouse.move(start.x + 6 * s * across[0], start.y + 6 * s * across[1]);
    await page.waitForTimeout(60);
  }
  await page.mouse.up();
  await page.waitForFunction(([b, a]) => Math.abs(window.posemfa.pose.angles()[b] - a) > 1, [bone, angleBefore], { timeout: 20000, polling: 50 });
  await page.waitForTimeout(300); // the last move's answer
  const after = await page.evaluate(() => window.posemfa.pose.positions());
  const touches = await page.evaluate((b) => window.posemfa.pose.touches(b), bone);
  let outside = 0;
  let inside = 0;
  for (let v = 0; v < touches.length; v++) {
    const d = Math.hypot(after[3 * v] - before[3 * v], after[3 * v + 1] - before[3 * v + 1], after[3 * v + 2] - before[3 * v + 2]);
    if (touches[v]) inside = Math.max(inside, d);
    else outside = Math.max(outside, d);
  }
  assert.ok(outside < 1e-6 * diag, `a vertex outside the subtree of ${sk.names[bone]} moved by ${outside / diag} of the diagonal`);
  assert.ok(inside > 1e-3 * diag, `the subtree moved by ${inside / diag} of the diagonal`);
  const jointAfter = await page.evaluate((b) => window.posemfa.pose.joint(b), bone);
  assert.ok(Math.hypot(...jointAfter.map((c, i) => c - joint[i])) < 1e-4 * diag, `the joint moved: ${joint} -> ${jointAfter}`);
  const angle = await page.locator('[data-testid=pose-angle]').innerText();
  // read against the training poses' largest turn of that part (pose-angle: "12.3° at its joint, relative to part 2
  // (training poses: up to 40.1°)")
  const m = /^([0-9.]+)°(?: at its joint, relative to part \d+| \(the root: its own turn\)) \((?:training poses: up to|beyond the training poses, which turn it at most) ([0-9.]+)°\)$/.exec(angle);
  assert.ok(m, angle);
  assert.ok(Number(m[1]) > 1, angle);
  assert.equal(Number(m[1]) > Number(m[2]) + 0.05, /beyond/.test(angle), angle);
  assert.equal(await page.locator('[data-testid=pose-angle].beyond').count(), /beyond/.test(angle) ? 1 : 0);
  // Undo: the mesh as before the drag
  await page.click('#pose-undo');
  await page.waitForFunction(([b, a]) => Math.abs(window.posemfa.pose.angles()[b] - a) < 1e-3, [bone, angleBefore], { timeout: 20000, polling: 50 });
  const undone = await page.evaluate(() => window.posemfa.pose.positions());
  assert.ok(maxAbs(undone, before) < 1e-5 * diag, `undo: ${maxAbs(undone, before)}`);
  // the buttons (keyboard): +10 degrees then -10 degrees on the selected part, back where it was
  assert.equal(await page.locator('#pose-part').inputValue(), String(bone));
  await page.click('#pose-plus');
  await page.waitForFunction(([b, a]) => Math.abs(window.posemfa.pose.angles()[b] - a) > 5, [bone, angleBefore], { timeout: 20000, polling: 50 });
  await page.click('#pose-minus');
  await page.waitForFunction(([b, a]) => Math.abs(window.posemfa.pose.angles()[b] - a) < 0.01, [bone, angleBefore], { timeout: 20000, polling: 50 });

  // the pose space: sliders at 0 give the mean; each training pose's coordinates give it back
  await page.evaluate((n) => window.posemfa.pose.modes(new Array(n).fill(0)), sk.nModes);
  const v0 = await page.evaluate(() => window.posemfa.pose.vector());
  assert.ok(maxAbs(v0.vector, v0.mean) < 1e-9, `sliders at 0: ${maxAbs(v0.vector, v0.mean)} from the mean`);
  for (let i = 0; i < sk.coords.length; i++) {
    await page.evaluate((c) => window.posemfa.pose.modes(c), sk.coords[i]);
    const v = await page.evaluate(() => window.posemfa.pose.vector());
    assert.ok(maxAbs(v.vector, v.training[i]) < 1e-6, `training pose ${i}: ${maxAbs(v.vector, v.training[i])}`);
  }
  assert.equal(await page.locator('#pose-modes input').count(), Math.min(sk.nModes, 6));
  await page.click('[data-testid=pose-random]');

  // new frames of the same mesh: solved onto the rig and played
  await page.setInputFiles('[data-testid=pose-frames]', asPayload(objFiles(path.join(dir, 'new'))));
  await page.waitForFunction(() => document.body.dataset.poseFrames === '4', null, { timeout: 60000, polling: 50 });
  const frames = await page.evaluate(() => window.posemfa.pose.frames());
  assert.deepEqual(frames.names, ['pose01.obj', 'pose02.obj', 'pose03.obj', 'pose04.obj']);
  assert.ok(frames.eRms.every((e) => e > 0 && e < 20), JSON.stringify(frames.eRms));
  const f0 = await page.evaluate(() => document.body.dataset.poseFrame);
  await page.waitForFunction((f) => document.body.dataset.poseFrame !== f, f0, { timeout: 10000, polling: 50 });
  assert.match(await page.locator('#caption').innerText(), /Added frame/);
  assert.match(await page.locator('[data-testid=pose-status]').innerText(), /4 frames solved onto the rig: E_RMS [0-9.]+/);
  assert.deepEqual(log.errors, []);
});

test('pose mode says which pose its rest pose is (the rig\'s bind pose: the file named reference), marks no thumbnail, and its hover box measures from it', async () => {
  const { page, context, log } = await session.open();
  await waitState(page, ['fitted', 'idle', 'error'], 60000);
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  // the third pose named "reference": the rig is bound in it (src/export/rig_report.rs default_bind_pose)
  const files = objFiles(path.join(dir, 'pop')).map((f, i) => (i === 2 ? { ...f, name: 'reference.obj' } : f));
  await page.setInputFiles('[data-testid=file-input]', asPayload(files));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 120000, polling: 50 });
  const names = await page.$$eval('#pose-select option', (o) => o.map((x) => x.textContent));
  const ref = names.indexOf('reference.obj');
  assert.ok(ref >= 0, names.join());
  const pressed = () => page.$$eval('#pose-strip button[aria-pressed=true]', (b) => b.map((x) => x.title));
  assert.deepEqual(await pressed(), [names[0]]);

  await enterPoseMode(page);
  await page.waitForFunction(() => /^Pose mode/.test(document.getElementById('caption').textContent));
  assert.equal(await page.locator('#caption').innerText(), 'Pose mode: the rest pose, the rig\'s bind pose (“reference.obj” rebuilt from its parts); drag a part to turn it about its joint (one too thin to grab: choose it in the Part list, then ↺ / ↻)');
  assert.deepEqual(await pressed(), [], 'a made pose is none of the training poses');
  // the rest pose is that training pose (as solved onto the rig), not another one
  const rest = await page.evaluate(() => window.posemfa.pose.positions());
  const dist = [];
  for (let i = 0; i < names.length; i++) {
    const p = await page.evaluate(async (k) => {
      const q = await window.posemfa.pose.training(k);
      return q;
    }, i);
    dist.push(maxAbs(rest, p));
  }
  const nearest = dist.indexOf(Math.min(...dist));
  assert.equal(nearest, ref, `the rest pose is nearest to ${names[nearest]}: ${dist.map((d) => d.toExponential(2)).join(', ')}`);
  await page.click('#pose-reset');
  await page.waitForFunction(() => /the rest pose/.test(document.getElementById('caption').textContent));

  // the hover box in pose mode: the part's rotation from the rest pose, as the caption says
  const box = await page.locator('#view canvas').boundingBox();
  let info = '';
  for (const [fx, fy] of [[0.5, 0.5], [0.45, 0.55], [0.55, 0.55], [0.5, 0.62], [0.4, 0.5], [0.6, 0.5]]) {
    await page.mouse.move(box.x + fx * box.width, box.y + fy * box.height);
    await page.waitForTimeout(250);
    info = (await page.locator("#info").innerText()).trim();
    if (info) break;
  }
  // (in the two measures the core has, at its joint and the whole part's own rotation; the root's only)
  assert.match(info, /^part \d+, from the rest pose “reference\.obj” \(the rig's bind pose\), in each training pose: /);
  // the angles of the rest pose's own row are 0
  const rows = await page.$$eval('#info table tr', (tr) => tr.map((r) => [...r.children].map((c) => c.textContent)));
  const own = rows.find((r) => r[0] === 'reference.obj');
  assert.ok(own, JSON.stringify(rows));
  assert.ok(own.filter((c) => c.endsWith('°')).every((c) => c === '0.0°'), JSON.stringify(own));
  assert.equal(rows.indexOf(own) - (rows[0][0] === '' ? 1 : 0), ref);

  // out of pose mode: the pose shown is marked again
  await page.check('#modes input[value=parts]', { force: true });
  await page.waitForFunction(() => window.posemfa.mode() === 'parts');
  assert.deepEqual(await pressed(), [names[0]]);
  assert.deepEqual(log.errors, []);
  await context.close();
});
