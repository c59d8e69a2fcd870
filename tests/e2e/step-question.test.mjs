// Step by step never looks dead: before it drops a finished fit it asks in the page, not
// with the browser's confirm box (which a browser may suppress and a script may never answer: Step and Run then
// did nothing and said nothing). No keeps the fit and says so; Yes starts the step-by-step fit.
// Run: npm run build && node --test tests/e2e/step-question.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState } from './helpers.mjs';

const session = pageSession();

for (const [width, height] of [[1280, 800], [390, 844]]) {
  test(`Step and Run ask in the page; No keeps the fit and says so; Yes starts (${width}x${height})`, async () => {
    const { page, context, log } = await session.open('#ex=arm', { width, height });
    assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
    const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
    for (const [sel, name] of [['[data-testid=teach-step]', 'Step'], ['#teach-run', 'Run']]) {
      await page.click(sel);
      const ask = page.locator('[data-testid=ask][role=alertdialog]');
      await ask.waitFor({ state: 'visible', timeout: 5000 });
      assert.match(await ask.innerText(), new RegExp(`^${name} starts a new step-by-step fit and drops the finished one \\(${parts} parts`));
      const box = await ask.boundingBox();
      assert.ok(box.y >= 0 && box.y + box.height <= height, `the question is in view: ${JSON.stringify(box)}`);
      await page.click('[data-testid=ask-no]');
      const kept = page.locator('[data-testid=ask].kept');
      await kept.waitFor({ state: 'visible', timeout: 5000 });
      assert.match(await kept.innerText(), new RegExp(`^Kept the finished fit \\(${parts} parts\\): no step-by-step fit was started`));
      assert.equal((await page.evaluate(() => window.posemfa.summary()))?.parts, parts, 'the fit stays');
      assert.equal(await page.evaluate(() => window.posemfa.teaching().active), false);
      assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
    }
    // Yes: the step-by-step fit starts, and the question goes
    await page.click('[data-testid=teach-step]');
    await page.click('[data-testid=ask-yes]');
    await page.waitForFunction(() => window.posemfa.teaching().iteration === 1, null, { timeout: 30000 });
    assert.equal(await page.locator('[data-testid=ask]').count(), 0);
    // Fit asks the same way before it drops the step-by-step fit
    await page.click('#fit');
    const ask = page.locator('[data-testid=ask][role=alertdialog]');
    await ask.waitFor({ state: 'visible', timeout: 5000 });
    assert.match(await ask.innerText(), /^Fit starts a new fit and drops the step-by-step fit at iteration 1/);
    await page.click('[data-testid=ask-no]');
    assert.match(await page.locator('[data-testid=ask].kept').innerText(), /^Kept the step-by-step fit at iteration 1/);
    assert.equal(await page.evaluate(() => window.posemfa.teaching().active), true);
    assert.deepEqual(log.dialogs, [], 'no browser dialog');
    assert.deepEqual(log.errors, []);
    await context.close();
  });
}
