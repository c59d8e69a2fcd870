// What ran, named: the Stages view's caption and pane labels (the merge tree's stages for the default fit,
// Algorithm 1's with the refinement off), the parts line of a finished or cancelled merge-tree fit, and the Stage
// field naming each run of the fit with its number.
// Run: npm run build && node --test tests/e2e/stages.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, openCancelledFirstFit, summary, text, frames, openFitted, setMode, untilFitted, nextFit } from './helpers.mjs';

const session = pageSession();
const fits = (page) => page.evaluate(() => window.posemfa.fitCount());

const fitted = (path, opts) => openFitted(session, path, opts);

// The parts line (next to the part count) of a merge-tree fit, finished or cancelled: the same words.
const TREE_PARTS = /^\(started from the merge tree's \d+ parts?(, cancelled)?\)$/;

test('the Stages view names what ran: the merge tree\'s stages for the default fit, Algorithm 1\'s otherwise; every pane labelled', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  assert.match(await text(page, '#stage-parts'), TREE_PARTS);
  await setMode(page, 'stages');
  await page.waitForFunction(() => window.posemfa.shown().join() === 'coarse,refined,final');
  await frames(page);
  const pose = await page.evaluate(() => document.getElementById('pose-select').selectedOptions[0].textContent);
  assert.equal(await text(page, '#caption'), `Merge-tree fit on pose “${pose}”: start (${s.coarseParts} parts) | after the part rule (${s.refinedParts}) | final (${s.parts})`);
  const labels = () => page.$$eval('#view .pane-label', (els) => els.map((e) => {
    const r = e.getBoundingClientRect();
    return { text: e.textContent, visible: !e.hidden && r.width > 0, x: r.left + r.width / 2 };
  }));
  let l = await labels();
  assert.deepEqual(l.map((x) => x.text), [`start (${s.coarseParts} parts)`, `after the part rule (${s.refinedParts} parts)`, `final (${s.parts} parts)`]);
  assert.ok(l.every((x) => x.visible), JSON.stringify(l));
  assert.ok(l[0].x < l[1].x && l[1].x < l[2].x, `left to right: ${JSON.stringify(l)}`);
  // one mesh: no label
  await setMode(page, 'parts');
  await frames(page);
  assert.equal((await labels()).filter((x) => x.visible).length, 0);
  // the refinement off: Algorithm 1's coarse stage alone, named as such
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.uncheck('#params input[name=refine]');
  await page.click('#fit');
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n, { timeout: 90000 });
  assert.equal(await waitState(page, ['fitted', 'error']), 'fitted');
  const a = await summary(page);
  // (a part of the coarse fit in pieces is a part per piece: the count after that is said when it is more)
  const pieces = a.parts > a.refinedParts ? `; ${a.parts} once each part is one connected piece` : '';
  assert.match(await text(page, '#stage-parts'), new RegExp(`^\\(coarse ${a.coarseParts}, no refinement${pieces}\\)$`));
  await setMode(page, 'stages');
  await page.waitForFunction(() => /^Algorithm 1 on pose/.test(document.getElementById('caption').textContent));
  await frames(page);
  assert.equal(await text(page, '#caption'), `Algorithm 1 on pose “${pose}”: coarse (${a.coarseParts} parts) | refined (${a.refinedParts}) | final (${a.parts})`);
  l = await labels();
  assert.deepEqual(l.map((x) => x.text.replace(/ \(.*/, '')), ['coarse', 'refined', 'final']);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a cancelled merge-tree fit says where its parts started as a finished one does', async () => {
  // a generated population large enough that Cancel lands in the fit's first run, before the merge tree of its
  // parts is built (a finished fit has that tree, and its slider; this one has none): the page's first fit, so
  // where it stopped is kept and shown
  const { page, context, log } = await openCancelledFirstFit(session, '?preset=quadruped&vertices=20000&poses=10');
  const s = await summary(page);
  assert.equal(s.cancelled, true, `cancelled before it ended: ${await text(page, '#stage')}`);
  assert.ok(s.coarseParts > 0, JSON.stringify({ ...s, logLikelihood: undefined }));
  assert.equal(await page.evaluate(() => window.posemfa.tree()), null, 'cancelled before its merge tree was built');
  assert.equal(await text(page, '#stage-parts'), `(started from the merge tree's ${s.coarseParts} part${s.coarseParts === 1 ? '' : 's'}, cancelled)`);
  assert.match(await text(page, '#stage-parts'), TREE_PARTS);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the Stage field names each run of the fit (the merge tree\'s start, the part rule\'s rounds) with its number', async () => {
  // a quadruped big enough that its first run spans several slices of the worker (40 ms each), and whose parts
  // are decided on a coarse mesh (8 000 vertices at 20 poses; with fewer poses it would be larger than half)
  const { page, context, log } = await session.open('?preset=quadruped&vertices=24000&poses=20');
  await untilFitted(page);
  const n = await fits(page);
  await page.evaluate(() => {
    window.__stages = [];
    // every text the field took, from the records (two changes in one task reach one callback)
    new MutationObserver((records) => {
      for (const r of records) {
        const texts = r.type === 'characterData' ? [r.target.data] : [...r.addedNodes].map((n) => n.textContent);
        for (const t of texts) if (window.__stages.at(-1) !== t) window.__stages.push(t);
      }
    }).observe(document.getElementById('stage'), { childList: true, characterData: true, subtree: true });
    document.getElementById('fit').click();
  });
  await nextFit(page, n);
  const stages = await page.evaluate(() => window.__stages);
  const runs = stages.filter((t) => /\(run \d+\)$/.test(t));
  // (24 000 vertices: the parts are decided on a coarse mesh, and the Stage field says so)
  assert.ok(runs.some((t) => /^fit from the merge tree's start, on a coarse mesh of \d+ vertices \(run 1\)$/.test(t)), JSON.stringify(stages));
  // run 2 is a refit after the part rule's first round: of the parts left when it removed some (still on the
  // coarse mesh), or, when it removed none (the start's flesh goes before run 1), the fit of all vertices
  assert.ok(
    runs.some((t) => /^(part rule, round 1: refit of the parts left, on a coarse mesh of \d+ vertices|the parts decided on a coarse mesh, fitted on all vertices) \(run 2\)$/.test(t)),
    JSON.stringify(stages),
  );
  assert.ok(!stages.includes('final'), `a bare "final": ${JSON.stringify(stages)}`);
  const numbers = runs.map((t) => Number(t.match(/\(run (\d+)\)$/)[1]));
  assert.deepEqual(numbers, [...numbers].sort((a, b) => a - b), 'run numbers only go up');
  assert.equal(stages.at(-1), 'done');
  assert.deepEqual(log.errors, []);
  await context.close();
});
