// The fit form: parameters in and out (the core's defaults fill it), Fit, Cancel, Defaults, and the example
// picker in the header (Generate & fit). The core checks the form's fields (wasm formParams, the same words as
// the CLI's): a field it cannot use is outlined and named with what it allows, and no fit starts until it is
// fixed; the message goes as soon as the value is fixed or Defaults is pressed.
import { state, subscribe } from '../state.js';

const $ = (id) => document.getElementById(id);
const form = () => $('params').elements;
const TEXT_FIELDS = ['parts', 'targetParts', 'seed', 'tol', 'varianceFloor'];

let checker = null; // (base, fields, vertices) => Promise<{ params, problems: [{ field, message }] }> (the core's check)
let checking = Promise.resolve(null);
let checkedFor = null; // the vertex count of the population the last check was for (null: none known)

/** Shows fit parameters in the form (and clears the marks of fields the core refused). */
export function fillParams(p) {
  const f = form();
  f.parts.value = p.parts;
  f.targetParts.value = p.targetParts ?? '';
  f.seed.value = p.seed;
  f.tol.value = p.tol;
  f.varianceFloor.value = p.varianceFloor;
  f.paperLambda.checked = p.lambdaRule === 'paper-eq18';
  f.refine.checked = p.refine;
  checking = Promise.resolve(null); // a check still in flight is of the old values
  showFieldProblems([]);
  showStartUse();
  showFitCount();
}

/** The Fit button says the count a fit will be made to, while "Parts in the end" holds one (typed, a link's, or
 * a Refine's, which stays for later fits): "Fit 8 parts"; plain "Fit" for the part rule's own count. */
export function showFitCount() {
  const n = bones(form().targetParts.value);
  $('fit').textContent = Number.isInteger(n) ? `Fit ${n} part${n === 1 ? '' : 's'}` : 'Fit';
  $('fit').title = Number.isInteger(n) ? `exactly ${n} as “Parts in the end” asks; empty it (auto) for the part rule's own count` : '';
}

/** Sets "Parts in the end" (the merge tree's Refine). */
export function setTargetParts(n) {
  form().targetParts.value = String(n);
  showFitCount();
}

/** Whether Fit ignores Initial parts and Seed: the merge tree (the default part rule, with the refinement on)
 * starts from its own patches, with no random draw and its own count (src/parts/hierarchy.rs). Step by step
 * always runs Algorithm 1, which uses both. */
const fitIgnoresStart = () => (state.baseParams?.partRule ?? 'tree') === 'tree' && form().refine.checked;

// The two fields greyed (still editable: Step by step uses them) with a line under them saying so, while Fit
// ignores them.
function showStartUse() {
  const ignored = fitIgnoresStart();
  for (const name of ['parts', 'seed']) form()[name].closest('label').classList.toggle('ignored', ignored);
  $('parts-note').hidden = !ignored;
}

/** A new population (files opened or dropped) starts from the defaults of the settings that change what is
 * fitted rather than how closely: "Parts in the end" (a count the last population's Refine N set or the user
 * typed for it) and the paper's literal Λ step (an example's). Seed, tolerance and the rest stay as typed. Called
 * once the core has accepted the files (session.js onLoaded): a refused drop leaves the form as it was. */
export function resetForNewPopulation(defaults) {
  const f = form();
  f.targetParts.value = defaults.targetParts ?? '';
  f.paperLambda.checked = defaults.lambdaRule === 'paper-eq18';
  showFitCount();
}

// "Parts in the end": empty or auto = the part rule's own count (null); a whole number as a number; anything else
// goes as typed (checkedParams refuses it before a fit).
const bones = (v) => {
  const t = v.trim();
  if (t === '' || t.toLowerCase() === 'auto') return null;
  return /^\d+$/.test(t) ? Number(t) : t;
};

// The form's check boxes over the hidden parameters (state.baseParams). fresh: the defaults a new population
// starts from (resetForNewPopulation), read without writing them into the form.
const base = (fresh = null) => ({
  ...(fresh ?? state.baseParams),
  lambdaRule: (fresh ? fresh.lambdaRule === 'paper-eq18' : form().paperLambda.checked) ? 'paper-eq18' : 'exact',
  refine: form().refine.checked,
});

/** The fit parameters as the form shows them, unchecked (for the link; a fit uses checkedParams). */
export function readParams() {
  const f = form();
  return {
    ...base(),
    parts: Number(f.parts.value),
    targetParts: bones(f.targetParts.value),
    seed: Number(f.seed.value),
    tol: Number(f.tol.value),
    varianceFloor: Number(f.varianceFloor.value),
  };
}

const labelOf = (name) => form()[name].closest('label').firstChild.textContent.trim();

