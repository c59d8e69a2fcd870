// The part rule's chart reads on its own: axis titles with the unit (powers of ten written as numbers), a legend
// of its marks, and one sentence on what to read from it; every label drawn whole, at 1280x800 and 390x844. Its
// note says what became of the rule's last decision when a count was asked for, and that after Refine it judged
// the refined parts and changed nothing.
// Run: npm run build && node --test tests/e2e/part-curve-chart.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, summary, text, frames } from './helpers.mjs';
import { decade } from '../../www/views/part-curve.js';

const session = pageSession();

for (const [width, height] of [[1280, 800], [390, 844]]) {
  test(`the part rule chart has axis titles with units, a legend and a sentence on reading it (${width}x${height})`, async () => {
    const { page, context, log } = await session.open('', { width, height });
    assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
    const chart = await page.$eval('#part-curve', (c) => ({ ...c.dataset, hidden: c.hidden }));
    assert.equal(chart.hidden, false);
    assert.match(chart.yTitle ?? '', /^pair score \(× part error\)$/, 'the y axis says what the score is and its unit');
    assert.match(chart.xTitle ?? '', /parts/, 'the x axis says what it counts');
    assert.equal(chart.clipped, '0', 'every label drawn whole');
    const legend = page.locator('[data-testid=part-curve-legend]');
    assert.ok(await legend.isVisible(), 'a legend under the chart');
    const text = await legend.innerText();
    for (const mark of ['a pair merged', 'the pair kept apart', 'the distinct ratio']) assert.ok(text.includes(mark), `the legend names "${mark}": ${text}`);
    assert.match(text, /log scale/);
    assert.match(text, /Read it: each dot is the cheapest pair of neighbouring parts at that count/);
    assert.match(text, /below the dashed line the two move as one and were merged/);
    // the legend's marks are drawn as the chart draws them (a filled dot, a hollow red one, a dashed line)
    const marks = await page.$$eval('[data-testid=part-curve-legend] span', (s) => s.map((e) => e.className));
    assert.deepEqual(marks, ['dot merged', 'dot kept', 'dash']);
    assert.deepEqual(log.errors, []);
    await context.close();
  });
}

test('powers of ten are written as numbers', () => {
  assert.deepEqual([0, 1, 2, 4].map(decade), ['1', '10', '100', '10000']);
  assert.deepEqual([-1, -3].map(decade), ['0.1', '0.001']);
  assert.deepEqual([5, 12, -4, -10].map(decade), ['10⁵', '10¹²', '10⁻⁴', '10⁻¹⁰']);
});

test('a count asked for: the part rule\'s note says its last decision was split or merged to the parts shown', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  // (Refine fits the slider's partition itself and the rule does not decide: tree.test.mjs)
  await page.fill('#params [name=targetParts]', '8');
  const c = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((x) => window.posemfa.fitCount() > x, c, { timeout: 120000 });
  await frames(page);
  const s = await summary(page);
  assert.equal(s.parts, 8);
  const last = s.partRounds[s.partRounds.length - 1];
  assert.notEqual(last.after, 8, JSON.stringify(s.partRounds));
  const note = await text(page, '[data-testid=part-curve-note]');
  assert.ok(note.endsWith(`merges ${last.parts - last.dissolved} → ${last.after}; then the count asked for in “Parts in the end” split or merged these to 8 parts, the parts shown.`), note);
  // an auto fit ends with the rule's own count: no such clause
  await page.fill('#params [name=targetParts]', '');
  const d = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((x) => window.posemfa.fitCount() > x, d, { timeout: 120000 });
  await frames(page);
  assert.ok(!(await text(page, '[data-testid=part-curve-note]')).includes('then '));
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('after Refine the part rule\'s chart says it judged the refined parts and changed nothing', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.evaluate((v) => {
    const s = document.getElementById('tree-slider');
    s.value = String(v);
    s.dispatchEvent(new Event('input'));
  }, parts - 2);
  await page.waitForFunction((v) => document.getElementById('tree-slider').dataset.count === String(v), parts - 2);
  await page.click('[data-testid=tree-refine]');
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 90000 });
  assert.equal(await waitState(page, ['fitted', 'error'], 90000), 'fitted');
  const title = await page.evaluate(() => document.getElementById('part-curve').dataset.title);
  assert.match(title, new RegExp(`^part rule on the refined parts, not applied: \\d+ merges? would make ${parts - 2} → \\d+$`));
  assert.equal(await page.textContent('#part-curve-note'), `The chart is the part rule on the ${parts - 2} parts refined from the merge tree: it judges them, and a Refine keeps them as they are.`);
  assert.deepEqual(log.errors, []);
  await context.close();
});
