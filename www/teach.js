// Teaching mode, page side (the worker side is teach-worker.js): Step / Run / Pause / Reset on the core's
// single-step API. One Step = one `fitter.step()` = one AECM iteration: the counter moves by one and the
// log-likelihood plot gains one point. While stepping, the mesh shows the responsibilities as soft colours
// (part colours blended by γ), the Algorithm 1 stage in progress, and beside the controls the equations the
// iteration computes. Nothing is computed here but colours. The teaching fit lives in the page state as
// state.teach = { id, running, iteration, stage, values, runs, soft } (null when there is none).
import { PALETTE_RGB, gammaColours } from './colors.js';
import { state, update, subscribe } from './state.js';
import { client, watchFit, jobKey } from './session.js';
import { checkedParams } from './controls/form.js';
import { renderView } from './views/render.js';
import { plot } from './views/viewer-instance.js';
import { showStep, stageText, FINISHING } from './views/result.js';
import { showProblems } from './problems.js';
import { ask } from './ask.js';

const OUTSIDE = [0.86, 0.87, 0.89]; // vertices outside the part being refined
const STAGES = ['coarse', 'refine', 'final', 'done'];
const $ = (id) => document.getElementById(id);

const active = () => state.teach !== null && state.fitId === state.teach.id;
const setTeach = (patch) => update({ teach: { ...state.teach, ...patch } });

function buttons() {
  const on = active();
  const running = on && state.teach.running;
  $('teach-run').disabled = running;
  $('teach-step').disabled = running;
  $('teach-pause').disabled = !running;
  $('teach-run').setAttribute('aria-pressed', String(running));
}

const BUTTON = { 'teach-step': 'Step', 'teach-run': 'Run', 'teach-reset': 'Reset' };

/** Step / Run / Reset: a step of the teaching fit in hand, or a new one (count: steps at once). A new one asks
 * before it drops a finished fit, whichever button starts it (a dismissed question changes nothing). */
export async function teach(type, { count = 1 } = {}) {
  if (!state.pop) return;
  if (type !== 'teach-reset' && active()) {
    setTeach({ running: type === 'teach-run' });
    client.post({ type, id: state.teach.id, count });
    return;
  }
  // (a finished model shown while a new Fit runs is dropped as well: asked too)
  // Asked in the page, under the buttons (never the browser's confirm box: a suppressed or unanswered one left
  // Step and Run looking dead); No leaves a line saying the finished fit was kept.
  if (state.model && !active()) {
    const parts = state.model.summary.parts;
    const yes = await ask($('teach-buttons'), `${BUTTON[type]} starts a new step-by-step fit and drops the finished one (${parts} parts, its exports and views). Drop it?`, {
      yes: `Drop it and ${BUTTON[type].toLowerCase()}`,
      no: 'Keep the finished fit',
      kept: `Kept the finished fit (${parts} parts): no step-by-step fit was started. Press ${BUTTON[type]} again to start one.`,
    });
    if (!yes || !state.model || active()) return;
  }
  // A new teaching fit: the current model (and any fit in progress) gives way to it.
  const params = await checkedParams();
  if (!params || !state.pop) return; // the form names the field it cannot use
  const { id, done } = client.request({ type, params, count }, { onEvent: onTeach, job: jobKey(state.source, params) });
  update({
    teach: { id, running: type === 'teach-run', values: [], runs: [], iteration: 0, stage: null, soft: null },
    fitId: id, model: null, gen: state.gen + 1, colours: { ...state.colours, live: null }, lastStep: null, phase: 'teaching',
  });
  showProblems([]);
  $('stage').textContent = 'starting';
  for (const k of ['iteration', 'elapsed', 'loglik']) $(k).textContent = '–';
  plot.set([], '');
  showLambdaRule();
  watchFit(id, done); // (Step by step is always Algorithm 1: its model's summary says so)
}

// Which Λ update the next fit uses: the exact conditional maximiser, or the paper's literal eq 18.
function showLambdaRule() {
  const literal = $('params').elements.paperLambda.checked;
  $('teach-eq-lambda-exact').hidden = literal;
  $('teach-eq-lambda-paper').hidden = !literal;
}

// Palette index of every component of the run (from the core: neighbours differ), kept for the whole run so
// that the colours do not jump between steps.
const assigned = { key: null, colourOf: [] };
function assignColours(m) {
  const key = `${JSON.stringify(m.stage)}:${m.parts}`;
  if (key === assigned.key) return;
  assigned.key = key;
  assigned.colourOf = Array.from(m.colours);
}

