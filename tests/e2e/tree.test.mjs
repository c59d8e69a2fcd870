// The merge tree on the built page (dist/): its slider shows every part count of the tree, each from the
// core at once (no fit), and stays put under a real mouse drag; a new fit of the same population keeps the
// colour of every part that stayed the same; after Refine N the Fit button says the N parts later fits keep.
// Prints the time of the slowest move (a figure, not a bar: speed goals are benchmarks).
// Run: npm run build && node --test tests/e2e/tree.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, readdirSync } from 'node:fs';
import path from 'node:path';
import { pageSession, waitState, moveTreeSlider, afterNextFit, ROOT, text } from './helpers.mjs';

const session = pageSession();

async function fitted(page) {
  assert.equal(await waitState(page, ['fitted', 'error'], 90000), 'fitted');
}

test('the slider shows every count of the merge tree, each partition with that many parts', async (t) => {
  const { page, log } = await session.open();
  await fitted(page);
  const tree = await page.evaluate(() => window.posemfa.tree());
  assert.ok(tree && tree.most > tree.fewest, JSON.stringify(tree));
  assert.ok(tree.decided >= tree.fewest && tree.decided <= tree.most, JSON.stringify(tree));
  assert.equal(await page.locator('#tree').isHidden(), false);
  let slowest = 0;
  for (let n = tree.most; n >= tree.fewest; n--) {
    const d = await moveTreeSlider(page, n);
    assert.equal(Number(d.parts), n, `count ${n}`);
    slowest = Math.max(slowest, Number(d.ms));
    assert.match(await page.locator('#tree-count').innerText(), new RegExp(`^${n} ${n === 1 ? 'part' : 'parts'} `)); // "1 part", not "1 parts"
  }
  t.diagnostic(`merge tree slider: ${tree.most - tree.fewest + 1} counts, slowest move ${slowest.toFixed(1)} ms`);
  // no fit ran for any of it
  assert.equal(await page.evaluate(() => window.posemfa.fitCount()), 1);
  assert.deepEqual(log.errors, []);
});

test('Refine fits the chosen count, and parts that stay keep their colours', async () => {
  const { page, log } = await session.open();
  await fitted(page);
  const before = await page.evaluate(() => window.posemfa.fittedParts());
  const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
  const want = parts - 2;
  await moveTreeSlider(page, want);
  const shown = await page.evaluate((n) => window.posemfa.treePartition(n), want);
  await page.click('[data-testid=tree-refine]');
  await page.waitForFunction(() => window.posemfa.fitCount() >= 2, null, { timeout: 90000 });
  await fitted(page);
  assert.equal((await page.evaluate(() => window.posemfa.summary())).parts, want);
  // the main view shows the refit's parts, not the merge tree's cut the slider showed before
  await page.waitForFunction((n) => document.getElementById('caption').textContent.includes(`coloured by part (${n} parts`), want, { timeout: 10000 });
  // more parts than the 12 colours: the caption says that parts apart from each other can share one
  assert.match(await page.textContent('#caption'), new RegExp(`coloured by part \\(${want} parts; 12 colours, so parts that do not touch can share one\\)$`));
  assert.equal((await page.evaluate(() => window.posemfa.tree())).shown, null);
  const after = await page.evaluate(() => window.posemfa.fittedParts());
  // parts that are the same (more than half of each in the other) keep their colour
  const same = sameParts(after.labels, before.labels);
  for (const [l, b] of same) assert.equal(after.colours[l], before.colours[b], `part ${l} (was ${b}) changed colour`);
  assert.ok(same.length >= want - 4, `only ${same.length} of ${want} parts matched an earlier part`);
  // Refine fits the partition the slider showed: each of its parts is one of the refit's
  assert.equal(sameParts(after.labels, shown.labels).length, want, 'the refit is not the partition the slider showed');
  assert.deepEqual(log.errors, []);
});

