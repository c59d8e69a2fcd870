// The article on the built page (dist/explain.html): the explorable explanation. Its test contract: every figure
// element has data-figure and data-state; window.explain.figures() gives [{name, state, logLikelihood}] and, for
// the eq 18 figure, {name, state, literal, exact}. Also what the figures' captions say (the model figure's part
// and scale, the responsibilities' iteration) and the sticky header's opaque background.
// Run: npm run build && node --test tests/e2e/explain.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession } from './helpers.mjs';

const session = pageSession();
const figures = (page) => page.evaluate(() => window.explain.figures());
const ready = (f) => f.state === 'fitted' || f.state === 'stepping';

// Iterations where a trace fell by more than rounding (the same rule as the figure's red dots).
function drops(values) {
  const out = [];
  for (let i = 1; i < values.length; i++) if (values[i - 1] - values[i] > 1e-9 * Math.max(1, Math.abs(values[i]))) out.push(i);
  return out;
}

// One load of the article: waits until every figure is fitted (or stepping), without scrolling (figures out of
// view are fitted in the background, in the article's order), checks the contract, and returns the page's own
// clock (performance.now(), from the start of the navigation) at each figure's first fitted state.
async function loadOnce() {
  const { page, context, log } = await session.open('explain.html');
  try {
    const names = await page.evaluate(() => [...document.querySelectorAll('[data-figure]')].map((e) => e.dataset.figure));
    assert.ok(names.length >= 9, `expected a figure per section, found ${names.join(', ')}`);
    for (const n of names) assert.match(await page.getAttribute(`[data-figure=${n}]`, 'data-state'), /^(loading|fitting|fitted|stepping|error)$/);
    await page.waitForFunction(() => {
      const f = window.explain?.figures() ?? [];
      return f.length && f.every((x) => x.state === 'fitted' || x.state === 'stepping' || x.state === 'error');
    }, null, { timeout: 20000, polling: 50 });
    const figs = await figures(page);
    assert.deepEqual(figs.filter((f) => !ready(f)).map((f) => `${f.name}: ${f.state}`), []);
    assert.deepEqual(figs.map((f) => f.name), names);
    for (const f of figs) {
      if (f.name === 'eq18') continue;
      assert.ok(Array.isArray(f.logLikelihood) && f.logLikelihood.length > 0, `${f.name}: no log-likelihood trace`);
      assert.ok(f.logLikelihood.every(Number.isFinite), `${f.name}: non-finite log-likelihood`);
    }
    const times = await page.evaluate(() => window.explain.readyTimes());
    const pool = await page.evaluate(() => window.explain.pool());
    // KaTeX typeset every equation (no raw TeX left), with its bundled fonts.
    await page.waitForFunction(() => document.body.dataset.typeset === 'done', null, { timeout: 10000 });
    assert.equal(await page.locator('.tex .katex, .tex-block .katex').count(), await page.locator('.tex, .tex-block').count());
    assert.ok(await page.evaluate(() => document.fonts.ready.then(() => document.fonts.check('16px KaTeX_Main'))), 'KaTeX_Main font not loaded');
    assert.deepEqual(log.errors, []);
    assert.deepEqual(log.external, []);
    return { first: times[names[0]], last: Math.max(...Object.values(times)), times, pool };
  } finally {
    await context.close();
  }
}

test('the article opens with no console errors and no external requests; every figure is fitted within 10 s, the first within 2 s', async () => {
  // The machine is shared and its speed drifts (shared/TOOLCHAIN.md): other processes only ever slow a load
  // down, so up to three loads are made and the test passes when one of them meets both budgets. Every load
  // must pass the contract checks.
  const runs = [];
  for (let k = 0; k < 3; k++) {
    const r = await loadOnce();
    runs.push(r);
    console.log(`# explain.html load ${k + 1}: first figure fitted at ${Math.round(r.first)} ms, all at ${Math.round(r.last)} ms; pool ${JSON.stringify(r.pool)}`);
    if (r.first <= 2000 && r.last <= 10000) break;
  }
  const best = runs.find((r) => r.first <= 2000 && r.last <= 10000);
  assert.ok(best, `no load met the budgets (first <= 2000 ms, all <= 10000 ms): ${runs.map((r) => `${Math.round(r.first)} / ${Math.round(r.last)}`).join(', ')}`);
});