// Soft colours: every vertex of the run gets its parts' colours blended by its responsibilities (colors.js
// gammaColours). Returns the colours and { vertices: with no part above γ = 0.9, blended: how many of them show
// a blend }.
function softColours(m) {
  const n = state.pop.nVertices;
  const K = m.parts;
  const out = new Float32Array(n * 3);
  if (!m.gamma || !K) {
    for (let v = 0; v < n; v++) out.set(OUTSIDE, 3 * v);
    return { colours: out, soft: null };
  }
  assignColours(m);
  const rows = gammaColours(m.gamma, K, assigned.colourOf);
  if (m.vertices) for (let v = 0; v < n; v++) out.set(OUTSIDE, 3 * v);
  const soft = { vertices: 0, blended: 0 };
  for (let j = 0; j < rows.length / 3; j++) {
    const rgb = rows.subarray(3 * j, 3 * j + 3);
    out.set(rgb, 3 * (m.vertices ? m.vertices[j] : j));
    let top = 0;
    for (let k = 0; k < K; k++) top = Math.max(top, m.gamma[j * K + k]);
    if (top < 0.9) {
      soft.vertices++;
      if (!PALETTE_RGB.some((c) => Math.abs(c[0] - rgb[0]) + Math.abs(c[1] - rgb[1]) + Math.abs(c[2] - rgb[2]) < 0.02)) soft.blended++;
    }
  }
  return { colours: out, soft };
}

// Algorithm 1's stages, the current one marked (a teaching fit before its first step: coarse). No teaching fit
// (run: false; none yet, or a new Fit or population dropped it): none marked, no note, the panel as it opened.
function showStage(stage, run = true) {
  const kind = run ? stage?.kind ?? 'coarse' : null;
  for (const li of $('teach-stages').children) {
    const here = li.dataset.stage === kind;
    li.classList.toggle('current', here);
    if (here) li.setAttribute('aria-current', 'step');
    else li.removeAttribute('aria-current');
    li.classList.toggle('past', kind !== null && STAGES.indexOf(li.dataset.stage) < STAGES.indexOf(kind));
  }
  // the same stage object as the Stage field (stageText): where the fit is now, which the next Step continues
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
  if (!m || !active() || !state.pop) return;
  const { colours, soft } = softColours(m);
  setTeach({ soft });
  update({ colours: { ...state.colours, live: colours } });
  if (state.model) return;
  renderView().then(() => {
    if (active() && state.mode === 'parts') {
      const where = m.vertices ? `; grey: outside coarse part ${m.stage.part + 1}` : '';
      $('caption').textContent = `Pose “${state.pop.names[state.pose]}”: responsibilities γ of the fit in progress as soft colours (part colours blended by γ${where})`;
    }
  });
}

// A 'teach' message of the worker: one step made (or several: m.steps), a reset, or a pause.
function onTeach(m) {
  if (!state.teach || m.id !== state.teach.id) return;
  const t = { running: m.running, stage: m.stage };
  const steps = m.steps ?? [];
  if (steps.length) {
    const values = state.teach.values.slice();
    const runs = state.teach.runs.slice();
    for (const s of steps) {
      if (!values.length || s.iteration === 1) runs.push(values.length);
      values.push(s.logLikelihood);
    }
    const s = steps[steps.length - 1];
    Object.assign(t, { values, runs, iteration: s.totalIterations });
    update({ lastStep: s });
    showStep(s, m.stage); // the Stage field says where the fit is now, as the note and the stage list do
    plot.set(values, `${stageText(s.stage)}: log-likelihood per step`, runs);
  }
  setTeach(t);
  if (m.stage?.kind === 'done') {
    $('stage').textContent = FINISHING; // the 'fitted' message follows, once the worker has built the model
    return;
  }
  if (!pending) requestAnimationFrame(show);
  pending = m;
}

export function installTeaching() {
  $('teach-step').addEventListener('click', () => teach('teach-step'));
  $('teach-run').addEventListener('click', () => teach('teach-run'));
  $('teach-reset').addEventListener('click', () => teach('teach-reset'));
  $('teach-pause').addEventListener('click', () => active() && client.post({ type: 'teach-pause' }));
  $('params').elements.paperLambda.addEventListener('change', showLambdaRule);
  subscribe((s, changed) => {
    if (changed.has('teach') || changed.has('fitId')) buttons();
    if (changed.has('teach')) {
      showStage(s.teach?.stage ?? null, s.teach !== null);
      $('teach-iteration').textContent = String(s.teach?.iteration ?? 0);
    }
    if (changed.has('pop') || changed.has('model')) showLambdaRule(); // the form was filled in code
    if (changed.has('fitId') && s.teach && s.fitId !== s.teach.id && s.teach.running) setTeach({ running: false });
  });

  window.posemfa.teaching = () => ({
    active: active(),
    running: active() && state.teach.running,
    iteration: state.teach?.iteration ?? 0,
    points: state.teach?.values.length ?? 0,
    logLikelihood: state.teach?.values.slice() ?? [],
    stage: state.teach?.stage ?? null,
    soft: state.teach?.soft ?? null,
  });
  /** Points on the log-likelihood plot now. */
  window.posemfa.plotPoints = () => plot.values.length;
  buttons();
  showLambdaRule();
  showStage(null, false);
}
