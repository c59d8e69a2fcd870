// Issue 30 on the built page (dist/): the page as a first-time user meets it. One test per finding: the latent
// view, the tied-legs example, a cancelled fit's verdict, bad parameters, the log-likelihood field, the
// article's captions, the OBJ export of what is shown, Reset in step mode, and the layout at 1280x800 / 390x844.
// Run: npm run build && node --test tests/e2e/firstuse.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { pageSession, waitState, tubePopulation, asPayload, openCancelledFirstFit, answerQuestions, askedQuestions } from './helpers.mjs';

const session = pageSession();
const summary = (page) => page.evaluate(() => window.posemfa.summary());
const frames = (page) => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
const text = (page, sel) => page.locator(sel).innerText();

// The Log-likelihood field's number: nats, its thousands apart (views/result.js natsText)
const natsValue = (t) => {
  const m = t.match(/^(−?)([\d\u202f]+\.\d{2}) nats$/);
  assert.ok(m, `"${t}" is a log-likelihood in nats`);
  return Number(`${m[1] ? '-' : ''}${m[2].replace(/\u202f/g, '')}`);
};

async function fitted(path = '', opts) {
  const p = await session.open(path, opts);
  const state = await waitState(p.page, ['fitted', 'error'], 90000);
  assert.equal(state, 'fitted', await text(p.page, '[data-testid=errors]'));
  await frames(p.page);
  return p;
}

async function mode(page, m) {
  await page.check(`#modes input[value=${m}]`, { force: true });
  await page.waitForFunction((x) => window.posemfa.mode() === x, m);
}

// The OBJ the export button writes now: { text, objects: [{ name, v: [[x, y, z]...], groups: [names] }] }.
async function exportObj(page) {
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-obj')]);
  const t = await readFile(await download.path(), 'utf8');
  const objects = [];
  let cur = null;
  for (const line of t.split('\n')) {
    if (line.startsWith('o ')) objects.push((cur = { name: line.slice(2), v: [], groups: [] }));
    else if (line.startsWith('v ')) {
      if (!cur) objects.push((cur = { name: null, v: [], groups: [] }));
      cur.v.push(line.slice(2).split(' ').map(Number));
    } else if (line.startsWith('g ')) cur.groups.push(line.slice(2));
  }
  return { text: t, name: download.suggestedFilename(), objects };
}

// RMS distance between two vertex lists, over the diagonal of the first one's bounding box.
function relativeRms(a, b) {
  assert.equal(a.length, b.length);
  let s = 0;
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  a.forEach((p, i) => {
    for (let k = 0; k < 3; k++) {
      s += (p[k] - b[i][k]) ** 2;
      lo[k] = Math.min(lo[k], p[k]);
      hi[k] = Math.max(hi[k], p[k]);
    }
  });
  const diag = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  return Math.sqrt(s / a.length) / diag;
}

