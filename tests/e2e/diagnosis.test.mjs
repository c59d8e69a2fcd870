// The diagnosis in the page: the core's verdict next to the result ("Articulated" / "Not articulated" with its
// reason and what to use instead) and the part rule's curve, on the built-in examples at their (default)
// parameters; a count too few to judge (the part rule off, or a Refine to 2 parts) gets no verdict.
// Run: npm run build && node --test tests/e2e/diagnosis.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, moveTreeSlider } from './helpers.mjs';

const session = pageSession();

async function fitExample(page, id) {
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.selectOption('#example', id);
  await page.click('#generate');
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, n, { timeout: 60000, polling: 20 });
  return page.evaluate(() => window.posemfa.summary());
}

test('the quadruped is diagnosed articulated with its 18 parts, the blob is not, in words and with a curve', async () => {
  const { page, context, log } = await session.open('');
  await waitState(page, ['fitted', 'idle', 'error'], 60000);
  const q = await page.evaluate(() => window.posemfa.summary());
  assert.ok(q.parts >= 17 && q.parts <= 19, `quadruped: ${q.parts} parts`);
  assert.equal(q.diagnosis.articulated, true, JSON.stringify(q.diagnosis));
  assert.match(await page.locator('[data-testid=diagnosis]').innerText(), /^Articulated: \d+ rigid parts explain/);
  assert.ok(q.partCurve.length >= 1 && q.partCurve.at(-1).merged === false, JSON.stringify(q.partCurve));
  assert.ok(q.partCurve.slice(0, -1).every((p) => p.merged), JSON.stringify(q.partCurve));
  assert.equal(q.partCurve.at(-1).parts, q.parts, 'the curve stops at the part count kept');
  assert.ok(await page.locator('#part-curve').isVisible());

  const b = await fitExample(page, 'blob');
  assert.equal(b.diagnosis.articulated, false, JSON.stringify(b.diagnosis));
  assert.ok(b.diagnosis.explained < 0.975, JSON.stringify(b.diagnosis));
  const text = await page.locator('[data-testid=diagnosis]').innerText();
  assert.match(text, /^Not articulated: rigid parts explain only/);
  assert.match(text, /deformation model/);
  assert.ok(await page.locator('[data-testid=diagnosis].fails').isVisible());
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a few parts the user fixed with the part rule off get no verdict, not "Not articulated"', async () => {
  const { page, context, log } = await session.open('');
  await waitState(page, ['fitted', 'idle', 'error'], 60000);
  // Algorithm 1's coarse stage alone with 4 parts: too few for the quadruped's 18, which says nothing about it
  await page.uncheck('#params [name=refine]');
  await page.fill('#params [name=parts]', '4');
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((f) => window.posemfa.fitCount() > f && document.body.dataset.state === 'fitted', n, { timeout: 60000, polling: 20 });
  const s = await page.evaluate(() => window.posemfa.summary());
  // (a part cut in two pieces by the coarse stage becomes two parts: 4 or a few more)
  assert.ok(s.parts >= 4 && s.parts <= 8, `${s.parts} parts`);
  assert.equal(s.diagnosis.undecided, true, JSON.stringify(s.diagnosis));
  const text = await page.locator('[data-testid=diagnosis]').innerText();
  assert.match(text, new RegExp(`^No verdict: ${s.parts} rigid parts \\(a count the part rule did not judge\\) explain`));
  assert.doesNotMatch(text, /deformation model/);
  assert.equal(await page.locator('[data-testid=diagnosis].fails').count(), 0);
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
