// The teaching side of the built page (dist/): presets and ground-truth accuracy, the teaching mode (Step / Run /
// Pause / Reset on the core's single-step API; Reset asks before it drops a finished fit), the state in
// location.hash, and embedding (embed=1, mount()).
// The step-by-step values are checked against the same core run in Node (pkg-node/, built with the page).
// Run: npm run build && node --test tests/e2e/teach.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { readFile } from 'node:fs/promises';
import { pageSession, waitState, canvasFingerprint, ROOT, answerQuestions, askedQuestions, summary, text, frames } from './helpers.mjs';

const session = pageSession();

const core = () => createRequire(import.meta.url)(join(ROOT, 'pkg-node', 'posemfa.js'));
const teaching = (page) => page.evaluate(() => window.posemfa.teaching());

// Opens `hash` (or the default) and waits until the page is fitted and any view in the link is applied.
async function fitted(hash = '', opts) {
  const p = await session.open(hash, opts);
  const state = await waitState(p.page, ['fitted', 'error'], 60000);
  assert.equal(state, 'fitted', await p.page.locator('[data-testid=errors]').innerText());
  await p.page.waitForFunction(() => !window.posemfa.restoring(), null, { polling: 20 });
  await frames(p.page);
  return p;
}

// The first `n` AECM iterations of an example, computed by the core in Node: progress objects.
function coreSteps(id, n, overrides = {}) {
  const w = core();
  const ex = w.examples().find((e) => e.id === id);
  const synth = new w.Synthetic(ex.spec);
  const pop = synth.population();
  // teaching runs Algorithm 1 (www/teach-worker.js), whatever the page's part rule
  const f = new w.Fitter(pop, { ...w.defaultParams(), ...ex.params, partRule: 'distinct', ...overrides });
  const out = Array.from({ length: n }, () => f.step());
  f.free();
  pop.free();
  synth.free();
  return out;
}

// The view's pixels (RGBA).
async function canvasPixels(page) {
  const b64 = await page.evaluate(() => {
    const src = document.querySelector('#view canvas');
    const c = Object.assign(document.createElement('canvas'), { width: src.width, height: src.height });
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const { data } = g.getImageData(0, 0, c.width, c.height);
    let s = '';
    for (let i = 0; i < data.length; i += 0x8000) s += String.fromCharCode(...data.subarray(i, i + 0x8000));
    return btoa(s);
  });
  return Buffer.from(b64, 'base64');
}

async function step(page) {
  const before = (await teaching(page)).iteration;
  await page.click('[data-testid=teach-step]');
  await page.waitForFunction((b) => window.posemfa.teaching().iteration !== b, before, { polling: 20 });
}

test('the page opens on the quadruped, fitted, with its ground-truth accuracy, and lists the presets with their notes', async () => {
  const { page, context, log } = await fitted();
  const opened = await page.evaluate(() => performance.getEntriesByName('posemfa:fitted')[0].startTime);
  const s = await summary(page);
  assert.equal(await page.locator('#example').inputValue(), 'quadruped');
  // The accuracy comes from the core (posemfa::metrics): the same numbers as Node's.
  const w = core();
  const ex = w.examples()[0];
  assert.equal(ex.id, 'quadruped');
  assert.ok(s.groundTruth && s.groundTruth.ari >= 0.95, `adjusted Rand ${s.groundTruth?.ari}`);
  assert.ok(s.groundTruth.rotationErrorDeg >= 0 && s.groundTruth.rotationErrorDeg <= 2, `median rotation error ${s.groundTruth.rotationErrorDeg}`);
  assert.equal(s.groundTruth.trueParts, 18);
  const shown = await page.locator('[data-testid=truth-acc]').innerText();
  assert.ok(shown.includes(`adjusted Rand ${s.groundTruth.ari.toFixed(3)}`) && shown.includes(`${s.groundTruth.rotationErrorDeg.toFixed(2)}°`), shown);
  console.log(`# opened on the fitted quadruped after ${Math.round(opened)} ms (fit ${Math.round(s.fitMs)} ms), adjusted Rand ${s.groundTruth.ari.toFixed(4)}, median rotation error ${s.groundTruth.rotationErrorDeg.toFixed(3)} deg`);

  // Every example of the core is listed with its note; the ones failing on purpose say so.
  const items = await page.locator('[data-testid=presets] li').evaluateAll((lis) => lis.map((li) => ({
    id: li.querySelector('button').dataset.id, note: li.querySelector('.note').textContent, fails: li.classList.contains('fails'),
    current: li.querySelector('button').getAttribute('aria-current'),
  })));
  assert.deepEqual(items.map((i) => i.id), w.examples().map((e) => e.id));
  for (const [i, e] of w.examples().entries()) {
    assert.equal(items[i].note, e.note);
    assert.equal(items[i].fails, e.failsOnPurpose);
  }
  // the tied legs are a limit shown, not a failure (connectivity keeps them two parts)
  assert.deepEqual(items.filter((i) => i.fails).map((i) => i.id).sort(), ['blob', 'literal-eq18']);
  assert.equal(items[0].current, 'true');

  // A preset that fails on purpose, picked from the list: its note says why.
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('[data-testid=presets] button[data-id=blob]');
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n);
  assert.match(await page.locator('#example-note').innerText(), /^Fails on purpose\. .*not articulated/);
  assert.equal(await page.locator('[data-testid=presets] button[data-id=blob]').getAttribute('aria-current'), 'true');
  await page.waitForFunction(() => location.hash.split('&')[0] === '#ex=blob');
  assert.deepEqual(log.errors, []);
  assert.deepEqual(log.external, []);
  await context.close();
});