test('latent view: the parts placed by the pose\'s R and b by default, readable; "each in its own frame" is a choice with its own caption', async () => {
  const { page, context, log } = await fitted();
  const pose = (await exportObj(page)).objects[0].v; // the Parts view: pose 1
  await mode(page, 'latent');
  await page.waitForFunction(() => /latent shape/i.test(document.querySelector('#caption').textContent));
  assert.match(await text(page, '#caption'), /turned by its R and moved by its b of pose/);
  assert.equal(await page.locator('[data-testid=latent-place]').isVisible(), true);
  const posed = await exportObj(page);
  assert.equal(posed.objects.length, 1);
  // where the parts are in the pose: within a few per cent of the pose itself (the model's residual)
  const r = relativeRms(pose, posed.objects[0].v);
  assert.ok(r < 0.03, `latent view vs the pose: RMS ${r} of the diagonal`);
  assert.match(posed.name, /latent-posed/);
  // the teaching choice: the parts in their own frames, on top of each other, and a caption saying so
  await page.selectOption('[data-testid=latent-place]', 'frames');
  await page.waitForFunction(() => /own frame/.test(document.querySelector('#caption').textContent));
  assert.match(await text(page, '#caption'), /on top of each other/);
  const frames_ = await exportObj(page);
  assert.ok(relativeRms(pose, frames_.objects[0].v) > 0.1, 'the latent frames are not the pose');
  await page.selectOption('[data-testid=latent-place]', 'moved');
  await page.waitForFunction(() => /not turned/.test(document.querySelector('#caption').textContent));
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

test('a cancelled fit gets no verdict: "cancelled: the diagnosis needs a finished fit"', async () => {
  const { page, context, log } = await fitted();
  assert.match(await text(page, '[data-testid=diagnosis]'), /^Articulated/);
  const n = await page.evaluate(() => window.posemfa.fitCount());
  // Cancel as soon as the first fit of new files runs (a new fit of a fitted population keeps the finished
  // model instead: fresh.test.mjs): its first slice (40 ms) is in its first run
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

// The parts line (next to the part count) of a merge-tree fit, finished or cancelled: the same words.
const TREE_PARTS = /^\(started from the merge tree's \d+ parts?(, cancelled)?\)$/;

test('the Stages view names what ran: the merge tree\'s stages for the default fit, Algorithm 1\'s otherwise; every pane labelled', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  assert.match(await text(page, '#stage-parts'), TREE_PARTS);
  await mode(page, 'stages');
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
  await mode(page, 'parts');
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
  await mode(page, 'stages');
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

test('bad parameters: each field named and outlined with what it allows, no fit, cleared when fixed or by Defaults', async () => {
  const { page, context, log } = await fitted();
  const n = await page.evaluate(() => window.posemfa.fitCount());
  const stage = await text(page, '#stage');
  await page.fill('#params [name=tol]', 'abc');
  await page.fill('#params [name=targetParts]', 'seven');
  await page.click('#fit');
  await page.waitForFunction(() => document.querySelectorAll('[data-testid=param-errors] li').length === 2, null, { timeout: 10000 });
  const lines = await page.locator('[data-testid=param-errors] li').allInnerTexts();
  assert.deepEqual(lines.sort(), [
    "Parts in the end: 'seven' is not a whole number: it must be a positive whole number, or auto (the part rule's own count)",
    "Tolerance (nats / vertex): 'abc' is not a number: it must be a positive number (try 1e-3)",
  ]);
  assert.equal(await page.getAttribute('#params [name=tol]', 'aria-invalid'), 'true');
  assert.equal(await page.getAttribute('#params [name=targetParts]', 'aria-invalid'), 'true');
  const outline = await page.$eval('#params [name=tol]', (e) => getComputedStyle(e).outlineStyle);
  assert.notEqual(outline, 'none');
  await page.waitForTimeout(500);
  assert.equal(await page.evaluate(() => window.posemfa.fitCount()), n, 'no fit started');
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  assert.equal(await text(page, '#stage'), stage, 'the Stage field did not move to "starting"');
  assert.equal(await text(page, '[data-testid=errors]'), '', 'no deserialiser words');
  // fixed: its line goes as it is typed
  await page.fill('#params [name=tol]', '1e-3');
  await page.waitForFunction(() => document.querySelectorAll('[data-testid=param-errors] li').length === 1);
  assert.equal(await page.getAttribute('#params [name=tol]', 'aria-invalid'), null);
  // Defaults: every mark goes
  await page.click('#reset-params');
  assert.equal(await page.locator('[data-testid=param-errors] li').count(), 0);
  assert.equal(await page.locator('#params [aria-invalid]').count(), 0);
  // a number out of range is named too (the core's range, as the CLI says it)
  await page.fill('#params [name=parts]', '0');
  await page.click('#fit');
  await page.waitForFunction(() => document.querySelectorAll('[data-testid=param-errors] li').length === 1);
  assert.match(await text(page, '[data-testid=param-errors]'), /^Initial parts: 0 must be a whole number from 1 to 512/);
  // what the line under the form says once the core's (asynchronous) check of `typed` in Initial parts matches
  // `expected` (the error names the text shown if it never does)
  const partsError = async (typed, expected) => {
    await page.fill('#params [name=parts]', '');
    await page.focus('#params [name=parts]');
    await page.keyboard.type(typed);
    await page.click('#fit');
    await page.waitForFunction((re) => new RegExp(re).test(document.querySelector('[data-testid=param-errors]').textContent), expected.source, { timeout: 15000 })
      .catch(async () => assert.fail(`${typed}: ${await text(page, '[data-testid=param-errors]')}`));
    assert.equal(await page.locator('[data-testid=param-errors] li').count(), 1);
  };
  // a whole number in exponent form is read as the number it is, and named as too large
  await partsError('1e9', /^Initial parts: 1000000000 is too large: it must be a whole number from 1 to 512/);
  // text the number field cannot read (it reads as empty) is named as no number, not as an empty field
  await partsError('1e', /^Initial parts: is not a number: it must be a whole number from 1 to 512/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the Log-likelihood field is the shown model\'s final value (the plot\'s last point), on every example tried', async () => {
  const { page, context, log } = await fitted();
  for (const id of ['quadruped', 'arm', 'snake', 'blob']) {
    if (id !== 'quadruped') {
      const n = await page.evaluate(() => window.posemfa.fitCount());
      await page.click(`[data-testid=presets] button[data-id=${id}]`);
      await page.waitForFunction((c) => window.posemfa.fitCount() > c && document.body.dataset.state === 'fitted', n, { timeout: 90000 })
        .catch(async (e) => { throw new Error(`${id}: ${e.message}; state ${await page.evaluate(() => [document.body.dataset.state, window.posemfa.fitCount()])}`); });
      await frames(page);
    }
    const ll = (await summary(page)).logLikelihood;
    assert.equal(natsValue(await text(page, '#loglik')).toFixed(2), ll[ll.length - 1].toFixed(2), id);
  }
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('article: the model figure\'s status names the part shown, its bars are on one stated scale; the responsibilities label follows the run', async () => {
  const { page, context, log } = await session.open('explain.html');
  const fig = page.locator('[data-figure=model]');
  await fig.scrollIntoViewIfNeeded();
  await page.waitForFunction(() => document.querySelector('[data-figure=model]').dataset.state === 'fitted' && document.querySelectorAll('[data-figure=model] .bar').length > 0, null, { timeout: 60000 });
  const options = await fig.locator('[data-ctl=part] option').count();
  for (const k of [1, options - 1]) {
    await fig.locator('[data-ctl=part]').selectOption(String(k));
    await page.waitForFunction((p) => document.querySelector('[data-figure=model] .fig-status').textContent.includes(`showing part ${p}.`)
      && document.querySelector('[data-figure=model] .bars-title')?.textContent.includes(`part ${p} `), k + 1, { timeout: 10000 });
    assert.match(await fig.locator('.bars-title').innerText(), /full width = 180°/);
    const bars = await fig.locator('.bar').evaluateAll((els) => els.map((e) => ({
      angle: parseFloat(e.querySelector('.val').textContent), width: parseFloat(e.querySelector('.fill').style.width),
    })));
    for (const b of bars) assert.ok(Math.abs(b.width - (100 * b.angle) / 180) < 0.1, `bar ${JSON.stringify(b)} is not on the 180° scale`);
  }
  // responsibilities: the view's label and the status give the same iteration, after a Reset too
  const resp = page.locator('[data-figure=responsibilities]');
  await resp.scrollIntoViewIfNeeded();
  await page.waitForFunction(() => window.explain.detail('responsibilities').steps >= 2, null, { timeout: 60000 });
  await resp.locator('[data-act=reset]').click();
  await page.waitForFunction(() => window.explain.detail('responsibilities').steps >= 3, null, { timeout: 60000 });
  await resp.locator('[data-act=pause]').click();
  await page.waitForTimeout(800);
  const label = await resp.locator('.posemfa-caption').innerText();
  const status = await resp.locator('.fig-status').innerText();
  const it = (await page.evaluate(() => window.explain.detail('responsibilities'))).iteration;
  assert.match(status, new RegExp(`Iteration ${it}\\b`));
  assert.match(label, new RegExp(`^Iteration ${it}\\b`), `label "${label}" beside status "${status}"`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('OBJ export: both meshes where two are shown, named for what they are; Stages: each stage\'s parts as groups', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  await mode(page, 'recon');
  await page.waitForFunction(() => window.posemfa.shown().join() === 'original,reconstruction');
  assert.equal(await text(page, '#export-obj'), 'OBJ of the 2 shown meshes');
  const recon = await exportObj(page);
  assert.deepEqual(recon.objects.map((o) => o.name), ['original', 'reconstruction']);
  assert.equal(recon.objects[0].v.length, s.vertices);
  assert.equal(recon.objects[1].v.length, s.vertices);
  const r = relativeRms(recon.objects[0].v, recon.objects[1].v);
  assert.ok(r > 0 && r < 0.03, `the reconstruction is its own mesh, close to the original: ${r}`);
  assert.match(recon.name, /original_reconstruction/);
  const faces = [...recon.text.matchAll(/^f /gm)].length;
  assert.ok(faces > 0 && faces % 2 === 0, `${faces} faces: each mesh its own triangles`);
  await mode(page, 'stages');
  await page.waitForFunction(() => window.posemfa.shown().join() === 'coarse,refined,final');
  const st = await exportObj(page);
  assert.deepEqual(st.objects.map((o) => o.name), ['coarse', 'refined', 'final']);
  const groups = st.objects.map((o) => o.groups.length);
  assert.equal(groups[0], s.coarseParts);
  assert.equal(groups[2], s.parts);
  assert.ok(st.objects[2].groups.every((g) => /^final_part_\d+$/.test(g)), st.objects[2].groups.join());
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('step by step: Reset asks before it drops a finished fit; the state follows; the Stage field and the note say the same part', async () => {
  const { page, context, log } = await fitted('#ex=arm');
  const parts = await text(page, '[data-testid=parts-count]');
  await answerQuestions(page, false);
  await page.click('#teach-reset'); // answered No in the page
  await page.waitForTimeout(300);
  assert.equal((await askedQuestions(page)).length, 1, 'Reset asked');
  assert.match((await askedQuestions(page))[0], /drops the finished one/);
  assert.equal(await text(page, '[data-testid=parts-count]'), parts, 'dismissed: the fit is kept');
  assert.equal(await page.isDisabled('#export-json'), false);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  // accepted: a new step-by-step fit, paused at iteration 0, and the page says it is paused, not fitting
  await answerQuestions(page, true);
  await page.click('#teach-reset');
  await page.waitForFunction(() => window.posemfa.teaching().active);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'paused');
  assert.equal(await page.evaluate(() => document.body.dataset.teaching), '1');
  // run into the refinement, then step through it: after every step the Stage field and the note name the
  // same coarse part, including at the steps that move from one part to the next
  await page.click('#teach-run');
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitting');
  await page.waitForFunction(() => window.posemfa.teaching().stage?.kind === 'refine', null, { timeout: 60000, polling: 5 });
  await page.click('#teach-pause');
  await page.waitForFunction(() => !window.posemfa.teaching().running);
  await page.waitForFunction(() => document.body.dataset.state === 'paused');
  const seen = new Set();
  for (let k = 0; k < 160 && seen.size < 3; k++) {
    const before = (await page.evaluate(() => window.posemfa.teaching())).iteration;
    await page.click('[data-testid=teach-step]');
    await page.waitForFunction((b) => window.posemfa.teaching().iteration > b, before, { timeout: 10000 });
    await frames(page);
    const t = await page.evaluate(() => window.posemfa.teaching());
    if (t.stage?.kind !== 'refine') break;
    const field = await text(page, '#stage');
    const note = await text(page, '#teach-stage-note');
    const a = field.match(/part (\d+) of (\d+)/);
    const b = note.match(/part (\d+) of (\d+)/);
    assert.ok(a && b, `${field} | ${note}`);
    assert.deepEqual(a.slice(1), b.slice(1), `Stage field "${field}" and note "${note}"`);
    seen.add(a[1]);
  }
  assert.ok(seen.size >= 2, `stepped through the refinement of ${seen.size} part(s) only`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

// Whether an element lies fully inside the window (not cut by its bottom or right edge, nor scrolled away).
const inWindow = (page, sel) => page.$eval(sel, (e) => {
  const r = e.getBoundingClientRect();
  return r.width > 0 && r.top >= 0 && r.left >= 0 && r.bottom <= innerHeight + 0.5 && r.right <= innerWidth + 0.5;
});

test('layout at 1280x800: nothing below the window, the running fit\'s progress in view; at 390x844 every label whole', async () => {
  const { page, context, log } = await fitted();
  assert.ok(await page.evaluate(() => document.documentElement.scrollHeight <= innerHeight), `page height ${await page.evaluate(() => document.documentElement.scrollHeight)}`);
  for (const sel of ['#pose-strip', '#view-wrap']) assert.ok(await inWindow(page, sel), `${sel} is cut off`);
  const thumbs = await page.$$eval('#pose-strip button', (bs) => bs.map((b) => b.getBoundingClientRect().bottom));
  assert.ok(thumbs.every((y) => y <= 800), `thumbnail bottoms ${thumbs}`);
  // a fit running: its Stage, Iteration and plot are in view
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction(() => document.body.dataset.state === 'fitting');
  for (const sel of ['#stage', '#iteration', '#plot']) assert.ok(await inWindow(page, sel), `${sel} is out of view while the fit runs`);
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n, { timeout: 90000 });
  // the part-rule chart: its text inside its canvas (the chart says where it drew its labels)
  const clipped = await page.$eval('#part-curve', (c) => c.dataset.clipped);
  assert.equal(clipped, '0', 'the part-rule chart clipped a label');
  await context.close();

  // a phone: no text cut mid-line in the app's panel, nor in the eq 18 figure's view labels
  const phone = await fitted('', { width: 390, height: 844 });
  const wide = await phone.page.evaluate(() => document.documentElement.scrollWidth);
  assert.ok(wide <= 390, `the page is ${wide} px wide`);
  phone.context.close();
  const art = await session.open('explain.html', { width: 390, height: 844 });
  await art.page.locator('[data-figure=eq18]').scrollIntoViewIfNeeded();
  await art.page.waitForFunction(() => document.querySelectorAll('[data-figure=eq18] .posemfa-caption').length === 2, null, { timeout: 30000 });
  await art.page.waitForFunction(() => document.querySelector('[data-figure=eq18]').dataset.state !== 'loading', null, { timeout: 60000 });
  // each label lies inside its view box (which hides what overflows it)
  const cut = await art.page.$$eval('[data-figure=eq18] .posemfa-caption', (els) => els.filter((e) => {
    const r = e.getBoundingClientRect();
    const box = e.closest('.fig-view').getBoundingClientRect();
    return r.bottom > box.bottom + 0.5 || r.right > box.right + 0.5 || e.scrollWidth > e.clientWidth + 1;
  }).map((e) => e.textContent));
  assert.deepEqual(cut, [], 'eq 18 view labels cut');
  assert.deepEqual([...log.errors, ...art.log.errors], []);
  await art.context.close();
});

// ---------------------------------------------------------------- the second first-use review

// The one line of the form's problems about `field`, once it is there.
async function fieldLine(page, field) {
  await page.waitForFunction((f) => document.querySelector(`[data-testid=param-errors] li[data-field=${f}]`), field, { timeout: 10000 });
  return page.locator(`[data-testid=param-errors] li[data-field=${field}]`).innerText();
}

test('Parts in the end: a negative count must be a positive whole number; more than the population holds is refused before a fit, naming the limit', async () => {
  const { page, context, log } = await fitted();
  const n = await page.evaluate(() => window.posemfa.fitCount());
  const stage = await text(page, '#stage');
  const field = '#params [name=targetParts]';
  const refused = async () => {
    assert.equal(await page.getAttribute(field, 'aria-invalid'), 'true');
    assert.notEqual(await page.$eval(field, (e) => getComputedStyle(e).outlineStyle), 'none');
    await page.waitForTimeout(400);
    assert.equal(await page.evaluate(() => window.posemfa.fitCount()), n, 'no fit started');
    assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted', 'the page is back at rest, not fitting');
    assert.equal(await text(page, '#stage'), stage, 'the Stage field did not move');
  };
  await page.fill(field, '-3');
  await page.click('#fit');
  assert.equal(await fieldLine(page, 'targetParts'), "Parts in the end: '-3' is negative: it must be a positive whole number, or auto (the part rule's own count)");
  await refused();
  // fixed: the line goes as it is typed
  await page.fill(field, '3');
  await page.waitForFunction(() => document.querySelectorAll('[data-testid=param-errors] li').length === 0);
  assert.equal(await page.getAttribute(field, 'aria-invalid'), null);
  // more parts than the population can hold (every part needs min_part_vertices = 4 vertices)
  const { vertices } = await summary(page);
  const most = Math.floor(vertices / 4);
  await page.fill(field, String(vertices + 1));
  await page.click('#fit');
  const line = await fieldLine(page, 'targetParts');
  assert.equal(line, `Parts in the end: ${vertices + 1} is more than this population allows: it has ${vertices} vertices and every part needs at least 4, so it must be at most ${most} (or auto)`);
  await refused();
  // Defaults: the mark goes
  await page.click('#reset-params');
  assert.equal(await page.locator('[data-testid=param-errors] li').count(), 0);
  assert.equal(await page.locator('#params [aria-invalid]').count(), 0);
  // the limit itself: one more is refused, the limit is accepted as it is typed (no fit is started here)
  await page.fill(field, String(most + 1));
  await page.click('#fit');
  assert.match(await fieldLine(page, 'targetParts'), new RegExp(`^Parts in the end: ${most + 1} is more than .* at most ${most} \\(or auto\\)$`));
  await page.fill(field, String(most));
  await page.waitForFunction(() => document.querySelectorAll('[data-testid=param-errors] li').length === 0);
  assert.equal(await page.evaluate(() => window.posemfa.fitCount()), n);
  assert.deepEqual(log.errors, []);
  await context.close();
});

const picked = (page) => page.$eval('#example', (s) => ({ value: s.value, text: s.selectedOptions[0]?.textContent ?? '' }));

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

// How many lines the element's own text takes (its text nodes' line boxes), and its height against one line.
const lines = (page, sel) => page.$$eval(sel, (els) => els.map((e) => {
  const tops = new Set();
  for (const n of e.childNodes) {
    if (n.nodeType !== Node.TEXT_NODE || !n.textContent.trim()) continue;
    const r = document.createRange();
    r.selectNodeContents(n);
    for (const q of r.getClientRects()) if (q.width > 0) tops.add(Math.round(q.top));
  }
  const lh = parseFloat(getComputedStyle(e).fontSize) * 1.6;
  return { text: e.textContent.trim(), lines: tops.size, height: e.getBoundingClientRect().height, oneLine: lh };
}));

test('pose mode at 1280x800: every pose-space slider\'s label is one line, its slider beside it', async () => {
  const { page, context, log } = await fitted();
  await mode(page, 'pose');
  await page.waitForFunction(() => window.posemfa.pose?.ready(), null, { timeout: 120000, polling: 50 });
  await page.waitForFunction(() => document.querySelectorAll('#pose-modes label').length > 0);
  const labels = await lines(page, '#pose-modes label');
  assert.ok(labels.length >= 1);
  // the status counts the modes and, when there are more than sliders, says which ones have one
  const status = await text(page, '[data-testid=pose-status]');
  const [, modes] = status.match(/^\d+ bones, (\d+) pose-space directions?/) ?? [];
  assert.ok(modes, status);
  assert.equal(labels.length, Math.min(Number(modes), 6), status);
  if (Number(modes) > 6) assert.match(status, /; sliders for the 6 largest$/);
  for (const l of labels) {
    assert.equal(l.lines, 1, `"${l.text}" takes ${l.lines} lines`);
    assert.ok(l.height <= l.oneLine * 1.3, `"${l.text}" is ${l.height} px high (one line: ${l.oneLine} px)`);
  }
  // the slider on the label's line
  const beside = await page.$$eval('#pose-modes label', (els) => els.map((e) => {
    const a = e.getBoundingClientRect();
    const b = e.querySelector('input').getBoundingClientRect();
    return b.top >= a.top - 0.5 && b.bottom <= a.bottom + 0.5 && b.left > a.left;
  }));
  assert.ok(beside.every(Boolean), JSON.stringify(beside));
  for (const l of await lines(page, '#pose-panel > label, #pose-panel > button')) assert.equal(l.lines, 1, `"${l.text}" takes ${l.lines} lines`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('article: the sticky header is opaque, so the text scrolling under it does not show through', async () => {
  const { page, context, log } = await session.open('explain.html');
  await page.evaluate(() => window.scrollTo(0, 1500));
  await page.waitForFunction(() => window.scrollY > 1000);
  const h = await page.$eval('header.top', (e) => {
    const r = e.getBoundingClientRect();
    return { top: r.top, bottom: r.bottom, background: getComputedStyle(e).backgroundColor };
  });
  assert.equal(h.top, 0, 'the header stays at the top');
  const m = h.background.match(/^rgba?\(([\d.]+),\s*([\d.]+),\s*([\d.]+)(?:,\s*([\d.]+))?\)$/);
  assert.ok(m, h.background);
  assert.equal(m[4] === undefined ? 1 : Number(m[4]), 1, `header background ${h.background} is not opaque`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

// Visible labels, buttons and selects whose text is cut (wider than their box) or that leave the window sideways,
// and labels whose control is broken off onto another line than their name.
const cutOff = (page) => page.evaluate(() => {
  const out = [];
  for (const e of document.querySelectorAll('label, button, .button, select, summary, h1, h2, legend, dt, dd')) {
    const r = e.getBoundingClientRect();
    if (r.width === 0 || r.height === 0 || getComputedStyle(e).visibility === 'hidden' || e.closest('.visually-hidden')) continue;
    const cut = e.clientWidth > 0 && e.scrollWidth > e.clientWidth + 1;
    // inside a box that scrolls sideways (the thumbnail strip) it is reached by scrolling, not cut
    let scrolls = false;
    for (let a = e.parentElement; a && a !== document.body; a = a.parentElement) scrolls ||= ['auto', 'scroll'].includes(getComputedStyle(a).overflowX);
    const out_ = !scrolls && (r.left < -0.5 || r.right > innerWidth + 0.5);
    // a label's control on the line of its name (not broken off onto the next line)
    let apart = false;
    const ctl = e.tagName === 'LABEL' && e.querySelector('select, input:not([type=checkbox]):not([type=radio]):not([type=hidden])');
    const name = ctl && [...e.childNodes].find((n) => n.nodeType === Node.TEXT_NODE && n.textContent.trim());
    if (ctl && name && ctl.getBoundingClientRect().width > 0) {
      const rg = document.createRange();
      rg.selectNodeContents(name);
      const t = [...rg.getClientRects()].filter((q) => q.width > 0);
      const c = ctl.getBoundingClientRect();
      const line = t[t.length - 1];
      apart = !!line && !(c.top < line.bottom && c.bottom > line.top);
    }
    if (apart) out.push(`label "${e.textContent.trim().slice(0, 40)}": its control is on another line than its name`);
    if (cut || out_) out.push(`${e.tagName.toLowerCase()}${e.id ? `#${e.id}` : ''} "${e.textContent.trim().slice(0, 40)}": ${cut ? `text ${e.scrollWidth} px in ${e.clientWidth} px` : `from ${r.left.toFixed(0)} to ${r.right.toFixed(0)} px`}`);
  }
  return out;
});

test('a phone (390x844): no label or button text cut, no control broken off its label, nothing wider than the window, in every view', async () => {
  const { page, context, log } = await fitted('', { width: 390, height: 844 });
  const width = () => page.evaluate(() => document.documentElement.scrollWidth);
  assert.ok(await width() <= 390, `the page is ${await width()} px wide`);
  assert.deepEqual(await cutOff(page), [], 'parts view');
  for (const m of ['interp', 'latent', 'pose']) {
    await mode(page, m);
    if (m === 'pose') await page.waitForFunction(() => window.posemfa.pose?.ready(), null, { timeout: 120000, polling: 50 });
    await frames(page);
    assert.ok(await width() <= 390, `${m}: the page is ${await width()} px wide`);
    assert.deepEqual(await cutOff(page), [], `${m} view`);
  }
  assert.deepEqual(log.errors, []);
  await context.close();
});
