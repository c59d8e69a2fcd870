// The article's page code (explain.html; loaded by www/explain/explain.js once the worker pool is started):
// typesets the equations with KaTeX (bundled from npm, its fonts by vite) and builds the live figures
// (www/explain/figures.js) on the shared worker pool (www/explain/pool.js).
//
// Test contract (tests/e2e/explain.test.mjs): every figure element has data-figure="<name>" and data-state
// (loading | fitting | fitted | stepping | error); window.explain.figures() returns
// [{ name, state, logLikelihood: [...] }] and, for the eq 18 figure, { name, state, literal: [...], exact: [...] }.
import katex from 'katex';
import 'katex/dist/katex.min.css';
import { FIGURES } from './figures.js';
import { thresholdText } from './article-threshold.js';

// In slices of a few equations, so that the figures' first messages are not held up behind all of them.
async function typeset() {
  const all = [...document.querySelectorAll('.tex, .tex-block')];
  for (let i = 0; i < all.length; i++) {
    const el = all[i];
    const tex = el.textContent;
    try {
      if (el.classList.contains('tex-block')) {
        // The paper's equation number beside the equation, not inside it: a long equation then scrolls
        // sideways on a phone while its number stays in view.
        const tag = /\\tag\{([^}]*)\}\s*$/.exec(tex);
        const body = document.createElement('div');
        body.className = 'eq';
        katex.render(tag ? tex.slice(0, tag.index) : tex, body, { displayMode: true, throwOnError: true, output: 'htmlAndMathml' });
        el.replaceChildren(body);
        if (tag) el.append(Object.assign(document.createElement('span'), { className: 'eqno', textContent: `(${tag[1]})` }));
      } else {
        katex.render(tex, el, { throwOnError: true, output: 'htmlAndMathml' });
      }
    } catch (e) {
      el.textContent = tex;
      console.error(`KaTeX could not typeset "${tex}": ${e.message}`);
    }
    if (i % 8 === 7) await new Promise((r) => setTimeout(r, 0));
  }
  fitEquations();
  window.addEventListener('resize', () => fitEquations());
  document.body.dataset.typeset = 'done';
}

// A displayed equation wider than the column (a phone): set a little smaller, down to 72 % of its size; one
// still too wide is set at 90 % and scrolls sideways, and says so: a fade at the edge it continues past and a "scroll" hint under
// it, gone once it is scrolled to its end (data-fit: "fits", "smaller", "scrolls").
const SIZES = [1, 0.9, 0.8, 0.72];
function fitEquations() {
  for (const block of document.querySelectorAll('.tex-block')) {
    const eq = block.querySelector('.eq');
    if (!eq) continue;
    let size = SIZES[0];
    for (size of SIZES) {
      eq.style.fontSize = size === 1 ? '' : `${size}em`;
      if (eq.scrollWidth <= eq.clientWidth + 1) break;
    }
    const scrolls = eq.scrollWidth > eq.clientWidth + 1;
    // one that scrolls anyway is not also made hard to read: a little smaller only
    if (scrolls) eq.style.fontSize = `${SIZES[1]}em`;
    block.dataset.fit = scrolls ? 'scrolls' : size === 1 ? 'fits' : 'smaller';
    block.classList.toggle('scrolls', scrolls);
    let hint = block.querySelector('.eq-hint');
    if (scrolls && !hint) {
      hint = Object.assign(document.createElement('span'), { className: 'eq-hint', textContent: 'scroll sideways for the rest →' });
      block.append(hint);
      eq.addEventListener('scroll', () => block.classList.toggle('at-end', eq.scrollLeft + eq.clientWidth >= eq.scrollWidth - 2), { passive: true });
    }
    if (!scrolls) hint?.remove();
  }
}

/** Builds the article's figures on `pool` (www/explain/pool.js). */
export function start(pool) {
  const figures = [];
  document.querySelectorAll('[data-figure]').forEach((el, index) => {
    const make = FIGURES[el.dataset.figure];
    if (!make) {
      el.dataset.state = 'error';
      console.error(`no figure called ${el.dataset.figure}`);
      return;
    }
    figures.push(make({ el, index, pool }));
  });
  for (const out of document.querySelectorAll('[data-out=pool]')) out.textContent = String(pool.size);
  // the verdict's threshold as the core has it (src/parts/diagnosis.rs MIN_EXPLAINED), the app's figure too
  pool.ready.then((info) => {
    for (const out of document.querySelectorAll('[data-out=min-explained]')) out.textContent = thresholdText(info.minExplained);
  });
  typeset();

  // Scrolling a figure into view starts its live part (a run, an animation); scrolling away pauses it. A
  // figure counts as in view when a fifth of it is on the screen.
  const observer = new IntersectionObserver((entries) => {
    for (const e of entries) figures.find((g) => g.el === e.target)?.setVisible(e.isIntersecting);
    pool.reprioritise();
  }, { threshold: 0.2 });
  for (const f of figures) observer.observe(f.el);

  window.explain = {
    /** [{name, state, logLikelihood}] ({name, state, literal, exact} for the eq 18 figure). */
    figures: () => figures.map((f) => f.contract()),
    /** The pool: {workers, upAt, up, waiting, busy}. */
    pool: () => pool.status(),
    /** Extra per-figure detail for tests: iteration counts, whether a live run is going, ... */
    detail: (name) => figures.find((f) => f.name === name)?.detail(),
    /** performance.now() when each figure first became fitted (or stepping), by name (null: not yet). */
    readyTimes: () => Object.fromEntries(figures.map((f) => [f.name, f.readyAt ?? null])),
  };
}
