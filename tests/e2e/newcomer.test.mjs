// A newcomer's review of the built page (docs/page-fixes.md, "A third review"): what each control says it does.
// The part-rule chart's axis and line, the Initial parts / Seed note, the teaching panel's Algorithm 1 sentence,
// what "Measure at this t" measures against, pose mode's caption after Random pose and its Part list, the
// result of an example that fails on purpose, and the rig box inside the panel. (Step and Run asking before they
// drop a finished fit: teach.test.mjs.)
// Run: npm run build && node --test tests/e2e/newcomer.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { pageSession, waitState, ROOT } from './helpers.mjs';
import { decade } from '../../www/views/part-curve.js';

const session = pageSession();
const core = () => createRequire(import.meta.url)(join(ROOT, 'pkg-node', 'posemfa.js'));
const summary = (page) => page.evaluate(() => window.posemfa.summary());
const text = (page, sel) => page.locator(sel).innerText();

async function fitted(path = '', opts) {
  const p = await session.open(path, opts);
  const state = await waitState(p.page, ['fitted', 'error'], 90000);
  assert.equal(state, 'fitted', await text(p.page, '[data-testid=errors]'));
  return p;
}

async function mode(page, m) {
  await page.check(`#modes input[value=${m}]`, { force: true });
  await page.waitForFunction((x) => window.posemfa.mode() === x, m);
}

// Clicks a preset and waits for its fit.
async function preset(page, id) {
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click(`[data-testid=presets] button[data-id=${id}]`);
  await page.waitForFunction((c) => window.posemfa.fitCount() > c && document.body.dataset.state === 'fitted', n, { timeout: 90000, polling: 20 });
}

test('powers of ten are written as numbers', () => {
  assert.deepEqual([0, 1, 2, 4].map(decade), ['1', '10', '100', '10000']);
  assert.deepEqual([-1, -3].map(decade), ['0.1', '0.001']);
  assert.deepEqual([5, 12, -4, -10].map(decade), ['10⁵', '10¹²', '10⁻⁴', '10⁻¹⁰']);
});