test('after Refine the slider keeps the tree it chose from: another count refines, the link restores the refit', async () => {
  const { page, log } = await session.open();
  await fitted(page);
  const tree = await page.evaluate(() => window.posemfa.tree());
  const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
  assert.ok(parts - 3 >= tree.fewest, JSON.stringify(tree));
  const refineTo = async (n) => {
    const fits = await page.evaluate(() => window.posemfa.fitCount());
    await moveTreeSlider(page, n);
    await page.click('[data-testid=tree-refine]');
    await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 90000 });
    await fitted(page);
    assert.equal((await page.evaluate(() => window.posemfa.summary())).parts, n);
  };
  await refineTo(parts - 2);
  // the tree is the one chosen from: every count, and the part rule's own, still on the slider
  const after = await page.evaluate(() => window.posemfa.tree());
  assert.deepEqual({ ...after, shown: null }, { ...tree, shown: null });
  assert.equal(await page.evaluate(() => document.getElementById('tree-slider').max), String(tree.most));
  assert.match(await page.locator('#tree-count').innerText(), new RegExp(`^${parts - 2} parts \\(the fit, refined from this count of the tree\\)`));
  // the part rule's count shows that fit's own parts again, and says whose count it is
  const d = await moveTreeSlider(page, tree.decided);
  assert.equal(Number(d.parts), tree.decided);
  assert.match(await page.locator('#tree-count').innerText(), /the part rule’s count/);
  // a second Refine chooses from the same tree
  const want = parts - 3;
  const shown = await page.evaluate((n) => window.posemfa.treePartition(n), want);
  await refineTo(want);
  const refit = await page.evaluate(() => window.posemfa.fittedParts());
  assert.equal(sameParts(refit.labels, shown.labels).length, want, 'the second Refine did not fit the partition shown');
  // the link names the tree's fit (its parameters, the count auto) and the count refined: opened, the page makes
  // the fit, then the Refine, and shows the same parts
  await page.waitForFunction((n) => location.hash.includes(`cut=${n}`), want, { timeout: 5000 });
  const hash = await page.evaluate(() => location.hash);
  assert.doesNotMatch(hash, /bones=/, hash);
  const again = await session.open(hash);
  await again.page.waitForFunction(() => window.posemfa?.fitCount() >= 2 && !window.posemfa.restoring(), null, { timeout: 120000 });
  assert.equal(await waitState(again.page, ['fitted', 'error'], 90000), 'fitted');
  const restored = await again.page.evaluate(() => window.posemfa.fittedParts());
  assert.deepEqual(restored.labels, refit.labels);
  assert.deepEqual(await again.page.evaluate(() => window.posemfa.tree()), { ...tree, shown: null });
  // a count the tree does not hold: the fit's own parts, and a note that says why
  const far = await session.open(hash.replace(`cut=${want}`, `cut=${tree.most + 5}`));
  await far.page.waitForFunction(() => window.posemfa?.fitCount() >= 1 && !window.posemfa.restoring(), null, { timeout: 120000 });
  await far.page.waitForFunction(() => document.getElementById('errors').textContent.includes('merge tree holds'), null, { timeout: 10000 });
  assert.match(await far.page.textContent('[data-testid=errors]'), new RegExp(`refined from ${tree.most + 5} parts of the merge tree, but its merge tree holds ${tree.fewest}-${tree.most} parts here: showing the fit’s own parts`));
  assert.equal((await far.page.evaluate(() => window.posemfa.summary())).parts, parts);
  assert.equal(await far.page.evaluate(() => window.posemfa.fitCount()), 1);
  for (const l of [log, again.log, far.log]) assert.deepEqual(l.errors, []);
});

test('moved in another view, the slider shows its partition in the Parts view and says it went there', async () => {
  const { page, log } = await session.open();
  await fitted(page);
  const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
  await page.check('#modes input[value=interp]');
  await page.waitForFunction(() => window.posemfa.mode() === 'interp');
  await moveTreeSlider(page, parts - 1);
  assert.equal(await page.evaluate(() => window.posemfa.mode()), 'parts');
  assert.match(await page.locator('#tree-count').innerText(), new RegExp(`^${parts - 1} parts of the merge tree.*, shown in the Parts view \\(from Interpolate\\)$`));
  // moved again in the Parts view: no word about it
  await moveTreeSlider(page, parts - 2);
  assert.doesNotMatch(await page.locator('#tree-count').innerText(), /shown in the Parts view/);
  assert.deepEqual(log.errors, []);
});

