// The pose strip (the thumbnails under the view): a drop while it is still being drawn draws the new population's
// strip; a glTF's frames are labelled by frame, not by the file name they all share; in the Interpolate view it
// marks From and To and takes no clicks.
// Run: npm run build && node --test tests/e2e/pose-strip.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { pageSession, waitState, asPayload, tubePopulation, dropAndFit, ROOT } from './helpers.mjs';

const session = pageSession();


test('a drop while the pose strip is still being drawn draws the new population\'s strip, with no error', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  // many poses: the strip takes seconds to draw, one thumbnail at a time, after the fit
  await dropAndFit(page, asPayload(tubePopulation({ poses: 48 }).files));
  const drawing = await page.evaluate(() => document.getElementById('pose-strip').dataset.drawn ?? null);
  // another mesh (other vertex count), dropped while the strip above is drawn
  const other = tubePopulation({ poses: 3, ringsPerSegment: 8 });
  await dropAndFit(page, asPayload(other.files));
  await page.waitForFunction((d) => (document.getElementById('pose-strip').dataset.drawn ?? null) !== d, drawing, { timeout: 60000 });
  assert.equal(await page.locator('#pose-strip canvas').count(), 3);
  assert.equal(await page.evaluate(() => window.posemfa.summary().vertices), other.nVertices);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the pose strip labels a glTF\'s frames by frame, not by the file name they all share', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const buffer = readFileSync(join(ROOT, 'tests/fixtures/blender/quadruped-shapekeys.glb'));
  await dropAndFit(page, [{ name: 'quadruped-shapekeys.glb', mimeType: 'model/gltf-binary', buffer }]);
  const labels = await page.locator('#pose-strip span').allTextContents();
  const titles = await page.locator('#pose-strip button').evaluateAll((bs) => bs.map((b) => b.title));
  assert.ok(labels.length > 2);
  assert.ok(titles.every((t) => t.startsWith('quadruped-shapekeys.glb ')), titles.join(' | '));
  assert.ok(labels.every((l, k) => !l.includes('.glb') && titles[k].endsWith(` ${l}`)), labels.join(' | '));
  assert.equal(new Set(labels).size, labels.length);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('in the Interpolate view the pose strip marks From and To and takes no clicks', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const pressed = () => page.locator('#pose-strip button').evaluateAll((bs) => bs.map((b) => b.getAttribute('aria-pressed') === 'true'));
  await page.check('#modes input[value=interp]', { force: true });
  await page.waitForFunction(() => window.posemfa.mode() === 'interp');
  await page.selectOption('#pose-a', '1');
  await page.selectOption('#pose-b', '3');
  const marks = await pressed();
  assert.deepEqual(marks.map((p, k) => (p ? k : -1)).filter((k) => k >= 0), [1, 3]);
  assert.equal(await page.locator('#pose-strip button:not([disabled])').count(), 0);
  assert.match(await page.getAttribute('#pose-strip', 'title'), /From and To/);
  // back in the Parts view the strip is the pose list again
  await page.check('#modes input[value=parts]', { force: true });
  await page.waitForFunction(() => window.posemfa.mode() === 'parts');
  assert.equal(await page.locator('#pose-strip button[disabled]').count(), 0);
  assert.equal((await pressed()).filter(Boolean).length, 1);
  assert.deepEqual(log.errors, []);
  await context.close();
});
