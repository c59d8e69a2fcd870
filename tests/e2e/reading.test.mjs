// The result read as what it is: the part rule's chart says it is the last round's
// merges, the Stages view's panels keep a part's colour from one stage to the next, a cancelled first fit leads
// with being a partial model (its exports too), Refine says it set "Parts in the end", the RMSE is one figure
// when both units print the same, the log-likelihood plot shows the whole fit's runs with a min and a max that
// differ when they do, pose mode's caption while the rig is built, and Run's length said before it runs.
// Run: npm run build && node --test tests/e2e/reading.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, openCancelledFirstFit, moveTreeSlider, summary, text, frames } from './helpers.mjs';

const session = pageSession();

async function fitted(path = '') {
  const p = await session.open(path);
  assert.equal(await waitState(p.page, ['fitted', 'error'], 120000), 'fitted');
  await frames(p.page);
  return p;
}

// Parts of two stages that are the same (each holds more than half of the other's vertices), and their colours.
function sameParts(a, b) {
  const sizeA = new Map();
  const sizeB = new Map();
  const both = new Map();
  a.labels.forEach((l, v) => {
    const m = b.labels[v];
    sizeA.set(l, (sizeA.get(l) ?? 0) + 1);
    sizeB.set(m, (sizeB.get(m) ?? 0) + 1);
    both.set(`${l},${m}`, (both.get(`${l},${m}`) ?? 0) + 1);
  });
  return [...both].map(([k, n]) => k.split(',').map(Number).concat(n))
    .filter(([l, m, n]) => 2 * n > sizeA.get(l) && 2 * n > sizeB.get(m))
    .map(([l, m]) => ({ l, m, colours: [a.colours[l], b.colours[m]] }));
}