test('eq 18 figure: the literal step lowers the log-likelihood at least once, the exact step never, from the same start', async () => {
  const { page, context, log } = await session.open('explain.html');
  try {
    await page.waitForFunction(() => window.explain?.figures().find((f) => f.name === 'eq18')?.state === 'fitted', null, { timeout: 15000, polling: 50 });
    const check = async (when) => {
      const eq = (await figures(page)).find((f) => f.name === 'eq18');
      assert.ok(eq.literal.length > 1 && eq.exact.length > 1, `${when}: traces ${eq.literal.length} / ${eq.exact.length}`);
      assert.ok(drops(eq.literal).length >= 1, `${when}: the literal trace never fell: ${eq.literal}`);
      assert.deepEqual(drops(eq.exact), [], `${when}: the exact trace fell`);
      // the same start: the first iteration's cycle 1 and E-step do not depend on the Λ rule, the first CM of
      // cycle 2 does; both traces start within the same order of magnitude and then part ways
      return eq;
    };
    const bg = await check('background fit');
    // Scrolled into view, it runs both fits again live, step by step; the figure's own data says what happened.
    await page.locator('[data-figure=eq18]').scrollIntoViewIfNeeded();
    await page.waitForFunction(() => window.explain.figures().find((f) => f.name === 'eq18').state === 'stepping', null, { timeout: 5000, polling: 50 });
    await page.waitForFunction(() => {
      const f = window.explain.figures().find((x) => x.name === 'eq18');
      return f.state === 'fitted' && f.literal.length > 1;
    }, null, { timeout: 30000, polling: 100 });
    const live = await check('live run');
    assert.deepEqual(live.literal, bg.literal, 'the live literal run differs from the background fit of the same start');
    assert.deepEqual(live.exact, bg.exact, 'the live exact run differs from the background fit of the same start');
    const text = await page.locator('[data-figure=eq18] figcaption').innerText();
    assert.match(text, /literal eq 18: \d+ iterations, [1-9]\d* drops?/);
    assert.match(text, /exact: \d+ iterations, 0 drops/);
    assert.deepEqual(log.errors, []);
  } finally {
    await context.close();
  }
});