// The parts of `a` that are a part of `b` (more than half of each in the other): [[part of a, part of b]].
function sameParts(a, b) {
  const overlap = new Map();
  const sizeA = new Map();
  const sizeB = new Map();
  a.forEach((l, v) => {
    const key = `${l},${b[v]}`;
    overlap.set(key, (overlap.get(key) ?? 0) + 1);
    sizeA.set(l, (sizeA.get(l) ?? 0) + 1);
    sizeB.set(b[v], (sizeB.get(b[v]) ?? 0) + 1);
  });
  return [...overlap].map(([key, n]) => [...key.split(',').map(Number), n])
    .filter(([l, m, n]) => 2 * n > sizeA.get(l) && 2 * n > sizeB.get(m)).map(([l, m]) => [l, m]);
}

test('on horse-poses every count of the tree shows at once (needs ../shared)', async (t) => {
  const horse = path.join(process.env.POSEMFA_SHARED ?? path.join(ROOT, '../shared'), 'data/horse-poses');
  if (!existsSync(horse)) {
    if (process.env.CI === 'true') assert.fail(`${horse} is absent, and CI=true`);
    t.skip(`${horse} is absent`);
    return;
  }
  const { page, log } = await session.open();
  await fitted(page);
  const fits = await page.evaluate(() => window.posemfa.fitCount());
  const names = readdirSync(horse).filter((f) => f.endsWith('.obj'));
  await page.setInputFiles('[data-testid=file-input]', names.map((n) => path.join(horse, n)));
  await page.waitForFunction((f) => window.posemfa.fitCount() > f, fits, { timeout: 300000, polling: 50 });
  await fitted(page);
  const tree = await page.evaluate(() => window.posemfa.tree());
  const times = [];
  const drawn = [];
  for (let n = tree.most; n >= tree.fewest; n--) {
    const d = await moveTreeSlider(page, n);
    assert.equal(Number(d.parts), n, `count ${n}`);
    times.push(Number(d.ms));
    drawn.push(Number(d.drawnMs));
  }
  const figures = (xs) => {
    xs.sort((a, b) => a - b);
    return `median ${xs[xs.length >> 1].toFixed(1)} ms, slowest ${xs.at(-1).toFixed(1)} ms`;
  };
  // in the view (its draw asked for) / on screen (the frame drawn: here software WebGL, 15-20 frames a second)
  t.diagnostic(`horse-poses: ${times.length} counts; in the view: ${figures(times)}; drawn: ${figures(drawn)}`);
  assert.deepEqual(log.errors, []);
});

// Every pose thumbnail's pixels, hashed (FNV-1a), once the strip says it drew them all.
async function thumbnails(page, drawnAfter) {
  await page.waitForFunction((d) => Number(document.getElementById('pose-strip').dataset.drawn ?? 0) > d, drawnAfter, { timeout: 30000 });
  return page.evaluate(() => ({
    drawn: Number(document.getElementById('pose-strip').dataset.drawn),
    hashes: [...document.querySelectorAll('#pose-strip canvas')].map((src) => {
      const c = document.createElement('canvas');
      c.width = src.width;
      c.height = src.height;
      const g = c.getContext('2d');
      g.drawImage(src, 0, 0);
      const { data } = g.getImageData(0, 0, c.width, c.height);
      let h = 2166136261;
      for (let i = 0; i < data.length; i++) h = Math.imul(h ^ data[i], 16777619);
      return h >>> 0;
    }),
  }));
}

