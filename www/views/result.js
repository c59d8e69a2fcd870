// The panel's figures: the population line (poses, vertices, source, ground truth), the example's note and
// the file list; the fit's progress (stage, iteration, elapsed time, log-likelihood and its plot); the
// result (parts, RMSE, iterations, fit time, ground-truth accuracy).
import { state, subscribe } from '../state.js';
import { onFitProgress, isTreeFit, readAnimation } from '../session.js';
import { drops } from '../trace.js';
import { accuracyText, tiedText } from '../ground-truth.js';
import { plot } from './viewer-instance.js';
import { drawPartCurve } from './part-curve.js';
import { eRmsText, ERMS_UNIT } from '../erms.js';

const $ = (id) => document.getElementById(id);

/** The run a progress object's `stage` names, as words (`Stage` in src/parts/hierarchy/result.rs: {kind:
 * "coarse" | "refine" | "final" | "done"}; a final-stage run also says which rule asked for it, which run it is
 * and, while the parts are decided on a coarse mesh, its vertex count). */
export function stageText(s) {
  if (!s) return '–';
  if (s.kind === 'refine') return `refining part ${s.part + 1} of ${s.of} (${s.subParts} sub-part${s.subParts === 1 ? '' : 's'})`;
  if (s.kind === 'final' && s.run) {
    // a large mesh's parts are decided on a coarse mesh of its vertices, then fitted on all of them
    const where = s.coarseVertices ? `, on a coarse mesh of ${s.coarseVertices} vertices` : '';
    if (s.run === 'first') return (s.rule === 'mergeTree' ? "fit from the merge tree's start" : 'final AECM') + where;
    if (s.run === 'settle') return 'the parts decided, refitted at the full tolerance' + where;
    if (s.run === 'round') return `part rule, round ${s.number}: refit of the parts left${where}`;
    if (s.run === 'allVertices') return 'the parts decided on a coarse mesh, fitted on all vertices';
    if (s.run === 'count') return `refit with the part count asked for${s.number > 1 ? ` (try ${s.number})` : ''}${where}`;
  }
  return { coarse: 'coarse', final: 'final', done: 'done' }[s.kind] ?? s.kind;
}

// Which AECM run of the fit the progress is in (1 for the first): one more after every run that finished.
let runsFinished = 0;
let runsFor = null;
// The whole fit's log-likelihood, every iteration of every run as the progress brought them (fitRuns.runs: where
// each run starts), for the plot once the fit has ended: the model's own trace is its final stage's only (one
// point when the last run goes on from the one before). lastFit: the fit in progress, or the last one.
let fitRuns = { id: null, values: [], runs: [] };
let lastFit = null;

function showPopulation(pop, source) {
  const tris = pop.faces.length / 3;
  $('pop-info').textContent = `${pop.nShapes} poses × ${pop.nVertices} vertices, ${tris} triangles (${pop.source})`;
  if (pop.truth) $('pop-info').textContent += `. Ground truth: ${pop.truth.partNames.length} part${pop.truth.partNames.length === 1 ? '' : 's'}.`;
  // where the poses came from, as the core says it (mesh::load); generated populations have none
  const provenance = pop.truth ? '' : pop.provenance;
  $('pop-source').hidden = !provenance;
  $('pop-source').textContent = provenance ? `Poses: ${provenance}` : '';
  // a glTF with several animations that move its mesh: the one read, and the others to read instead
  const clips = pop.clips?.names.length > 1 ? pop.clips : null;
  $('clip-row').hidden = !clips;
  $('clip').replaceChildren(...(clips?.names ?? []).map((n) => Object.assign(document.createElement('option'), { value: n, textContent: n })));
  if (clips) $('clip').value = clips.names[clips.read];
  const ex = source?.example;
  $('example-note').hidden = !ex;
  $('example-note').classList.toggle('fails', !!ex?.failsOnPurpose);
  $('example-note').textContent = ex ? `${ex.failsOnPurpose ? 'Fails on purpose. ' : ''}${ex.note}` : '';
  $('names').replaceChildren(...pop.names.map((n) => Object.assign(document.createElement('li'), { textContent: n })));
}