test('a figure starts when scrolled into view, pauses when scrolled away, resumes, and Reset starts it again', async () => {
  const { page, context, log } = await session.open('explain.html');
  try {
    const detail = () => page.evaluate(() => window.explain.detail('aecm'));
    await page.waitForFunction(() => window.explain?.figures().find((f) => f.name === 'aecm')?.state === 'fitted', null, { timeout: 15000, polling: 50 });
    assert.equal((await detail()).steps, 0, 'the live run started out of view');
    await page.locator('[data-figure=aecm]').scrollIntoViewIfNeeded();
    await page.waitForFunction(() => window.explain.detail('aecm').steps >= 2, null, { timeout: 10000, polling: 50 });
    assert.equal(await page.getAttribute('[data-figure=aecm]', 'data-state'), 'stepping');
    // away: it pauses
    await page.evaluate(() => window.scrollTo(0, 0));
    await page.waitForFunction(() => !window.explain.detail('aecm').visible, null, { timeout: 5000, polling: 50 });
    await page.waitForTimeout(600); // a step in flight may still land
    const paused = (await detail()).steps;
    await page.waitForTimeout(1500);
    assert.equal((await detail()).steps, paused, 'it kept stepping out of view');
    assert.notEqual(await page.getAttribute('[data-figure=aecm]', 'data-state'), 'stepping');
    // back: it resumes where it was
    await page.locator('[data-figure=aecm]').scrollIntoViewIfNeeded();
    await page.waitForFunction((p) => window.explain.detail('aecm').steps > p, paused, { timeout: 10000, polling: 50 });
    // Step runs exactly one iteration
    await page.click('[data-figure=aecm] [data-act=pause]');
    await page.waitForTimeout(700);
    const before = (await detail()).steps;
    await page.click('[data-figure=aecm] [data-act=step]');
    await page.waitForFunction((b) => window.explain.detail('aecm').steps === b + 1, before, { timeout: 5000, polling: 50 });
    await page.waitForTimeout(800);
    assert.equal((await detail()).steps, before + 1, 'Step made more than one iteration');
    // Reset: from iteration 0 again
    await page.click('[data-figure=aecm] [data-act=reset]');
    await page.waitForFunction(() => window.explain.detail('aecm').steps <= 2, null, { timeout: 5000, polling: 50 });
    const ll = (await figures(page)).find((f) => f.name === 'aecm').logLikelihood;
    assert.deepEqual(drops(ll), []);
    // The hierarchy figure replays Algorithm 1 in view: the coarse run, then the refinement of each coarse part.
    await page.locator('[data-figure=hierarchy]').scrollIntoViewIfNeeded();
    await page.waitForFunction(() => /refining coarse part \d+ of \d+ with m_k = \d+/.test(document.querySelector('[data-figure=hierarchy] [data-out=stage]').textContent), null, { timeout: 15000, polling: 50 });
    assert.equal(await page.getAttribute('[data-figure=hierarchy]', 'data-state'), 'stepping');
    assert.deepEqual(log.errors, []);
  } finally {
    await context.close();
  }
});

test('once fitted, every figure\'s status line says something, and never "undefined" or NaN', async () => {
  const { page, context, log } = await session.open('explain.html');
  try {
    const statuses = () => page.evaluate(() => [...document.querySelectorAll('[data-figure]')].map((e) => ({
      name: e.dataset.figure, state: e.dataset.state, status: e.querySelector('.fig-status')?.textContent ?? null,
    })));
    await page.waitForFunction(() => [...document.querySelectorAll('[data-figure]')].every((e) => ['fitted', 'stepping'].includes(e.dataset.state) && e.querySelector('.fig-status').textContent.trim() !== ''), null, { timeout: 20000, polling: 100 })
      .catch(async (e) => {
        throw new Error(`${e.message}: ${JSON.stringify(await statuses())}`);
      });
    const all = await statuses();
    assert.equal(all.length, 12); // 12 with the pose-space figure
    assert.deepEqual(all.filter((f) => /undefined|NaN/.test(f.status)), []);
    assert.deepEqual(log.errors, []);
  } finally {
    await context.close();
  }
});

test('the article is linked from the app and back, keyboard reachable, and readable at phone width', async () => {
  const { page, context, log } = await session.open('');
  try {
    const href = await page.getAttribute('#explain-link', 'href');
    assert.equal(href, './explain.html');
    await page.click('#explain-link');
    await page.waitForURL(/explain\.html$/);
    assert.equal(await page.getAttribute('header.top a[href="./index.html"]', 'href'), './index.html');
    // Tab reaches the figures' controls.
    const reached = new Set();
    for (let i = 0; i < 80; i++) {
      await page.keyboard.press('Tab');
      const f = await page.evaluate(() => document.activeElement?.closest('[data-figure]')?.dataset.figure ?? null);
      if (f) reached.add(f);
    }
    assert.ok(reached.size >= 4, `Tab reached only ${[...reached].join(', ')}`);
    assert.deepEqual(log.errors, []);
  } finally {
    await context.close();
  }
  const phone = await session.open('explain.html', { width: 390, height: 800 });
  try {
    await phone.page.waitForFunction(() => window.explain?.figures().every((f) => f.state === 'fitted' || f.state === 'stepping'), null, { timeout: 20000, polling: 100 });
    // nothing wider than the screen but scrolling equation boxes
    const wide = await phone.page.evaluate(() => document.documentElement.scrollWidth);
    assert.ok(wide <= 390, `the page is ${wide} px wide at a 390 px window`);
    const figs = await phone.page.evaluate(() => [...document.querySelectorAll('[data-figure]')].map((e) => e.getBoundingClientRect().width));
    assert.ok(figs.every((w) => w <= 390 && w >= 300), `figure widths ${figs}`);
    assert.deepEqual(phone.log.errors, []);
    assert.deepEqual(phone.log.external, []);
  } finally {
    await phone.context.close();
  }
});

