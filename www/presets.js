// The preset list: every built-in example of the core (posemfa::synth::presets) with its one line of what to
// notice, the ones that fail on purpose marked so; a click generates and fits it.
import './teach.css';
import { subscribe } from './state.js';

/** runExample(example): what a click on a preset does. */
export function installPresets(runExample) {
  const $ = (id) => document.getElementById(id);

  function render(examples) {
    $('presets-box').hidden = !examples.length;
    $('presets').replaceChildren(...examples.map((ex) => {
      const li = document.createElement('li');
      li.classList.toggle('fails', ex.failsOnPurpose);
      const b = document.createElement('button');
      b.type = 'button';
      b.dataset.id = ex.id;
      b.textContent = ex.title.replace(/^Fails on purpose: /, '');
      b.addEventListener('click', () => runExample(ex));
      const note = document.createElement('span');
      note.className = 'note';
      note.textContent = ex.note; // one line; all of it on hover or focus, and its title
      note.title = ex.note;
      li.append(b, note);
      return li;
    }));
  }

  function mark(id) {
    for (const b of $('presets').querySelectorAll('button')) b.setAttribute('aria-current', String(b.dataset.id === id));
  }

  subscribe((s, changed) => {
    if (changed.has('examples')) render(s.examples);
    if (changed.has('pop')) mark(s.source?.example?.id ?? null);
  });
}
