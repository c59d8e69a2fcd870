// The rig panel's fields and captions: a bad Influences value is refused at the
// field, in view, saying what is allowed (1 to 8) in words a person reads (no parser's), an empty field is
// "empty"; no file is made and the E_RMS line does not stay "…". Rigid weights say one bone per vertex (not "4
// influences"), and the caption lists the file's clips (the rigid rig's extra "interpolated" clip is named).
// Run: npm run build && node --test tests/e2e/rig-panel.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState } from './helpers.mjs';

const session = pageSession();
const problem = '[data-testid=rig-influences-problem]';

// Presses the glTF button; returns the download (null when none came within `ms`).
async function pressGltf(page, ms = 1500) {
  const download = page.waitForEvent('download', { timeout: ms }).catch(() => null);
  await page.click('#export-gltf');
  return download;
}

for (const [width, height] of [[1280, 800], [390, 844]]) {
  test(`a bad Influences value is refused at the field, in view, with what is allowed (${width}x${height})`, async () => {
    const { page, context, log } = await session.open('', { width, height });
    assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
    for (const [typed, says] of [['0', /^Influences '0' is less than 1: it must be a whole number from 1 to 8/], ['99', /^Influences '99' is more than 8: it must be a whole number from 1 to 8/], ['-3', /^Influences '-3' is less than 1: it must be a whole number from 1 to 8/], ['', /^Influences is empty: it must be a whole number from 1 to 8/], ['2.5', /not a whole number/]]) {
      await page.fill('#rig [name=influences]', typed);
      const file = await pressGltf(page);
      assert.equal(file, null, `no file for Influences "${typed}"`);
      const box = page.locator(problem);
      await box.waitFor({ state: 'visible', timeout: 5000 });
      const text = await box.innerText();
      assert.match(text, says, `Influences "${typed}"`);
      assert.doesNotMatch(text, /usize|column|= 0/, `no parser's words: ${text}`);
      assert.ok(await box.isVisible());
      // in view: the message's box lies inside the window
      const r = await box.boundingBox();
      assert.ok(r && r.y >= 0 && r.y + r.height <= height, `the message is in view: ${JSON.stringify(r)} of ${height}`);
      assert.equal(await page.locator('#rig [name=influences]').getAttribute('aria-invalid'), 'true');
      assert.doesNotMatch(await page.locator('[data-testid=rig-erms]').innerText(), /…/, 'the E_RMS line does not say it is working');
    }
    // fixed: the message goes, and the file comes with the count asked for in its caption
    await page.fill('#rig [name=influences]', '2');
    await page.locator(problem).waitFor({ state: 'hidden', timeout: 5000 });
    const file = await pressGltf(page, 60000);
    assert.ok(file, 'a file for Influences 2');
    await page.waitForFunction(() => document.querySelector('[data-testid=rig-erms]').dataset.erms);
    assert.match(await page.locator('[data-testid=rig-erms]').innerText(), /at most 2 bones per vertex/);
    assert.deepEqual(log.errors, []);
    await context.close();
  });
}

test('rigid weights say one bone per vertex; the caption names the file\'s clips', async () => {
  const { page, context, log } = await session.open();
  assert.equal(await waitState(page, ['fitted', 'error'], 120000), 'fitted');
  const erms = page.locator('[data-testid=rig-erms]');
  await page.selectOption('#rig [name=weights]', 'rigid');
  assert.equal(await page.locator('#rig [name=influences]').isDisabled(), true, 'Influences does not apply to rigid weights');
  assert.match(await page.locator('[data-testid=rig-weights-note]').innerText(), /one bone/);
  assert.ok(await pressGltf(page, 60000));
  await page.waitForFunction(() => document.querySelector('[data-testid=rig-erms]').dataset.erms);
  const rigid = await erms.innerText();
  assert.match(rigid, /\d+ bones, one bone per vertex \(rigid\)/);
  assert.doesNotMatch(rigid, /influences/);
  // the file's clips, as the core lists them: rigid weights with free joints add the fit's own interpolation
  assert.deepEqual((await erms.getAttribute('data-clips')).split('|'), ['training poses', 'interpolated']);
  assert.match(rigid, /2 clips: “training poses”, one key per pose; “interpolated”, the fit's own part-wise interpolation/);
  await page.selectOption('#rig [name=weights]', 'fitted');
  assert.ok(await pressGltf(page, 60000));
  await page.waitForFunction(() => document.querySelector('[data-testid=rig-erms]').dataset.erms);
  assert.equal(await erms.getAttribute('data-clips'), 'training poses');
  assert.match(await erms.innerText(), /at most 4 bones per vertex; .*1 clip: “training poses”/);
  assert.deepEqual(log.errors, []);
  await context.close();
});
