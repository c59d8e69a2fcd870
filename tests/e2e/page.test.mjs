// The built page (dist/) in headless Chromium, through its test contract: document.body.dataset.state,
// the data-testid elements, window.posemfa.summary(). Populations are generated here (helpers.mjs).
// Run: npm run build && node --test tests/e2e/
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { zipSync, strToU8 } from 'fflate';
import { pageSession, waitState, tubePopulation, asPayload, paletteCounts, canvasFingerprint, summary } from './helpers.mjs';

const session = pageSession();

const SUMMARY_KEYS = ['shapes', 'vertices', 'parts', 'rmse', 'iterations', 'fitMs'];

// Opens the page (at `path`, e.g. '?faultInjection=1') and waits until it has settled (its default fitted).
async function fresh(opts, path = '') {
  const p = await session.open(path, opts);
  await waitState(p.page, ['fitted', 'idle', 'error'], 60000);
  return p;
}

// Picks files through the file input with the given initial part count; waits until that fit has ended.
async function fitFiles(page, files, { parts } = {}) {
  if (parts) await page.fill('#params input[name=parts]', String(parts));
  const counts = await page.evaluate(() => [window.posemfa.fitCount(), window.posemfa.loadErrorCount()]);
  await page.setInputFiles('[data-testid=file-input]', asPayload(files));
  return waitFit(page, counts);
}

// Waits until one more fit has ended, or the load was refused; returns the state.
async function waitFit(page, [fits, loadErrors], timeout = 60000) {
  await page.waitForFunction(([f, l]) => window.posemfa.fitCount() > f || window.posemfa.loadErrorCount() > l, [fits, loadErrors], { timeout, polling: 20 })
    .catch(async (e) => { throw new Error(`${e.message}; errors shown: ${await page.locator('[data-testid=errors]').innerText()}`); });
  if (await page.evaluate((l) => window.posemfa.loadErrorCount() > l, loadErrors)) {
    throw new Error(`the files were refused: ${await page.locator('[data-testid=errors]').innerText()}`);
  }
  return page.evaluate(() => document.body.dataset.state);
}

const counters = (page) => page.evaluate(() => [window.posemfa.fitCount(), window.posemfa.loadErrorCount()]);

