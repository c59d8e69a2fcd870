// The Pose view's sliders, thumbnails, exports and added frames: on entering it the pose-space sliders show the
// rest pose's coordinates and follow the pose shown (a turn, the mean pose at 0, the added frames as they play);
// a thumbnail click shows that training pose as the rig makes it; the toolbar's "OBJ of the shown mesh" writes
// the posed mesh, and "Posed mesh (OBJ)" and "Pose (.glb)" the added frame on screen rather than the pose made
// under it; frames of another vertex count are refused naming the file, and a later good "Add frames" clears the
// error; after Random pose the caption describes the whole pose, and the Part list is in number order. The tests
// on the fitted page of `posePage()` go on from each other, in order.
// Run: npm run build && node --test tests/e2e/pose-view.test.mjs
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { pageSession, asPayload, ROOT, enterPoseMode, waitState, objFiles, debugCli, text, openFitted, setMode } from './helpers.mjs';

const session = pageSession();
let dir;
let opened = null;

before(() => {
  const bin = debugCli();
  dir = mkdtempSync(path.join(tmpdir(), 'posemfa-pose-view-'));
  // the training poses; new frames of the same mesh (another seed); frames of another mesh (fewer vertices)
  execFileSync(bin, ['generate', 'quadruped', '--vertices', '1500', '--poses', '6', '--seed', '4', '--out', path.join(dir, 'pop')]);
  execFileSync(bin, ['generate', 'quadruped', '--vertices', '1500', '--poses', '4', '--seed', '11', '--out', path.join(dir, 'new')]);
  execFileSync(bin, ['generate', 'quadruped', '--vertices', '700', '--poses', '2', '--seed', '11', '--out', path.join(dir, 'small')]);
});

after(() => {
  if (dir) rmSync(dir, { recursive: true, force: true });
});

// The page with the population fitted and the Pose view open (once for the file: the tests go on from each other).
async function posePage() {
  if (opened) return opened;
  opened = await session.open();
  const { page } = opened;
  await waitState(page, ['fitted', 'idle', 'error'], 60000);
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.setInputFiles('[data-testid=file-input]', asPayload(objFiles(path.join(dir, 'pop'))));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 120000, polling: 50 });
  await enterPoseMode(page);
  await page.waitForFunction(() => /^Pose mode/.test(document.getElementById('caption').textContent));
  return opened;
}

const sliders = (page) => page.$$eval('#pose-modes input', (ins) => ins.map((i) => ({ value: Number(i.value), step: Number(i.step) })));
// the sliders within half a step (a range input keeps its value on its steps) of coordinates `coords`
const slidersAt = (got, coords) => got.every((s, m) => Math.abs(s.value - coords[m]) <= s.step / 2 + 1e-9);
const slidersText = (got, coords) => JSON.stringify({ sliders: got.map((s) => s.value.toFixed(3)), coords: got.map((_, m) => coords[m].toFixed(3)) });

// A download's name and text (or bytes) after clicking `selector`.
async function downloaded(page, selector, { binary = false } = {}) {
  const [d] = await Promise.all([page.waitForEvent('download', { timeout: 30000 }), page.click(selector)]);
  const file = await d.path();
  return { name: d.suggestedFilename(), body: binary ? readFileSync(file) : readFileSync(file, 'utf8') };
}

const vertices = (obj) => obj.split('\n').filter((l) => l.startsWith('v ')).map((l) => l.slice(2).split(' ').map(Number));
const headerOf = (obj) => obj.split('\n').filter((l) => l.startsWith('#')).join('\n');
const rms = (a, b) => Math.sqrt(a.reduce((s, p, i) => s + (p[0] - b[i][0]) ** 2 + (p[1] - b[i][1]) ** 2 + (p[2] - b[i][2]) ** 2, 0) / a.length);
const fitted = (path, opts) => openFitted(session, path, opts);

const errorsText = (page) => page.locator('[data-testid=errors]').innerText();