test('Step advances exactly one AECM iteration: counter +1, plot +1 point, the core\'s own values', async () => {
  const { page, context, log } = await fitted();
  const reference = coreSteps('quadruped', 5);
  assert.equal(await page.evaluate(() => window.posemfa.teaching().active), false);
  await answerQuestions(page, true); // the first Step drops the fit the page opened with: yes (asked in the page)

  const split = []; // vertices with no part above γ = 0.9 after each step, and how many are shown blended
  for (let k = 1; k <= 5; k++) {
    await step(page);
    await frames(page);
    const t = await teaching(page);
    split.push(t.soft);
    assert.equal(t.iteration, k, 'one Step, one iteration');
    if (k === 1) assert.match((await askedQuestions(page)).join('\n'), /^Step starts a new step-by-step fit and drops the finished one/);
    assert.equal(await page.locator('[data-testid=teach-iteration]').innerText(), String(k));
    assert.equal(t.points, k);
    assert.equal(await page.evaluate(() => window.posemfa.plotPoints()), k);
    // between steps nothing runs, and the page says so
    assert.equal(await page.evaluate(() => document.body.dataset.state), 'paused');
    assert.equal(await page.evaluate(() => document.body.dataset.teaching), '1');
  }
  const t = await teaching(page);
  // The same five iterations as fitter.step() five times in Node, to the last digit.
  assert.deepEqual(t.logLikelihood, reference.map((p) => p.logLikelihood));
  assert.deepEqual(reference.map((p) => p.totalIterations), [1, 2, 3, 4, 5]);
  for (let i = 1; i < 5; i++) assert.ok(t.logLikelihood[i] >= t.logLikelihood[i - 1], `exact AECM never lowers the log-likelihood: ${t.logLikelihood}`);
  assert.deepEqual(log.dialogs, [], 'no browser dialog');
  assert.equal((await askedQuestions(page)).length, 1, 'only the Step that dropped the finished fit asked: the next ones go on with the teaching fit');
  assert.match(await page.locator('#teach-stages li.current').innerText(), /coarse/);
  assert.match(await page.locator('#teach-eq').innerText(), /eqs 13–14[\s\S]*eq 12[\s\S]*Λ[\s\S]*eq 19[\s\S]*eq 31[\s\S]*eq 16[\s\S]*eq 12/);

  // Soft colours: every vertex whose responsibilities are split shows a blend of its parts' colours (the
  // model's γ are nearly hard: a few boundary vertices per step).
  for (const sp of split) assert.equal(sp.blended, sp.vertices, JSON.stringify(split));
  assert.ok(split.reduce((a, sp) => a + sp.vertices, 0) >= 1, JSON.stringify(split));

  // Run, then Pause: it stops, and 5 more Steps move the counter and the plot by exactly 5.
  await page.click('#teach-run');
  await page.waitForFunction(() => window.posemfa.teaching().iteration >= 12, null, { polling: 10 });
  await page.click('#teach-pause');
  await page.waitForFunction(() => !window.posemfa.teaching().running);
  const paused = await teaching(page);
  await page.waitForTimeout(200);
  assert.equal((await teaching(page)).iteration, paused.iteration, 'paused: no more iterations');
  assert.equal(paused.points, paused.iteration);
  for (let k = 1; k <= 5; k++) await step(page);
  const after5 = await teaching(page);
  assert.equal(after5.iteration, paused.iteration + 5);
  assert.equal(after5.points, paused.points + 5);
  assert.equal(await page.evaluate(() => window.posemfa.plotPoints()), paused.points + 5);
  assert.deepEqual(after5.logLikelihood, coreSteps('quadruped', paused.iteration + 5).map((p) => p.logLikelihood));

  // Reset: a new fit at iteration 0, empty plot; Run to the end gives the fitted model (and its accuracy).
  await page.click('#teach-reset');
  await page.waitForFunction(() => window.posemfa.teaching().points === 0 && window.posemfa.plotPoints() === 0);
  assert.equal(await page.locator('[data-testid=teach-iteration]').innerText(), '0');
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#teach-run');
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, fits, { timeout: 60000 });
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  const s = await summary(page);
  const done = await teaching(page);
  assert.equal(done.active, false);
  assert.equal(done.points, done.iteration);
  assert.ok(s.groundTruth.ari >= 0.95, `stepped to the end: adjusted Rand ${s.groundTruth.ari}`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('Step and Run after a finished fit ask before they drop it; dismissed, the fit and its exports stay', async () => {
  const { page, context, log } = await fitted('#ex=arm');
  const before = await summary(page);
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await answerQuestions(page, false);
  for (const [sel, name] of [['[data-testid=teach-step]', 'Step'], ['#teach-run', 'Run']]) {
    const asked = (await askedQuestions(page)).length;
    await page.click(sel); // answered No in the page
    for (let i = 0; i < 100 && (await askedQuestions(page)).length === asked; i++) await page.waitForTimeout(20);
    assert.equal((await askedQuestions(page)).length, asked + 1, `${name} asked`);
    // the No is seen: a line says the finished fit was kept
    assert.match(await page.locator('[data-testid=ask].kept').innerText(), new RegExp(`^Kept the finished fit \\(${before.parts} parts\\): no step-by-step fit was started. Press ${name} again`));
    assert.match((await askedQuestions(page))[asked], new RegExp(`^${name} starts a new step-by-step fit and drops the finished one \\(${before.parts} parts, its exports and views\\)`));
    await page.waitForTimeout(300);
    // nothing changed: the same model, its part count, its exports, no teaching fit
    assert.equal(await page.locator('[data-testid=parts-count]').innerText(), String(before.parts));
    assert.deepEqual(await summary(page), before);
    for (const id of ['export-json', 'export-gltf']) assert.equal(await page.isDisabled(`#${id}`), false, `${id} after ${name}`);
    assert.equal((await teaching(page)).active, false);
    assert.equal(await page.locator('[data-testid=teach-iteration]').innerText(), '0');
    assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  }
  assert.equal(await page.evaluate(() => window.posemfa.fitCount()), fits, 'no fit started');
  // the export still answers: the model's JSON, of this fit
  const [json] = await Promise.all([page.waitForEvent('download'), page.click('#export-json')]);
  const model = JSON.parse(await readFile(await json.path(), 'utf8'));
  assert.equal(model.labels.length, before.vertices);
  assert.equal(new Set(model.labels).size, before.parts);
  // accepted, Step drops it: a teaching fit at iteration 1, no model
  await answerQuestions(page, true);
  await step(page);
  assert.equal((await askedQuestions(page)).length, 3);
  assert.deepEqual(log.dialogs, [], 'no browser dialog');
  assert.equal((await teaching(page)).iteration, 1);
  assert.equal(await page.isDisabled('#export-json'), true, 'the dropped fit has no export');
  assert.deepEqual(log.errors, []);
  await context.close();
});

// The Step by step panel as it shows: the iteration counter, the stage marked, its note.
const panel = (page) => page.evaluate(() => ({
  iteration: document.querySelector('[data-testid=teach-iteration]').textContent,
  current: [...document.querySelectorAll('#teach-stages li.current')].map((li) => li.dataset.stage),
  note: document.getElementById('teach-stage-note').textContent,
}));

test('Fit asks before it drops a paused step-by-step fit; accepted, or with a new population, the panel starts again', async () => {
  const { page, context, log } = await fitted('#ex=arm');
  const opened = await panel(page);
  assert.deepEqual(opened, { iteration: '0', current: [], note: '' }, 'no step-by-step fit yet: nothing marked');
  await answerQuestions(page, true); // the first Step drops the finished fit
  for (let k = 0; k < 3; k++) await step(page);
  await frames(page);
  const paused = await panel(page);
  assert.equal(paused.iteration, '3');
  assert.equal(paused.current.length, 1, JSON.stringify(paused));
  assert.notEqual(paused.note, '');
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'paused');
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  // dismissed: nothing changes, the step-by-step fit stays where it was
  await answerQuestions(page, false);
  const asked = (await askedQuestions(page)).length;
  await page.click('#fit');
  for (let i = 0; i < 100 && (await askedQuestions(page)).length === asked; i++) await page.waitForTimeout(20);
  assert.equal((await askedQuestions(page))[asked], 'Fit starts a new fit and drops the step-by-step fit at iteration 3. Drop it?');
  await page.waitForTimeout(300);
  assert.deepEqual(await panel(page), paused);
  const kept = await teaching(page);
  assert.deepEqual([kept.active, kept.iteration], [true, 3]);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'paused');
  assert.equal(await page.evaluate(() => window.posemfa.fitCount()), fits, 'no fit started');
  await step(page); // and it goes on
  assert.equal((await teaching(page)).iteration, 4);
  // accepted: the new fit runs, the panel is back to how it opened
  await answerQuestions(page, true);
  await page.click('#fit');
  await page.waitForFunction(() => !window.posemfa.teaching().active);
  assert.deepEqual(await panel(page), opened);
  assert.equal(await waitState(page, ['fitted', 'error'], 60000), 'fitted');
  assert.deepEqual(await panel(page), opened, 'the finished fit brings no step-by-step stage back');
  assert.equal((await askedQuestions(page)).length, asked + 2);
  // a new population drops a paused step-by-step fit too (the worker lets it go with the population)
  await step(page);
  await step(page);
  assert.equal((await teaching(page)).iteration, 2);
  await page.selectOption('#example', 'snake');
  await page.click('#generate');
  await page.waitForFunction(() => !window.posemfa.teaching().active);
  assert.deepEqual(await panel(page), opened);
  assert.equal(await waitState(page, ['fitted', 'error'], 60000), 'fitted');
  assert.deepEqual(await panel(page), opened);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the literal eq 18 preset shows the log-likelihood dropping while stepping', async () => {
  const { page, context, log } = await fitted('#ex=literal-eq18');
  await answerQuestions(page, true); // Step drops the example's finished fit
  assert.equal(await page.locator('#params [name=paperLambda]').isChecked(), true);
  assert.equal(await page.locator('#teach-eq-lambda-paper').isVisible(), true);
  assert.equal(await page.locator('#teach-eq-lambda-exact').isVisible(), false);
  for (let k = 0; k < 6; k++) await step(page);
  const t = await teaching(page);
  const drops = t.logLikelihood.filter((v, i) => i > 0 && v < t.logLikelihood[i - 1]);
  assert.ok(drops.length >= 1, `no drop in ${t.logLikelihood}`);
  assert.deepEqual(t.logLikelihood, coreSteps('literal-eq18', 6).map((p) => p.logLikelihood));
  await context.close();
});

