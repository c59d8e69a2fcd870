// Pose mode's drag and readout: the readout and the hover box say what their angles measure and agree where they
// measure the same thing (the turn at the part's joint, relative to the part carrying it; the hover box adds the
// whole part's own rotation), and a part turned past what the training poses do is said to be beyond them; a
// drag turns the part by the angle swept around its joint, scaled by how far out the pointer is against the
// part's reach on the screen (near a joint a short move sweeps a large angle), and a press that turns nothing
// adds no Undo step; the part dragged is highlighted (the rest greyed) and its joint marked while dragging; the
// Part list names each part by where it is.
// Run: npm run build && node --test tests/e2e/pose-drag.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, enterPoseMode, paletteCounts } from './helpers.mjs';

const session = pageSession();
// press points over the middle of the view, row by row
const grid = () => Array.from({ length: 72 }, (_, i) => [0.3 + 0.05 * (i % 9), 0.35 + 0.05 * Math.floor(i / 9)]);
const inSubtree = (sk, bone, b) => { for (; b >= 0; b = sk.parent[b]) if (b === bone) return true; return false; };

// The bone (not the root) carrying the most vertices below it (a neck with its head, a leg).
function biggestLimb(sk) {
  let best = -1;
  let most = 0;
  for (const k of sk.order) {
    if (sk.parent[k] < 0) continue;
    const n = Array.from(sk.boneOfVertex).filter((b) => inSubtree(sk, k, b)).length;
    if (n > most) [best, most] = [k, n];
  }
  return best;
}