test('on entering the Pose view the pose-space sliders show the rest pose\'s coordinates, not 0', async () => {
  const { page } = await posePage();
  const v = await page.evaluate(() => window.posemfa.pose.vector());
  const got = await sliders(page);
  assert.ok(got.length >= 1);
  // (the rest pose is a training pose, away from the mean: some coordinate is off 0 by more than a step)
  assert.ok(got.some((s, m) => Math.abs(v.coords[m]) > s.step), slidersText(got, v.coords));
  assert.ok(slidersAt(got, v.coords), `on entry: ${slidersText(got, v.coords)}`);
});

test('a thumbnail clicked in the Pose view shows that training pose as the rig makes it, names it, and the sliders follow', async () => {
  const { page } = await posePage();
  const sk = await page.evaluate(() => window.posemfa.pose.skeleton());
  const k = sk.bindPose === 3 ? 2 : 3;
  const name = sk.trainingNames[k];
  const rest = await page.evaluate(() => window.posemfa.pose.positions());
  await page.click(`#pose-strip button:nth-child(${k + 1})`);
  await page.waitForFunction((n) => document.getElementById('caption').textContent.includes(`training pose “${n}”`), name, { timeout: 20000 });
  assert.match(await page.locator('#caption').innerText(), /as the rig makes it/);
  const shown = await page.evaluate(() => window.posemfa.pose.shownPositions?.() ?? []);
  const made = await page.evaluate(() => window.posemfa.pose.positions());
  const diff = (a, b) => a.reduce((m, x, i) => Math.max(m, Math.abs(x - b[i])), 0);
  assert.ok(diff(made, rest) > 1e-3 * sk.diagonal, 'the view left the rest pose');
  // the rig's own training pose k (the test helper asks the same query)
  const training = await page.evaluate((i) => window.posemfa.pose.training(i), k);
  assert.ok(diff(made, training) < 1e-6 * sk.diagonal, `the shown pose is training pose ${k} as the rig makes it: ${diff(made, training)}`);
  assert.ok(diff(Array.from(shown), training) < 1e-6 * sk.diagonal, 'the picture shows it');
  await page.waitForFunction((c) => [...document.querySelectorAll('#pose-modes input')].every((s, m) => Math.abs(Number(s.value) - c[m]) <= Number(s.step) / 2 + 1e-9), sk.coords[k], { timeout: 10000 });
});

test('the toolbar\'s "OBJ of the shown mesh" in the Pose view writes the posed mesh shown', async () => {
  const { page } = await posePage();
  await page.click('#pose-plus'); // a made pose: the selected part turned 10°
  await page.waitForFunction(() => /turned/.test(document.getElementById('caption').textContent), null, { timeout: 20000 });
  const bar = await downloaded(page, '#export-obj');
  assert.equal(await errorsText(page), '');
  assert.match(bar.name, /^posemfa-.*pose.*\.obj$/);
  assert.match(headerOf(bar.body), /a pose made in posemfa pose mode/);
  const panel = await downloaded(page, '#pose-export-obj');
  assert.deepEqual(vertices(bar.body), vertices(panel.body), 'the toolbar writes the same mesh as the Pose panel');
  const nv = await page.evaluate(() => window.posemfa.pose.skeleton().boneOfVertex.length);
  assert.equal(vertices(bar.body).length, nv);
});

