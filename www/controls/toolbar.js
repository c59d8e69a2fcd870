// The view toolbar: the mode (parts, stages, reconstruction, latent, interpolation, ground truth), flat
// colours, and the camera's reset; under it, how the latent view places the parts.
import { state, update, subscribe } from '../state.js';
import { viewer } from '../views/viewer-instance.js';
import { renderView } from '../views/render.js';

const $ = (id) => document.getElementById(id);
const radio = (mode) => document.querySelector(`#modes input[value=${mode}]`);

export function installToolbar() {
  for (const r of document.querySelectorAll('input[name=mode]')) r.addEventListener('change', () => update({ mode: r.value }));
  $('flat').addEventListener('change', (e) => viewer.setFlat(e.target.checked));
  $('reset-view').addEventListener('click', () => viewer.reset());
  $('latent-place').addEventListener('change', () => renderView({ frame: true }));
  subscribe((s, changed) => {
    if (changed.has('pop')) radio('truth').parentElement.hidden = !s.pop.truth;
    if (changed.has('mode')) {
      radio(s.mode).checked = true;
      $('interp').hidden = s.mode !== 'interp';
      $('latent-opts').hidden = s.mode !== 'latent';
    }
  });
  // the mode the page starts with
  radio(state.mode).checked = true;
  $('latent-opts').hidden = state.mode !== 'latent';
}
