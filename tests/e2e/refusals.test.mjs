// Files the page refuses, and what stays: poses that are all one shape, a pose file cut short (its file and
// line named), a .txt dropped (one problem, naming the file ignored); the fitted population stays each time.
// Run: npm run build && node --test tests/e2e/refusals.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, tubePopulation, asPayload, text } from './helpers.mjs';

const session = pageSession();

async function fitted(page) {
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted', await text(page, '[data-testid=errors]'));
}

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

test('a pose file cut short is refused naming its file and line, saying it looks cut short; the population stays', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const before = await page.evaluate(() => ({ summary: window.posemfa.summary(), errors: window.posemfa.loadErrorCount() }));
  const { files } = tubePopulation({ poses: 3 });
  // the second pose stops in the middle of a vertex line, as an interrupted copy leaves it
  const whole = files[1].text;
  const cutAt = whole.indexOf('\n', Math.floor(whole.length / 4)) + 6;
  const cut = whole.slice(0, cutAt);
  const line = cut.split('\n').length;
  assert.doesNotMatch(cut.slice(-5), /\n/); // it ends 5 characters into a vertex line
  await page.setInputFiles('[data-testid=file-input]', asPayload([files[0], { name: files[1].name, text: cut }, files[2]]));
  await page.waitForFunction((n) => window.posemfa.loadErrorCount() > n, before.errors, { timeout: 30000 });
  const text = await page.textContent('[data-testid=errors]');
  assert.ok(text.includes(`${files[1].name}, line ${line}: `), text);
  assert.match(text, /looks cut short.*copy or export it again/);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  assert.deepEqual(await page.evaluate(() => window.posemfa.summary()), before.summary);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('one .txt dropped is one problem, naming the file ignored', async () => {
  const { page, context } = await session.open();
  await fitted(page);
  await page.setInputFiles('[data-testid=file-input]', [{ name: 'notes.txt', mimeType: 'text/plain', buffer: Buffer.from('hello') }]);
  await page.waitForFunction(() => window.posemfa.loadErrorCount() > 0);
  const box = await text(page, '[data-testid=errors]');
  assert.match(box, /^1 problem; the previous population is kept/);
  assert.equal(await page.locator('[data-testid=errors] li').count(), 1);
  assert.match(box, /no mesh file .*ignored: notes\.txt/);
  await context.close();
});
