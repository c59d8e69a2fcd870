// The part rule's chart reads on its own (issue 55, finding 8): axis titles with the unit, a legend of its marks,
// and one sentence on what to read from it; every label drawn whole, at 1280x800 and 390x844.
// Run: npm run build && node --test tests/e2e/part-curve-chart.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState } from './helpers.mjs';

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
