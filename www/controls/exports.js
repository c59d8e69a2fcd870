// The export buttons: the model as JSON, the shown meshes as OBJ in the population's original units, and the
// rigged model as binary glTF. Each file comes from the worker (the Rust exporters: src/export/).
import { state, subscribe } from '../state.js';
import { query } from '../session.js';
import { poseName } from '../views/render.js';
import { showProblems } from '../problems.js';
import { eRmsText, percentText, ERMS_UNIT } from '../erms.js';
import { download, safeName, populationStem } from '../download.js';
import { exportPoseObj } from './pose-export.js';

const $ = (id) => document.getElementById(id);

// A cancelled first fit's model stays exportable (someone who stopped a long fit may want what it reached), and
// each button says it writes that partial model: its JSON has "complete": false and no diagnosis, its rig and
// OBJ groups are its parts where it stopped.
// (each button's own tooltip, index.html, when the model is a finished fit)
const TITLES = Object.fromEntries(['export-json', 'export-obj', 'export-gltf'].map((id) => [id, $(id).title]));
const PARTIAL = 'the partial model where the cancelled fit stopped, not a finished fit';

function showButtons() {
  const partial = !!state.model?.summary?.cancelled;
  const tag = partial ? ' (partial)' : '';
  $('export-json').disabled = !state.model;
  $('export-json').textContent = `Model JSON${tag}`;
  $('export-json').title = partial ? `${PARTIAL} ("complete": false, no diagnosis)` : TITLES['export-json'];
  $('export-obj').disabled = !state.pop;
  const n = state.shown.length;
  $('export-obj').textContent = `${n > 1 ? `OBJ of the ${n} shown meshes` : 'OBJ of the shown mesh'}${tag}`;
  $('export-obj').title = partial ? `the shown meshes with the parts of ${PARTIAL} (and its geometry, in the views made from the model)` : TITLES['export-obj'];
  $('export-model').disabled = !state.model;
  $('export-model').textContent = `Save model${tag}`;
  $('export-gltf').disabled = !state.model;
  $('export-gltf').textContent = `glTF (.glb)${tag}`;
  $('export-gltf').title = partial ? `the rig of ${PARTIAL}` : TITLES['export-gltf'];
}

// What each weights choice means (the rig panel's note under its fields): rigid weights put every vertex on one
// bone, so Influences does not apply to them (the field is greyed).
const WEIGHTS_NOTE = {
  rigid: 'Rigid: every vertex moves with one bone, its part\'s (Influences does not apply).',
  smooth: 'Smooth: vertices near a joint blend its two bones, at most Influences bones per vertex.',
  fitted: 'Fitted: weights fitted to the poses, at most Influences bones per vertex.',
};
function showWeights() {
  const f = $('rig').elements;
  const rigid = f.weights.value === 'rigid';
  f.influences.disabled = rigid;
  // a bone's own motion is fitted only with fitted weights and free joints
  f.bones.disabled = f.weights.value !== 'fitted' || f.joints.value !== 'free';
  $('rig-weights-note').textContent = WEIGHTS_NOTE[$('rig').elements.weights.value] ?? '';
  if (rigid) showFieldProblem(null);
}

// The Influences field's problem beside it (null: none), in the core's words (wasm rigFields).
function showFieldProblem(message) {
  const input = $('rig').elements.influences;
  const box = $('rig-influences-problem');
  box.hidden = !message;
  box.textContent = message ? `Influences ${message}.` : '';
  if (message) input.setAttribute('aria-invalid', 'true');
  else input.removeAttribute('aria-invalid');
}

/** The rig options of the export panel ({weights, influences, joints, morphs, bones}: src/export/rig_report.rs),
 * the Influences field checked by the core as typed; null when it cannot be used (said beside the field, which
 * gets the focus). Rigid weights leave it out (one bone per vertex); Bones only with fitted weights and free
 * joints. */
export async function rigOptions({ show = true } = {}) {
  const f = $('rig').elements;
  const opts = { weights: f.weights.value, joints: f.joints.value, morphs: f.morphs.value };
  if (!f.bones.disabled) opts.bones = f.bones.value;
  if (opts.weights === 'rigid') return opts;
  const { problems } = await query('rigFields', { influences: f.influences.value });
  showFieldProblem(problems[0]?.message ?? null);
  if (problems.length) {
    if (!show) return null; // (checked as it is typed: said beside the field, where the person is)
    f.influences.focus({ preventScroll: true });
    $('rig-influences-problem').scrollIntoView({ block: 'center' });
    return null;
  }
  return { ...opts, influences: Number(f.influences.value.trim()) };
}

// What the file's clips are (the core lists them: rig.clips), for the line beside its E_RMS.
const CLIPS = {
  'training poses': '“training poses”, one key per pose',
  interpolated: '“interpolated”, the fit\'s own part-wise interpolation through the poses in order (written for rigid and smooth weights with free joints)',
};

// What a bone's own motion adds to the caption (rigid: nothing).
const BONES = { scale: ', bones that scale', affine: ', affine bones' };

