// The export buttons: the model as JSON, the shown mesh as OBJ in the population's original units, and the
// rigged model as binary glTF. Each file comes from the worker (the Rust exporters).
import { state, subscribe } from '../state.js';
import { query } from '../session.js';
import { poseName } from '../views/render.js';
import { interpValues } from './interp.js';
import { showProblems } from '../problems.js';

const $ = (id) => document.getElementById(id);

function download(name, data, type) {
  const url = URL.createObjectURL(new Blob([data], { type }));
  const a = Object.assign(document.createElement('a'), { href: url, download: name });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

// OBJ text of a unit-box mesh, written back in the population's original units: original = unit / scale + offset.
function objText(positions, faces, normalization, comment) {
  const [ox, oy, oz, s] = normalization;
  const lines = [`# ${comment}`, `# posemfa, ${positions.length / 3} vertices, ${faces.length / 3} triangles`];
  const num = (x) => String(Number(x.toPrecision(9)));
  for (let k = 0; k < positions.length; k += 3) {
    lines.push(`v ${num(positions[k] / s + ox)} ${num(positions[k + 1] / s + oy)} ${num(positions[k + 2] / s + oz)}`);
  }
  for (let k = 0; k < faces.length; k += 3) lines.push(`f ${faces[k] + 1} ${faces[k + 1] + 1} ${faces[k + 2] + 1}`);
  return lines.join('\n') + '\n';
}

const safeName = (s) => s.replace(/\.obj$/i, '').replace(/[^A-Za-z0-9._-]+/g, '_');

function showButtons() {
  $('export-json').disabled = !state.model;
  $('export-obj').disabled = !state.pop;
  $('export-gltf').disabled = !state.model;
}

// A failed export (the worker could not answer) is listed as a problem; what is shown stays.
const orReport = (f) => async () => {
  try {
    await f();
  } catch (e) {
    showProblems(e.problems ?? [{ file: null, line: null, message: String(e.message ?? e) }], 'The export failed');
  }
};

export function installExports() {
  $('export-json').addEventListener('click', orReport(async () => download('posemfa-model.json', await query('toJson'), 'application/json')));
  $('export-obj').addEventListener('click', () => {
    const slot = state.shown[0];
    if (!slot) return;
    const what = state.mode === 'interp' ? `${slot.name} interpolation t=${interpValues().t}` : `${slot.name}`;
    const name = `posemfa-${safeName(poseName(state.pose))}-${safeName(what)}.obj`;
    download(name, objText(slot.positions, state.pop.faces, state.pop.normalization, what), 'model/obj');
  });
  $('export-gltf').addEventListener('click', orReport(async () => {
    const skin = $('interp-skin').value; // the skinning chosen for the interpolation
    download(`posemfa-model-${skin}.glb`, await query('toGlb', skin), 'model/gltf-binary');
  }));
  subscribe((s, changed) => {
    if (changed.has('pop') || changed.has('model') || changed.has('phase')) showButtons();
  });
}