test('the pose thumbnails take the merge tree\'s colours with the slider, and the fit\'s again when it goes back', async () => {
  const { page, log } = await session.open();
  await fitted(page);
  const fit = await thumbnails(page, 0);
  assert.ok(fit.hashes.length >= 2, `${fit.hashes.length} thumbnails`);
  const tree = await page.evaluate(() => window.posemfa.tree());
  const parts = (await page.evaluate(() => window.posemfa.summary())).parts;
  const other = tree.fewest === parts ? tree.most : tree.fewest;
  assert.notEqual(other, parts);
  await moveTreeSlider(page, other);
  const moved = await thumbnails(page, fit.drawn);
  moved.hashes.forEach((h, i) => assert.notEqual(h, fit.hashes[i], `thumbnail ${i} kept the fitted parts' colours at ${other} parts`));
  await moveTreeSlider(page, parts);
  const back = await thumbnails(page, moved.drawn);
  assert.deepEqual(back.hashes, fit.hashes, 'back at the fit\'s count: the fitted parts\' colours');
  assert.deepEqual(log.errors, []);
});

test('the vertex box goes when the slider shows another partition; asked again, it says the part is the fit\'s', async () => {
  const { page, context, log } = await session.open();
  await fitted(page);
  const fit = (await page.evaluate(() => window.posemfa.summary())).parts;
  const tree = await page.evaluate(() => window.posemfa.tree());
  const info = () => page.locator('#info').innerText().then((t) => t.trim());
  await page.evaluate(() => window.posemfa.inspect(0));
  await page.waitForFunction(() => /^Vertex 0 /.test(document.getElementById('info').textContent));
  assert.match(await info(), /^Vertex 0 \(.*\): part \d+ \n/);
  const n = fit > tree.fewest ? fit - 1 : fit + 1;
  await moveTreeSlider(page, n);
  assert.equal(await info(), '', `the box of the ${fit}-part fit is still up over the tree's ${n} parts`);
  assert.equal(await page.locator('#info').isVisible(), false);
  // a new click while the tree's partition shows: the part named is the fit's, and the box says so
  await page.evaluate(() => window.posemfa.inspect(0));
  await page.waitForFunction(() => /^Vertex 0 /.test(document.getElementById('info').textContent));
  assert.match(await info(), new RegExp(`^Vertex 0 \\(.*\\): part \\d+ of the fit's ${fit} \\(the view shows the merge tree's ${n}\\)`));
  // back at the fit's count: the box goes again, and a click names the part plainly
  await moveTreeSlider(page, fit);
  assert.equal(await info(), '');
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('the merge tree\'s slider stays put under a real mouse drag, and its value follows the mouse', async () => {
  const { page, context, log } = await session.open();
  await fitted(page);
  const tree = await page.evaluate(() => window.posemfa.tree());
  assert.ok(tree.most - tree.fewest >= 10, JSON.stringify(tree));
  const slider = page.locator('#tree-slider');
  await slider.scrollIntoViewIfNeeded();
  const box = await slider.boundingBox();
  const span = tree.most - tree.fewest;
  // x of value v on the track (the thumb's centre runs over the track less one thumb width; about 16 px)
  const thumb = 16;
  const xOf = (v) => box.x + thumb / 2 + ((v - tree.fewest) / span) * (box.width - thumb);
  const y = box.y + box.height / 2;
  const start = Number(await slider.inputValue());
  await page.mouse.move(xOf(start), y);
  await page.mouse.down();
  const seen = [];
  for (let v = start - 1; v >= tree.fewest + 2; v -= 1) {
    await page.mouse.move(xOf(v), y, { steps: 2 });
    await page.waitForTimeout(60); // the count's words change under the mouse meanwhile
    const now = await slider.boundingBox();
    assert.ok(Math.abs(now.x - box.x) < 0.5 && Math.abs(now.y - box.y) < 0.5 && Math.abs(now.width - box.width) < 0.5,
      `the slider moved from ${JSON.stringify(box)} to ${JSON.stringify(now)} at value ${v}`);
    const value = Number(await slider.inputValue());
    seen.push(value);
    assert.ok(Math.abs(value - v) <= 1, `the mouse is at ${v}, the slider says ${value}`);
  }
  await page.mouse.up();
  await page.waitForFunction((v) => document.getElementById('tree-slider').dataset.count === String(v), seen.at(-1));
  assert.match(await text(page, '#tree-count'), new RegExp(`^${seen.at(-1)} parts `));
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