// An example that fails on purpose: what failed in this fit, read off its summary (the iteration cap, the drops of
// the log-likelihood, the core's verdict), so that the result never reads as a success. Null for other fits and
// for a fit stopped early (its summary says so itself).
function failureText(s, example) {
  if (!s || !example?.failsOnPurpose || s.cancelled || s.unfinished) return null;
  const ll = s.logLikelihood ?? [];
  const fell = drops(ll).length;
  const d = s.diagnosis;
  const notArticulated = !!d && !d.articulated && !d.undecided;
  const failed = [];
  if (s.complete && !s.converged) failed.push(`AECM did not converge (it stopped at the iteration cap after ${s.iterations} iteration${s.iterations === 1 ? '' : 's'})`);
  if (fell) failed.push(`the log-likelihood fell ${fell} time${fell === 1 ? '' : 's'} in the final stage's ${ll.length} iterations, which a maximisation step never does`);
  if (notArticulated) failed.push(`the shape is not articulated: rigid parts explain only ${(100 * d.explained).toFixed(1)} % of its motion (the verdict below)`);
  if (!failed.length) {
    return { failed: false, text: `This example is meant to fail, but this fit did not: it converged in ${s.iterations} iteration${s.iterations === 1 ? '' : 's'}, its log-likelihood never fell${d && d.articulated ? ', and the verdict is articulated' : ''}.` };
  }
  const g = s.groundTruth;
  const parts = g && g.ari >= 0.95 && !notArticulated ? ` Its parts still match the ground truth (adjusted Rand ${g.ari.toFixed(3)}): the fit failed, not the parts.` : '';
  const what = failed.join('; ');
  return { failed: true, text: `Failed, as this example means to. ${what[0].toUpperCase()}${what.slice(1)}.${parts}` };
}

// A model from a cancelled fit (the page's first fit of its population; a cancelled refit keeps the finished model
// instead): where the fit stopped, which can still be a coarse stage's parts. The result leads with that, so that
// its parts and RMSE are not read as a result. The count is the fit's own, from its last progress message.
function cancelText(s) {
  if (!s?.cancelled) return '';
  const n = state.lastStep?.totalIterations ?? 0;
  const when = n ? `after ${n} iteration${n === 1 ? '' : 's'}` : 'before its first iteration';
  return `Cancelled ${when}: a partial model, not a result. Its parts, RMSE and views are where the fit stopped, and the exports write that partial model; Fit again for a finished one.`;
}