test('with an added frame on screen, "Posed mesh (OBJ)" and "Pose (.glb)" hold that frame; the made pose otherwise', async () => {
  const { page } = await posePage();
  await page.click('#pose-reset');
  await page.waitForFunction(() => /the rest pose/.test(document.getElementById('caption').textContent), null, { timeout: 20000 });
  const rest = await downloaded(page, '#pose-export-obj');
  const restGlb = await downloaded(page, '#pose-export-glb', { binary: true });
  assert.match(headerOf(rest.body), /a pose made in posemfa pose mode/);

  const files = objFiles(path.join(dir, 'new'));
  await page.setInputFiles('[data-testid=pose-frames]', asPayload(files));
  await page.waitForFunction(() => document.body.dataset.poseFrames === '4', null, { timeout: 60000, polling: 50 });
  const f0 = await page.evaluate(() => document.body.dataset.poseFrame);
  await page.waitForFunction((f) => document.body.dataset.poseFrame !== f, f0, { timeout: 10000, polling: 50 });
  await page.click('#pose-play'); // pause on a frame
  await page.waitForTimeout(700);
  const { frame, names } = await page.evaluate(() => window.posemfa.pose.frames());
  const name = names[frame];
  assert.match(await page.locator('#caption').innerText(), new RegExp(`Added frame “${name.replace('.', '\\.')}”`));
  const obj = await downloaded(page, '#pose-export-obj');
  assert.match(headerOf(obj.body), new RegExp(`frame ${name.replace('.', '\\.')} solved onto the rig`));
  assert.doesNotMatch(headerOf(obj.body), /a pose made in posemfa pose mode/);
  assert.match(obj.name, new RegExp(`frame-${name.replace(/\.obj$/, '')}\\.obj$`));
  // the file holds the frame (as the rig makes it: near the frame's own file), not the rest pose
  const input = vertices(files.find((f) => f.name === name).text);
  const got = vertices(obj.body);
  assert.equal(got.length, input.length);
  const toFrame = rms(got, input);
  const restToFrame = rms(vertices(rest.body), input);
  assert.ok(toFrame < restToFrame / 3, `rms to the frame's file: ${toFrame} (the rest pose's: ${restToFrame})`);
  const glb = await downloaded(page, '#pose-export-glb', { binary: true });
  assert.equal(glb.body.subarray(0, 4).toString('latin1'), 'glTF');
  assert.match(glb.name, new RegExp(`frame-${name.replace(/\.obj$/, '')}\\.glb$`));
  assert.ok(!glb.body.equals(restGlb.body), 'the .glb holds the frame, not the rest pose');
  // a pose made while paused: the exports are of it again
  await page.click('#pose-reset');
  await page.waitForFunction(() => /the rest pose/.test(document.getElementById('caption').textContent), null, { timeout: 20000 });
  const back = await downloaded(page, '#pose-export-obj');
  assert.match(headerOf(back.body), /a pose made in posemfa pose mode/);
  assert.deepEqual(vertices(back.body), vertices(rest.body));
});

test('while added frames play the sliders follow the frame shown; paused, they hold its coordinates', async () => {
  const { page } = await posePage();
  await page.click('#pose-play'); // play the frames added by the test before
  const seen = new Set();
  for (let i = 0; i < 12 && seen.size < 2; i++) {
    await page.waitForTimeout(300);
    seen.add(JSON.stringify((await sliders(page)).map((s) => s.value)));
  }
  assert.ok(seen.size >= 2, 'the sliders move while the frames play');
  await page.click('#pose-play'); // pause
  await page.waitForTimeout(700);
  const { frame } = await page.evaluate(() => window.posemfa.pose.frames());
  const v = await page.evaluate((f) => window.posemfa.pose.frameVector(f), frame);
  const got = await sliders(page);
  assert.ok(slidersAt(got, v.coords), `paused on frame ${frame}: ${slidersText(got, v.coords)}`);
});

test('frames of another vertex count are refused naming the file; a later good "Add frames" clears the error', async () => {
  const { page, log } = await posePage();
  const good = objFiles(path.join(dir, 'new'));
  const small = objFiles(path.join(dir, 'small'));
  const nv = await page.evaluate(() => window.posemfa.pose.skeleton().boneOfVertex.length);
  const nSmall = vertices(small[0].text).length;
  assert.notEqual(nSmall, nv);
  // the second file (in the names' natural order) is the one of the other mesh
  await page.setInputFiles('[data-testid=pose-frames]', asPayload([{ name: 'a10.obj', text: small[0].text }, { name: 'a2.obj', text: good[0].text }]));
  await page.waitForFunction(() => /vertices/.test(document.getElementById('errors').textContent), null, { timeout: 30000 });
  const text = await errorsText(page);
  assert.match(text, new RegExp(`a10\\.obj: has ${nSmall} vertices but the rig has ${nv}: add frames of the fitted mesh`));
  assert.doesNotMatch(text, /invalid request/);
  assert.doesNotMatch(await page.locator('[data-testid=pose-status]').innerText(), /invalid request/);
  await page.setInputFiles('[data-testid=pose-frames]', asPayload(good.slice(0, 2)));
  await page.waitForFunction(() => document.body.dataset.poseFrames === '2', null, { timeout: 60000, polling: 50 });
  assert.equal(await errorsText(page), '', 'the old error is gone');
  assert.deepEqual(log.errors, []);
});

