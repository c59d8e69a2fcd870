// Teaching mode, page side (the worker side is teach-worker.js): Step / Run / Pause / Reset on the core's
// single-step API. One Step = one `fitter.step()` = one AECM iteration: the counter moves by one and the
// log-likelihood plot gains one point. While stepping, the mesh shows the responsibilities as soft colours
// (part colours blended by γ), the Algorithm 1 stage in progress, and beside the controls the equations the
// iteration computes. Nothing is computed here but colours.
import { PALETTE, hexToRgb, colourParts } from './colors.js';

const PALETTE_RGB = PALETTE.map(hexToRgb);
const OUTSIDE = [0.86, 0.87, 0.89]; // vertices outside the part being refined

/**
 * ctx: { app, send, setState, plot, renderView, readParams, stageText } from main.js. Returns
 * { onMessage(m) }: true when the message was the teaching mode's alone.
 */
export function installTeaching(ctx) {
  const { app, send, setState, plot, renderView, readParams, stageText } = ctx;
  const $ = (id) => document.getElementById(id);
  const t = {
    id: null, // request id of the teaching fit (app.fitId while it is the page's fit)
    running: false,
    values: [], // log-likelihood after every step, one point each
    runs: [], // index in `values` where every AECM run starts
    runKey: null, // the run the colour assignment belongs to
    colourOf: [], // palette index of every component of that run
    iteration: 0, // AECM iterations made (all runs)
    stage: null,
  };
  const active = () => t.id !== null && app.fitId === t.id;

  function buttons() {
    const on = active();
    $('teach-run').disabled = on && t.running;
    $('teach-step').disabled = on && t.running;
    $('teach-pause').disabled = !(on && t.running);
    $('teach-run').setAttribute('aria-pressed', String(on && t.running));
  }

  function begin(type) {
    if (!app.pop) return;
    if (type !== 'teach-reset' && active()) {
      t.running = type === 'teach-run';
      send({ type, id: t.id });
      buttons();
      return;
    }
    // A new teaching fit: the current model (and any fit in progress) gives way to it.
    const id = send({ type, params: readParams() });
    Object.assign(t, { id, running: type === 'teach-run', values: [], runs: [], runKey: null, iteration: 0, stage: null });
    app.fitId = id;
    app.model = null;
    app.gen++;
    app.cache.clear();
    app.colours.live = null;
    app.lastStep = null;
    $('errors').replaceChildren();
    $('stage').textContent = 'starting';
    for (const k of ['iteration', 'elapsed', 'loglik']) $(k).textContent = '–';
    $('teach-iteration').textContent = '0';
    plot.set([], '');
    setState('teaching');
    showLambdaRule();
    buttons();
  }

  $('teach-step').addEventListener('click', () => begin('teach-step'));
  $('teach-run').addEventListener('click', () => begin('teach-run'));
  $('teach-reset').addEventListener('click', () => begin('teach-reset'));
  $('teach-pause').addEventListener('click', () => {
    if (!active()) return;
    send({ type: 'teach-pause' });
  });
  $('params').elements.paperLambda.addEventListener('change', showLambdaRule);

  // Which Λ update the next fit uses: the exact conditional maximiser, or the paper's literal eq 18.
  function showLambdaRule() {
    const literal = $('params').elements.paperLambda.checked;
    $('teach-eq-lambda-exact').hidden = literal;
    $('teach-eq-lambda-paper').hidden = !literal;
  }
  showLambdaRule();

  // Palette index of every component of the run: neighbours differ (colors.js); fixed for the whole run so
  // that the colours do not jump between steps.
  function assignColours(m, labels) {
    const key = `${JSON.stringify(m.stage)}:${m.parts}`;
    if (key === t.runKey) return;
    t.runKey = key;
    let full = labels;
    if (m.vertices) {
      full = new Uint32Array(app.pop.nVertices).fill(m.parts); // one extra label for the rest of the mesh
      m.vertices.forEach((v, j) => { full[v] = labels[j]; });
    }
    const c = colourParts(full, app.pop.faces);
    t.colourOf = Array.from({ length: m.parts }, (_, k) => (c[k] >= 0 ? c[k] : k % PALETTE.length));
  }

  // Soft colours: every vertex of the run gets its parts' colours blended by its responsibilities.
  function softColours(m) {
    const n = app.pop.nVertices;
    const K = m.parts;
    const out = new Float32Array(n * 3);
    if (!m.gamma || !K) {
      for (let v = 0; v < n; v++) out.set(OUTSIDE, 3 * v);
      return out;
    }
    const rows = m.gamma.length / K;
    const argmax = new Uint32Array(rows);
    for (let j = 0; j < rows; j++) {
      let best = 0;
      for (let k = 1; k < K; k++) if (m.gamma[j * K + k] > m.gamma[j * K + best]) best = k;
      argmax[j] = best;
    }
    assignColours(m, argmax);
    if (m.vertices) for (let v = 0; v < n; v++) out.set(OUTSIDE, 3 * v);
    const soft = { vertices: 0, blended: 0 }; // vertices with no part above γ = 0.9, and how many show a blend
    for (let j = 0; j < rows; j++) {
      let r = 0;
      let g = 0;
      let b = 0;
      for (let k = 0; k < K; k++) {
        const w = m.gamma[j * K + k];
        if (w === 0) continue;
        const c = PALETTE_RGB[t.colourOf[k]];
        r += w * c[0];
        g += w * c[1];
        b += w * c[2];
      }
      out.set([r, g, b], 3 * (m.vertices ? m.vertices[j] : j));
      if (m.gamma[j * K + argmax[j]] < 0.9) {
        soft.vertices++;
        if (!PALETTE_RGB.some((c) => Math.abs(c[0] - r) + Math.abs(c[1] - g) + Math.abs(c[2] - b) < 0.02)) soft.blended++;
      }
    }
    t.soft = soft;
    return out;
  }

  // Algorithm 1's stages, the current one marked.
  function showStage(stage) {
    t.stage = stage;
    const kind = stage?.kind ?? 'coarse';
    for (const li of $('teach-stages').children) {
      const here = li.dataset.stage === kind;
      li.classList.toggle('current', here);
      if (here) li.setAttribute('aria-current', 'step');
      else li.removeAttribute('aria-current');
      li.classList.toggle('past', ['coarse', 'refine', 'final', 'done'].indexOf(li.dataset.stage) < ['coarse', 'refine', 'final', 'done'].indexOf(kind));
    }
    const note = {
      coarse: 'Coarse stage: AECM with m parts on all vertices, started from k-means++.',
      refine: stage?.kind === 'refine'
        ? `Refinement of coarse part ${stage.part + 1} of ${stage.of}: AECM on its vertices alone (the rest grey) with m_k = ${stage.subParts} component${stage.subParts > 1 ? 's' : ''}; m_k grows while the mean variance falls.`
        : '',
      final: 'Final stage: AECM on all vertices, started from the refined labels (eq 20).',
      done: 'Done: labels (eq 20), latent shape (eq 21), reconstruction (eq 22).',
    }[kind];
    $('teach-stage-note').textContent = note ?? '';
  }

  let pending = null;
  function show() {
    const m = pending;
    pending = null;
    if (!m || !active() || !app.pop) return;
    app.colours.live = softColours(m);
    if (app.model) return;
    renderView().then(() => {
      if (active() && app.mode === 'parts') {
        const where = m.vertices ? `; grey: outside coarse part ${m.stage.part + 1}` : '';
        $('caption').textContent = `Pose “${app.pop.names[app.pose]}”: responsibilities γ of the fit in progress as soft colours (part colours blended by γ${where})`;
      }
    });
  }

  function onTeach(m) {
    if (m.id !== t.id) return;
    t.running = m.running;
    if (m.kind === 'step' && m.step) {
      const s = m.step;
      if (!t.values.length || s.iteration === 1) t.runs.push(t.values.length);
      t.values.push(s.logLikelihood);
      t.iteration = s.totalIterations;
      app.lastStep = s;
      $('teach-iteration').textContent = String(s.totalIterations);
      $('stage').textContent = stageText(s.stage);
      $('iteration').textContent = `${s.iteration} (total ${s.totalIterations})`;
      $('loglik').textContent = s.logLikelihood.toFixed(2);
      plot.set(t.values, `${stageText(s.stage)}: log-likelihood per step`, t.runs);
    }
    showStage(m.stage);
    buttons();
    if (m.stage?.kind === 'done') return; // the 'fitted' message follows
    if (!pending) requestAnimationFrame(show);
    pending = m;
  }

  window.posemfa.teaching = () => ({
    active: active(),
    running: active() && t.running,
    iteration: t.iteration,
    points: t.values.length,
    logLikelihood: t.values.slice(),
    stage: t.stage,
    soft: t.soft ?? null,
  });
  /** Points on the log-likelihood plot now. */
  window.posemfa.plotPoints = () => plot.values.length;

  buttons();
  showStage(null);
  return {
    onMessage(m) {
      if (m.type === 'teach') {
        onTeach(m);
        return true;
      }
      if (m.type === 'loaded' || m.type === 'fitted') queueMicrotask(showLambdaRule); // the form was filled in code
      if ((m.type === 'fitted' || m.type === 'fit-error') && m.id === t.id) {
        t.running = false;
        queueMicrotask(buttons);
      }
      return false;
    },
  };
}