function showRig(r, opts) {
  const out = $('rig-erms');
  // E_RMS (www/erms.js) beside the fit's own figure in the same measure (its rigid parts alone: what rigid weights play)
  const own = state.model?.summary?.eRms;
  const fit = Number.isFinite(own) ? `; the fit's rigid parts alone: ${eRmsText(own)}` : '';
  const per = opts.weights === 'rigid' ? 'one bone per vertex (rigid)' : `at most ${opts.influences} bone${opts.influences === 1 ? '' : 's'} per vertex${BONES[opts.bones] ?? ''}`;
  const clips = r.clips ? `; ${r.clips.length} clip${r.clips.length === 1 ? '' : 's'}: ${r.clips.map((c) => CLIPS[c] ?? `“${c}”`).join('; ')}` : '';
  // (a model file saved with its rig gives it back when these are its options: no weight solve)
  const kept = r.source === 'model file' ? '; the rig kept in the model file' : '';
  out.textContent = `${eRmsText(r.eRms)} (${ERMS_UNIT}; ${r.bones} bones, ${per}; max error ${percentText(r.maxErrorOverDiagonal)} % of the diagonal${fit}${kept}${clips})`;
  out.dataset.clips = (r.clips ?? []).join('|');
  out.dataset.source = r.source ?? '';
  out.dataset.erms = String(r.eRms);
  out.dataset.bones = String(r.bones);
  out.dataset.ms = String(r.rigMs + r.writeMs + r.evaluateMs);
}

// A failed export (the worker could not answer) is listed as a problem; what is shown stays.
const orReport = (f) => async () => {
  try {
    await f();
  } catch (e) {
    showProblems(e.problems ?? [{ file: null, line: null, message: String(e.message ?? e) }], 'The export failed');
  }
};

// The OBJ's file name after the population: what the first mesh shown is of (its pose, or the two poses and t of
// an interpolation) unless the meshes' own names say it ("pose_5", "latent-posed-pose-5"), then those names.
function shownInName(what, names) {
  const named = safeName(names.join('+'));
  if (what.kind === 'interpolation' || what.kind === 'linear') {
    return `${safeName(poseName(what.from))}-to-${safeName(poseName(what.to))}-t${what.t.toFixed(2)}-${named}`;
  }
  const pose = Number.isInteger(what.pose) && !what.kind.startsWith('latent') ? safeName(poseName(what.pose)) : '';
  return pose && !named.includes(pose) ? `${pose}-${named}` : named;
}

export function installExports() {
  $('export-json').addEventListener('click', orReport(async () => download(`posemfa-${populationStem()}-model.json`, await query('toJson'), 'application/json')));
  // The core writes what the view shows, in the population's original units, exact floats: every mesh shown
  // side by side as one OBJ object named for what it is (original | reconstruction, coarse | refined | final...),
  // a mesh coloured by parts with one group per part of that stage.
  // In the Pose view the mesh shown is the poser's (a pose made, or an added frame): it writes that (pose-export.js).
  $('export-obj').addEventListener('click', orReport(async () => {
    if (state.mode === 'pose') return exportPoseObj();
    const slots = state.shown;
    if (!slots.length) return;
    const names = slots.map((x) => x.name);
    const name = `posemfa-${populationStem()}-${shownInName(slots[0].what, names)}.obj`;
    const header = `${$('caption').textContent}\nobjects: ${names.join(', ')}\nposemfa, ${state.pop.nVertices} vertices and ${state.pop.faces.length / 3} triangles per object`;
    const meshes = slots.map((x) => ({ name: x.name, what: x.what, parts: state.model ? x.parts ?? null : null }));
    download(name, await query('objScene', meshes, header), 'model/obj');
  }));
  // The rig as chosen in the panel, built, written and measured by the core (the same as `posemfa export-gltf` and
  // `posemfa rig-report`); its E_RMS is shown with the file.
  $('export-gltf').addEventListener('click', orReport(async () => {
    const opts = await rigOptions();
    if (!opts) {
      // refused at the field (said beside it): nothing is being made
      $('rig-erms').textContent = '– (no file: see Influences above)';
      delete $('rig-erms').dataset.erms;
      return;
    }
    $('rig-erms').textContent = '…';
    let r;
    try {
      r = await query('rig', opts);
    } catch (e) {
      $('rig-erms').textContent = '– (the export failed: see the message at the top of the panel)';
      throw e;
    }
    showRig(r, opts);
    const extras = `${opts.joints === 'fixed' ? '-fixed-joints' : ''}${opts.morphs !== 'none' ? `-${opts.morphs}-morphs` : ''}${opts.bones && opts.bones !== 'rigid' ? `-${opts.bones}-bones` : ''}`;
    download(`posemfa-${populationStem()}-rig-${opts.weights}-${r.bones}bones${extras}.glb`, r.glb, 'model/gltf-binary');
  }));
  // The fit as a model file (src/model_file.rs): the page, the embed and `posemfa --model` open it without fitting.
  $('export-model').addEventListener('click', orReport(async () => {
    const without = $('model-without-poses').checked || state.model.summary.hasData === false;
    const bytes = await query('save', !without);
    download(`posemfa-${populationStem()}${without ? '-without-poses' : ''}.posemfa`, bytes, 'application/octet-stream');
  }));
  $('rig').addEventListener('change', () => {
    $('rig-erms').textContent = '–';
    delete $('rig-erms').dataset.erms;
    showWeights();
  });
  // a value typed is checked as it is typed, beside the field (the glTF button checks it again)
  $('rig').elements.influences.addEventListener('input', () => { rigOptions({ show: false }).catch(() => {}); });
  showWeights();
  subscribe((s, changed) => {
    if (changed.has('pop') || changed.has('model') || changed.has('phase') || changed.has('shown')) showButtons();
    if (changed.has('model')) {
      $('rig-erms').textContent = '–';
      delete $('rig-erms').dataset.erms;
    }
  });
}
