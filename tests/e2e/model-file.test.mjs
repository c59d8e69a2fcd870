// Model files (.posemfa, src/model_file.rs) in the page: a file written by `posemfa fit --save` opens without
// fitting and every view works from it; the page saves one; a link (src=URL, the embed's iframe form) fetches a
// model file or a .zip of poses from the page's own server and from a second origin that allows it, and says
// why when the second origin does not (the header it must send) or the address is not found; a cut file, a file
// of a newer version and a model given poses of another mesh are refused by name, and what was shown stays.
// Run: npm run build && node --test tests/e2e/model-file.test.mjs
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import http from 'node:http';
import { readFileSync, readdirSync, mkdtempSync } from 'node:fs';
import { readFile } from 'node:fs/promises';
import { execFileSync } from 'node:child_process';
import { join } from 'node:path';
import { tmpdir } from 'node:os';
import { zipSync, strToU8 } from 'fflate';
import { pageSession, waitState, tubePopulation, debugCli, summary } from './helpers.mjs';

const session = pageSession();
const counters = (page) => page.evaluate(() => [window.posemfa.fitCount(), window.posemfa.loadErrorCount()]);
const labels = (page) => page.evaluate(() => window.posemfa.fittedParts()?.labels ?? null);

// A generated population written as OBJ and fitted by the CLI: its model file with and without the poses, its
// JSON, and its pose files.
const dir = mkdtempSync(join(tmpdir(), 'posemfa-model-'));
const posesDir = join(dir, 'arm-poses');
let cli;
let withPoses;
let withoutPoses;
let fitJson;
let poseFiles;
before(() => {
  cli = debugCli();
  execFileSync(cli, ['generate', 'arm', '--vertices', '700', '--poses', '5', '--seed', '3', '--out', posesDir]);
  poseFiles = readdirSync(posesDir).filter((n) => n.endsWith('.obj')).map((n) => ({ name: n, buffer: readFileSync(join(posesDir, n)) }));
  execFileSync(cli, ['fit', posesDir, '--quiet', '--save', join(dir, 'arm.posemfa'), '--json', join(dir, 'arm.json')]);
  execFileSync(cli, ['fit', '--model', join(dir, 'arm.posemfa'), '--quiet', '--save', join(dir, 'bare.posemfa'), '--without-poses']);
  execFileSync(cli, ['fit', '--model', join(dir, 'arm.posemfa'), '--quiet', '--save', join(dir, 'rigged.posemfa'), '--with-rig']);
  withPoses = readFileSync(join(dir, 'arm.posemfa'));
  withoutPoses = readFileSync(join(dir, 'bare.posemfa'));
  fitJson = JSON.parse(readFileSync(join(dir, 'arm.json'), 'utf8'));
});

// A second origin (another port): /cors/NAME with Access-Control-Allow-Origin, /plain/NAME without.
let other;
const served = new Map();
before(async () => {
  other = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://x');
    const body = served.get(url.pathname.split('/').pop());
    const headers = url.pathname.startsWith('/cors/') ? { 'access-control-allow-origin': '*' } : {};
    if (!body) return res.writeHead(404, headers).end('not found');
    res.writeHead(200, { ...headers, 'content-type': 'application/octet-stream' }).end(body);
  });
  await new Promise((ok) => other.listen(0, '127.0.0.1', ok));
});
after(() => new Promise((ok) => other.close(ok)));

const tube = tubePopulation({ segments: 3, poses: 6 });
// the arm's model file saved without its poses, and the poses as OBJ files, in one archive
const demoZip = () => Buffer.from(zipSync({ 'demo/arm.posemfa': new Uint8Array(withoutPoses), ...Object.fromEntries(poseFiles.map((f) => [`demo/poses/${f.name}`, new Uint8Array(f.buffer)])) }));
const tubeZip = () => Buffer.from(zipSync(Object.fromEntries(tube.files.map((f) => [`tube/${f.name}`, strToU8(f.text)]))));

async function fresh(path = '') {
  const p = await session.open(path);
  await waitState(p.page, ['fitted', 'idle', 'error'], 90000);
  return p;
}

