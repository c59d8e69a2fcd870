// What a new fit, a cancelled fit and a failed fit leave on the page: a new population starts from the default
// settings, not the last population's; while a fit has no parts yet the mesh is grey and the caption says so;
// fits A, B and A again show A in A's colours; Cancel or a failure on a new fit of the same population keeps the
// finished fit with its verdict and figures; a cancelled first fit gets no verdict, and its caption says where it
// stopped.
// Run: npm run build && node --test tests/e2e/fit-lifecycle.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { pageSession, waitState, tubePopulation, asPayload, moveTreeSlider, openCancelledFirstFit, dropAndFit, summary, text, frames, openFitted, untilFitted, nextFit } from './helpers.mjs';

const session = pageSession();
const fits = (page) => page.evaluate(() => window.posemfa.fitCount());

// The Log-likelihood field's number: nats, its thousands apart (views/result.js natsText)
const natsValue = (t) => {
  const m = t.match(/^(−?)([\d\u202f]+\.\d{2}) nats$/);
  assert.ok(m, `"${t}" is a log-likelihood in nats`);
  return Number(`${m[1] ? '-' : ''}${m[2].replace(/\u202f/g, '')}`);
};

const fitted = (path, opts) => openFitted(session, path, opts);

test('a new population starts with "Parts in the end" on auto and the exact Λ step, whatever the last one had', async () => {
  const { page, context, log } = await session.open('#ex=literal-eq18');
  await untilFitted(page);
  assert.equal(await page.isChecked('#params [name=paperLambda]'), true, 'the eq 18 example ticks the literal step');
  // Refine N on that population: "Parts in the end" = N
  const parts = (await summary(page)).parts;
  const tree = await page.evaluate(() => window.posemfa.tree());
  const want = parts > tree.fewest + 1 ? parts - 1 : parts + 1;
  await moveTreeSlider(page, want);
  let n = await fits(page);
  await page.click('[data-testid=tree-refine]');
  await nextFit(page, n);
  assert.equal((await summary(page)).parts, want);
  assert.equal(await page.inputValue('#params [name=targetParts]'), String(want));
  // a new population of 3 rigid pieces: fitted with the defaults of both, not with N parts and eq 18
  n = await fits(page);
  const tube = tubePopulation({ segments: 3, poses: 8 });
  await page.setInputFiles('[data-testid=file-input]', asPayload(tube.files));
  await nextFit(page, n);
  assert.equal(await page.inputValue('#params [name=targetParts]'), '');
  assert.equal(await page.isChecked('#params [name=paperLambda]'), false);
  const s = await summary(page);
  assert.notEqual(s.parts, want, `the tube was fitted with the ${want} parts asked for the last population`);
  assert.equal(s.converged, true, 'the default fit of the tube converges');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('while a fit has no parts yet the caption says the mesh is grey, not coloured by parts', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  // every caption the parts view shows from the drop on, with the page's state when it showed it
  await page.evaluate(() => {
    window.captionsSeen = [];
    const caption = document.getElementById('caption');
    new MutationObserver(() => window.captionsSeen.push({ text: caption.textContent, state: document.body.dataset.state }))
      .observe(caption, { childList: true, characterData: true, subtree: true });
  });
  await dropAndFit(page, asPayload(tubePopulation({ poses: 6 }).files));
  const seen = await page.evaluate(() => window.captionsSeen);
  const during = seen.filter((c) => c.state === 'fitting').map((c) => c.text);
  assert.ok(during.length > 0, `captions while fitting: ${JSON.stringify(seen)}`);
  // the new population comes with no parts: grey, and the caption says so until the first parts arrive
  assert.match(during[0], /grey until the fit in progress has its first parts/);
  const first = during.findIndex((t) => /coloured by the parts of the fit in progress/.test(t));
  if (first >= 0) assert.ok(during.slice(first).every((t) => !/grey until/.test(t)), `parts, then grey again: ${during.join(' | ')}`);
  assert.match(await page.textContent('#caption'), /coloured by part/);
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

test('Cancel on a new fit of the same population keeps the finished fit, its verdict and figures, and says so', async () => {
  // a quadruped big enough that a new fit spans many slices of the worker (40 ms each): the built-in example
  // can finish before the Cancel is read
  const { page, context, log } = await session.open('?preset=quadruped&vertices=24000&poses=10');
  await untilFitted(page);
  const before = await summary(page);
  const parts = await page.evaluate(() => window.posemfa.fittedParts());
  const verdict = await text(page, '[data-testid=diagnosis]');
  assert.match(verdict, /^Articulated/);
  const n = await fits(page);
  // Cancel as soon as the new fit runs
  await page.evaluate(() => new Promise((done) => {
    const seen = new MutationObserver(() => {
      if (document.body.dataset.state !== 'fitting') return;
      seen.disconnect();
      document.getElementById('cancel').click();
      done();
    });
    seen.observe(document.body, { attributes: true, attributeFilter: ['data-state'] });
    document.getElementById('fit').click();
  }));
  await nextFit(page, n);
  const after = await summary(page);
  assert.equal(after.cancelled, false, 'the model shown is the finished one');
  assert.equal(after.parts, before.parts);
  assert.deepEqual(after.logLikelihood, before.logLikelihood);
  assert.deepEqual(await page.evaluate(() => window.posemfa.fittedParts()), parts);
  assert.match(await text(page, '#stage'), /cancelled.*finished fit before it is kept/);
  assert.doesNotMatch(await text(page, '#stage'), /best/);
  assert.equal(await text(page, '[data-testid=diagnosis]'), verdict);
  assert.equal(natsValue(await text(page, '#loglik')).toFixed(2), before.logLikelihood.at(-1).toFixed(2));
  // the worker kept it too: the exported model is the finished fit's
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-json')]);
  const json = JSON.parse(await readFile(await download.path(), 'utf8'));
  assert.deepEqual(json.labels, parts.labels);
  assert.equal(json.complete, true);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a fit that fails keeps the finished fit and its figures; the next Fit clears the failure', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const c = await page.evaluate(() => window.posemfa.fitCount());
  const tube = tubePopulation({ poses: 6 });
  await page.setInputFiles('[data-testid=file-input]', asPayload(tube.files));
  await page.waitForFunction((x) => window.posemfa.fitCount() > x && document.body.dataset.state === 'fitted', c, { timeout: 120000 });
  const kept = { loglik: await text(page, '#loglik'), parts: (await page.evaluate(() => window.posemfa.summary())).parts };
  // the most parts the form lets through (every part needs 4 vertices): the tube's parts cannot all be cut so
  // far, and the fit fails after running
  await page.fill('input[name=targetParts]', String(Math.floor(tube.nVertices / 4)));
  const d = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((x) => window.posemfa.fitCount() > x && document.body.dataset.state !== 'fitting', d, { timeout: 120000 });
  const box = await text(page, '[data-testid=errors]');
  assert.match(box, /^The fit failed; the previous model is kept/);
  assert.match(box, /cannot reach \d+ parts: .* ask for at most \d+ parts/);
  assert.doesNotMatch(box, /min_part_vertices|target_parts/, 'the page has no such field');
  assert.equal(await text(page, '#stage'), 'new fit failed: the finished fit before it is kept');
  assert.equal(await text(page, '#loglik'), kept.loglik, 'the kept fit\'s log-likelihood, not the failed run\'s');
  assert.match(await text(page, '#iteration'), /^\d+ in the final stage$/);
  assert.equal((await page.evaluate(() => window.posemfa.summary())).parts, kept.parts);
  // a field that cannot be used: said under the form as soon as it is left, and the old failure goes on Fit
  await page.fill('input[name=targetParts]', 'abc');
  await page.locator('input[name=targetParts]').blur();
  await page.waitForFunction(() => document.querySelectorAll('[data-testid=param-errors] li').length === 1, null, { timeout: 10000 });
  await page.click('#fit');
  await page.waitForFunction(() => !/The fit failed/.test(document.querySelector('[data-testid=errors]').innerText), null, { timeout: 10000 });
  assert.match(await text(page, '[data-testid=param-errors]'), /^Parts in the end: /);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a cancelled fit gets no verdict: "cancelled: the diagnosis needs a finished fit"', async () => {
  const { page, context, log } = await fitted();
  assert.match(await text(page, '[data-testid=diagnosis]'), /^Articulated/);
  const n = await page.evaluate(() => window.posemfa.fitCount());
  // Cancel as soon as the first fit of new files runs (a new fit of a fitted population keeps the finished
  // model instead: the test of Cancel on a new fit above): its first slice (40 ms) is in its first run
  // (a tolerance no fit reaches, without the refinement: Algorithm 1's coarse AECM runs on, as in page.test.mjs)
  const tube = tubePopulation({ segments: 5, poses: 24, ringsPerSegment: 60, around: 40, seed: 11 });
  await page.fill('#params input[name=tol]', '1e-12');
  await page.uncheck('#params input[name=refine]');
  await page.evaluate(() => {
    const seen = new MutationObserver(() => {
      if (document.body.dataset.state !== 'fitting') return;
      seen.disconnect();
      document.getElementById('cancel').click();
    });
    seen.observe(document.body, { attributes: true, attributeFilter: ['data-state'] });
  });
  await page.setInputFiles('[data-testid=file-input]', asPayload(tube.files));
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n, { timeout: 60000 });
  const s = await summary(page);
  assert.equal(s.cancelled, true, `the fit was cancelled before it ended: ${JSON.stringify({ ...s, logLikelihood: s.logLikelihood?.length })} ${await text(page, "#stage")}`);
  assert.equal(s.diagnosis, null);
  assert.equal(await text(page, '[data-testid=diagnosis]'), 'Cancelled: the diagnosis needs a finished fit.');
  assert.equal(await page.locator('[data-testid=diagnosis].fails').count(), 0);
  assert.match(await text(page, '#stage'), /^cancelled: where the fit stopped$/); // not "best": it may not be
  // with the refinement off the fit is Algorithm 1's: its stages by Algorithm 1's names
  assert.match(await text(page, '#stage-parts'), /^\(coarse \d+, no refinement, cancelled\)$/);
  // its iterations are the run's it stopped in, not "the final stage's"
  assert.match(await text(page, '#iterations'), /^\d+ in the run where the fit was cancelled$/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a cancelled first fit\'s caption: where it stopped, then the count and the colours', async () => {
  const { page, context, log } = await openCancelledFirstFit(session, '?preset=quadruped&vertices=20000&poses=10');
  await frames(page);
  const s = await summary(page);
  assert.equal(s.cancelled, true);
  assert.match(await text(page, '#caption'), new RegExp(`^Pose “[^”]+”, coloured by part where the cancelled fit stopped \\(${s.parts} parts(; 12 colours, so parts that do not touch can share one)?\\)$`));
  assert.deepEqual(log.errors, []);
  await context.close();
});