test('pose mode: the pose-space sliders follow the pose shown (rest pose, a turn), 0 at the mean pose', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await enterPoseMode(page);
  const sliders = () => page.$$eval('#pose-modes input', (xs) => xs.map((x) => Number(x.value)));
  // each slider's value as the range and step put the pose's coordinate
  const placed = (coords) => page.$$eval('#pose-modes input', (xs, c) => xs.map((x) => {
    const probe = x.cloneNode();
    probe.value = String(c[Number(x.dataset.mode)]);
    return Number(probe.value);
  }), coords);
  // the sliders at the pose's coordinates, once the actions asked for have all been made (the pose is read
  // again until the two agree: a click's turn can still be on its way when the pose is first read)
  const settled = async (what) => {
    let want = null;
    for (let tries = 0; tries < 100; tries++) {
      want = await placed((await page.evaluate(() => window.posemfa.pose.vector())).coords);
      const now = await sliders();
      if (now.every((x, k) => x === want[k])) return want;
      await page.waitForTimeout(100);
    }
    return assert.fail(`${what}: sliders ${await sliders()} for the pose's ${want}`);
  };
  await page.click('#pose-reset');
  const rest = await settled('rest pose');
  await page.click('#pose-mean');
  const zero = await placed(new Array(rest.length).fill(0));
  await page.waitForFunction((w) => [...document.querySelectorAll('#pose-modes input')].every((x, k) => Number(x.value) === w[k]), zero, { timeout: 10000 });
  assert.notDeepEqual(rest, zero, 'the rest pose is not the mean pose, and its sliders say so');
  await page.click('#pose-plus');
  await page.click('#pose-plus');
  const turned = await settled('after a turn');
  assert.notDeepEqual(turned, zero, 'a turned part moves the pose off the mean');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('pose mode: after Random pose the caption describes the whole pose until a part is turned; the Part list is in number order', async () => {
  const { page, context, log } = await fitted(); // the quadruped: 18 bones, whose parent-first order is not by number
  await setMode(page, 'pose');
  await page.waitForFunction(() => window.posemfa.pose.ready(), null, { timeout: 60000 });
  const sk = await page.evaluate(() => window.posemfa.pose.skeleton());
  const options = await page.$$eval('#pose-part option', (os) => os.map((o) => ({ value: Number(o.value), name: o.textContent })));
  assert.deepEqual(options.map((o) => o.value).sort((a, b) => a - b), sk.order.slice().sort((a, b) => a - b), 'every bone listed once');
  const numbers = options.map((o) => Number(o.name.match(/\d+/)?.[0]));
  assert.deepEqual(numbers, numbers.slice().sort((a, b) => a - b), `in number order: ${options.map((o) => o.name)}`);
  const caption = (re) => page.waitForFunction((r) => new RegExp(r).test(document.getElementById('caption').textContent), re.source, { timeout: 15000 })
    .catch(async () => assert.fail(`caption "${await text(page, '#caption')}" does not match ${re}`));
  await page.click('#pose-plus');
  await caption(/^Pose mode: .+ turned 10\.0° from the rest pose/);
  await page.click('[data-testid=pose-random]');
  const n = sk.order.length;
  await caption(new RegExp(`^Pose mode: a random pose of all ${n} parts, within the training poses' range \\(drag a part`));
  await page.click('#pose-mean');
  await caption(/^Pose mode: the mean pose of the training poses/);
  await page.click('#pose-undo'); // back to the random pose, and its caption
  await caption(/^Pose mode: a random pose of all/);
  await page.click('#pose-plus'); // a part turned: the caption names it again
  await caption(/^Pose mode: .+ turned -?\d+\.\d° from the rest pose/);
  assert.deepEqual(log.errors, []);
  await context.close();
});