function showResult() {
  const s = state.model?.summary;
  const cancelled = cancelText(s);
  $('cancel-lead').hidden = !cancelled;
  $('cancel-lead').textContent = cancelled;
  const failure = failureText(s, state.source?.example);
  $('fail-lead').hidden = !failure;
  $('fail-lead').classList.toggle('fails', !!failure?.failed);
  $('fail-lead').textContent = failure?.text ?? '';
  // what a limit example shows, read off the fit (a fit stopped early shows no result to read)
  const tied = s && !s.cancelled && !s.unfinished ? tiedText(s.groundTruth) : '';
  $('limit-lead').hidden = !tied;
  $('limit-lead').textContent = tied;
  $('parts-count').textContent = s ? s.parts : '–';
  // the merge tree (the default part rule) starts from its own cut, not from Algorithm 1's coarse and refined
  // stages: said the same for a finished fit and for one cancelled before it finished (which has no tree yet)
  // (Algorithm 1 without the refinement: a part of the coarse fit in pieces becomes a part per piece)
  const pieces = s && s.complete && !s.cancelled && !isTreeFit(state.model) && s.parts > s.refinedParts ? `; ${s.parts} once each part is one connected piece` : '';
  // (the refinement off: no refined stage of its own; an exact count asked for in "Parts in the end" says so, a
  // Refine's count has its own note)
  const algorithm1 = s?.refine === false ? `coarse ${s?.coarseParts}, no refinement${pieces}` : `coarse ${s?.coarseParts}, refined ${s?.refinedParts}${pieces}`;
  const asked = Number.isInteger(s?.partsAsked) && !state.model?.refinedFromTree ? `; ${s.partsAsked} as asked in “Parts in the end”` : '';
  const stages = (isTreeFit(state.model) ? `started from the merge tree's ${s?.coarseParts} part${s?.coarseParts === 1 ? '' : 's'}` : algorithm1) + asked;
  $('stage-parts').textContent = s ? `(${stages}${s.cancelled ? ', cancelled' : ''})` : '';
  // a generated population is in the unit box already: one figure for both units when they print the same
  const [unit, original] = s ? [s.rmse.toExponential(3), s.rmseOriginal.toExponential(3)] : [];
  // and the rig's measure (E_RMS: per coordinate, so the RMSE / sqrt 3, over the diagonal), so that the fit and its
  // exported rig compare
  const eRms = Number.isFinite(s?.eRms) ? `; E_RMS ${eRmsText(s.eRms)} (the rig's measure: ${ERMS_UNIT})` : '';
  $('rmse').textContent = !s ? '–' : unit === original ? `${unit} (unit box = original units)${eRms}` : `${unit} (unit box) = ${original} original units${eRms}`;
  // a finished fit that stopped at the iteration cap says so (it is not converged)
  const how = s?.converged ? ', converged' : s?.complete ? ', not converged: stopped at the iteration cap' : '';
  // a cancelled fit's iterations are those of the run it stopped in, which need not be the final stage's
  const where = s?.cancelled ? 'in the run where the fit was cancelled' : 'in the final stage';
  $('iterations').textContent = s ? `${s.iterations} ${where}${s.cancelled ? '' : how}` : '–';
  // a model file opened: no fit ran here; its fit's time is the one it was saved with
  const savedMs = (s?.stageStats ?? []).reduce((t, x) => t + (x.ms ?? 0), 0);
  $('fit-time').textContent = !s ? '–' : s.opened ? `none: opened from ${s.opened} (its fit took ${Math.round(savedMs)} ms)` : `${Math.round(s.fitMs)} ms`;
  $('truth-acc').textContent = accuracyText(s?.groundTruth);
  $('truth-acc').classList.toggle('good', s?.groundTruth?.ari >= 0.95);
  // the core's verdict (model::diagnosis), in its own words, next to the result
  // a fit stopped early gets no verdict (the core's words say why)
  const d = s?.diagnosis;
  $('diagnosis').hidden = !d && !s?.unfinished;
  $('diagnosis').classList.toggle('fails', d ? !d.articulated && !d.undecided : false);
  $('diagnosis').classList.toggle('unfinished', !d && !!s?.unfinished);
  $('diagnosis').textContent = d ? `${d.undecided ? 'No verdict' : d.articulated ? 'Articulated' : 'Not articulated'}: ${d.reason}.` : s?.unfinished ? `${s.unfinished[0].toUpperCase()}${s.unfinished.slice(1)}.` : '';
  const curve = s?.partCurve ?? [];
  $('part-curve').hidden = curve.length === 0;
  $('part-curve-note').hidden = curve.length === 0;
  $('part-curve-legend').hidden = curve.length === 0;
  $('part-curve-note').textContent = curve.length ? curveNote(s) : '';
  // the line the scores were compared with: the distinct ratio of the fit's parameters (the form never changes it)
  drawPartCurve($('part-curve'), curve, { ratio: state.baseParams?.distinctRatio ?? null, applied: !refinedParts(s) });
}