test('the state in the URL round-trips: a shared link restores the same view', async () => {
  // Parameters, pose and view from a link.
  {
    const { page, context } = await fitted('#ex=arm&parts=4&seed=2&view=stages&pose=2&flat=1');
    assert.equal(await page.locator('#example').inputValue(), 'arm');
    assert.equal(await page.locator('#params [name=parts]').inputValue(), '4');
    assert.equal(await page.locator('#params [name=seed]').inputValue(), '2');
    assert.equal(await page.evaluate(() => window.posemfa.mode()), 'stages');
    assert.equal(await page.locator('#pose-select').inputValue(), '2');
    assert.equal(await page.locator('#flat').isChecked(), true);
    assert.deepEqual(await page.evaluate(() => window.posemfa.shown()), ['coarse', 'refined', 'final']);
    const s = await page.evaluate(() => window.posemfa.urlState());
    assert.deepEqual({ ex: s.ex, parts: s.params.parts, seed: s.params.seed, mode: s.view.mode, pose: s.view.pose, flat: s.view.flat },
      { ex: 'arm', parts: 4, seed: 2, mode: 'stages', pose: 2, flat: true });
    await context.close();
  }

  // A person changes the view and moves the camera; the link opened elsewhere draws the same picture.
  const a = await fitted();
  const pa = a.page;
  const defaultCam = (await pa.evaluate(() => window.posemfa.urlState())).view.cam;
  await pa.click('#pose-strip button:nth-child(4)');
  await pa.check('#modes input[value=interp]', { force: true });
  await pa.selectOption('#pose-a', '1');
  await pa.selectOption('#pose-b', '6');
  await pa.fill('[data-testid=interp-t]', '0.3');
  await pa.check('#side-by-side');
  await pa.selectOption('#interp-skin', 'smooth');
  await pa.waitForFunction(() => window.posemfa.shown().join() === 'part-wise,linear' && /t = 0\.30/.test(document.querySelector('#caption').textContent));
  const box = await pa.locator('#view canvas').boundingBox();
  await pa.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await pa.mouse.down();
  await pa.mouse.move(box.x + box.width / 2 + 90, box.y + box.height / 2 + 12, { steps: 6 });
  await pa.mouse.up();
  await pa.mouse.move(box.x + 3, box.y + 3); // off the mesh: no hover
  // Wait until the camera has settled (damping) and the hash has stopped changing.
  const now = () => pa.evaluate(() => JSON.stringify([location.href, window.posemfa.urlState()]));
  let seen = await now();
  for (let still = 0; still < 3;) {
    await pa.waitForTimeout(400);
    const x = await now();
    still = x === seen ? still + 1 : 0;
    seen = x;
  }
  const [href, stateA] = JSON.parse(seen);
  assert.equal(stateA.view.mode, 'interp');
  assert.equal(stateA.view.pose, 3);
  assert.deepEqual([stateA.view.a, stateA.view.b, stateA.view.t, stateA.view.side, stateA.view.skin], [1, 6, 0.3, true, 'smooth']);
  assert.ok(href.includes('view=interp') && href.includes('cam='), href);
  const pixelsA = await canvasPixels(pa);

  const b = await fitted(new URL(href).hash);
  const stateB = await b.page.evaluate(() => window.posemfa.urlState());
  assert.deepEqual({ ...stateB, view: { ...stateB.view, cam: null } }, { ...stateA, view: { ...stateA.view, cam: null } });
  // (OrbitControls re-derives the position from spherical coordinates on every frame: last-digit changes)
  stateB.view.cam.forEach((c, i) => assert.ok(Math.abs(c - stateA.view.cam[i]) < 1e-6, `camera ${stateB.view.cam} vs ${stateA.view.cam}`));
  assert.notDeepEqual(stateA.view.cam, defaultCam, 'the camera was moved');
  // in the Interpolate view the strip marks the From and To poses (the pose chosen, 3, is in the state above)
  const marked = await b.page.locator('#pose-strip button').evaluateAll((bs) => bs.map((x, k) => (x.getAttribute('aria-pressed') === 'true' ? k : -1)).filter((k) => k >= 0));
  assert.deepEqual(marked, [1, 6]);
  // The same picture, up to a few anti-aliased pixels (the camera's last digits, above).
  const pixelsB = await canvasPixels(b.page);
  assert.equal(pixelsB.length, pixelsA.length);
  let differ = 0;
  for (let i = 0; i < pixelsA.length; i += 4) if (pixelsA[i] !== pixelsB[i] || pixelsA[i + 1] !== pixelsB[i + 1] || pixelsA[i + 2] !== pixelsB[i + 2]) differ++;
  assert.ok(differ <= pixelsA.length / 4 / 2000, `the shared link draws the same picture: ${differ} of ${pixelsA.length / 4} pixels differ`);
  const picture = await canvasFingerprint(b.page);

  // Reloading keeps it too.
  await b.page.reload();
  await waitState(b.page, ['fitted'], 60000);
  await b.page.waitForFunction(() => !window.posemfa.restoring());
  await frames(b.page);
  assert.equal(await canvasFingerprint(b.page), picture, 'a reload draws the same picture');
  assert.deepEqual(a.log.errors, []);
  assert.deepEqual(b.log.errors, []);
  await a.context.close();
  await b.context.close();
});