// Picks files ({ name, buffer }) and waits until they were opened or refused; returns whether they were refused.
async function pick(page, files) {
  const [fits, errs] = await counters(page);
  await page.setInputFiles('[data-testid=file-input]', files.map((f) => ({ name: f.name, mimeType: 'application/octet-stream', buffer: f.buffer })));
  await page.waitForFunction(([f, l]) => window.posemfa.fitCount() > f || window.posemfa.loadErrorCount() > l, [fits, errs], { timeout: 120000, polling: 50 });
  return page.evaluate((l) => window.posemfa.loadErrorCount() > l, errs);
}

test('a model file opens without fitting, and every view works from it', async () => {
  const { page, log, context } = await fresh();
  const refused = await pick(page, [{ name: 'arm.posemfa', buffer: withPoses }]);
  assert.equal(refused, false, await page.locator('[data-testid=errors]').innerText());
  const s = await summary(page);
  assert.equal(s.opened, 'arm.posemfa');
  assert.equal(s.hasData, true);
  assert.equal(s.parts, fitJson.parts.length);
  assert.equal(s.rmse, fitJson.rmse, 'the RMSE the CLI measured');
  assert.deepEqual(await labels(page), fitJson.labels, 'the labels the CLI fitted');
  const stages = await page.evaluate(() => window.posemfa.stageParts('coarse').labels);
  assert.deepEqual(stages, fitJson.coarse_labels);
  const tree = await page.evaluate(() => window.posemfa.tree());
  assert.ok(tree && tree.most >= tree.fewest, 'the merge tree slider has the saved tree');
  assert.equal(tree.decided, fitJson.tree_count);
  const cut = await page.evaluate((n) => window.posemfa.treePartition(n), tree.fewest);
  assert.equal(new Set(cut.labels).size, tree.fewest);
  for (const mode of ['stages', 'recon', 'latent', 'interp', 'pose', 'parts']) {
    await page.check(`#modes input[value=${mode}]`);
    await page.waitForFunction((m) => window.posemfa.mode() === m && window.posemfa.shown().length > 0, mode, { timeout: 60000 });
  }
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  // saved again from the page: a model file that opens as the same fit
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('[data-testid=export-model]')]);
  assert.match(download.suggestedFilename(), /\.posemfa$/);
  const saved = await readFile(await download.path());
  assert.equal(saved.subarray(0, 8).toString('latin1'), 'POSEMFA\0');
  assert.equal(await pick(page, [{ name: 'again.posemfa', buffer: saved }]), false);
  assert.deepEqual(await labels(page), fitJson.labels);
  assert.deepEqual(log.errors, [], 'no console errors');
  await context.close();
});

test('a model file saved with its rig gives the Rig panel that rig; other options build their own', async () => {
  const { page, log, context } = await fresh();
  assert.equal(await pick(page, [{ name: 'rigged.posemfa', buffer: readFileSync(join(dir, 'rigged.posemfa')) }]), false);
  const erms = page.locator('[data-testid=rig-erms]');
  const press = async () => {
    await page.evaluate(() => { delete document.querySelector('[data-testid=rig-erms]').dataset.erms; });
    const download = page.waitForEvent('download', { timeout: 60000 });
    await page.click('#export-gltf');
    await download;
    await page.waitForFunction(() => document.querySelector('[data-testid=rig-erms]').dataset.erms);
  };
  // --with-rig keeps the rig of fitted weights with the default options
  await page.selectOption('#rig [name=weights]', 'fitted');
  await page.fill('#rig [name=influences]', '4');
  await press();
  assert.equal(await erms.getAttribute('data-source'), 'model file');
  assert.match(await erms.innerText(), /the rig kept in the model file/);
  const kept = Number(await erms.getAttribute('data-erms'));
  await page.fill('#rig [name=influences]', '3');
  await press();
  assert.equal(await erms.getAttribute('data-source'), 'built');
  assert.doesNotMatch(await erms.innerText(), /kept in the model file/);
  await page.fill('#rig [name=influences]', '4');
  await press();
  assert.equal(Number(await erms.getAttribute('data-erms')), kept, 'the kept rig measures as it did');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a model saved without its poses opens on its own and with its poses; poses of another mesh are refused', async () => {
  const { page, context } = await fresh();
  assert.equal(await pick(page, [{ name: 'bare.posemfa', buffer: withoutPoses }]), false);
  let s = await summary(page);
  assert.equal(s.hasData, false);
  assert.deepEqual(await labels(page), fitJson.labels);
  assert.match(await page.locator('[data-testid=errors]').innerText(), /saved without its poses/);
  // with the poses it was fitted to
  assert.equal(await pick(page, [{ name: 'bare.posemfa', buffer: withoutPoses }, ...poseFiles]), false, await page.locator('[data-testid=errors]').innerText());
  s = await summary(page);
  assert.equal(s.hasData, true);
  assert.equal(s.rmse, fitJson.rmse);
  // poses of another mesh: refused by name, the model shown stays
  const before = await labels(page);
  const other = tube.files.map((f) => ({ name: f.name, buffer: Buffer.from(f.text) }));
  assert.equal(await pick(page, [{ name: 'bare.posemfa', buffer: withoutPoses }, ...other]), true);
  assert.match(await page.locator('[data-testid=errors]').innerText(), /bare\.posemfa.*fitted to another mesh/s);
  assert.deepEqual(await labels(page), before, 'the model shown stays');
  await context.close();
});

