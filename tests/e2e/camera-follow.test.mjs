// The camera follows the poses: the view is framed for every training pose's extent, so that
// picking another pose, interpolating or making a pose never cuts the mesh off, and picking poses that fit does
// not move the camera.
// Run: npm run build && node --test tests/e2e/camera-follow.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, tubePopulation, asPayload, dropAndFit } from './helpers.mjs';

const session = pageSession();

// A chain of four pieces whose first pose (the one the page frames when it opens) is curled up and whose others
// stretch out: the "crouching animal" of the issue. Files named so that the curled pose sorts first.
function curledFirst() {
  const tube = tubePopulation({ segments: 4, poses: 10, maxDeg: 120, seed: 3 });
  const extent = (f) => {
    const xs = [];
    const ys = [];
    for (const line of f.text.split('\n')) {
      if (!line.startsWith('v ')) continue;
      const [, x, y] = line.split(' ').map(Number);
      xs.push(x);
      ys.push(y);
    }
    return Math.max(Math.max(...xs) - Math.min(...xs), Math.max(...ys) - Math.min(...ys));
  };
  const sorted = tube.files.map((f) => ({ f, e: extent(f) })).sort((a, b) => a.e - b.e);
  return { files: sorted.map(({ f }, i) => ({ name: `pose${String(i + 1).padStart(2, '0')}.obj`, text: f.text })), ratio: sorted.at(-1).e / sorted[0].e };
}

const camera = (page) => page.evaluate(() => window.posemfa.camera());
const BACKGROUND = [0xee, 0xf0, 0xf3];
// Mesh pixels on the view's border (2 px wide): a mesh cut off by the view's edge shows there.
const onBorder = (page) => page.evaluate((bg) => {
  const { data, width, height } = window.__viewImage();
  let n = 0;
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) {
      if (x > 1 && x < width - 2 && y > 1 && y < height - 2) continue;
      const p = 4 * (y * width + x);
      if (Math.abs(data[p] - bg[0]) > 6 || Math.abs(data[p + 1] - bg[1]) > 6 || Math.abs(data[p + 2] - bg[2]) > 6) n++;
    }
  }
  return n;
}, BACKGROUND);
// In the view: no vertex projected outside it (the page's count) and no mesh pixel on its border.
async function inView(page, what) {
  assert.equal(await onBorder(page), 0, `${what}: the mesh reaches the view's edge`);
  assert.equal(await page.evaluate(() => window.posemfa.outOfView()), 0, `${what} has vertices outside the view`);
}
const shownAfter = async (page, act) => {
  await act();
  await page.waitForTimeout(400);
};

for (const [width, height] of [[1280, 800], [390, 844]]) test(`every pose picked, and an interpolation between the smallest and the largest, stay in the view (${width}x${height})`, async () => {
  const { page, context, log } = await session.open('', { width, height });
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const { files, ratio } = curledFirst();
  assert.ok(ratio > 1.5, `the poses' extents differ by ${ratio}`);
  await dropAndFit(page, asPayload(files), { fitted: true });
  await page.waitForTimeout(400);
  await inView(page, 'the first pose');
  let framed = null;
  for (let i = 1; i < files.length; i++) {
    await shownAfter(page, () => page.selectOption('#pose-select', String(i)));
    await inView(page, `pose ${i + 1}`);
    framed ??= await camera(page);
    assert.deepEqual(await camera(page), framed, `the camera moved for pose ${i + 1}`);
  }
  // interpolating from the curled pose to the stretched one: every t in the view, the camera still
  await page.click('input[name=mode][value=interp]');
  await page.waitForTimeout(500);
  await page.selectOption('#pose-a', '0');
  await page.selectOption('#pose-b', String(files.length - 1));
  const slider = page.locator('#interp-t');
  const interpFramed = await camera(page);
  for (const t of ['0', '0.25', '0.5', '0.75', '1']) {
    await slider.evaluate((s, v) => { s.value = v; s.dispatchEvent(new Event('input')); }, t);
    await page.waitForTimeout(500);
    await inView(page, `t = ${t}`);
  }
  assert.deepEqual(await camera(page), interpFramed, 'the camera did not move with t');
  assert.deepEqual(log.errors, []);
  await context.close();
});
