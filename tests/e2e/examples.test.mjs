// The built-in examples: the picker shows every title in full and says "your files" once files are opened;
// the tied-legs example says what it shows (app and article); an example that fails on purpose leads its result
// with what failed in this fit.
// Run: npm run build && node --test tests/e2e/examples.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, tubePopulation, asPayload, summary, text, frames, openFitted } from './helpers.mjs';

const session = pageSession();

const fitted = (path, opts) => openFitted(session, path, opts);

// Clicks a preset and waits for its fit.
async function preset(page, id) {
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click(`[data-testid=presets] button[data-id=${id}]`);
  await page.waitForFunction((c) => window.posemfa.fitCount() > c && document.body.dataset.state === 'fitted', n, { timeout: 90000, polling: 20 });
}

const picked = (page) => page.$eval('#example', (s) => ({ value: s.value, text: s.selectedOptions[0]?.textContent ?? '' }));

test('the example picker shows every example\'s title in full (1280 wide), and on a phone stays inside the window', async () => {
  for (const width of [1280, 390]) {
    const { page, context, log } = await fitted('', { width, height: 800 });
    const m = await page.evaluate(() => {
      const sel = document.getElementById('example');
      const g = document.createElement('canvas').getContext('2d');
      const cs = getComputedStyle(sel);
      g.font = `${cs.fontWeight} ${cs.fontSize} ${cs.fontFamily}`;
      const titles = [...sel.options].filter((o) => !o.hidden).map((o) => o.textContent);
      const widest = Math.max(...titles.map((t) => g.measureText(t).width));
      const r = sel.getBoundingClientRect();
      return { titles: titles.length, widest, inner: sel.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight), right: r.right, page: document.documentElement.scrollWidth, title: sel.title, shown: sel.selectedOptions[0].textContent };
    });
    assert.ok(m.titles >= 5, JSON.stringify(m));
    if (width === 1280) assert.ok(m.inner >= m.widest, `the picker's text box is ${m.inner} px for a title of ${m.widest} px`);
    assert.ok(m.right <= width + 0.5 && m.page <= width, JSON.stringify(m));
    assert.equal(m.title, m.shown, 'the whole title on hover');
    assert.deepEqual(log.errors, []);
    await context.close();
  }
});

test('the example picker says "your files" once files are opened, not the example shown before; Generate needs an example again', async () => {
  const { page, context, log } = await fitted();
  const first = await picked(page);
  assert.equal(first.value, 'quadruped');
  assert.ok(first.text.length > 0 && !/your files/.test(first.text), JSON.stringify(first));
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.setInputFiles('[data-testid=file-input]', asPayload(tubePopulation({ segments: 3, poses: 6 }).files));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 90000 });
  const mine = await picked(page);
  assert.equal(mine.text, 'your files');
  assert.notEqual(mine.value, 'quadruped');
  assert.equal(await page.isDisabled('#generate'), true, 'Generate & fit has no example to generate');
  // picking an example again: Generate works, and the picker names it
  await page.selectOption('#example', 'arm');
  assert.equal(await page.isDisabled('#generate'), false);
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#generate');
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n, { timeout: 90000 });
  assert.equal((await picked(page)).value, 'arm');
  assert.equal(await page.locator('#example option[value=arm]').evaluate((o) => o.selected), true);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the tied-legs example says what it shows: one motion, two parts kept apart by connectivity (app and article)', async () => {
  const { page, context, log } = await fitted('#ex=too-few-poses');
  const note = await text(page, '#example-note');
  assert.doesNotMatch(note, /Fails on purpose/);
  assert.match(note, /same motion/);
  assert.match(note, /do not touch/);
  const title = await page.locator('[data-testid=presets] button[data-id=too-few-poses]').innerText();
  assert.doesNotMatch(title, /fails|never move apart/i);
  const s = await summary(page);
  assert.ok(s.groundTruth.ari > 0.95, `the legs are two parts each, as the note says: ARI ${s.groundTruth.ari}`);
  // after the fit the result says what the limit was, with the fit's own figures for each tied pair
  const lead = await text(page, '[data-testid=limit-lead]');
  assert.match(lead, /^The tied parts: in each of the 3 pairs \(front left upper and front right upper; front left lower and front right lower; front left foot and front right foot\)/);
  assert.match(lead, /motion cannot tell them apart, and they stay two parts only because they do not touch\.$/);
  const shown = Number(lead.match(/agree within ([\d.]+)°/)[1]);
  const worst = Math.max(...s.groundTruth.tied.map((t) => t.motionGapDeg));
  assert.ok(shown < 1 && Math.abs(shown - worst) < 0.006, `${lead} (core: ${worst})`);
  // (the page names parts from 1, the summary's labels are indices from 0)
  for (const t of s.groundTruth.tied) assert.match(lead, new RegExp(`\\b${t.fitted[0] + 1} and ${t.fitted[1] + 1}\\b`));
  await context.close();

  const art = await session.open('explain.html');
  await art.page.locator('[data-figure=tied]').scrollIntoViewIfNeeded();
  await art.page.waitForFunction(() => /agree within/.test(document.querySelector('[data-figure=tied] .fig-status')?.textContent ?? ''), null, { timeout: 60000, polling: 100 });
  const cap = await art.page.locator('[data-figure=tied] figcaption').innerText();
  assert.doesNotMatch(cap, /can only give them one motion/);
  assert.match(cap, /do not touch/);
  const status = await art.page.locator('[data-figure=tied] .fig-status').innerText();
  const within = Number(status.match(/agree within ([\d.]+)°/)[1]);
  assert.ok(within < 1, status);
  assert.deepEqual([...log.errors, ...art.log.errors], []);
  await art.context.close();
});

