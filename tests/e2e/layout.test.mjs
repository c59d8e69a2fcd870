// The layout: at 1280x800 nothing below the window and the running fit's progress in view; pose mode's slider
// labels one line each; on a phone (390x844) no label or button text cut, no control broken off its label and
// nothing wider than the window, in every view.
// Run: npm run build && node --test tests/e2e/layout.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession, waitState, text, frames, openFitted, setMode } from './helpers.mjs';

const session = pageSession();

const fitted = (path, opts) => openFitted(session, path, opts);

// Whether an element lies fully inside the window (not cut by its bottom or right edge, nor scrolled away).
const inWindow = (page, sel) => page.$eval(sel, (e) => {
  const r = e.getBoundingClientRect();
  return r.width > 0 && r.top >= 0 && r.left >= 0 && r.bottom <= innerHeight + 0.5 && r.right <= innerWidth + 0.5;
});

// How many lines the element's own text takes (its text nodes' line boxes), and its height against one line.
const lines = (page, sel) => page.$$eval(sel, (els) => els.map((e) => {
  const tops = new Set();
  for (const n of e.childNodes) {
    if (n.nodeType !== Node.TEXT_NODE || !n.textContent.trim()) continue;
    const r = document.createRange();
    r.selectNodeContents(n);
    for (const q of r.getClientRects()) if (q.width > 0) tops.add(Math.round(q.top));
  }
  const lh = parseFloat(getComputedStyle(e).fontSize) * 1.6;
  return { text: e.textContent.trim(), lines: tops.size, height: e.getBoundingClientRect().height, oneLine: lh };
}));

