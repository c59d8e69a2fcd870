// "Measure at this t" in the Interpolate view: its report says what each error is measured against and how to
// read the stretch, scrolls in its own box, and leaves the view and the pose strip in the window.
// Run: npm run build && node --test tests/e2e/interpolate-report.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, text, openFitted, setMode } from './helpers.mjs';

const session = pageSession();

const fitted = (path, opts) => openFitted(session, path, opts);

test('"Measure at this t" says what each error is measured against', async () => {
  const { page, context, log } = await fitted('#ex=arm');
  await setMode(page, 'interp');
  await page.click('#measure');
  await page.waitForFunction(() => document.querySelector('#report table'));
  const table = await page.$$eval('#report tr', (rows) => rows.map((r) => [...r.children].map((c) => c.textContent)));
  assert.equal(table[0].at(-1), 'error measured against');
  const against = Object.fromEntries(table.slice(1).map((r) => [r[0], r.at(-1)]));
  assert.equal(against['rigid, residual off'], 'rigid reconstruction (eq 22)');
  assert.equal(against['rigid (default: anchor root, exact ends, residual)'], 'training poses');
  assert.equal(against['linear vertex interpolation'], 'training poses');
  // every row with the residual off, and only those, is measured against the reconstruction
  for (const [name, a] of Object.entries(against)) assert.equal(a === 'rigid reconstruction (eq 22)', /residual off/.test(name), name);
  const key = await text(page, '#report .report-key');
  assert.match(key, /^Edge stretch: every edge's length at t against .* two training poses\. Error at t=0 \/ t=1: .* rigid reconstruction \(eq 22\)/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('"Measure at this t": a line says how to read the stretch; the report scrolls in its own box, the poses stay in the window (1280x800, 390 wide)', async () => {
  for (const [width, height] of [[1280, 800], [390, 844]]) {
    const { page, context, log } = await fitted('', { width, height });
    await setMode(page, 'interp');
    await page.click('#measure');
    await page.waitForFunction(() => document.querySelector('#report table'));
    const reading = await text(page, '[data-testid=report-reading]');
    assert.match(reading, /^Reading the stretch: 0 % is every edge at exactly its mixed length, which is what a rigid motion gives inside a part that is rigid in the training poses\. Large figures on the edges crossing a part boundary .* where rigid parts pull apart or overlap at a joint, with no skinning/);
    const at = await page.evaluate(() => {
      const box = (id) => document.querySelector(id).getBoundingClientRect();
      const table = document.querySelector('#report .report-table');
      return {
        strip: box('#pose-strip'), view: box('#view-wrap'), report: box('#report'), page: document.documentElement.scrollWidth,
        inner: [innerWidth, innerHeight], across: [table.scrollWidth, table.clientWidth, getComputedStyle(table).overflowX],
      };
    });
    assert.ok(at.page <= width, `the page is ${at.page} px wide at ${width}`);
    assert.ok(at.report.right <= width + 0.5, `the report ends at ${at.report.right} px`);
    // what does not fit across scrolls in the table's own box
    if (at.across[0] > at.across[1]) assert.equal(at.across[2], 'auto', JSON.stringify(at.across));
    if (width === 1280) {
      // the page is the window's height: the view and the pose strip stay in it
      assert.ok(at.strip.bottom <= height + 0.5, `the pose strip ends at ${at.strip.bottom} px of ${height}`);
      assert.ok(at.view.height >= 200, `the view is ${at.view.height} px high`);
    }
    assert.deepEqual(log.errors, []);
    await context.close();
  }
});