test('the panel says what is used: the part-rule chart, Initial parts and Seed, the teaching mode, the rig box', async () => {
  const { page, context, log } = await fitted();
  const s = await summary(page);
  // the part-rule chart: its axis in whole decades written as numbers, the distinct ratio drawn, and its one
  // decision said in words
  const chart = await page.$eval('#part-curve', (c) => ({ ...c.dataset }));
  assert.equal(Number(chart.points), s.partCurve.filter((p) => p.score > 0).length);
  assert.equal(chart.ratio, String(core().defaultParams().distinctRatio), 'the line: the distinct ratio the fit used');
  for (const k of ['axisLo', 'axisHi']) assert.match(chart[k], /^(\d+(\.\d+)?|10[⁻¹²³⁴⁵⁶⁷⁸⁹⁰]+)$/, `${k}: ${chart[k]}`);
  const top = s.partCurve.map((p) => p.score).concat(Number(chart.ratio));
  assert.equal(chart.axisHi, decade(Math.ceil(Math.log10(Math.max(...top)))));
  assert.equal(chart.axisLo, decade(Math.floor(Math.log10(Math.min(...top)))));
  if (s.partCurve.length === 1) assert.match(chart.note, /^one decision, (above the line: not merged|below the line: merged)$/);
  else assert.equal(chart.note, '');
  assert.equal(chart.clipped, '0');

  // Initial parts and Seed: greyed with a note while Fit (the merge tree) ignores them, not with the refinement off
  const startUse = () => page.evaluate(() => ({
    note: !document.getElementById('parts-note').hidden && document.getElementById('parts-note').getBoundingClientRect().height > 0,
    ignored: ['parts', 'seed'].map((n) => document.querySelector(`#params [name=${n}]`).closest('label').classList.contains('ignored')),
    editable: ['parts', 'seed'].every((n) => !document.querySelector(`#params [name=${n}]`).disabled),
  }));
  assert.deepEqual(await startUse(), { note: true, ignored: [true, true], editable: true });
  assert.match(await text(page, '[data-testid=parts-note]'), /^Fit ignores Initial parts and Seed: .*merge tree.* Step by step \(Algorithm 1\) uses them/);
  await page.uncheck('#params [name=refine]');
  assert.deepEqual(await startUse(), { note: false, ignored: [false, false], editable: true });
  await page.check('#params [name=refine]');
  assert.deepEqual(await startUse(), { note: true, ignored: [true, true], editable: true });

  // the teaching panel says why its count can differ from Fit's
  assert.ok(await page.locator('[data-testid=teach-about]').isVisible());
  assert.match(await text(page, '[data-testid=teach-about]'), /Algorithm 1 \(random k-means\+\+ splits\), so its part count can differ from Fit's, .*deterministic merge tree/);

  // the rig box lies inside the panel, its right edge not cut off
  const fits = () => page.evaluate(() => {
    const panel = document.getElementById('panel');
    const p = panel.getBoundingClientRect();
    const inner = p.left + panel.clientLeft + panel.clientWidth - parseFloat(getComputedStyle(panel).paddingRight);
    return { right: document.getElementById('rig').getBoundingClientRect().right, inner, scroll: panel.scrollWidth - panel.clientWidth };
  });
  const r = await fits();
  assert.ok(r.right <= r.inner + 0.5 && r.scroll <= 0, JSON.stringify(r));
  assert.deepEqual(log.errors, []);
  await context.close();

  const phone = await fitted('', { width: 390, height: 844 });
  const rp = await phone.page.evaluate(() => {
    const rig = document.getElementById('rig').getBoundingClientRect();
    return { right: rig.right, width: document.documentElement.clientWidth };
  });
  assert.ok(rp.right <= rp.width, JSON.stringify(rp));
  await phone.context.close();
});

test('"Measure at this t" says what each error is measured against', async () => {
  const { page, context, log } = await fitted('#ex=arm');
  await mode(page, 'interp');
  await page.click('#measure');
  await page.waitForFunction(() => document.querySelector('#report table'));
  const table = await page.$$eval('#report tr', (rows) => rows.map((r) => [...r.children].map((c) => c.textContent)));
  assert.equal(table[0].at(-1), 'error measured against');
  const against = Object.fromEntries(table.slice(1).map((r) => [r[0], r.at(-1)]));
  assert.equal(against['rigid, residual off'], 'rigid reconstruction (eq 22)');
  assert.equal(against['rigid (default: anchor root, exact ends, residual)'], 'training poses');
  assert.equal(against['linear vertex interpolation'], 'training poses');
  // every row with the residual off, and only those, is measured against the reconstruction
  for (const [name, a] of Object.entries(against)) assert.equal(a === 'rigid reconstruction (eq 22)', /residual off/.test(name), name);
  const key = await text(page, '#report .report-key');
  assert.match(key, /^Edge stretch: every edge's length at t against .* two training poses\. Error at t=0 \/ t=1: .* rigid reconstruction \(eq 22\)/);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('"Measure at this t": a line says how to read the stretch; the report scrolls in its own box, the poses stay in the window (1280x800, 390 wide)', async () => {
  for (const [width, height] of [[1280, 800], [390, 844]]) {
    const { page, context, log } = await fitted('', { width, height });
    await mode(page, 'interp');
    await page.click('#measure');
    await page.waitForFunction(() => document.querySelector('#report table'));
    const reading = await text(page, '[data-testid=report-reading]');
    assert.match(reading, /^Reading the stretch: 0 % is every edge at exactly its mixed length, which is what a rigid motion gives inside a part that is rigid in the training poses\. Large figures on the edges crossing a part boundary .* where rigid parts pull apart or overlap at a joint, with no skinning/);
    const at = await page.evaluate(() => {
      const box = (id) => document.querySelector(id).getBoundingClientRect();
      const table = document.querySelector('#report .report-table');
      return {
        strip: box('#pose-strip'), view: box('#view-wrap'), report: box('#report'), page: document.documentElement.scrollWidth,
        inner: [innerWidth, innerHeight], across: [table.scrollWidth, table.clientWidth, getComputedStyle(table).overflowX],
      };
    });
    assert.ok(at.page <= width, `the page is ${at.page} px wide at ${width}`);
    assert.ok(at.report.right <= width + 0.5, `the report ends at ${at.report.right} px`);
    // what does not fit across scrolls in the table's own box
    if (at.across[0] > at.across[1]) assert.equal(at.across[2], 'auto', JSON.stringify(at.across));
    if (width === 1280) {
      // the page is the window's height: the view and the pose strip stay in it
      assert.ok(at.strip.bottom <= height + 0.5, `the pose strip ends at ${at.strip.bottom} px of ${height}`);
      assert.ok(at.view.height >= 200, `the view is ${at.view.height} px high`);
    }
    assert.deepEqual(log.errors, []);
    await context.close();
  }
});

test('the example picker shows every example\'s title in full (1280 wide), and on a phone stays inside the window', async () => {
  for (const width of [1280, 390]) {
    const { page, context, log } = await fitted('', { width, height: 800 });
    const m = await page.evaluate(() => {
      const sel = document.getElementById('example');
      const g = document.createElement('canvas').getContext('2d');
      const cs = getComputedStyle(sel);
      g.font = `${cs.fontWeight} ${cs.fontSize} ${cs.fontFamily}`;
      const titles = [...sel.options].filter((o) => !o.hidden).map((o) => o.textContent);
      const widest = Math.max(...titles.map((t) => g.measureText(t).width));
      const r = sel.getBoundingClientRect();
      return { titles: titles.length, widest, inner: sel.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight), right: r.right, page: document.documentElement.scrollWidth, title: sel.title, shown: sel.selectedOptions[0].textContent };
    });
    assert.ok(m.titles >= 5, JSON.stringify(m));
    if (width === 1280) assert.ok(m.inner >= m.widest, `the picker's text box is ${m.inner} px for a title of ${m.widest} px`);
    assert.ok(m.right <= width + 0.5 && m.page <= width, JSON.stringify(m));
    assert.equal(m.title, m.shown, 'the whole title on hover');
    assert.deepEqual(log.errors, []);
    await context.close();
  }
});

test('figures say their units: the Log-likelihood in nats, the variance floor in unit-box units², the pose space\'s directions and spread', async () => {
  const { page, context, log } = await fitted();
  assert.match(await text(page, '#loglik'), /^−?\d{1,3}(\u202f\d{3})*\.\d{2} nats$/);
  const floor = await page.$eval('#params [name=varianceFloor]', (e) => e.closest('label').firstChild.textContent.trim());
  assert.equal(floor, 'Variance floor (unit-box units²)');
  // a refused floor is named by its label, with the same unit the core says
  await page.fill('#params [name=varianceFloor]', '-1');
  await page.click('#fit');
  await page.waitForFunction(() => document.querySelector('[data-testid=param-errors] li[data-field=varianceFloor]'));
  assert.match(await text(page, '[data-testid=param-errors] li[data-field=varianceFloor]'), /^Variance floor \(unit-box units²\): .*unit-box units²/);
  await page.click('#reset-params');
  await mode(page, 'pose');
  await page.waitForFunction(() => window.posemfa.pose.ready(), null, { timeout: 60000 });
  await page.waitForFunction(() => document.querySelectorAll('#pose-modes label').length > 0);
  const labels = await page.$$eval('#pose-modes label', (l) => l.map((x) => x.textContent.trim()));
  labels.forEach((l, m) => assert.match(l, new RegExp(`^direction ${m + 1} \\(±\\d+\\.\\d°\\)$`), l));
  assert.match(await text(page, '[data-testid=pose-status]'), /^\d+ bones, \d+ pose-space directions?: the main directions of the training poses' joint rotations \(0: their mean pose; ±: their spread, one standard deviation\)(; sliders for the 6 largest)?$/);
  const titles = await page.$$eval('#pose-modes label', (l) => l.map((x) => x.title));
  titles.forEach((t, m) => assert.match(t, new RegExp(`^pose-space direction ${m + 1}: the training poses spread ±\\d+\\.\\d° along it`), t));
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('pose mode: after Random pose the caption describes the whole pose until a part is turned; the Part list is in number order', async () => {
  const { page, context, log } = await fitted(); // the quadruped: 18 bones, whose parent-first order is not by number
  await mode(page, 'pose');
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

test('an example that fails on purpose leads its result with what failed in this fit; others do not', async () => {
  const { page, context, log } = await fitted();
  assert.equal(await page.locator('[data-testid=fail-lead]').isVisible(), false, 'the quadruped did not fail');
  assert.equal(await page.locator('[data-testid=limit-lead]').isVisible(), false, 'the quadruped ties no parts');
  assert.match(await text(page, '[data-testid=truth-acc]'), /\(18 true parts\)$/);

  await preset(page, 'blob');
  assert.ok(await page.locator('[data-testid=fail-lead].fails').isVisible());
  assert.match(await text(page, '[data-testid=fail-lead]'), /^Failed, as this example means to\. The shape is not articulated: rigid parts explain only \d+\.\d % of its motion \(the verdict below\)\.$/);
  assert.match(await text(page, '[data-testid=truth-acc]'), /^one true part, so no adjusted Rand index \(every labelling scores 0 against one part\); rotation error \d+\.\d\d° against each pose's best rigid fit$/);

  await preset(page, 'literal-eq18');
  let s = await summary(page);
  const drops = (ll) => ll.filter((v, i) => i > 0 && v < ll[i - 1]).length;
  assert.equal(s.converged, false);
  const lead = await text(page, '[data-testid=fail-lead]');
  assert.ok(await page.locator('[data-testid=fail-lead].fails').isVisible());
  assert.ok(lead.startsWith(`Failed, as this example means to. AECM did not converge (it stopped at the iteration cap after ${s.iterations} iterations); `
    + `the log-likelihood fell ${drops(s.logLikelihood)} times in the final stage's ${s.logLikelihood.length} iterations`), lead);
  assert.ok(drops(s.logLikelihood) > 0);
  // the lead comes first in the result, before the part count
  const order = await page.evaluate(() => {
    const lead = document.getElementById('fail-lead');
    return lead.compareDocumentPosition(document.getElementById('parts-count')) & Node.DOCUMENT_POSITION_FOLLOWING;
  });
  assert.ok(order);

  // the same example with the exact Λ step: what the lead says follows this fit, not the example's name
  await page.uncheck('#params [name=paperLambda]');
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction((c) => window.posemfa.fitCount() > c && document.body.dataset.state === 'fitted', n, { timeout: 90000, polling: 20 });
  s = await summary(page);
  assert.equal(drops(s.logLikelihood), 0, 'the exact step never lowers the log-likelihood');
  const after = await text(page, '[data-testid=fail-lead]');
  assert.doesNotMatch(after, /fell \d+ times/);
  if (s.converged) {
    assert.match(after, new RegExp(`^This example is meant to fail, but this fit did not: it converged in ${s.iterations} iterations`));
    assert.equal(await page.locator('[data-testid=fail-lead].fails').count(), 0);
  } else {
    assert.match(after, /^Failed, as this example means to\. AECM did not converge/);
  }
  assert.deepEqual(log.errors, []);
  await context.close();
});
