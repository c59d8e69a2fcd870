// The fit form: parameters in and out (the core's defaults fill it), Fit, Cancel, Defaults, and the example
// picker in the header (Generate & fit).
import { state } from '../state.js';

const $ = (id) => document.getElementById(id);
const form = () => $('params').elements;

/** Shows fit parameters in the form. */
export function fillParams(p) {
  const f = form();
  f.parts.value = p.parts;
  f.targetParts.value = p.targetParts ?? '';
  f.seed.value = p.seed;
  f.tol.value = p.tol;
  f.varianceFloor.value = p.varianceFloor;
  f.paperLambda.checked = p.lambdaRule === 'paper-eq18';
  f.refine.checked = p.refine;
}

// "Parts in the end": empty or auto = Algorithm 1's own count (null); a whole number as a number; anything else
// goes as typed, and the core refuses it with a message naming targetParts.
const bones = (v) => {
  const t = v.trim();
  if (t === '' || t.toLowerCase() === 'auto') return null;
  return /^\d+$/.test(t) ? Number(t) : t;
};

/** The fit parameters: the form's over the hidden ones (state.baseParams). */
export function readParams() {
  const f = form();
  return {
    ...state.baseParams,
    parts: Number(f.parts.value),
    targetParts: bones(f.targetParts.value),
    seed: Number(f.seed.value),
    tol: Number(f.tol.value),
    varianceFloor: Number(f.varianceFloor.value),
    lambdaRule: f.paperLambda.checked ? 'paper-eq18' : 'exact',
    refine: f.refine.checked,
  };
}

/** actions: { startFit, cancelFit, runExample }. */
export function installForm({ startFit, cancelFit, runExample }) {
  $('params').addEventListener('submit', (e) => {
    e.preventDefault();
    startFit();
  });
  $('cancel').addEventListener('click', cancelFit);
  $('reset-params').addEventListener('click', () => state.baseParams && fillParams(state.baseParams));
  $('generate').addEventListener('click', () => runExample(state.examples.find((e) => e.id === $('example').value)));
}

/** The example picker, filled when the core's examples are known. */
export function showExamples(examples) {
  document.querySelector('.generate').hidden = !examples.length;
  $('example').replaceChildren(...examples.map((e) => Object.assign(document.createElement('option'), { value: e.id, textContent: e.title })));
}