// The parts were given to the fit (a Refine, startLabels): the rule ran no round on them, it only recorded their tree.
const refinedParts = (s) => isTreeFit(state.model) && (s.partRounds ?? []).length === 0;

// How the fit came to the count the chart's last round began with (the chart is that round's merges only): the
// merge tree's start and the flesh dissolved on it before the first AECM, then every round of the part rule, as
// the core recorded them (summary.startParts, summary.partRounds).
function curveNote(s) {
  const n = (k) => `${k} part${k === 1 ? '' : 's'}`;
  if (refinedParts(s)) return `The chart is the part rule on the ${n(s.parts)} refined from the merge tree: it judges them, and a Refine keeps them as they are.`;
  const said = [];
  if (isTreeFit(state.model)) {
    const flesh = s.startParts != null ? s.coarseParts - s.startParts : 0;
    said.push(`the merge tree's start had ${n(s.coarseParts)}${flesh > 0 ? `, ${flesh} of them flesh between parts, dissolved before the first AECM` : ''}`);
  }
  (s.partRounds ?? []).forEach((r, i) => {
    said.push(`round ${i + 1} judged the AECM's ${n(r.parts)}: ${r.dissolved} dissolved as flesh, merges ${r.parts - r.dissolved} → ${r.after}`);
  });
  // a finished fit that ended with another count than the rule's last decision: the count asked for made it so
  const last = s.partRounds?.[s.partRounds.length - 1];
  if (last && s.complete && !s.cancelled && last.after !== s.parts) {
    const asked = $('params').elements.targetParts.value.trim() === String(s.parts);
    said.push(`then ${asked ? `the count asked for in “Parts in the end” split or merged these to ${n(s.parts)}` : `the fit ended with ${n(s.parts)}`}, the parts shown`);
  }
  const story = said.join('; ');
  return `The chart is the part rule's last round.${story ? ` ${story[0].toUpperCase()}${story.slice(1)}.` : ''}`;
}

/** A log-likelihood for the panel: in nats (natural log), its thousands apart (U+202F), two decimals. */
export function natsText(v) {
  const [whole, frac] = Math.abs(v).toFixed(2).split('.');
  return `${v < 0 ? '−' : ''}${whole.replace(/\B(?=(\d{3})+(?!\d))/g, '\u202f')}.${frac} nats`;
}

/** The Stage field between the fit's last iteration and its model: the worker builds the result (labels,
 * latent shape, summary, the verdict's own fits), which takes a while on a large population; the field says
 * "done" once the model is in (fitEnded). */
export const FINISHING = 'finishing: building the result (labels, latent shape, summary, verdict)';

/** Shows one AECM iteration's progress object (stage: where the fit is now, when it has moved on since;
 * runNumber: the run's number among the fit's runs). */
export function showStep(step, stage = step.stage, runNumber = null) {
  $('stage').textContent = stageText(stage) + (runNumber ? ` (run ${runNumber})` : '');
  $('iteration').textContent = `${step.iteration} (total ${step.totalIterations})`;
  $('loglik').textContent = natsText(step.logLikelihood);
}

function fitStarted() {
  $('stage').textContent = 'starting';
  for (const k of ['iteration', 'elapsed', 'loglik']) $(k).textContent = '–';
  plot.set([], '');
}

