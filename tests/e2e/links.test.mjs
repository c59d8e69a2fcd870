// Links (the state in location.hash): a link made in the Pose view opens in the Pose view; a link with an unknown
// example or values the page does not read says what it ignored, and a link it reads whole says nothing.
// Run: npm run build && node --test tests/e2e/links.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState } from './helpers.mjs';

const session = pageSession();


test('a link made in the Pose view opens in the Pose view', async () => {
  const { page, context, log } = await session.open('#ex=quadruped&view=pose');
  await page.waitForFunction(() => window.posemfa?.fitCount() >= 1 && !window.posemfa.restoring(), null, { timeout: 120000 });
  await page.waitForFunction(() => window.posemfa.mode() === 'pose' && window.posemfa.pose?.ready(), null, { timeout: 120000 });
  await page.waitForFunction(() => /[#&]view=pose(&|$)/.test(location.hash), null, { timeout: 10000 });
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a link with an unknown example or unreadable values says what it ignored', async () => {
  const { page, context, log } = await session.open('#ex=nonsense&parts=abc&view=wat&seed=3');
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await page.waitForFunction(() => /This link names the example/.test(document.getElementById('errors').textContent), null, { timeout: 30000 });
  const text = await page.textContent('[data-testid=errors]');
  assert.match(text, /This link names the example “nonsense”, which is not one of the built-in examples \(.*quadruped.*\): showing the default example\./);
  assert.match(text, /Ignored in this link \(not values this page reads\): parts=abc, view=wat\./);
  assert.doesNotMatch(text, /seed=3/);
  // a link the page reads whole says nothing
  const again = await context.newPage();
  await again.goto(`${page.url().split('#')[0]}#ex=quadruped&view=stages`);
  assert.equal(await waitState(again, ['fitted', 'error'], 120000), 'fitted');
  assert.equal(await again.textContent('[data-testid=errors]'), '');
  assert.deepEqual(log.errors, []);
  await context.close();
});
