// The ninth newcomer's review (docs/page-fixes.md, thirty-fourth session) on the built page (dist/): what a
// first-time user found misleading, each fix checked as the user met it.
// Run: npm run build && node --test tests/e2e/review9.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, asPayload } from './helpers.mjs';

const session = pageSession();

test('the 3D view takes keys once focused: arrows pan, Shift+arrows orbit, + and - zoom, 0 frames again', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const camera = () => page.evaluate(() => {
    const c = window.posemfa.urlState().view.cam;
    const d = Math.hypot(c[0] - c[3], c[1] - c[4], c[2] - c[5]);
    return { c, d };
  });
  // the camera is in the link once the user moved it; before that, the framed camera
  await page.focus('#view canvas');
  const framed = await camera();
  const settle = () => page.waitForTimeout(600); // OrbitControls' damping glides on for a few frames
  await page.keyboard.press('+');
  await settle();
  const nearer = await camera();
  assert.ok(nearer.d < 0.9 * framed.d, `+ zooms in: ${framed.d} -> ${nearer.d}`);
  await page.keyboard.press('-');
  await page.keyboard.press('-');
  await settle();
  assert.ok((await camera()).d > nearer.d * 1.4, '- zooms out');
  await page.keyboard.press('0');
  await settle();
  const again = await camera();
  assert.ok(Math.abs(again.d - framed.d) < 1e-6 * framed.d, `0 frames again: ${framed.d} / ${again.d}`);
  // Shift+arrow turns the camera about its target (its distance stays), an arrow moves the target
  await page.keyboard.press('Shift+ArrowLeft');
  await settle();
  const turned = await camera();
  assert.ok(Math.abs(turned.d - framed.d) < 1e-3 * framed.d, 'an orbit keeps the distance');
  // by the whole step at once (2π·10 / the view's height), not the damped fraction of it
  const height = await page.evaluate(() => document.querySelector('#view canvas').clientHeight);
  const offset = (c) => [0, 1, 2].map((i) => c[i] - c[3 + i]);
  const [u, v] = [offset(framed.c), offset(turned.c)];
  const angle = Math.acos(Math.min(1, u.reduce((s, x, i) => s + x * v[i], 0) / (framed.d * turned.d)));
  assert.ok(Math.abs(angle / (2 * Math.PI * 10 / height) - 1) < 0.05, `Shift+ArrowLeft turned ${angle} rad`);
  await page.keyboard.press('ArrowUp');
  await settle();
  const panned = await camera();
  assert.ok(Math.hypot(...panned.c.slice(3).map((x, i) => x - turned.c[3 + i])) > 1e-3 * framed.d, 'ArrowUp pans the target');
  assert.match(await page.getAttribute('#view canvas', 'aria-label'), /arrows pan, Shift\+arrows orbit, \+ and - zoom, 0 resets the camera/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a link made in the Pose view opens in the Pose view', async () => {
  const { page, context, log } = await session.open('#ex=quadruped&view=pose');
  await page.waitForFunction(() => window.posemfa?.fitCount() >= 1 && !window.posemfa.restoring(), null, { timeout: 120000 });
  await page.waitForFunction(() => window.posemfa.mode() === 'pose' && window.posemfa.pose?.ready(), null, { timeout: 120000 });
  await page.waitForFunction(() => /[#&]view=pose(&|$)/.test(location.hash), null, { timeout: 10000 });
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('poses that are all one shape are refused at load, and the fitted population stays', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const before = await page.evaluate(() => ({ summary: window.posemfa.summary(), errors: window.posemfa.loadErrorCount() }));
  const text = 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n';
  await page.setInputFiles('[data-testid=file-input]', asPayload([{ name: 'a.obj', text }, { name: 'b.obj', text }]));
  await page.waitForFunction((n) => window.posemfa.loadErrorCount() > n, before.errors, { timeout: 30000 });
  assert.match(await page.textContent('[data-testid=errors]'), /a\.obj, b\.obj: all 2 poses are the same shape .*: there is no motion to learn; open poses in which the parts move/);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  assert.deepEqual(await page.evaluate(() => window.posemfa.summary()), before.summary);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('after Refine the part rule\'s chart says it judged the refined parts and changed nothing', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.evaluate((v) => {
    const s = document.getElementById('tree-slider');
    s.value = String(v);
    s.dispatchEvent(new Event('input'));
  }, parts - 2);
  await page.waitForFunction((v) => document.getElementById('tree-slider').dataset.count === String(v), parts - 2);
  await page.click('[data-testid=tree-refine]');
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 90000 });
  assert.equal(await waitState(page, ['fitted', 'error'], 90000), 'fitted');
  const title = await page.evaluate(() => document.getElementById('part-curve').dataset.title);
  assert.match(title, new RegExp(`^part rule on the refined parts, not applied: \\d+ merges? would make ${parts - 2} → \\d+$`));
  assert.equal(await page.textContent('#part-curve-note'), `The chart is the part rule on the ${parts - 2} parts refined from the merge tree: it judges them, and a Refine keeps them as they are.`);
  assert.deepEqual(log.errors, []);
  await context.close();
});