// kept: 'cancel' / 'failure', a new fit was cancelled or failed and this finished model stays (its figures are
// shown again). runs: the whole
// fit's trace as the progress brought it (fitRuns), when the model is that fit's.
function fitEnded(model, { kept = null, runs = null } = {}) {
  const { cancelled, fitMs, logLikelihood, iterations } = model.summary;
  // a cancelled first fit shows where it stopped: not "best", it may be below what a finished fit reaches
  const opened = model.summary.opened;
  $('stage').textContent = kept ? `new fit ${kept === 'cancel' ? 'cancelled' : 'failed'}: the finished fit before it is kept` : cancelled ? 'cancelled: where the fit stopped' : opened ? `opened from ${opened}: not fitted here` : 'done';
  if (kept || opened) $('iteration').textContent = `${iterations} in the final stage`;
  else if (state.lastStep) $('iteration').textContent = `${state.lastStep.iteration} (total ${state.lastStep.totalIterations})`;
  $('elapsed').textContent = opened ? '– (opened, not fitted)' : `${(fitMs / 1000).toFixed(2)} s`;
  // the model's own final value (the plot's last point), not the last progress message seen
  $('loglik').textContent = logLikelihood?.length ? natsText(logLikelihood[logLikelihood.length - 1]) : '–';
  const final = logLikelihood ?? [];
  if (!kept && wholeFit(runs, final)) {
    // every run, each to its own scale (they can differ in vertices and parts); the last is the model's own trace
    plot.set(runs.values, `${cancelled ? 'stopped early' : 'the whole fit'}: log-likelihood of its ${runs.runs.length} AECM runs (min, max: the last run's)`, runs.runs);
  } else plot.set(final, `${cancelled ? 'stopped early' : 'final stage'}: log-likelihood`);
}

// The progress brought more than one run, and its last run is the model's own trace (not a run cancelled midway
// after the model's).
function wholeFit(runs, final) {
  if (!runs || runs.runs.length < 2 || !final.length) return false;
  const last = runs.values.slice(runs.runs[runs.runs.length - 1]);
  return last.length === final.length && last.every((v, i) => v === final[i]);
}

export function installResult() {
  $('clip').addEventListener('change', (e) => readAnimation(e.target.value));
  onFitProgress((m) => {
    if (runsFor !== m.id) [runsFor, runsFinished] = [m.id, 0];
    if (fitRuns.id !== m.id) fitRuns = { id: m.id, values: [], runs: [] };
    for (const s of m.steps) {
      if (!fitRuns.values.length || s.iteration === 1) fitRuns.runs.push(fitRuns.values.length);
      fitRuns.values.push(s.logLikelihood);
    }
    const last = m.steps[m.steps.length - 1];
    // the Stage field names the run of the slice's last step (its stage; Fitter.run: a slice never goes past the
    // end of a run, so every run is named once at least) and its number: one more than the runs finished before
    // it; the plot shows the run in progress now (m.run, the last step's run once the fit is done)
    const before = runsFinished + m.steps.slice(0, -1).filter((s) => s.runFinished).length;
    runsFinished += m.steps.filter((s) => s.runFinished).length;
    if (last) {
      showStep(last, last.stage, before + 1);
      plot.set(m.trace, `${stageText(m.run?.kind && m.run.kind !== 'done' ? m.run : last.stage)}: log-likelihood`);
    }
    if (m.run?.done) $('stage').textContent = FINISHING;
    $('elapsed').textContent = `${(m.elapsedMs / 1000).toFixed(2)} s`;
  });
  subscribe((s, changed) => {
    if (changed.has('pop')) showPopulation(s.pop, s.source);
    if (changed.has('fitId') && s.fitId !== null && s.phase === 'fitting') fitStarted();
    // a model that came with the end of a fit is that fit's (not one shown again after a crash)
    const ended = changed.has('fitId') && s.fitId === null && fitRuns.id === lastFit ? fitRuns : null;
    if (changed.has('model') && s.model) fitEnded(s.model, { runs: ended });
    // a fit that failed or was superseded without a model: the Stage field does not stay at 'starting'
    if (changed.has('fitId') && s.fitId === null && !changed.has('model')) {
      if (s.keptAfter && s.model) fitEnded(s.model, { kept: s.keptAfter });
      else $('stage').textContent = s.model ? 'done' : 'idle';
    }
    if (changed.has('pop') || changed.has('model')) showResult();
    if (s.fitId !== null) lastFit = s.fitId;
  });
}