// Visible labels, buttons and selects whose text is cut (wider than their box) or that leave the window sideways,
// and labels whose control is broken off onto another line than their name.
const cutOff = (page) => page.evaluate(() => {
  const out = [];
  for (const e of document.querySelectorAll('label, button, .button, select, summary, h1, h2, legend, dt, dd')) {
    const r = e.getBoundingClientRect();
    if (r.width === 0 || r.height === 0 || getComputedStyle(e).visibility === 'hidden' || e.closest('.visually-hidden')) continue;
    const cut = e.clientWidth > 0 && e.scrollWidth > e.clientWidth + 1;
    // inside a box that scrolls sideways (the thumbnail strip) it is reached by scrolling, not cut
    let scrolls = false;
    for (let a = e.parentElement; a && a !== document.body; a = a.parentElement) scrolls ||= ['auto', 'scroll'].includes(getComputedStyle(a).overflowX);
    const out_ = !scrolls && (r.left < -0.5 || r.right > innerWidth + 0.5);
    // a label's control on the line of its name (not broken off onto the next line)
    let apart = false;
    const ctl = e.tagName === 'LABEL' && e.querySelector('select, input:not([type=checkbox]):not([type=radio]):not([type=hidden])');
    const name = ctl && [...e.childNodes].find((n) => n.nodeType === Node.TEXT_NODE && n.textContent.trim());
    if (ctl && name && ctl.getBoundingClientRect().width > 0) {
      const rg = document.createRange();
      rg.selectNodeContents(name);
      const t = [...rg.getClientRects()].filter((q) => q.width > 0);
      const c = ctl.getBoundingClientRect();
      const line = t[t.length - 1];
      apart = !!line && !(c.top < line.bottom && c.bottom > line.top);
    }
    if (apart) out.push(`label "${e.textContent.trim().slice(0, 40)}": its control is on another line than its name`);
    if (cut || out_) out.push(`${e.tagName.toLowerCase()}${e.id ? `#${e.id}` : ''} "${e.textContent.trim().slice(0, 40)}": ${cut ? `text ${e.scrollWidth} px in ${e.clientWidth} px` : `from ${r.left.toFixed(0)} to ${r.right.toFixed(0)} px`}`);
  }
  return out;
});

test('layout at 1280x800: nothing below the window, the running fit\'s progress in view; at 390x844 every label whole', async () => {
  const { page, context, log } = await fitted();
  assert.ok(await page.evaluate(() => document.documentElement.scrollHeight <= innerHeight), `page height ${await page.evaluate(() => document.documentElement.scrollHeight)}`);
  for (const sel of ['#pose-strip', '#view-wrap']) assert.ok(await inWindow(page, sel), `${sel} is cut off`);
  const thumbs = await page.$$eval('#pose-strip button', (bs) => bs.map((b) => b.getBoundingClientRect().bottom));
  assert.ok(thumbs.every((y) => y <= 800), `thumbnail bottoms ${thumbs}`);
  // a fit running: its Stage, Iteration and plot are in view
  const n = await page.evaluate(() => window.posemfa.fitCount());
  await page.click('#fit');
  await page.waitForFunction(() => document.body.dataset.state === 'fitting');
  for (const sel of ['#stage', '#iteration', '#plot']) assert.ok(await inWindow(page, sel), `${sel} is out of view while the fit runs`);
  await page.waitForFunction((c) => window.posemfa.fitCount() > c, n, { timeout: 90000 });
  // the part-rule chart: its text inside its canvas (the chart says where it drew its labels)
  const clipped = await page.$eval('#part-curve', (c) => c.dataset.clipped);
  assert.equal(clipped, '0', 'the part-rule chart clipped a label');
  await context.close();

  // a phone: no text cut mid-line in the app's panel, nor in the eq 18 figure's view labels
  const phone = await fitted('', { width: 390, height: 844 });
  const wide = await phone.page.evaluate(() => document.documentElement.scrollWidth);
  assert.ok(wide <= 390, `the page is ${wide} px wide`);
  phone.context.close();
  const art = await session.open('explain.html', { width: 390, height: 844 });
  await art.page.locator('[data-figure=eq18]').scrollIntoViewIfNeeded();
  await art.page.waitForFunction(() => document.querySelectorAll('[data-figure=eq18] .posemfa-caption').length === 2, null, { timeout: 30000 });
  await art.page.waitForFunction(() => document.querySelector('[data-figure=eq18]').dataset.state !== 'loading', null, { timeout: 60000 });
  // each label lies inside its view box (which hides what overflows it)
  const cut = await art.page.$$eval('[data-figure=eq18] .posemfa-caption', (els) => els.filter((e) => {
    const r = e.getBoundingClientRect();
    const box = e.closest('.fig-view').getBoundingClientRect();
    return r.bottom > box.bottom + 0.5 || r.right > box.right + 0.5 || e.scrollWidth > e.clientWidth + 1;
  }).map((e) => e.textContent));
  assert.deepEqual(cut, [], 'eq 18 view labels cut');
  assert.deepEqual([...log.errors, ...art.log.errors], []);
  await art.context.close();
});

test('pose mode at 1280x800: every pose-space slider\'s label is one line, its slider beside it', async () => {
  const { page, context, log } = await fitted();
  await setMode(page, 'pose');
  await page.waitForFunction(() => window.posemfa.pose?.ready(), null, { timeout: 120000, polling: 50 });
  await page.waitForFunction(() => document.querySelectorAll('#pose-modes label').length > 0);
  const labels = await lines(page, '#pose-modes label');
  assert.ok(labels.length >= 1);
  // the status counts the modes and, when there are more than sliders, says which ones have one
  const status = await text(page, '[data-testid=pose-status]');
  const [, modes] = status.match(/^\d+ bones, (\d+) pose-space directions?/) ?? [];
  assert.ok(modes, status);
  assert.equal(labels.length, Math.min(Number(modes), 6), status);
  if (Number(modes) > 6) assert.match(status, /; sliders for the 6 largest$/);
  for (const l of labels) {
    assert.equal(l.lines, 1, `"${l.text}" takes ${l.lines} lines`);
    assert.ok(l.height <= l.oneLine * 1.3, `"${l.text}" is ${l.height} px high (one line: ${l.oneLine} px)`);
  }
  // the slider on the label's line
  const beside = await page.$$eval('#pose-modes label', (els) => els.map((e) => {
    const a = e.getBoundingClientRect();
    const b = e.querySelector('input').getBoundingClientRect();
    return b.top >= a.top - 0.5 && b.bottom <= a.bottom + 0.5 && b.left > a.left;
  }));
  assert.ok(beside.every(Boolean), JSON.stringify(beside));
  for (const l of await lines(page, '#pose-panel > label, #pose-panel > button')) assert.equal(l.lines, 1, `"${l.text}" takes ${l.lines} lines`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('a phone (390x844): no label or button text cut, no control broken off its label, nothing wider than the window, in every view', async () => {
  const { page, context, log } = await fitted('', { width: 390, height: 844 });
  const width = () => page.evaluate(() => document.documentElement.scrollWidth);
  assert.ok(await width() <= 390, `the page is ${await width()} px wide`);
  assert.deepEqual(await cutOff(page), [], 'parts view');
  for (const m of ['interp', 'latent', 'pose']) {
    await setMode(page, m);
    if (m === 'pose') await page.waitForFunction(() => window.posemfa.pose?.ready(), null, { timeout: 120000, polling: 50 });
    await frames(page);
    assert.ok(await width() <= 390, `${m}: the page is ${await width()} px wide`);
    assert.deepEqual(await cutOff(page), [], `${m} view`);
  }
  assert.deepEqual(log.errors, []);
  await context.close();
});