test('a shared teaching link opens on the same step and stage', async () => {
  const a = await fitted('#ex=arm');
  await answerQuestions(a.page, true); // the first Step drops the finished fit
  for (let k = 0; k < 7; k++) await step(a.page);
  await a.page.waitForFunction(() => /[#&]teach=7&stage=\w+/.test(location.hash), null, { timeout: 10000 });
  const ta = await teaching(a.page);
  const href = await a.page.evaluate(() => location.href);
  assert.match(href, new RegExp(`teach=7&stage=${ta.stage?.kind ?? 'coarse'}`));

  const { page, context, log } = await session.open(new URL(href).hash);
  await page.waitForFunction(() => window.posemfa.teaching().iteration === 7 && !window.posemfa.restoring(), null, { timeout: 60000, polling: 20 });
  const tb = await teaching(page);
  assert.equal(tb.active, true);
  assert.deepEqual(tb.stage, ta.stage);
  assert.deepEqual(tb.logLikelihood, ta.logLikelihood, 'the same seven iterations');
  assert.equal(await page.locator('[data-testid=teach-iteration]').innerText(), '7');
  assert.equal(await page.evaluate(() => document.body.dataset.teaching), '1');
  assert.equal(await page.evaluate(() => window.posemfa.fitCount()), 0, 'the link fitted nothing besides its steps');
  // and it goes on from there: one more Step is the core's 8th iteration
  await step(page);
  assert.deepEqual((await teaching(page)).logLikelihood, coreSteps('arm', 8).map((p) => p.logLikelihood));
  assert.deepEqual(log.errors, []);
  await a.context.close();
  await context.close();
});

test('"Parts in the end" (targetParts) is in the link: bones=N restores it, auto is left out', async () => {
  const { page, context, log } = await fitted('#ex=arm&parts=4&bones=5');
  assert.equal(await page.locator('#params [name=targetParts]').inputValue(), '5');
  assert.equal((await summary(page)).parts, 5, 'the link\'s count was fitted');
  assert.equal((await page.evaluate(() => window.posemfa.urlState())).params.targetParts, 5);
  await page.waitForFunction(() => /^#ex=arm&parts=4&bones=5&/.test(location.hash), null, { timeout: 10000 });
  // chosen in the form: the link follows each fit
  const fit = async (value) => {
    const n = await page.evaluate(() => window.posemfa.fitCount());
    await page.fill('#params [name=targetParts]', value);
    await page.click('#params [type=submit]');
    await page.waitForFunction((c) => window.posemfa.fitCount() > c && document.body.dataset.state === 'fitted', n, { timeout: 60000 });
  };
  await fit('2');
  assert.equal((await summary(page)).parts, 2);
  await page.waitForFunction(() => /&bones=2&/.test(location.hash), null, { timeout: 10000 });
  await fit('auto');
  await page.waitForFunction(() => !/bones=/.test(location.hash), null, { timeout: 10000 });
  assert.equal((await page.evaluate(() => window.posemfa.urlState())).params.targetParts, null);
  // bones=auto in a link is the same as none
  const b = await fitted('#ex=arm&parts=4&bones=auto');
  assert.equal(await b.page.locator('#params [name=targetParts]').inputValue(), '');
  assert.deepEqual(log.errors, []);
  assert.deepEqual(b.log.errors, []);
  await b.context.close();
  await context.close();
});

test('the teaching panel never shows "undefined", through every stage of Algorithm 1', async () => {
  const { page, context, log } = await fitted('#ex=arm');
  await answerQuestions(page, true); // Run drops the finished fit
  // Every text the panel shows while a teaching run goes from the coarse stage to done.
  await page.evaluate(() => {
    const panel = document.getElementById('teach');
    window.teachTexts = new Set([panel.innerText]);
    new MutationObserver(() => window.teachTexts.add(panel.innerText)).observe(panel, { subtree: true, childList: true, characterData: true, attributes: true });
  });
  await page.click('#teach-run');
  // Waits on the texts the observer saw (after every message), not on polling, which can miss a short stage
  // when the page is busy.
  await page.waitForFunction(() => [...window.teachTexts].some((t) => /Done: labels/.test(t)), null, { timeout: 120000, polling: 100 })
    .catch(async (e) => {
      throw new Error(`${e.message}: teaching ${JSON.stringify(await teaching(page))}, state ${await page.evaluate(() => document.body.dataset.state)}`);
    });
  await waitState(page, 'fitted', 60000);
  const texts = await page.evaluate(() => [...window.teachTexts]);
  const bad = texts.filter((t) => /undefined|NaN|\[object /.test(t));
  assert.deepEqual(bad, [], 'texts of the teaching panel');
  // the refinement's note names its coarse part and m_k, a number
  assert.ok(texts.some((t) => /Refinement of coarse part \d+ of \d+: .* m_k = \d+ component/.test(t)), texts.join('\n---\n').slice(0, 2000));
  assert.ok(texts.some((t) => /Done: labels/.test(t)));
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('embed=1 and the hide/show flags give a minimal view', async () => {
  const { page, context } = await fitted('#ex=arm&embed=1', { width: 640, height: 400 });
  for (const sel of ['header', '#panel', '.toolbar', '.poses', '#interp']) assert.equal(await page.locator(sel).isVisible(), false, `${sel} hidden`);
  assert.equal(await page.locator('#caption').isVisible(), true);
  const box = await page.locator('#view canvas').boundingBox();
  assert.ok(box.width >= 600 && box.height >= 320, `the view fills the frame: ${JSON.stringify(box)}`);
  assert.equal(await page.evaluate(() => document.documentElement.scrollHeight <= window.innerHeight), true, 'no scrolling');
  assert.equal((await summary(page)).shapes, 8);
  assert.match(await page.evaluate(() => location.hash), /embed=1/, 'the flags stay in the link');
  await context.close();

  const p1 = await fitted('#ex=arm&embed=1&show=poses', { width: 640, height: 400 });
  assert.equal(await p1.page.locator('.poses').isVisible(), true, 'show= brings a control back');
  assert.equal(await p1.page.locator('#panel').isVisible(), false);
  await p1.context.close();

  const p2 = await fitted('#ex=arm&hide=presets,teach,caption');
  assert.equal(await p2.page.locator('#presets-box').isVisible(), false);
  assert.equal(await p2.page.locator('#teach').isVisible(), false);
  assert.equal(await p2.page.locator('#caption').isVisible(), false);
  assert.equal(await p2.page.locator('#panel').isVisible(), true);
  await p2.context.close();
});

test('the embed page shows a fitted model in an iframe and through mount()', async () => {
  const { page, context, log } = await session.open('www/embed-demo.html');
  const frame = page.frameLocator('[data-testid=embed-iframe]');
  const inner = page.frames().find((f) => f.url().includes('index.html'));
  await inner.waitForFunction(() => document.body.dataset.state === 'fitted', null, { timeout: 90000, polling: 50 });
  assert.equal(await frame.locator('#panel').isVisible(), false);
  const s = await inner.evaluate(() => window.posemfa.summary());
  assert.ok(s.groundTruth.ari >= 0.95, `iframe: adjusted Rand ${s.groundTruth.ari}`);

  await page.waitForFunction(() => document.querySelector('[data-testid=embed-mount]').dataset.state === 'fitted', null, { timeout: 90000, polling: 50 });
  const m = await page.evaluate(() => window.mounted.summary());
  assert.ok(m.parts >= 3 && m.parts <= 6, `mount(): the 3-part arm gave ${m.parts} parts`);
  assert.ok(m.groundTruth.ari > 0.9, `mount(): adjusted Rand ${m.groundTruth.ari}`);
  assert.match(await page.locator('[data-testid=embed-mount] .posemfa-caption').innerText(), /parts fitted/);
  // Both canvases draw a mesh (pixels other than the background).
  const meshPixels = (sel, f = page) => f.evaluate(async (sel) => {
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    const src = document.querySelector(sel);
    const c = Object.assign(document.createElement('canvas'), { width: src.width, height: src.height });
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const { data } = g.getImageData(0, 0, c.width, c.height);
    let n = 0;
    for (let i = 0; i < data.length; i += 4) if (data[i] !== 0xee || data[i + 1] !== 0xf0 || data[i + 2] !== 0xf3) n++;
    return n;
  }, sel);
  assert.ok(await meshPixels('[data-testid=embed-mount] canvas') > 2000);
  assert.ok(await meshPixels('#view canvas', inner) > 2000);

  // unmount() takes everything away; mounting again works.
  await page.click('#toggle');
  assert.equal(await page.locator('[data-testid=embed-mount] canvas').count(), 0);
  assert.equal(await page.evaluate(() => document.querySelector('[data-testid=embed-mount]').dataset.state), undefined);
  await page.click('#toggle');
  await page.waitForFunction(() => document.querySelector('[data-testid=embed-mount]').dataset.state === 'fitted', null, { timeout: 90000 });
  assert.deepEqual(log.errors, []);
  assert.deepEqual(log.external, []);
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