test('pose mode: the readout and the hover box say what they measure, and agree at the joint', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const sk = await page.evaluate(() => window.posemfa.pose.skeleton());
  const canvas = await page.locator('#view canvas').boundingBox();
  // hover a vertex of a non-root part until the hover box names a part with a parent
  let named = null;
  for (const v of Array.from(sk.boneOfVertex.keys()).filter((i) => i % 7 === 0)) {
    const b = sk.boneOfVertex[v];
    if (sk.parent[b] < 0) continue;
    const p = await page.evaluate((i) => window.posemfa.pose.screenOf(i), v);
    if (p.x < canvas.x + 5 || p.x > canvas.x + canvas.width - 5 || p.y < canvas.y + 5 || p.y > canvas.y + canvas.height - 5) continue;
    await page.mouse.move(p.x, p.y);
    const ok = await page.waitForFunction(() => document.querySelector('#info [data-measures]')?.dataset.measures === 'at its joint|whole part' || null, null, { timeout: 1500 }).then(() => true, () => false);
    if (!ok) continue;
    named = /part (\d+), from the rest pose/.exec(await page.locator('#info').innerText());
    if (named) break;
  }
  assert.ok(named, 'the hover box of a part that has a joint');
  const bone = sk.names.indexOf(`part ${named[1]}`);
  const parent = sk.names[sk.parent[bone]];
  const head = await page.locator('#info').innerText();
  assert.match(head, new RegExp(`at its joint \\(its turn relative to ${parent}, as the readout\\), and the whole part \\(its own rotation: the turns of the parts carrying it included\\)`));
  // the columns: at its joint, whole part; one row per training pose (or the largest few)
  const rows = await page.$$eval('#info table tr', (trs) => trs.map((tr) => [...tr.cells].map((c) => c.textContent)));
  assert.deepEqual(rows[0].slice(1), ['at its joint', 'whole part']);
  const joint = rows.slice(1).map((r) => Number(r[2].replace('°', '')));
  // the readout of the same part: its angle at its joint, relative to its parent, and the training poses' largest
  await page.selectOption('#pose-part', String(bone));
  const readout = await page.locator('[data-testid=pose-angle]').innerText();
  const m = new RegExp(`^0\\.0° at its joint, relative to ${parent} \\(training poses: up to ([0-9.]+)°\\)$`).exec(readout);
  assert.ok(m, `the readout says what it measures: ${readout}`);
  assert.ok(Math.abs(Math.max(...joint) - Number(m[1])) <= 0.051, `the hover box's largest turn at the joint ${Math.max(...joint)}° is the readout's ${m[1]}°`);
  // the root's readout says it is its own turn
  const root = sk.order.find((k) => sk.parent[k] < 0);
  await page.selectOption('#pose-part', String(root));
  assert.match(await page.locator('[data-testid=pose-angle]').innerText(), /^0\.0° \(the root: its own turn\) \(training poses: up to [0-9.]+°\)$/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('pose mode: a 70 px drag near a joint turns the part by the distance over its reach; the part and its joint are shown', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const sk = await page.evaluate(() => window.posemfa.pose.skeleton());
  // the Part list names parts by where they are
  const options = await page.$$eval('#pose-part option', (os) => os.map((o) => o.textContent));
  for (const o of options) assert.match(o, /^■ part \d+ · (root|on part \d+) · (<1|\d+) %$/);
  // and the line under it says the part picked in full
  await page.selectOption('#pose-part', String(sk.order.find((k) => sk.parent[k] >= 0)));
  assert.match(await page.locator('[data-testid=pose-part-about]').innerText(), /^part \d+: on part \d+, (carries \d+ parts?|an end part), (<1|\d+) % of the mesh$/);
  await page.check('#flat');
  const bone = biggestLimb(sk);
  const pivot = await page.evaluate((b) => window.posemfa.pose.jointOnScreen(b), bone);
  // a vertex of the part itself, 12 to 30 px from its joint on the screen, that a press picks
  const mine = Array.from(sk.boneOfVertex.keys()).filter((v) => sk.boneOfVertex[v] === bone);
  let start = null;
  for (const v of mine) {
    const p = await page.evaluate((i) => window.posemfa.pose.screenOf(i), v);
    const d = Math.hypot(p.x - pivot.x, p.y - pivot.y);
    if (d < 12 || d > 30) continue;
    await page.mouse.move(p.x, p.y);
    await page.mouse.down();
    await page.waitForTimeout(150);
    if (await page.evaluate(() => window.posemfa.pose.dragging()) === bone) {
      start = p;
      break;
    }
    await page.mouse.up();
  }
  assert.ok(start, `a press on ${sk.names[bone]} near its joint`);
  await page.waitForFunction(() => window.posemfa.pose.highlighted().mark !== null, null, { timeout: 10000 });
  const shown = await page.evaluate(() => window.posemfa.pose.highlighted());
  assert.equal(shown.bone, bone, 'the part dragged is highlighted');
  assert.ok(Math.hypot(shown.mark.x - pivot.x, shown.mark.y - pivot.y) < 2, `its joint is marked: ${JSON.stringify(shown.mark)} for ${JSON.stringify(pivot)}`);
  assert.ok(shown.reach >= 100, `the reach of ${sk.names[bone]} and what it carries on the screen: ${shown.reach} px`);
  // the parts that do not turn are greyed: the colours only they have leave the view while the drag lasts
  const partOf = (k) => Number(sk.names[k].replace(/\D+/g, '')) - 1;
  const colours = await page.evaluate(() => window.posemfa.partColours());
  const turning = new Set(sk.order.filter((k) => inSubtree(sk, bone, k)).map((k) => colours[partOf(k)]));
  const still = [...new Set(sk.order.filter((k) => !inSubtree(sk, bone, k)).map((k) => colours[partOf(k)]))].filter((c) => !turning.has(c));
  assert.ok(still.length >= 2, `colours of parts that do not turn: ${still}`);
  const pixels = async () => { const c = await paletteCounts(page); return still.reduce((n, h) => n + c[h], 0); };
  await page.waitForTimeout(200);
  const during = await pixels();
  assert.ok(during < 50, `the parts that do not turn are greyed while ${sk.names[bone]} is dragged: ${during} px in their colours`);
  // 70 px across the line from the joint, in 10 moves
  const before = (await page.evaluate(() => window.posemfa.pose.angles()))[bone];
  const r = Math.hypot(start.x - pivot.x, start.y - pivot.y);
  const across = [-(start.y - pivot.y) / r, (start.x - pivot.x) / r];
  for (let s = 1; s <= 10; s++) {
    await page.mouse.move(start.x + 7 * s * across[0], start.y + 7 * s * across[1]);
    await page.waitForTimeout(40);
  }
  await page.waitForTimeout(500);
  await page.mouse.up();
  await page.waitForTimeout(300);
  const turned = Math.abs((await page.evaluate(() => window.posemfa.pose.angles()))[bone] - before);
  const most = (70 / shown.reach) * (180 / Math.PI);
  assert.ok(turned > 3, `the drag turned ${sk.names[bone]} (${turned}°)`);
  assert.ok(turned <= most * 1.05 + 0.5, `a 70 px drag turned ${sk.names[bone]} by ${turned.toFixed(1)}°, more than 70 px over its reach of ${shown.reach.toFixed(0)} px (${most.toFixed(1)}°)`);
  // released: the highlight and the mark go, the colours are back
  assert.deepEqual(await page.evaluate(() => { const h = window.posemfa.pose.highlighted(); return [h.bone, h.mark]; }), [-1, null]);
  await page.waitForTimeout(200);
  assert.ok((await pixels()) > 500, 'the parts that did not turn in their colours again');
  // a random pose stays in the view
  await page.click('[data-testid=pose-random]');
  await page.waitForTimeout(800);
  assert.equal(await page.evaluate(() => window.posemfa.outOfView()), 0, 'a random pose is in the view');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('pose mode: a drag made and released before the page knows where the joint is still turns the part, and the view stays put', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const sk = await page.evaluate(() => window.posemfa.pose.skeleton());
  const bone = biggestLimb(sk);
  const pivot = await page.evaluate((b) => window.posemfa.pose.jointOnScreen(b), bone);
  const before = (await page.evaluate(() => window.posemfa.pose.angles()))[bone];
  const viewBox = () => page.evaluate(() => JSON.stringify(document.getElementById('view').getBoundingClientRect()));
  const box0 = await viewBox();
  // a vertex of the root: it does not turn, and stays where it is on the screen
  const rootVertex = Array.from(sk.boneOfVertex.keys()).find((v) => sk.parent[sk.boneOfVertex[v]] < 0);
  const still = async () => [await page.evaluate((i) => window.posemfa.pose.screenOf(i), rootVertex), await page.evaluate(() => window.posemfa.camera())];
  const [root0, camera0] = await still();
  // press, a quarter turn around the joint in 12 moves and the release, all in one task of the page: the worker
  // cannot have said where the joint is before the release (a quick flick on a busy machine)
  let done = null;
  for (const v of Array.from(sk.boneOfVertex.keys()).filter((i) => sk.boneOfVertex[i] === bone && i % 3 === 0)) {
    const p = await page.evaluate((i) => window.posemfa.pose.screenOf(i), v);
    const r = Math.hypot(p.x - pivot.x, p.y - pivot.y);
    if (r < 30) continue;
    const held = await page.evaluate(([p, pivot, r, bone]) => {
      const canvas = document.querySelector('#view canvas');
      const at = (type, x, y, target) => target.dispatchEvent(new PointerEvent(type, { clientX: x, clientY: y, button: 0, buttons: 1, bubbles: true, cancelable: true, pointerId: 1, isPrimary: true }));
      at('pointerdown', p.x, p.y, canvas);
      if (window.posemfa.pose.dragging() !== bone) {
        at('pointerup', p.x, p.y, window);
        return false;
      }
      const a0 = Math.atan2(p.y - pivot.y, p.x - pivot.x);
      for (let s = 1; s <= 12; s++) {
        const a = a0 + (s / 12) * (Math.PI / 2);
        at('pointermove', pivot.x + r * Math.cos(a), pivot.y + r * Math.sin(a), window);
      }
      at('pointerup', pivot.x + r * Math.cos(a0 + Math.PI / 2), pivot.y + r * Math.sin(a0 + Math.PI / 2), window);
      return true;
    }, [p, pivot, r, bone]);
    if (held) { done = { r }; break; }
  }
  assert.ok(done, `a press that holds ${sk.names[bone]} at least 30 px from its joint`);
  await page.waitForFunction(([b, a]) => Math.abs(window.posemfa.pose.angles()[b] - a) > 5, [bone, before], { timeout: 20000, polling: 50 });
  await page.waitForTimeout(500);
  const turned = Math.abs((await page.evaluate(() => window.posemfa.pose.angles()))[bone] - before);
  const { reach } = await page.evaluate(() => window.posemfa.pose.highlighted());
  const want = 90 * Math.min(1, done.r / reach);
  assert.ok(Math.abs(turned - want) < 1.5, `a quarter turn ${done.r.toFixed(0)} px out (reach ${reach.toFixed(0)} px) turned ${sk.names[bone]} by ${turned.toFixed(1)}°, not ${want.toFixed(1)}°`);
  assert.equal(await page.locator('#pose-undo').isDisabled(), false, 'the turn can be undone');
  assert.equal(await page.evaluate(() => window.posemfa.pose.highlighted().bone), -1, 'nothing is highlighted after the release');
  // the caption now says what turned, in fewer words than it said before: the view stays where it was (a view
  // that moves under the pointer at a press makes the next press land on another part)
  assert.match(await page.locator('#caption').innerText(), /turned/);
  assert.equal(await viewBox(), box0, 'the view stays in its place on the page');
  const [root1, camera1] = await still();
  if (JSON.stringify(camera1) === JSON.stringify(camera0)) {
    assert.ok(Math.hypot(root1.x - root0.x, root1.y - root0.y) < 0.5, `the root stays where it was on the screen: ${JSON.stringify(root0)} -> ${JSON.stringify(root1)}`);
  }
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('pose mode: a drag turns the part by the angle swept around its joint (scaled by how far out against the part\'s reach); a press that turns nothing adds no Undo', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const sk = await page.evaluate(() => window.posemfa.pose.skeleton());
  const box = await page.locator('#view canvas').boundingBox();
  let found = null;
  for (const [fx, fy] of grid()) {
    const start = { x: box.x + fx * box.width, y: box.y + fy * box.height };
    await page.mouse.move(start.x, start.y);
    await page.mouse.down();
    await page.waitForTimeout(100);
    const bone = await page.evaluate(() => window.posemfa.pose.dragging());
    if (bone >= 0 && sk.parent[bone] >= 0) {
      const pivot = await page.evaluate((b) => window.posemfa.pose.jointOnScreen(b), bone);
      if (Math.hypot(start.x - pivot.x, start.y - pivot.y) > 25) {
        found = { bone, start, pivot };
        break;
      }
    }
    await page.mouse.up();
  }
  assert.ok(found, 'a press on a non-root part, more than 25 px from its joint on the screen');
  const { bone, start, pivot } = found;
  const angle = () => page.evaluate((b) => window.posemfa.pose.angles()[b], bone);
  const before = await angle();
  // straight away from the joint: no angle swept, nothing turns, no Undo step
  const r = Math.hypot(start.x - pivot.x, start.y - pivot.y);
  const out = [(start.x - pivot.x) / r, (start.y - pivot.y) / r];
  for (let s = 1; s <= 6; s++) {
    await page.mouse.move(start.x + 5 * s * out[0], start.y + 5 * s * out[1]);
    await page.waitForTimeout(40);
  }
  await page.mouse.up();
  await page.waitForTimeout(300);
  assert.ok(Math.abs((await angle()) - before) < 1e-6, `a radial drag turned the part by ${(await angle()) - before}°`);
  assert.equal(await page.locator('#pose-undo').isDisabled(), true, 'a drag that turned nothing adds no Undo step');
  // a quarter turn around the joint, a vertical move among them: the part turns by a quarter turn
  await page.mouse.move(start.x, start.y);
  await page.mouse.down();
  await page.waitForTimeout(300); // the joint's place on the screen arrives
  const a0 = Math.atan2(start.y - pivot.y, start.x - pivot.x);
  for (let s = 1; s <= 12; s++) {
    const a = a0 + (s / 12) * (Math.PI / 2);
    await page.mouse.move(pivot.x + r * Math.cos(a), pivot.y + r * Math.sin(a));
    await page.waitForTimeout(40);
  }
  await page.mouse.up();
  await page.waitForFunction(([b, a]) => Math.abs(window.posemfa.pose.angles()[b] - a) > 5, [bone, before], { timeout: 20000, polling: 50 });
  await page.waitForTimeout(500);
  await page.waitForTimeout(300);
  const turned = (await angle()) - before;
  // (the sweep is scaled by how far out the pointer is against the reach on the screen of what turns,
  // at most 1: held at the part's far end or beyond, a quarter turn turns it a quarter; nearer its joint, less)
  const { reach } = await page.evaluate(() => window.posemfa.pose.highlighted());
  const want = 90 * Math.min(1, r / reach);
  assert.ok(Math.abs(turned - want) < 1.5, `a quarter turn of the pointer around the joint ${r.toFixed(0)} px out (reach ${reach.toFixed(0)} px) turned ${sk.names[bone]} by ${turned}°, not ${want.toFixed(1)}°`);
  assert.equal(await page.locator('#pose-undo').isDisabled(), false);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a part turned past what the training poses do is said to be beyond them', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const angle = () => page.locator('[data-testid=pose-angle]').innerText();
  assert.match(await angle(), /^0\.0°(?: at its joint, relative to part \d+| \(the root: its own turn\)) \(training poses: up to [0-9.]+°\)$/);
  const most = Number(/up to ([0-9.]+)°/.exec(await angle())[1]);
  // 10° a press, until past the training poses' largest turn of this part
  for (let k = 0; k < Math.ceil(most / 10) + 1; k++) {
    const before = await angle();
    await page.click('#pose-plus');
    await page.waitForFunction((b) => document.querySelector('[data-testid=pose-angle]').innerText !== b, before, { timeout: 20000 });
  }
  assert.match(await angle(), new RegExp(`^[0-9.]+°(?: at its joint, relative to part \\d+| \\(the root: its own turn\\)) \\(beyond the training poses, which turn it at most ${most.toFixed(1).replace('.', '\\.')}°\\)$`));
  assert.equal(await page.locator('[data-testid=pose-angle].beyond').count(), 1);
  await page.click('#pose-reset');
  await page.waitForFunction(() => /^0\.0° /.test(document.querySelector('[data-testid=pose-angle]').innerText), null, { timeout: 20000 });
  assert.equal(await page.locator('[data-testid=pose-angle].beyond').count(), 0);
  assert.deepEqual(log.errors, []);
  await context.close();
});
