// The article's equations on a phone: at 390x844 every displayed equation either fits the
// column (set smaller if need be, not below 72 % of its size) or shows that it scrolls sideways (a fade at its
// edge and a hint under it); none runs under its equation number.
// Run: npm run build && node --test tests/e2e/article-phone.test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { pageSession } from './helpers.mjs';

const session = pageSession();

test('on a phone every equation fits or shows that it scrolls', async () => {
  const { page, context, log } = await session.open('explain.html', { width: 390, height: 844 });
  await page.waitForFunction(() => document.body.dataset.typeset === 'done', null, { timeout: 60000 });
  const blocks = await page.$$eval('.tex-block', (all) => all.map((b) => {
    const eq = b.querySelector('.eq');
    const no = b.querySelector('.eqno');
    const hint = b.querySelector('.eq-hint');
    const style = getComputedStyle(eq);
    return {
      tex: eq.textContent.slice(0, 40),
      fit: b.dataset.fit,
      overflows: eq.scrollWidth > eq.clientWidth + 1,
      size: parseFloat(style.fontSize) / parseFloat(getComputedStyle(b).fontSize),
      mask: style.maskImage || style.webkitMaskImage || 'none',
      hint: hint ? hint.getBoundingClientRect().height > 0 && getComputedStyle(hint).visibility === 'visible' : false,
      eqRight: eq.getBoundingClientRect().right,
      noLeft: no ? no.getBoundingClientRect().left : Infinity,
      right: document.documentElement.clientWidth,
    };
  }));
  assert.ok(blocks.length >= 10, `${blocks.length} equations`);
  for (const b of blocks) {
    assert.ok(['fits', 'smaller', 'scrolls'].includes(b.fit), `${b.tex}: data-fit ${b.fit}`);
    assert.ok(b.eqRight <= b.noLeft + 0.5, `${b.tex}: runs under its number`);
    assert.ok(b.eqRight <= b.right + 0.5, `${b.tex}: runs past the page`);
    assert.ok(b.size >= 0.7, `${b.tex}: set at ${b.size} of its size`);
    if (b.overflows) {
      assert.equal(b.fit, 'scrolls', `${b.tex}: wider than the column and not said`);
      assert.notEqual(b.mask, 'none', `${b.tex}: scrolls with no fade at its edge`);
      assert.ok(b.hint, `${b.tex}: scrolls with no hint`);
    } else assert.notEqual(b.fit, 'scrolls', `${b.tex}`);
  }
  // scrolled to its end, an equation's fade and hint go
  const scrolling = blocks.findIndex((b) => b.fit === 'scrolls');
  if (scrolling >= 0) {
    const end = await page.evaluate((i) => {
      const b = document.querySelectorAll('.tex-block')[i];
      const eq = b.querySelector('.eq');
      eq.scrollLeft = eq.scrollWidth;
      eq.dispatchEvent(new Event('scroll'));
      return b.classList.contains('at-end');
    }, scrolling);
    assert.equal(end, true);
  }
  const counts = blocks.reduce((c, b) => ({ ...c, [b.fit]: (c[b.fit] ?? 0) + 1 }), {});
  console.log(`# equations at 390 px: ${JSON.stringify(counts)}`);
  assert.deepEqual(log.errors, []);
  await context.close();
});