// Every field the core refused: outlined (aria-invalid), and one line under the form naming it.
function showFieldProblems(problems) {
  const f = form();
  for (const name of TEXT_FIELDS) {
    const bad = problems.some((p) => p.field === name);
    f[name].classList.toggle('invalid', bad);
    if (bad) f[name].setAttribute('aria-invalid', 'true');
    else f[name].removeAttribute('aria-invalid');
  }
  const box = $('param-errors');
  box.replaceChildren(...problems.map((p) => {
    const li = document.createElement('li');
    li.dataset.field = p.field;
    li.textContent = `${TEXT_FIELDS.includes(p.field) ? labelOf(p.field) : p.field}: ${p.message}`;
    return li;
  }));
  $('params').dataset.invalid = problems.length ? '1' : '';
}

/** The core's check of the form (the latest one asked); shows what it refuses. Resolves to the parameters, or
 * null when a field cannot be used. `vertices`: the vertex count of the population to fit, when it is known
 * (the core then refuses more parts than it can hold). `fresh`: the defaults (state.defaults) for the fit of a
 * new population: the hidden parameters, "Parts in the end" and the Λ step as resetForNewPopulation sets them,
 * the other fields as typed; the form is not changed (it is, once the population is accepted). */
export function checkedParams({ vertices = null, fresh = null } = {}) {
  if (!checker) return Promise.resolve(fresh ? { ...readParams(), ...base(fresh), targetParts: fresh.targetParts ?? null } : readParams());
  checkedFor = vertices;
  const fields = Object.fromEntries(TEXT_FIELDS.map((n) => [n, String(form()[n].value)]));
  if (fresh) fields.targetParts = String(fresh.targetParts ?? '');
  // a number field holding text that is no number reads as empty (the browser keeps the text to itself): the
  // core's "is empty" would contradict what the user sees
  const unreadable = (name) => form()[name].validity?.badInput;
  const mine = checker(base(fresh), fields, vertices).then((r) => {
    const problems = r.problems.map((p) => (unreadable(p.field) ? { ...p, message: p.message.replace(/^is empty:/, 'is not a number:') } : p));
    if (mine === checking) showFieldProblems(problems);
    return r.params;
  });
  checking = mine;
  return mine;
}

/** actions: { startFit, cancelFit, runExample, check }. */
export function installForm({ startFit, cancelFit, runExample, check }) {
  checker = check;
  $('params').addEventListener('submit', (e) => {
    e.preventDefault();
    startFit();
  });
  // a refused field is checked again as it is typed: its mark goes as soon as it is fixed
  $('params').addEventListener('input', (e) => {
    if (e.target.name === 'targetParts') showFitCount();
    if (TEXT_FIELDS.includes(e.target.name) && $('params').dataset.invalid) checkedParams({ vertices: checkedFor });
  });
  // and a field is checked as soon as it is left changed, not only when Fit is pressed
  $('params').addEventListener('change', (e) => {
    if (TEXT_FIELDS.includes(e.target.name)) checkedParams({ vertices: state.pop?.nVertices ?? null });
  });
  $('params').elements.refine.addEventListener('change', showStartUse);
  $('cancel').addEventListener('click', cancelFit);
  $('reset-params').addEventListener('click', () => state.baseParams && fillParams(state.baseParams));
  $('generate').addEventListener('click', () => {
    const ex = state.examples.find((e) => e.id === $('example').value);
    if (ex) runExample(ex);
  });
  $('example').addEventListener('change', showPicked);
  subscribe((s, changed) => {
    if (changed.has('pop')) showSource(s.source);
    if (changed.has('baseParams')) showStartUse();
  });
  showStartUse();
}

// The picker says what is shown: the example's name, or "your files" / "a generated population" (an entry that
// cannot be picked), so that it never names an example that is not shown. Generate & fit needs an example.
const OTHER = '-shown-';
function showSource(source) {
  const other = $('example').querySelector(`option[value="${OTHER}"]`);
  if (!other) return;
  other.hidden = !!source?.example || !source;
  other.textContent = source?.spec ? 'a generated population' : 'your files';
  $('example').value = source?.example?.id ?? (source ? OTHER : $('example').value);
  showPicked();
}
const showPicked = () => {
  $('generate').disabled = $('example').value === OTHER;
  // the whole title on hover, where a narrow window cuts the select's text
  $('example').title = $('example').selectedOptions[0]?.textContent ?? '';
};

/** The example picker, filled when the core's examples are known. */
export function showExamples(examples) {
  document.querySelector('.generate').hidden = !examples.length;
  const other = Object.assign(document.createElement('option'), { value: OTHER, disabled: true, hidden: true, textContent: 'your files' });
  $('example').replaceChildren(other, ...examples.map((e) => Object.assign(document.createElement('option'), { value: e.id, textContent: e.title, title: e.title })));
  $('example').value = state.source?.example?.id ?? examples[0]?.id ?? '';
  showSource(state.source);
}
