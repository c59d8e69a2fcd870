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
  document.body.dataset.typeset = 'done';
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
