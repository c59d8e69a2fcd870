// An eighth newcomer's review (docs/page-fixes.md): the clicked vertex's box goes when a new model comes (its
// part and error were the old model's) and when pose mode shows the rig's rest pose; the diagnosis of a count
// Refine asked for is no verdict when that count is too few, not "Not articulated"; fits A, B and A again show A
// in A's colours. (Refine fitting the partition the slider shows: tree.test.mjs.)
// Run: npm run build && node --test tests/e2e/review8.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, moveTreeSlider, enterPoseMode } from './helpers.mjs';

const session = pageSession();
const info = (page) => page.locator('#info').innerText().then((t) => t.trim());

async function pick(page, v) {
  await page.evaluate((x) => window.posemfa.inspect(x), v);
  await page.waitForFunction((x) => document.getElementById('info').textContent.startsWith(`Vertex ${x} `), v);
}

test('the vertex box goes with the model it was about, and in pose mode', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await pick(page, 5);
  const c = await page.evaluate(() => window.posemfa.fitCount());
  await page.fill('input[name=targetParts]', '9');
  await page.click('#fit');
  await page.waitForFunction((x) => window.posemfa.fitCount() > x && document.body.dataset.state === 'fitted', c, { timeout: 120000 });
  assert.equal(await info(page), '', 'the box of the model before is still up');
  // asked again: the new model's part
  await pick(page, 5);
  const part = (await page.evaluate(() => window.posemfa.fittedParts())).labels[5];
  assert.match(await info(page), new RegExp(`^Vertex 5 \\(.*\\): part ${part + 1} `));
  await page.click('[data-testid=mode-pose]');
  await page.waitForFunction(() => document.getElementById('info').textContent.trim() === '', null, { timeout: 10000 });
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('Refine of a few parts: no verdict, not "Not articulated"', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  assert.match(await page.locator('[data-testid=diagnosis]').innerText(), /^Articulated/);
  const c = await page.evaluate(() => window.posemfa.fitCount());
  await moveTreeSlider(page, 2);
  await page.click('[data-testid=tree-refine]');
  await page.waitForFunction((x) => window.posemfa.fitCount() > x && document.body.dataset.state === 'fitted', c, { timeout: 120000 });
  assert.equal((await page.evaluate(() => window.posemfa.summary())).parts, 2);
  assert.match(await page.locator('[data-testid=diagnosis]').innerText(), /^No verdict: 2 rigid parts \(a count the part rule did not judge\) explain/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('fits A, B and A again: the second A has the first A\'s colours', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const fitWith = async (parts) => {
    const c = await page.evaluate(() => window.posemfa.fitCount());
    await page.fill('input[name=targetParts]', parts);
    await page.click('#fit');
    await page.waitForFunction((x) => window.posemfa.fitCount() > x && document.body.dataset.state === 'fitted', c, { timeout: 120000 });
    return page.evaluate(() => window.posemfa.fittedParts());
  };
  const a = await page.evaluate(() => window.posemfa.fittedParts());
  const b = await fitWith('6');
  assert.equal(new Set(b.labels).size, 6);
  const again = await fitWith('');
  assert.deepEqual(again.labels, a.labels, 'the same fit');
  assert.deepEqual(again.colours, a.colours, 'A\'s parts in other colours after B');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('pose mode: the pose-space sliders follow the pose shown (rest pose, a turn), 0 at the mean pose', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const sliders = () => page.$$eval('#pose-modes input', (xs) => xs.map((x) => Number(x.value)));
  // each slider's value as the range and step put the pose's coordinate
  const placed = (coords) => page.$$eval('#pose-modes input', (xs, c) => xs.map((x) => {
    const probe = x.cloneNode();
    probe.value = String(c[Number(x.dataset.mode)]);
    return Number(probe.value);
  }), coords);
  // the sliders at the pose's coordinates, once the actions asked for have all been made (the pose is read
  // again until the two agree: a click's turn can still be on its way when the pose is first read)
  const settled = async (what) => {
    let want = null;
    for (let tries = 0; tries < 100; tries++) {
      want = await placed((await page.evaluate(() => window.posemfa.pose.vector())).coords);
      const now = await sliders();
      if (now.every((x, k) => x === want[k])) return want;
      await page.waitForTimeout(100);
    }
    return assert.fail(`${what}: sliders ${await sliders()} for the pose's ${want}`);
  };
  await page.click('#pose-reset');
  const rest = await settled('rest pose');
  await page.click('#pose-mean');
  const zero = await placed(new Array(rest.length).fill(0));
  await page.waitForFunction((w) => [...document.querySelectorAll('#pose-modes input')].every((x, k) => Number(x.value) === w[k]), zero, { timeout: 10000 });
  assert.notDeepEqual(rest, zero, 'the rest pose is not the mean pose, and its sliders say so');
  await page.click('#pose-plus');
  await page.click('#pose-plus');
  const turned = await settled('after a turn');
  assert.notDeepEqual(turned, zero, 'a turned part moves the pose off the mean');
  assert.deepEqual(log.errors, []);
  await context.close();
});
