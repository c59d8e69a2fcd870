// A low-poly character in flat colours: each triangle shows one part's colour (colours no
// longer blend across a large triangle that spans two parts: "a rainbow"), and the hover box of a population
// with many poses lists a bounded number of them (a summary and the largest few), inside the view.
// Run: npm run build && node --test tests/e2e/flat-colours.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, paletteCounts, tubePopulation, asPayload, dropAndFit } from './helpers.mjs';

const session = pageSession();
const BACKGROUND = [0xee, 0xf0, 0xf3];

// The view's pixels: { mesh: not background, blended: mesh pixels of no palette colour (tol 3 per channel) }.
async function blendedPixels(page) {
  const counts = await paletteCounts(page);
  const mesh = await page.evaluate((bg) => {
    const { data } = window.__viewImage();
    let n = 0;
    for (let p = 0; p < data.length; p += 4) if (Math.abs(data[p] - bg[0]) > 3 || Math.abs(data[p + 1] - bg[1]) > 3 || Math.abs(data[p + 2] - bg[2]) > 3) n++;
    return n;
  }, BACKGROUND);
  const palette = Object.values(counts).reduce((a, b) => a + b, 0);
  return { mesh, blended: mesh - palette, colours: Object.values(counts).filter((c) => c > 50).length };
}

test('a low-poly character in flat colours: one part colour per triangle', async () => {
  // 106 vertices: four pieces of three rings of eight, triangles large enough that a ring of them spans every
  // joint
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const tube = tubePopulation({ segments: 4, ringsPerSegment: 3, around: 8, poses: 8, radius: 0.25 });
  await dropAndFit(page, asPayload(tube.files), { fitted: true });
  const s = await page.evaluate(() => window.posemfa.summary());
  assert.ok(s.vertices === 106 && s.parts >= 3, JSON.stringify({ vertices: s.vertices, parts: s.parts }));
  await page.check('#flat');
  await page.waitForTimeout(400);
  const px = await blendedPixels(page);
  assert.ok(px.mesh > 5000 && px.colours >= 3, JSON.stringify(px));
  // only the triangles' edges (antialiasing) may mix two colours: under 6 % of the mesh's pixels
  assert.ok(px.blended / px.mesh < 0.06, `${px.blended} of ${px.mesh} mesh pixels are blends of part colours`);
  console.log(`# flat colours, 106 vertices: ${JSON.stringify(px)}`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the hover box of a population of many poses is bounded and stays in the view', async () => {
  const { page, context, log } = await session.open('?preset=quadruped&vertices=300&poses=60');
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const canvas = await page.locator('#view canvas').boundingBox();
  // hover the mesh: the first point of a grid over the view's middle that is on it
  let hovered = false;
  for (let i = 0; i < 49 && !hovered; i++) {
    await page.mouse.move(canvas.x + canvas.width * (0.35 + 0.05 * (i % 7)), canvas.y + canvas.height * (0.35 + 0.05 * Math.floor(i / 7)));
    hovered = await page.waitForFunction(() => document.querySelector('#info table'), null, { timeout: 600 }).then(() => true, () => false);
  }
  assert.ok(hovered, 'a part hovered');
  const rows = await page.$$eval('#info table tr', (r) => r.length);
  assert.ok(rows <= 13, `${rows} rows for 60 poses`);
  assert.match(await page.locator('[data-testid=hover-summary]').innerText(), /^60 poses: median [0-9.]+°, largest [0-9.]+°; the 6 largest, in pose order \(54 more not listed\):$/);
  const info = await page.locator('#info').boundingBox();
  assert.ok(info.y + info.height <= canvas.y + canvas.height + 0.5, `the box ends inside the view: ${JSON.stringify(info)} in ${JSON.stringify(canvas)}`);
  assert.ok(info.height < canvas.height * 0.6, `the box covers ${info.height} of ${canvas.height} px of the view`);
  assert.deepEqual(log.errors, []);
  await context.close();
});