test('an example that fails on purpose leads its result with what failed in this fit; others do not', async () => {
  const { page, context, log } = await fitted();
  assert.equal(await page.locator('[data-testid=fail-lead]').isVisible(), false, 'the quadruped did not fail');
  assert.equal(await page.locator('[data-testid=limit-lead]').isVisible(), false, 'the quadruped ties no parts');
  assert.match(await text(page, '[data-testid=truth-acc]'), /\(18 true parts\)$/);

  await preset(page, 'blob');
  assert.ok(await page.locator('[data-testid=fail-lead].fails').isVisible());
  assert.match(await text(page, '[data-testid=fail-lead]'), /^Failed, as this example means to\. The shape is not articulated: rigid parts explain only \d+\.\d % of its motion \(the verdict below\)\.$/);
  assert.match(await text(page, '[data-testid=truth-acc]'), /^one true part, so no adjusted Rand index \(every labelling scores 0 against one part\); rotation error \d+\.\d\d° against each pose's best rigid fit$/);

  await preset(page, 'literal-eq18');
  let s = await summary(page);
  const drops = (ll) => ll.filter((v, i) => i > 0 && v < ll[i - 1]).length;
  assert.equal(s.converged, false);
  const lead = await text(page, '[data-testid=fail-lead]');
  assert.ok(await page.locator('[data-testid=fail-lead].fails').isVisible());
  assert.ok(lead.startsWith(`Failed, as this example means to. AECM did not converge (it stopped at the iteration cap after ${s.iterations} iterations); `
    + `the log-likelihood fell ${drops(s.logLikelihood)} times in the final stage's ${s.logLikelihood.length} iterations`), lead);
  assert.ok(drops(s.logLikelihood) > 0);
  // the lead comes first in the result, before the part count
  const order = await page.evaluate(() => {
    const lead = document.getElementById('fail-lead');
    return lead.compareDocumentPosition(document.getElementById('parts-count')) & Node.DOCUMENT_POSITION_FOLLOWING;
  });
  assert.ok(order);

  // the same example with the exact Λ step: what the lead says follows this fit, not the example's name
  await page.uncheck('#params [name=paperLambda]');
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((c) => window.posemfa.fitCount() > c && document.body.dataset.state === 'fitted', n, { timeout: 90000, polling: 20 });
  s = await summary(page);
  assert.equal(drops(s.logLikelihood), 0, 'the exact step never lowers the log-likelihood');
  const after = await text(page, '[data-testid=fail-lead]');
  assert.doesNotMatch(after, /fell \d+ times/);
  if (s.converged) {
    assert.match(after, new RegExp(`^This example is meant to fail, but this fit did not: it converged in ${s.iterations} iterations`));
    assert.equal(await page.locator('[data-testid=fail-lead].fails').count(), 0);
  } else {
    assert.match(after, /^Failed, as this example means to\. AECM did not converge/);
  }
  assert.deepEqual(log.errors, []);
  await context.close();
});
