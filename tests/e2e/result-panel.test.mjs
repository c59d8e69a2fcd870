// The result's figures say what they are: E_RMS per coordinate, as the rig's (a small one in significant digits,
// not "0.000"); the Log-likelihood in nats, and the shown model's final value on every example tried; the
// variance floor in unit-box units²; the pose space's directions with their spread.
// Run: npm run build && node --test tests/e2e/result-panel.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, summary, text, frames, openFitted, setMode } from './helpers.mjs';

const session = pageSession();

// The Log-likelihood field's number: nats, its thousands apart (views/result.js natsText)
const natsValue = (t) => {
  const m = t.match(/^(−?)([\d\u202f]+\.\d{2}) nats$/);
  assert.ok(m, `"${t}" is a log-likelihood in nats`);
  return Number(`${m[1] ? '-' : ''}${m[2].replace(/\u202f/g, '')}`);
};

const fitted = (path, opts) => openFitted(session, path, opts);

test('E_RMS: per coordinate, as the rig\'s; a small one in significant digits, not "0.000"', async () => {
  const { page, context, log } = await session.open('#ex=arm');
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  await frames(page);
  const s = await summary(page);
  // the arm's rigid parts are exact but for float rounding: far below a thousandth of the diagonal
  assert.ok(s.eRms > 0 && s.eRms < 0.01, String(s.eRms));
  const rmse = await text(page, '#rmse');
  assert.ok(rmse.endsWith(`; E_RMS ${s.eRms.toPrecision(2)} (the rig's measure: RMS error per coordinate, in thousandths of the bounding-box diagonal)`), rmse);
  assert.doesNotMatch(rmse, /E_RMS 0\.000 /);
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
  await setMode(page, 'pose');
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
