// The fit panel's fields: what is used (Initial parts and Seed greyed while Fit ignores them, the part-rule chart,
// the teaching mode, the rig box inside the panel); bad values named and outlined with what they allow, no fit,
// cleared when fixed or by Defaults; "Parts in the end" refused past what the population holds; the Fit button
// says the count later fits keep, and the parts line says both the coarse count and the count asked for.
// Run: npm run build && node --test tests/e2e/panel.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { join } from 'node:path';
import { pageSession, waitState, afterNextFit, ROOT, summary, text, frames, openFitted } from './helpers.mjs';
import { decade } from '../../www/views/part-curve.js';

const session = pageSession();
const core = () => createRequire(import.meta.url)(join(ROOT, 'pkg-node', 'posemfa.js'));

const fitted = (path, opts) => openFitted(session, path, opts);

// The one line of the form's problems about `field`, once it is there.
async function fieldLine(page, field) {
  await page.waitForFunction((f) => document.querySelector(`[data-testid=param-errors] li[data-field=${f}]`), field, { timeout: 10000 });
  return page.locator(`[data-testid=param-errors] li[data-field=${field}]`).innerText();
}

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
