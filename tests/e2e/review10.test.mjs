// What the ninth review's notes left (docs/page-fixes.md, thirty-fifth session) on the built page (dist/): the
// caption during a fit, tooltips, a file cut short; and the tenth review's (helper-12): a drop while the strip
// is drawn, export names, the strip's labels of one file's frames.
// Run: npm run build && node --test tests/e2e/review10.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { pageSession, waitState, asPayload, tubePopulation, moveTreeSlider, enterPoseMode, afterNextFit, dropAndFit, ROOT } from './helpers.mjs';

const session = pageSession();

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

test('every export button says what it writes before it is pressed', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const ids = ['export-json', 'export-obj', 'export-gltf', 'pose-export-obj', 'pose-export-glb', 'pose-export-frames'];
  const titles = await page.evaluate((list) => list.map((id) => document.getElementById(id)?.title ?? null), ids);
  titles.forEach((t, k) => assert.ok(t && t.length > 10, `#${ids[k]} has a tooltip: ${t}`));
  assert.equal(new Set(titles).size, ids.length, 'each says its own');
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

test('a drop while the pose strip is still being drawn draws the new population\'s strip, with no error', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  // many poses: the strip takes seconds to draw, one thumbnail at a time, after the fit
  await dropAndFit(page, asPayload(tubePopulation({ poses: 48 }).files));
  const drawing = await page.evaluate(() => document.getElementById('pose-strip').dataset.drawn ?? null);
  // another mesh (other vertex count), dropped while the strip above is drawn
  const other = tubePopulation({ poses: 3, ringsPerSegment: 8 });
  await dropAndFit(page, asPayload(other.files));
  await page.waitForFunction((d) => (document.getElementById('pose-strip').dataset.drawn ?? null) !== d, drawing, { timeout: 60000 });
  assert.equal(await page.locator('#pose-strip canvas').count(), 3);
  assert.equal(await page.evaluate(() => window.posemfa.summary().vertices), other.nVertices);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('export names: an interpolation by its two poses and t, files sharing no name by "population", a rig by its options', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  // 1.obj, 2.obj, ...: the names share nothing but digits
  const files = tubePopulation({ poses: 4 }).files.map((f, k) => ({ name: `${k + 1}.obj`, text: f.text }));
  await dropAndFit(page, asPayload(files), { fitted: true });
  const saved = async (selector) => (await Promise.all([page.waitForEvent('download'), page.click(selector)]))[0].suggestedFilename();
  assert.equal(await saved('#export-json'), 'posemfa-population-model.json');
  // the Pose selector on another pose than the interpolation's: the name follows the interpolation
  await page.selectOption('#pose-select', '3');
  await page.check('#modes input[value=interp]', { force: true });
  await page.waitForFunction(() => window.posemfa.mode() === 'interp');
  await page.selectOption('#pose-a', '0');
  await page.selectOption('#pose-b', '2');
  await page.waitForFunction(() => /“1\.obj” → “3\.obj”/.test(document.getElementById('caption').textContent), null, { timeout: 30000 });
  assert.match(await saved('#export-obj'), /^posemfa-population-1-to-3-t0\.50-.+\.obj$/);
  await page.selectOption('#rig select[name=morphs]', 'residual');
  assert.match(await saved('#export-gltf'), /^posemfa-population-rig-.+-\d+bones.*-residual-morphs\.glb$/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the pose strip labels a glTF\'s frames by frame, not by the file name they all share', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const buffer = readFileSync(join(ROOT, 'tests/fixtures/blender/quadruped-shapekeys.glb'));
  await dropAndFit(page, [{ name: 'quadruped-shapekeys.glb', mimeType: 'model/gltf-binary', buffer }]);
  const labels = await page.locator('#pose-strip span').allTextContents();
  const titles = await page.locator('#pose-strip button').evaluateAll((bs) => bs.map((b) => b.title));
  assert.ok(labels.length > 2);
  assert.ok(titles.every((t) => t.startsWith('quadruped-shapekeys.glb ')), titles.join(' | '));
  assert.ok(labels.every((l, k) => !l.includes('.glb') && titles[k].endsWith(` ${l}`)), labels.join(' | '));
  assert.equal(new Set(labels).size, labels.length);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a glTF with two animations that move the mesh offers the other one, and reads it when chosen', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  assert.equal(await page.locator('#clip-row').isVisible(), false, 'no list for OBJ poses');
  const buffer = readFileSync(join(ROOT, 'tests/fixtures/blender/quadruped-skinned-seams.glb'));
  await dropAndFit(page, [{ name: 'quadruped-skinned-seams.glb', mimeType: 'model/gltf-binary', buffer }]);
  assert.equal(await page.locator('#clip-row').isVisible(), true);
  const options = await page.locator('#clip option').allTextContents();
  assert.deepEqual(options, ['interpolated', 'training poses']);
  assert.equal(await page.inputValue('#clip'), 'interpolated');
  assert.match(await page.textContent('#pop-source'), /frames of animation 'interpolated' .*of the 2 animations that move it/);
  await afterNextFit(page, () => page.selectOption('#clip', 'training poses'), { fitted: true });
  assert.match(await page.textContent('#pop-source'), /frames of animation 'training poses' /);
  assert.doesNotMatch(await page.textContent('#pop-source'), /animations that move it/);
  assert.equal(await page.inputValue('#clip'), 'training poses');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a link with an unknown example or unreadable values says what it ignored', async () => {
  const { page, context, log } = await session.open('#ex=nonsense&parts=abc&view=wat&seed=3');
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await page.waitForFunction(() => /This link names the example/.test(document.getElementById('errors').textContent), null, { timeout: 30000 });
  const text = await page.textContent('[data-testid=errors]');
  assert.match(text, /This link names the example “nonsense”, which is not one of the built-in examples \(.*quadruped.*\): showing the default example\./);
  assert.match(text, /Ignored in this link \(not values this page reads\): parts=abc, view=wat\./);
  assert.doesNotMatch(text, /seed=3/);
  // a link the page reads whole says nothing
  const again = await context.newPage();
  await again.goto(`${page.url().split('#')[0]}#ex=quadruped&view=stages`);
  assert.equal(await waitState(again, ['fitted', 'error'], 120000), 'fitted');
  assert.equal(await again.textContent('[data-testid=errors]'), '');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('with the refinement off and a count asked for, the parts line says both, not "refined"', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await page.uncheck('#params input[name=refine]');
  assert.equal(await page.textContent('#fit'), 'Fit');
  await page.fill('#params input[name=targetParts]', '5');
  // the button says the count the field asks for, which later fits keep
  assert.equal(await page.textContent('#fit'), 'Fit 5 parts');
  await afterNextFit(page, () => page.click('#fit'), { fitted: true });
  const s = await page.evaluate(() => window.posemfa.summary());
  assert.equal(s.parts, 5);
  assert.deepEqual([s.refine, s.partsAsked], [false, 5]);
  assert.equal(await page.textContent('#stage-parts'), `(coarse ${s.coarseParts}, no refinement; 5 as asked in “Parts in the end”)`);
  assert.match(await page.textContent('#iterations'), /^\d+ in the final stage/);
  assert.equal(await page.textContent('#fit'), 'Fit 5 parts');
  await page.click('#reset-params');
  assert.equal(await page.textContent('#fit'), 'Fit');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('in the Interpolate view the pose strip marks From and To and takes no clicks', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const pressed = () => page.locator('#pose-strip button').evaluateAll((bs) => bs.map((b) => b.getAttribute('aria-pressed') === 'true'));
  await page.check('#modes input[value=interp]', { force: true });
  await page.waitForFunction(() => window.posemfa.mode() === 'interp');
  await page.selectOption('#pose-a', '1');
  await page.selectOption('#pose-b', '3');
  const marks = await pressed();
  assert.deepEqual(marks.map((p, k) => (p ? k : -1)).filter((k) => k >= 0), [1, 3]);
  assert.equal(await page.locator('#pose-strip button:not([disabled])').count(), 0);
  assert.match(await page.getAttribute('#pose-strip', 'title'), /From and To/);
  // back in the Parts view the strip is the pose list again
  await page.check('#modes input[value=parts]', { force: true });
  await page.waitForFunction(() => window.posemfa.mode() === 'parts');
  assert.equal(await page.locator('#pose-strip button[disabled]').count(), 0);
  assert.equal((await pressed()).filter(Boolean).length, 1);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('after Refine N the Fit button says the N parts later fits will keep', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
  await moveTreeSlider(page, parts - 2);
  await afterNextFit(page, () => page.click('[data-testid=tree-refine]'), { timeout: 90000 });
  assert.equal(await page.textContent('#fit'), `Fit ${parts - 2} parts`);
  assert.match(await page.getAttribute('#fit', 'title'), /empty it \(auto\) for the part rule's own count/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a part turned past what the training poses do is said to be beyond them', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const angle = () => page.locator('[data-testid=pose-angle]').innerText();
  assert.match(await angle(), /^0\.0°(?: at its joint, relative to part \d+| \(the root: its own turn\)) \(training poses: up to [0-9.]+°\)$/);
  const most = Number(/up to ([0-9.]+)°/.exec(await angle())[1]);
  // 10° a press, until past the training poses' largest turn of this part
  for (let k = 0; k < Math.ceil(most / 10) + 1; k++) {
    const before = await angle();
    await page.click('#pose-plus');
    await page.waitForFunction((b) => document.querySelector('[data-testid=pose-angle]').innerText !== b, before, { timeout: 20000 });
  }
  assert.match(await angle(), new RegExp(`^[0-9.]+°(?: at its joint, relative to part \\d+| \\(the root: its own turn\\)) \\(beyond the training poses, which turn it at most ${most.toFixed(1).replace('.', '\\.')}°\\)$`));
  assert.equal(await page.locator('[data-testid=pose-angle].beyond').count(), 1);
  await page.click('#pose-reset');
  await page.waitForFunction(() => /^0\.0° /.test(document.querySelector('[data-testid=pose-angle]').innerText), null, { timeout: 20000 });
  assert.equal(await page.locator('[data-testid=pose-angle].beyond').count(), 0);
  assert.deepEqual(log.errors, []);
  await context.close();
});
