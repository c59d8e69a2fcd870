// Interpolation between two poses: From / To, t (slider and Play), side by side with linear blending, the
// skinning and the eq 24 residual, and "Measure at this t" (the core's articulation report).
import { state, subscribe } from '../state.js';
import { query } from '../session.js';
import { renderView, poseName } from '../views/render.js';
import { interpValues } from './interp-values.js';

const $ = (id) => document.getElementById(id);
const play = { playing: false, last: 0, dir: 1 };

function onInput() {
  $('report').replaceChildren();
  $('interp-t-out').textContent = Number($('interp-t').value).toFixed(2);
  if (state.mode === 'interp') renderView();
}

function updateNote() {
  const partwise = !!state.model;
  for (const id of ['side-by-side', 'interp-skin', 'interp-residual', 'measure']) $(id).disabled = !partwise;
  $('interp-note').textContent = partwise ? '' : 'Linear vertex blending until the fit ends; then the part-wise interpolation.';
  $('report').replaceChildren();
}

// The core's figures of every interpolation method at this t: volume change and edge stretch.
async function measure() {
  const { a, b, t } = interpValues();
  $('report').textContent = 'measuring…';
  let r;
  try {
    r = await query('articulationReport', a, b, t);
  } catch (e) {
    $('report').textContent = e.message;
    return;
  }
  const pct = (x) => `${(100 * x).toFixed(1)} %`;
  const table = document.createElement('table');
  const head = document.createElement('tr');
  // what each figure is measured against (src/articulate/report.rs), in a column and the key under the table: the
  // stretch against the training poses' edges, the end error against the training poses or, with the residual
  // off, their rigid reconstruction
  for (const h of ['method', 'volume change', 'edge stretch p99 (boundary)', 'largest stretch', 'error at t=0 / t=1', 'error measured against']) {
    head.append(Object.assign(document.createElement('th'), { textContent: h }));
  }
  table.append(head);
  for (const m of r.methods) {
    const tr = document.createElement('tr');
    // the core's target of the end error: the training shapes, or with the residual off their rigid reconstruction
    const against = m.options && !m.options.residual ? 'rigid reconstruction (eq 22)' : 'training poses';
    for (const c of [m.name, pct(m.volumeChange), pct(m.stretch.boundaryP99), pct(m.stretch.allMax),
      m.endpointError.map((e) => e.toExponential(1)).join(' / '), against]) {
      tr.append(Object.assign(document.createElement('td'), { textContent: c }));
    }
    table.append(tr);
  }
  const cap = document.createElement('div');
  cap.textContent = `“${poseName(a)}” → “${poseName(b)}” at t = ${t.toFixed(2)}; volume relative to (1-t)·V(from) + t·V(to); errors in unit-box units`;
  const key = document.createElement('p');
  key.className = 'report-key';
  key.textContent = 'Edge stretch: every edge\'s length at t against (1-t)·L(from) + t·L(to), its lengths in the two training poses. '
    + 'Error at t=0 / t=1: the largest vertex distance from the ends to what the method is meant to reproduce, the training poses, or with the residual off '
    + 'their rigid reconstruction (eq 22). So a rigid row with the residual off can end exactly (error near 0) on a reconstruction whose joints still '
    + 'stretch the training poses\' edges.';
  // what the stretch figures mean (src/articulate/report.rs): 0 % keeps every edge at its mixed length
  const reading = document.createElement('p');
  reading.className = 'report-reading';
  reading.dataset.testid = 'report-reading';
  reading.textContent = 'Reading the stretch: 0 % is every edge at exactly its mixed length, which is what a rigid motion gives inside a part that is rigid in the training poses. '
    + 'Large figures on the edges crossing a part boundary (the p99 column) are where rigid parts pull apart or overlap at a joint, with no skinning to blend '
    + 'them: compare the smooth-skin rows.';
  const box = Object.assign(document.createElement('div'), { className: 'report-table' });
  box.append(table);
  $('report').replaceChildren(cap, box, reading, key);
}

function stopPlay() {
  play.playing = false;
  $('play').textContent = 'Play';
}

// Play runs t back and forth between 0 and 1 in 2 s.
function startPlay() {
  if (play.playing) return stopPlay();
  play.playing = true;
  play.last = performance.now();
  $('play').textContent = 'Pause';
  const tick = async (now) => {
    if (!play.playing) return;
    const slider = $('interp-t');
    let t = Number(slider.value) + (play.dir * (now - play.last)) / 2000;
    play.last = now;
    if (t >= 1 || t <= 0) {
      play.dir *= -1;
      t = Math.min(Math.max(t, 0), 1);
    }
    slider.value = t;
    $('interp-t-out').textContent = t.toFixed(2);
    await renderView();
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}

export function installInterp() {
  for (const id of ['pose-a', 'pose-b', 'interp-t', 'interp-skin', 'interp-residual']) $(id).addEventListener('input', onInput);
  $('side-by-side').addEventListener('change', () => renderView({ frame: true }));
  $('measure').addEventListener('click', measure);
  $('play').addEventListener('click', startPlay);
  subscribe((s, changed) => {
    if (changed.has('mode') && s.mode !== 'interp') stopPlay();
    if (changed.has('pop') || changed.has('model')) updateNote();
  });
  updateNote();
}