test('the page loads and fits its built-in population, with no external request', async () => {
  const t0 = Date.now();
  const { page, context, log } = await fresh();
  const marks = await page.evaluate(() => performance.getEntriesByName('posemfa:fitted').map((m) => m.startTime));
  const state = await page.evaluate(() => document.body.dataset.state);
  assert.equal(state, 'fitted', `state ${state}; errors: ${await page.locator('[data-testid=errors]').innerText()}`);
  const s = await summary(page);
  for (const k of SUMMARY_KEYS) assert.equal(typeof s[k], 'number', `summary.${k} = ${s[k]}`);
  assert.ok(s.shapes >= 2 && s.vertices > 100 && s.parts >= 2, JSON.stringify(s));
  assert.ok(s.fitMs > 0 && s.fitMs < Date.now() - t0, `fitMs ${s.fitMs}`);
  assert.equal(await page.locator('[data-testid=parts-count]').innerText(), String(s.parts));
  assert.equal(marks.length, 1, 'fitted once, at load');
  assert.equal(await page.evaluate(() => typeof window.posemfa.injectFault), 'undefined', 'fault injection only with ?faultInjection=1');
  // The generator's ground truth is shown beside the fit.
  await page.check('#modes input[value=truth]', { force: true });
  await page.waitForFunction(() => /ground truth/.test(document.querySelector('#caption').textContent));
  assert.deepEqual(log.external, []);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('an example from the list is generated and fitted with its own parameters and note', async () => {
  const { page, context } = await fresh();
  const ids = await page.locator('#example option').evaluateAll((os) => os.map((o) => o.value));
  assert.ok(ids.includes('arm') && ids.length >= 3, `examples: ${ids}`);
  const n = await counters(page);
  await page.selectOption('#example', 'arm');
  await page.click('#generate');
  assert.equal(await waitFit(page, n), 'fitted');
  assert.match(await page.locator('#example-note').innerText(), /\S/);
  assert.match(await page.locator('#pop-info').innerText(), /Ground truth: 3 parts/);
  const s = await summary(page);
  assert.ok(s.parts >= 3 && s.parts <= 6, `the 3-part arm gave ${s.parts} parts`);
  assert.equal(await page.locator('[data-testid=parts-count]').innerText(), String(s.parts));
  await context.close();
});

test('a population picked through the file input is fitted and its parts are coloured on screen', async () => {
  const { page, context, log } = await fresh();
  const tube = tubePopulation({ segments: 3, poses: 8, seed: 3 });
  assert.equal(await fitFiles(page, tube.files, { parts: 3 }), 'fitted');
  const s = await summary(page);
  for (const k of SUMMARY_KEYS) assert.equal(typeof s[k], 'number', `summary.${k} = ${s[k]}`);
  assert.equal(s.shapes, 8);
  assert.equal(s.vertices, tube.nVertices);
  assert.ok(s.parts >= 3 && s.parts <= 12, `a 3-part tube gave ${s.parts} parts`);
  assert.ok(s.rmse < 1e-3, `rmse ${s.rmse}: the tube's parts are exactly rigid`);
  assert.equal(await page.locator('[data-testid=parts-count]').innerText(), String(s.parts));

  // Flat colours: the canvas shows the palette colours exactly; every part of the bent tube faces the camera.
  await page.check('#flat');
  await page.waitForTimeout(200);
  const counts = await paletteCounts(page);
  const partColours = await page.evaluate(() => window.posemfa.partColours());
  assert.equal(partColours.length, s.parts);
  const used = new Set(partColours);
  const onScreen = Object.entries(counts).filter(([, n]) => n >= 50).map(([c]) => c);
  assert.ok(onScreen.length >= Math.min(s.parts, used.size), `colours on screen ${JSON.stringify(counts)}, parts ${s.parts}`);
  for (const c of onScreen) assert.ok(used.has(c), `${c} on screen is no part's colour`);
  // Adjacent parts never share a colour: with this palette every part of a 3-12 part tube has its own.
  assert.equal(used.size, Math.min(s.parts, (await page.evaluate(() => window.posemfa.palette)).length));
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the interpolation slider changes the geometry, part-wise beside linear blending', async () => {
  const { page, context } = await fresh();
  const tube = tubePopulation({ segments: 3, poses: 6, seed: 5 });
  assert.equal(await fitFiles(page, tube.files, { parts: 3 }), 'fitted');
  await page.check('#modes input[value=interp]', { force: true });
  await page.selectOption('#pose-a', '0');
  await page.selectOption('#pose-b', '3');
  const setT = async (t) => {
    await page.fill('[data-testid=interp-t]', String(t));
    await page.waitForFunction((t) => document.querySelector('#caption').textContent.includes(`t = ${t.toFixed(2)}`), t);
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    return canvasFingerprint(page);
  };
  assert.deepEqual(await page.evaluate(() => window.posemfa.shown()), ['part-wise']);
  const at0 = await setT(0);
  const atHalf = await setT(0.5);
  const at1 = await setT(1);
  assert.notEqual(at0, atHalf);
  assert.notEqual(atHalf, at1);
  assert.notEqual(at0, at1);
  assert.equal(await setT(0), at0, 'the same t draws the same picture');

  // Side by side: the part-wise shape beside the linear blend, which differs from it mid-way.
  await page.check('#side-by-side');
  await page.waitForFunction(() => window.posemfa.shown().join() === 'part-wise,linear');
  await setT(0.5);
  const [left, right] = await page.evaluate(() => {
    // pixels that are not the background, in the left and the right half of the view
    const { data, width } = window.__viewImage();
    const n = [0, 0];
    for (let i = 0; i < data.length; i += 4) {
      if (data[i] !== 0xee || data[i + 1] !== 0xf0 || data[i + 2] !== 0xf3) n[(i / 4) % width < width / 2 ? 0 : 1]++;
    }
    return n;
  });
  assert.ok(left > 500 && right > 500, `both halves draw a mesh: ${left}, ${right}`);
  await context.close();
});

test('the glTF export of the fitted model validates', async () => {
  const { validateFile } = await import('../../scripts/validate-gltf.mjs');
  const { page, context } = await fresh();
  assert.ok(await page.locator('#export-gltf').isEnabled());
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-gltf')]);
  const path = await download.path();
  const bytes = await (await import('node:fs/promises')).readFile(path);
  assert.equal(bytes.subarray(0, 4).toString('latin1'), 'glTF');
  const report = await validateFile(path);
  assert.equal(report.errors, 0, JSON.stringify(report.messages.slice(0, 5)));
  await context.close();
});

test('a malformed file lists its error and keeps the previous population and model', async () => {
  const { page, context } = await fresh();
  const tube = tubePopulation({ segments: 3, poses: 5, seed: 9 });
  assert.equal(await fitFiles(page, tube.files, { parts: 3 }), 'fitted');
  const before = await summary(page);
  const shownBefore = await page.locator('#pop-info').innerText();
  const bad = { name: 'broken.obj', text: 'v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n' };
  await page.setInputFiles('[data-testid=file-input]', asPayload([bad, tube.files[0]]));
  await page.waitForFunction(() => document.querySelector('[data-testid=errors]').textContent.includes('broken.obj'));
  const errors = await page.locator('[data-testid=errors]').innerText();
  assert.match(errors, /broken\.obj, line 2: /);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  assert.deepEqual(await summary(page), before);
  assert.equal(await page.locator('#pop-info').innerText(), shownBefore);
  assert.equal(await page.locator('[data-testid=parts-count]').innerText(), String(before.parts));
  await context.close();
});

test('the parameters show their defaults, and an invalid one is reported with the model kept', async () => {
  const { page, context } = await fresh();
  const form = (name) => page.locator(`#params [name=${name}]`);
  assert.equal(await form('parts').inputValue(), '11');
  assert.equal(Number(await form('tol').inputValue()), 1e-3);
  assert.equal(Number(await form('varianceFloor').inputValue()), 1e-7);
  assert.equal(await form('paperLambda').isChecked(), false);
  const before = await summary(page);
  const n = await counters(page);
  // the core checks the form before a fit: the field is named with what it allows, no fit starts
  await form('tol').fill('-1');
  await page.click('#fit');
  await page.waitForFunction(() => /Tolerance \(nats \/ vertex\): -1 must be a positive number/.test(document.querySelector('[data-testid=param-errors]').textContent));
  assert.deepEqual(await counters(page), n, 'no fit started');
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  assert.deepEqual(await summary(page), before);
  await page.click('#reset-params');
  assert.equal(Number(await form('tol').inputValue()), 1e-3);
  assert.equal(await page.locator('[data-testid=param-errors] li').count(), 0);
  await context.close();
});

test('file names are shown as text, never as HTML', async () => {
  const { page, context, log } = await fresh();
  const name = '<img src=x onerror=alert(1)>.obj';
  await page.setInputFiles('[data-testid=file-input]', asPayload([{ name, text: 'v 0 0 0\nv 1 1\n' }, { name: 'b.obj', text: 'v 0 0 0\n' }]));
  await page.waitForFunction((n) => document.querySelector('[data-testid=errors]').textContent.includes(n), name);
  await page.waitForTimeout(300);
  assert.equal(await page.locator('[data-testid=errors] img').count(), 0);
  assert.ok((await page.locator('[data-testid=errors]').innerText()).includes(name));
  assert.ok(await page.getByText(name, { exact: false }).first().isVisible());
  assert.deepEqual(log.dialogs, []);

  // A valid population with such names lists them as text too.
  const tube = tubePopulation({ segments: 2, poses: 3, seed: 2 });
  tube.files[0].name = name;
  assert.equal(await fitFiles(page, tube.files, { parts: 2 }), 'fitted');
  assert.equal(await page.locator('#names img, #pose-strip img, #caption img').count(), 0);
  assert.ok((await page.locator('#names').textContent()).includes(name));
  assert.deepEqual(log.dialogs, []);
  await context.close();
});

test('a dropped .zip is opened, natural-sorted and fitted', async () => {
  const { page, context } = await fresh();
  const tube = tubePopulation({ segments: 2, poses: 10, seed: 4 });
  // pose10 must come after pose9: natural order, not text order.
  const entries = Object.fromEntries(tube.files.map((f, i) => [`poses/p${i + 1}.obj`, strToU8(f.text)]));
  entries['poses/readme.txt'] = strToU8('not a mesh');
  const zip = Buffer.from(zipSync(entries));
  const n = await counters(page);
  await page.evaluate(async (b64) => {
    const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const dt = new DataTransfer();
    dt.items.add(new File([bytes], 'tube.zip', { type: 'application/zip' }));
    window.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
  }, zip.toString('base64'));
  assert.equal(await waitFit(page, n), 'fitted');
  const names = await page.locator('#names li').allTextContents();
  assert.deepEqual(names, tube.files.map((_, i) => `tube.zip/poses/p${i + 1}.obj`));
  assert.equal((await summary(page)).shapes, 10);
  await context.close();
});

test('a dropped folder is walked through webkitGetAsEntry, readEntries called until it returns nothing', async () => {
  const { page, context } = await fresh();
  const tube = tubePopulation({ segments: 2, poses: 10, seed: 5 });
  const n = await counters(page);
  const calls = await page.evaluate((texts) => {
    // Playwright cannot make FileSystemEntry objects, so the drop carries stand-ins with the same interface:
    // a folder whose reader hands out 3 entries per call (Chromium: at most 100), a subfolder, a text file.
    const log = { readEntries: 0 };
    const fileEntry = (path, text) => {
      const file = new File([text], path.split('/').pop());
      return { isFile: true, isDirectory: false, name: file.name, fullPath: path, file: (ok) => setTimeout(() => ok(file)) };
    };
    const dirEntry = (path, children) => ({
      isFile: false, isDirectory: true, fullPath: path,
      createReader() {
        let i = 0;
        return {
          readEntries(ok) {
            log.readEntries += 1;
            const batch = children.slice(i, i + 3);
            i += batch.length;
            setTimeout(() => ok(batch));
          },
        };
      },
    });
    const top = texts.slice(0, 8).map((t, i) => fileEntry(`/poses/p${i + 1}.obj`, t));
    const sub = dirEntry('/poses/q', texts.slice(8).map((t, i) => fileEntry(`/poses/q/p${i + 9}.obj`, t)));
    const root = dirEntry('/poses', [...top, sub, fileEntry('/poses/notes.txt', 'not a mesh')]);
    const dt = { items: [{ kind: 'file', webkitGetAsEntry: () => root }], files: [] };
    const ev = new Event('drop', { bubbles: true, cancelable: true });
    Object.defineProperty(ev, 'dataTransfer', { value: dt });
    window.dispatchEvent(ev);
    window.__folderLog = log;
    return log;
  }, tube.files.map((f) => f.text));
  assert.ok(calls, 'the drop was dispatched');
  assert.equal(await waitFit(page, n), 'fitted');
  const names = await page.locator('#names li').allTextContents();
  const expected = [...Array.from({ length: 8 }, (_, i) => `poses/p${i + 1}.obj`), 'poses/q/p9.obj', 'poses/q/p10.obj'];
  assert.deepEqual(names, expected);
  // 10 entries in the top folder at 3 per call: 4 batches and the empty answer; 2 + 1 in the subfolder
  assert.equal(await page.evaluate(() => window.__folderLog.readEntries), 5 + 2);
  assert.equal((await summary(page)).shapes, 10);
  await context.close();
});

test('a worker whose wasm instance traps is replaced, gets the population again, and the page stays usable', async () => {
  const { page, context } = await fresh(undefined, '?faultInjection=1');
  const tube = tubePopulation({ segments: 2, poses: 6, seed: 9 });
  assert.equal(await fitFiles(page, tube.files), 'fitted');
  const before = await summary(page);
  // The next fit makes the core panic (a real trap of the wasm instance: panic = "abort"), once.
  await page.evaluate(() => window.posemfa.injectFault('panic', 1));
  await page.click('#fit');
  await page.waitForFunction(() => window.posemfa.restartCount() === 1 && document.body.dataset.state === 'fitted', null, { timeout: 60000, polling: 20 });
  const after = await summary(page);
  assert.deepEqual([after.shapes, after.vertices, after.parts], [before.shapes, before.vertices, before.parts]);
  assert.match(await page.locator('[data-testid=errors]').innerText(), /worker stopped \(.*unreachable.*\) and was restarted/);
  assert.equal(await page.locator('[data-testid=parts-count]').innerText(), String(after.parts));
  // the new worker answers questions about the model: the JSON export (a query to the worker) works
  const download = page.waitForEvent('download');
  await page.click('#export-json');
  assert.match((await download).suggestedFilename(), /^posemfa-.+-model\.json$/);
  await context.close();
});

test('a crash that recurs ends after at most 2 restarts with a message; the page keeps its model and answers summary()', async () => {
  const { page, context } = await fresh(undefined, '?faultInjection=1');
  assert.equal(await page.evaluate(() => typeof window.posemfa.injectFault), 'function');
  const before = await summary(page);
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  await page.evaluate(() => window.posemfa.injectFault('panic')); // every fit from now on traps
  await page.click('#fit');
  await page.waitForFunction(() => /keeps crashing/.test(document.querySelector('[data-testid=errors]').textContent), null, { timeout: 60000, polling: 20 });
  const errors = await page.locator('[data-testid=errors]').innerText();
  assert.match(errors, /after 2 restarts .*it was not restarted/, errors);
  assert.equal(await page.evaluate(() => window.posemfa.restartCount()), 2);
  await page.waitForTimeout(1500);
  assert.equal(await page.evaluate(() => window.posemfa.restartCount()), 2, 'no restart after the cap');
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  assert.deepEqual(await summary(page), before, 'summary() still answers with the model it had');
  assert.equal(await page.locator('[data-testid=parts-count]').innerText(), String(before.parts));
  assert.ok(await page.evaluate((f) => window.posemfa.fitCount() > f, fits));
  // Still usable: with the fault gone, an example is generated and fitted by a new worker.
  await page.evaluate(() => window.posemfa.injectFault(null));
  const n = await counters(page);
  await page.selectOption('#example', 'arm');
  await page.click('#generate');
  assert.equal(await waitFit(page, n), 'fitted');
  assert.equal((await summary(page)).shapes, 8);
  assert.equal(await page.evaluate(() => window.posemfa.restartCount()), 2);
  await context.close();
});

test('Cancel stops a fit within a slice and keeps its best state so far', async () => {
  const { page, context } = await fresh();
  // A tolerance no fit reaches: the coarse stage would run to its iteration cap (seconds to minutes). With the
  // refinement on, the coarse stage runs at the refinement's own tolerance, so it is turned off here.
  const big = tubePopulation({ segments: 5, poses: 24, ringsPerSegment: 60, around: 40, seed: 11 });
  await page.fill('#params input[name=parts]', '11');
  await page.fill('#params input[name=tol]', '1e-12');
  await page.uncheck('#params input[name=refine]');
  const n = await counters(page);
  await page.setInputFiles('[data-testid=file-input]', asPayload(big.files));
  await waitState(page, ['fitting'], 60000);
  await page.waitForFunction(() => /\d/.test(document.querySelector('#iteration').textContent));
  await page.waitForTimeout(300);
  const t0 = Date.now();
  await page.click('#cancel');
  assert.equal(await waitFit(page, n, 30000), 'fitted');
  const waited = Date.now() - t0;
  assert.ok(waited < 3000, `the cancel took ${waited} ms to be seen`);
  const s = await summary(page);
  assert.equal(s.cancelled, true);
  assert.equal(s.complete, false);
  assert.ok(s.parts >= 1 && s.vertices === big.nVertices && Number.isFinite(s.rmse));
  assert.match(await page.locator('#stage').innerText(), /cancelled/);
  assert.doesNotMatch(await page.locator('#stage').innerText(), /best/); // a state stopped early, not the best
  assert.ok(await page.locator('#cancel').isDisabled());
  assert.notEqual(await page.locator('[data-testid=parts-count]').innerText(), '–');
  await context.close();
});

test('the OBJ export writes the shown pose in the original units; the JSON export is the model', async () => {
  const { page, context } = await fresh();
  const tube = tubePopulation({ segments: 2, poses: 4, seed: 6 });
  // Move and scale the population away from the unit box, so that the normalisation matters.
  const moved = tube.files.map((f) => ({
    name: f.name,
    text: f.text.replace(/^v (\S+) (\S+) (\S+)$/gm, (_, x, y, z) => `v ${(+x * 40 + 100).toFixed(4)} ${(+y * 40 - 7).toFixed(4)} ${(+z * 40).toFixed(4)}`),
  }));
  assert.equal(await fitFiles(page, moved, { parts: 2 }), 'fitted');
  await page.click('#pose-strip button:nth-child(3)');
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-obj')]);
  const text = await (await import('node:fs/promises')).readFile(await download.path(), 'utf8');
  const verts = (t) => [...t.matchAll(/^v (\S+) (\S+) (\S+)$/gm)].map((m) => m.slice(1, 4).map(Number));
  const got = verts(text);
  const want = verts(moved[2].text);
  assert.equal(got.length, want.length);
  let worst = 0;
  got.forEach((v, i) => v.forEach((c, k) => { worst = Math.max(worst, Math.abs(c - want[i][k])); }));
  // the population keeps unit-box coordinates in f32 (half the memory of f64): in original units within half an f32 step of
  // the unit box (2^-25) times the population box's side, with a 2x margin
  const all = moved.flatMap((f) => verts(f.text));
  const side = Math.max(...[0, 1, 2].map((k) => Math.max(...all.map((v) => v[k])) - Math.min(...all.map((v) => v[k]))));
  assert.ok(worst <= 2 ** -24 * side, `largest coordinate difference ${worst}: more than f32 rounding in a box of side ${side}`);
  // the header says what was exported: the view's caption and the objects written (here one: the pose)
  assert.match(text, /^# Pose “tube3\.obj”, coloured by part \(\d+ parts\)\n# objects: pose tube3\.obj\n# posemfa, \d+ vertices and \d+ triangles per object\no pose_tube3\.obj\n/);
  assert.equal([...text.matchAll(/^f /gm)].length, [...moved[2].text.matchAll(/^f /gm)].length);

  // The model as JSON: the core's own text, for this population and fit.
  const [json] = await Promise.all([page.waitForEvent('download'), page.click('#export-json')]);
  const model = JSON.parse(await (await import('node:fs/promises')).readFile(await json.path(), 'utf8'));
  const s = await summary(page);
  assert.deepEqual(model.shapes, moved.map((f) => f.name));
  assert.equal(model.labels.length, s.vertices);
  assert.equal(model.rmse, s.rmse);
  await context.close();
});

test('works on a narrow window, the canvas follows its size, and the controls are keyboard reachable', async () => {
  const { page, context } = await fresh({ width: 420, height: 860 });
  const w = await page.evaluate(() => document.querySelector('#view canvas').getBoundingClientRect().width);
  assert.ok(w > 200 && w <= 420, `canvas width ${w}`);
  const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  assert.ok(overflow <= 0, `page wider than the window by ${overflow}px`);
  await page.setViewportSize({ width: 1280, height: 800 });
  await page.waitForFunction(() => document.querySelector('#view canvas').getBoundingClientRect().width > 700);

  const reached = new Set();
  for (let i = 0; i < 40; i++) {
    await page.keyboard.press('Tab');
    reached.add(await page.evaluate(() => document.activeElement?.id || document.activeElement?.getAttribute('name') || document.activeElement?.tagName));
  }
  for (const id of ['file-input', 'parts', 'fit', 'mode', 'flat']) assert.ok(reached.has(id), `${id} not reached by Tab: ${[...reached]}`);
  await context.close();
});
