// The 3D view and the Latent view: once focused the view takes keys (arrows pan, Shift+arrows orbit, + and - zoom,
// 0 frames again); the Latent view places the parts by the pose's R and b by default, "each in its own frame" is
// a choice with its own caption.
// Run: npm run build && node --test tests/e2e/views.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, summary, text, frames, openFitted, setMode, exportObj, relativeRms } from './helpers.mjs';

const session = pageSession();

const fitted = (path, opts) => openFitted(session, path, opts);

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

test('latent view: the parts placed by the pose\'s R and b by default, readable; "each in its own frame" is a choice with its own caption', async () => {
  const { page, context, log } = await fitted();
  const pose = (await exportObj(page)).objects[0].v; // the Parts view: pose 1
  await setMode(page, 'latent');
  await page.waitForFunction(() => /latent shape/i.test(document.querySelector('#caption').textContent));
  assert.match(await text(page, '#caption'), /turned by its R and moved by its b of pose/);
  assert.equal(await page.locator('[data-testid=latent-place]').isVisible(), true);
  const posed = await exportObj(page);
  assert.equal(posed.objects.length, 1);
  // where the parts are in the pose: within a few per cent of the pose itself (the model's residual)
  const r = relativeRms(pose, posed.objects[0].v);
  assert.ok(r < 0.03, `latent view vs the pose: RMS ${r} of the diagonal`);
  assert.match(posed.name, /latent-posed/);
  // the teaching choice: the parts in their own frames, on top of each other, and a caption saying so
  await page.selectOption('[data-testid=latent-place]', 'frames');
  await page.waitForFunction(() => /own frame/.test(document.querySelector('#caption').textContent));
  assert.match(await text(page, '#caption'), /on top of each other/);
  const frames_ = await exportObj(page);
  assert.ok(relativeRms(pose, frames_.objects[0].v) > 0.1, 'the latent frames are not the pose');
  await page.selectOption('[data-testid=latent-place]', 'moved');
  await page.waitForFunction(() => /not turned/.test(document.querySelector('#caption').textContent));
  assert.deepEqual(log.errors, []);
  await context.close();
});