test('a cut file and a file of a newer version are refused by name, and what was shown stays', async () => {
  const { page, context } = await fresh();
  const before = await labels(page);
  assert.equal(await pick(page, [{ name: 'cut.posemfa', buffer: withPoses.subarray(0, withPoses.length - 1000) }]), true);
  assert.match(await page.locator('[data-testid=errors]').innerText(), /cut\.posemfa.*cut short/s);
  const newer = Buffer.from(withPoses);
  newer.writeUInt32LE(3, 8);
  assert.equal(await pick(page, [{ name: 'newer.posemfa', buffer: newer }]), true);
  assert.match(await page.locator('[data-testid=errors]').innerText(), /format version 3.*reads model files of version 1 to 2.*newer posemfa/s);
  assert.deepEqual(await labels(page), before);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'fitted');
  await context.close();
});

test('a link opens a model file or a .zip from its own server, in the embed, and keeps src', async () => {
  const p = await session.open('');
  // the page's own origin: answered by the test through the browser's routing
  await p.context.route('**/links/**', (route) => {
    const name = new URL(route.request().url()).pathname.split('/').pop();
    const body = { 'arm.posemfa': withPoses, 'tube.zip': tubeZip(), 'demo.zip': demoZip() }[name];
    return body ? route.fulfill({ status: 200, body, contentType: 'application/octet-stream' }) : route.fulfill({ status: 404, body: 'not found' });
  });
  await p.page.goto(p.page.url().replace(/#.*$/, '') + '#embed=1&src=links/arm.posemfa&view=interp');
  await p.page.reload();
  await waitState(p.page, ['fitted', 'error'], 90000);
  const s = await summary(p.page);
  assert.equal(s.opened, 'arm.posemfa');
  assert.deepEqual(await labels(p.page), fitJson.labels);
  await p.page.waitForFunction(() => window.posemfa.mode() === 'interp' && !window.posemfa.restoring(), null, { timeout: 60000 });
  await p.page.waitForFunction(() => /src=links%2Farm\.posemfa|src=links\/arm\.posemfa/.test(location.hash), null, { timeout: 5000 });

  await p.page.goto(p.page.url().replace(/#.*$/, '') + '#embed=1&src=links/tube.zip');
  await p.page.reload();
  await waitState(p.page, ['fitted', 'error'], 90000);
  const z = await summary(p.page);
  assert.equal(z.opened, undefined, 'a zip of poses is fitted');
  assert.equal(z.shapes, 6);

  // a paper's demo in one archive: its model file (without the poses) and the OBJ poses it was fitted to
  await p.page.goto(p.page.url().replace(/#.*$/, '') + '#embed=1&src=links/demo.zip');
  await p.page.reload();
  await waitState(p.page, ['fitted', 'error'], 90000);
  const d = await summary(p.page);
  assert.equal(d.opened, 'demo.zip/demo/arm.posemfa', 'the model file in the archive is opened, not fitted again');
  assert.deepEqual(await labels(p.page), fitJson.labels);
  assert.equal(d.hasData, true, "the archive's poses are the model's data");

  await p.page.goto(p.page.url().replace(/#.*$/, '') + '#embed=1&src=links/none.posemfa');
  await p.page.reload();
  await p.page.waitForFunction(() => document.querySelector('[data-testid=fetch-status]').dataset.state === 'error', null, { timeout: 60000 });
  assert.match(await p.page.locator('[data-testid=fetch-status]').innerText(), /HTTP 404.*not found/s);
  await p.context.close();
});

test('a link to a second origin opens when the server allows it, and says which header is missing when not', async () => {
  served.set('arm.posemfa', withPoses);
  const base = `http://127.0.0.1:${other.address().port}`;
  const p = await session.open(`#embed=1&src=${encodeURIComponent(`${base}/cors/arm.posemfa`)}`);
  await waitState(p.page, ['fitted', 'error'], 90000);
  assert.equal((await summary(p.page)).opened, 'arm.posemfa');
  await p.context.close();

  const q = await session.open(`#src=${encodeURIComponent(`${base}/plain/arm.posemfa`)}`);
  await q.page.waitForFunction(() => document.querySelector('[data-testid=fetch-status]').dataset.state === 'error', null, { timeout: 60000 });
  const said = await q.page.locator('[data-testid=fetch-status]').innerText();
  assert.match(said, /does not let this page .* read the file/);
  assert.match(said, /Access-Control-Allow-Origin/);
  // the full page (not the embed) falls back to the default example behind the message
  await waitState(q.page, ['fitted'], 90000);
  assert.match(await q.page.locator('[data-testid=errors]').innerText(), /Access-Control-Allow-Origin/);
  await q.context.close();
});

test('the example paper page shows its three views of one model file', async () => {
  const { page, log, context } = await session.open('examples/paper-demo/index.html');
  const frames = await page.locator('iframe[data-view]').all();
  assert.equal(frames.length, 3);
  const views = [];
  for (const f of frames) {
    await f.scrollIntoViewIfNeeded();
    const frame = await (await f.elementHandle()).contentFrame();
    await frame.waitForFunction(() => document.body.dataset.state === 'fitted' && !window.posemfa.restoring(), null, { timeout: 120000 });
    const [mode, opened, panelShown] = await frame.evaluate(() => [
      window.posemfa.mode(), window.posemfa.summary().opened, getComputedStyle(document.getElementById('pose-panel')).display !== 'none',
    ]);
    assert.match(opened, /\.posemfa$/, 'opened from the model file, not fitted');
    assert.equal(panelShown, false, 'the embed hides the pose panel: the mesh is dragged');
    views.push(mode);
  }
  assert.deepEqual(views, ['parts', 'interp', 'pose']);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('mount(element, { url }) opens a model file in an element of another page, and says why it cannot', async () => {
  served.set('arm.posemfa', withPoses);
  const base = `http://127.0.0.1:${other.address().port}`;
  const { page, log, context } = await session.open('examples/paper-demo/index.html');
  const result = await page.evaluate(async ([good, bad]) => {
    const { mount } = await import('../../mount.js');
    const a = document.createElement('div');
    const b = document.createElement('div');
    for (const d of [a, b]) { d.style.height = '240px'; document.body.append(d); }
    const ok = mount(a, { url: good });
    const summary = await ok.ready;
    const refused = mount(b, { url: bad });
    const error = await refused.ready.then(() => null, (e) => e.message);
    return { opened: summary.opened, parts: summary.parts, state: a.dataset.state, caption: b.textContent, error, badState: b.dataset.state };
  }, [`${base}/cors/arm.posemfa`, `${base}/plain/arm.posemfa`]);
  assert.equal(result.opened, 'arm.posemfa');
  assert.equal(result.parts, fitJson.parts.length);
  assert.equal(result.state, 'fitted');
  assert.equal(result.badState, 'error');
  assert.match(result.error, /Access-Control-Allow-Origin/);
  assert.match(result.caption, /Access-Control-Allow-Origin/);
  // (the browser logs the refused fetch itself)
  assert.deepEqual(log.errors.filter((e) => !/CORS policy|ERR_FAILED/.test(e)), []);
  await context.close();
});