test('the part rule\'s chart says it is the last round\'s merges, and from what count; the Stages view\'s start is named beside it', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  assert.ok(s.partCurve.length > 0 && s.partsFrom === 'merge tree', JSON.stringify(s.partCurve));
  const from = s.partCurve[0].parts;
  const title = await page.evaluate(() => document.getElementById('part-curve').dataset.title);
  assert.match(title, new RegExp(`^part rule, last round: \\d+ merges?, ${from} → ${s.parts} parts?$`));
  const note = await text(page, '[data-testid=part-curve-note]');
  // the default quadruped starts from more parts than its last round saw: the note says where they went, with
  // the core's record of the start and of every round
  assert.ok(s.coarseParts > from, `${s.coarseParts} > ${from}`);
  const flesh = s.coarseParts - s.startParts;
  assert.ok(s.partRounds.length > 0 && flesh > 0, JSON.stringify(s));
  assert.ok(note.startsWith(`The chart is the part rule's last round. The merge tree's start had ${s.coarseParts} parts, ${flesh} of them flesh between parts, dissolved before the first AECM; `), note);
  s.partRounds.forEach((r, i) => assert.ok(note.includes(`round ${i + 1} judged the AECM's ${r.parts} parts: ${r.dissolved} dissolved as flesh, merges ${r.parts - r.dissolved} → ${r.after}`), note));
  const last = s.partRounds[s.partRounds.length - 1];
  assert.equal(last.parts - last.dissolved, from, JSON.stringify(s.partRounds));
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the Stages view: a part that is the same in two neighbouring stages keeps its colour', async () => {
  const { page, context, log } = await fitted();
  const stage = (name) => page.evaluate((n) => window.posemfa.stageParts(n), name);
  const [coarse, refined, final] = [await stage('coarse'), await stage('refined'), await stage('final')];
  for (const [name, a, b] of [['start -> after the part rule', coarse, refined], ['after the part rule -> final', refined, final]]) {
    const same = sameParts(a, b);
    assert.ok(same.length >= 10, `${name}: ${same.length} parts the same`);
    const differ = same.filter((p) => p.colours[0] !== p.colours[1]);
    assert.deepEqual(differ, [], `${name}: the same part in another colour`);
  }
  // each panel still tells its own parts apart: the 18 final parts have 12 colours, every one used
  assert.equal(new Set(final.colours).size, Math.min(12, final.colours.length));
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a cancelled first fit leads with being a partial model, and its exports say they write it; a finished fit does not', async () => {
  // large enough that Cancel lands in the fit's first run (as stages.test.mjs's cancelled merge-tree fit)
  const { page, context, log } = await openCancelledFirstFit(session, '?preset=quadruped&vertices=20000&poses=10');
  await frames(page);
  const s = await summary(page);
  assert.equal(s.cancelled, true, await text(page, '#stage'));
  const lead = await text(page, '[data-testid=cancel-lead]');
  assert.match(lead, /^Cancelled (after \d+ iterations?|before its first iteration): a partial model, not a result\./);
  const total = (await text(page, '#iteration')).match(/total (\d+)/)?.[1];
  if (total) assert.ok(lead.startsWith(`Cancelled after ${total} iteration`), `${lead} / ${total}`);
  for (const id of ['export-json', 'export-obj', 'export-gltf']) {
    assert.match(await text(page, `#${id}`), /\(partial\)$/, id);
    assert.match(await page.getAttribute(`#${id}`, 'title'), /partial model where the cancelled fit stopped/, id);
  }
  assert.match(await text(page, '#caption'), /where the cancelled fit stopped/);
  // Fit again, to its end: no lead, the exports' own names
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n, { timeout: 120000 });
  await frames(page);
  assert.equal((await summary(page)).cancelled, false);
  assert.equal(await page.isHidden('[data-testid=cancel-lead]'), true);
  assert.equal(await text(page, '#export-json'), 'Model JSON');
  assert.equal(await text(page, '#export-gltf'), 'glTF (.glb)');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('Refine says it set "Parts in the end", while the field holds its count', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  const n = s.parts - 3;
  assert.equal(await page.isHidden('[data-testid=refine-note]'), true);
  await moveTreeSlider(page, n);
  const c = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('[data-testid=tree-refine]');
  await page.waitForFunction((x) => window.posemfa.fitCount() > x, c, { timeout: 120000 });
  assert.equal((await summary(page)).parts, n);
  assert.equal(await page.inputValue('#params [name=targetParts]'), String(n));
  assert.equal(await text(page, '[data-testid=refine-note]'), `Refine fits with “Parts in the end” set to ${n}, and the field keeps it: later fits too make exactly ${n} parts, each its own (not this partition: Refine again from the slider for that), until it is auto (empty) again.`);
  // the field emptied (auto): the line goes
  await page.fill('#params [name=targetParts]', '');
  assert.equal(await page.isHidden('[data-testid=refine-note]'), true);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('RMSE: one figure when the unit box and the original units print the same', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  assert.equal(s.rmse.toExponential(3), s.rmseOriginal.toExponential(3), 'a generated population is in the unit box');
  // then the rig's measure (added with the fit's E_RMS; this line had not followed)
  assert.equal(await text(page, '#rmse'), `${s.rmse.toExponential(3)} (unit box = original units); E_RMS ${s.eRms.toFixed(3)} (the rig's measure: RMS error per coordinate, in thousandths of the bounding-box diagonal)`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the log-likelihood plot of a finished fit shows all its runs, and its min and max differ when they do', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  const plot = await page.evaluate(() => ({ ...document.getElementById('plot').dataset, points: window.posemfa.plotPoints() }));
  const total = Number((await text(page, '#iteration')).match(/total (\d+)/)[1]);
  assert.ok(total > s.logLikelihood.length, `the quadruped's fit has runs before its final stage: ${total}`);
  assert.equal(plot.points, total, 'one point per iteration of the whole fit');
  assert.ok(Number(plot.runs) >= 2, JSON.stringify(plot));
  assert.match(plot.title, /^the whole fit: log-likelihood of its \d+ AECM runs/);
  // the final stage rises: its min and max print differently
  const ll = s.logLikelihood;
  assert.ok(Math.max(...ll) > Math.min(...ll), JSON.stringify(ll));
  assert.notEqual(plot.min, plot.max, JSON.stringify(plot));
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('pose mode: while the rig is built the caption says so, not the last mode\'s words', async (t) => {
  // large enough that the rig takes a while (500-700 ms here)
  const { page, context, log } = await fitted('?preset=quadruped&vertices=20000&poses=10');
  await page.check('#modes input[value=interp]', { force: true });
  await page.waitForFunction(() => /part-wise/.test(document.getElementById('caption').textContent), null, { timeout: 30000 });
  // every change of the two lines, in order, as it happens (a MutationObserver, not a poll: a timer can be held
  // back while the page renders, and then a poll sees too little)
  await page.evaluate(() => {
    window.__seen = [];
    const t0 = performance.now();
    const record = () => window.__seen.push({
      ms: performance.now() - t0,
      caption: document.getElementById('caption').textContent,
      status: document.getElementById('pose-status').textContent,
    });
    window.__observer = new MutationObserver(record);
    for (const id of ['caption', 'pose-status']) window.__observer.observe(document.getElementById(id), { childList: true, characterData: true, subtree: true });
  });
  await page.check('#modes input[value=pose]', { force: true });
  await page.waitForFunction(() => document.body.dataset.pose === 'ready' && /^Pose mode: the rest pose/.test(document.getElementById('caption').textContent), null, { timeout: 60000 });
  const seen = await page.evaluate(() => {
    window.__observer.disconnect();
    return window.__seen;
  });
  const start = seen.findIndex((x) => x.status === 'building the rig…');
  assert.ok(start >= 0, 'the rig was built');
  const end = seen.findIndex((x, i) => i > start && x.status !== 'building the rig…');
  assert.ok(end > start, JSON.stringify(seen));
  t.diagnostic(`the rig took ${Math.round(seen[end].ms - seen[start].ms)} ms to build`);
  // while it builds, the caption changes once, to say so (after a moment: a quick build shows no such line), and
  // never to the last mode's words
  const during = seen.slice(start + 1, end).filter((x, i, all) => x.caption !== (i === 0 ? seen[start].caption : all[i - 1].caption));
  assert.ok(during.length > 0, `the caption did not change while the rig was built: ${JSON.stringify(seen)}`);
  for (const x of during) assert.match(x.caption, /^Pose mode: building the rig…/, `at ${Math.round(x.ms)} ms`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('Step by step says before Run that it takes far longer than Fit', async () => {
  const { page, context, log } = await fitted();
  assert.match(await text(page, '[data-testid=teach-about]'), /Run makes its AECM iterations one at a time and shows each .*so it takes far longer than Fit/);
  assert.deepEqual(log.errors, []);
  await context.close();
});