test('article: the model figure\'s status names the part shown, its bars are on one stated scale; the responsibilities label follows the run', async () => {
  const { page, context, log } = await session.open('explain.html');
  const fig = page.locator('[data-figure=model]');
  await fig.scrollIntoViewIfNeeded();
  await page.waitForFunction(() => document.querySelector('[data-figure=model]').dataset.state === 'fitted' && document.querySelectorAll('[data-figure=model] .bar').length > 0, null, { timeout: 60000 });
  const options = await fig.locator('[data-ctl=part] option').count();
  for (const k of [1, options - 1]) {
    await fig.locator('[data-ctl=part]').selectOption(String(k));
    await page.waitForFunction((p) => document.querySelector('[data-figure=model] .fig-status').textContent.includes(`showing part ${p}.`)
      && document.querySelector('[data-figure=model] .bars-title')?.textContent.includes(`part ${p} `), k + 1, { timeout: 10000 });
    assert.match(await fig.locator('.bars-title').innerText(), /full width = 180°/);
    const bars = await fig.locator('.bar').evaluateAll((els) => els.map((e) => ({
      angle: parseFloat(e.querySelector('.val').textContent), width: parseFloat(e.querySelector('.fill').style.width),
    })));
    for (const b of bars) assert.ok(Math.abs(b.width - (100 * b.angle) / 180) < 0.1, `bar ${JSON.stringify(b)} is not on the 180° scale`);
  }
  // responsibilities: the view's label and the status give the same iteration, after a Reset too
  const resp = page.locator('[data-figure=responsibilities]');
  await resp.scrollIntoViewIfNeeded();
  await page.waitForFunction(() => window.explain.detail('responsibilities').steps >= 2, null, { timeout: 60000 });
  await resp.locator('[data-act=reset]').click();
  await page.waitForFunction(() => window.explain.detail('responsibilities').steps >= 3, null, { timeout: 60000 });
  await resp.locator('[data-act=pause]').click();
  await page.waitForTimeout(800);
  const label = await resp.locator('.posemfa-caption').innerText();
  const status = await resp.locator('.fig-status').innerText();
  const it = (await page.evaluate(() => window.explain.detail('responsibilities'))).iteration;
  assert.match(status, new RegExp(`Iteration ${it}\\b`));
  assert.match(label, new RegExp(`^Iteration ${it}\\b`), `label "${label}" beside status "${status}"`);
  assert.deepEqual(log.errors, []);
  await context.close();
});

test('article: the sticky header is opaque, so the text scrolling under it does not show through', async () => {
  const { page, context, log } = await session.open('explain.html');
  await page.evaluate(() => window.scrollTo(0, 1500));
  await page.waitForFunction(() => window.scrollY > 1000);
  const h = await page.$eval('header.top', (e) => {
    const r = e.getBoundingClientRect();
    return { top: r.top, bottom: r.bottom, background: getComputedStyle(e).backgroundColor };
  });
  assert.equal(h.top, 0, 'the header stays at the top');
  const m = h.background.match(/^rgba?\(([\d.]+),\s*([\d.]+),\s*([\d.]+)(?:,\s*([\d.]+))?\)$/);
  assert.ok(m, h.background);
  assert.equal(m[4] === undefined ? 1 : Number(m[4]), 1, `header background ${h.background} is not opaque`);
  assert.deepEqual(log.errors, []);
  await context.close();
});
