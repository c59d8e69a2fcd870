// The pose list and the thumbnail strip (arrow keys step through it); the interpolation's From / To lists.
import { state, update, subscribe } from '../state.js';
import { viewer } from '../views/viewer-instance.js';
import { thumbnailColours } from '../views/render.js';
import { showTrainingPose } from './pose.js';

const $ = (id) => document.getElementById(id);

// The strip's label of each pose: the file's own name (the full path is in the title); the poses of one file
// (a glTF's, FBX's or USD's frames: "character.glb frame 012") by what tells them apart ("frame 012").
function stripLabels(names) {
  const file = /^(.+?\.[A-Za-z0-9]+) ./.exec(names[0] ?? '')?.[1];
  const oneFile = file && names.length > 1 && names.every((n) => n.startsWith(`${file} `));
  return names.map((n) => (oneFile ? n.slice(file.length + 1) : n.split('/').pop()));
}

function fillPoseLists(names) {
  const opts = () => names.map((n, i) => Object.assign(document.createElement('option'), { value: i, textContent: n }));
  $('pose-select').replaceChildren(...opts());
  $('pose-a').replaceChildren(...opts());
  $('pose-b').replaceChildren(...opts());
  $('pose-a').value = 0;
  $('pose-b').value = Math.min(1, names.length - 1);
  const labels = stripLabels(names);
  $('pose-strip').replaceChildren(...names.map((n, i) => {
    const b = document.createElement('button');
    b.type = 'button';
    b.title = n;
    b.setAttribute('aria-pressed', String(i === state.pose));
    b.setAttribute('aria-label', `pose ${n}`);
    const c = document.createElement('canvas');
    c.width = 160;
    c.height = 120;
    const label = document.createElement('span');
    label.textContent = labels[i];
    b.append(c, label);
    b.addEventListener('click', () => choosePose(i));
    return b;
  }));
}

/** Shows pose i; in the Pose view, as the rig makes it (the view shows the rig's poses, not the files'). */
export const choosePose = (i) => {
  update({ pose: i, hoverPart: null });
  if (state.mode === 'pose') showTrainingPose(i);
};

// The pose shown is marked in the strip; in pose mode none is (the view shows a pose made from the rig, not a
// training pose).
// In the Interpolate view the From / To lists choose the poses shown: the strip marks those two and waits.
function showPose(i) {
  $('pose-select').value = i;
  const made = state.mode === 'pose';
  const interp = state.mode === 'interp';
  const ends = interp ? [Number($('pose-a').value), Number($('pose-b').value)] : [];
  $('pose-strip').title = interp ? 'the Interpolate view shows the poses chosen in From and To above' : '';
  [...$('pose-strip').children].forEach((b, k) => {
    b.disabled = interp;
    b.setAttribute('aria-pressed', String(interp ? ends.includes(k) : !made && k === i));
  });
}

let thumbsToken = 0;
let drawnWith = null; // the colours the thumbnails were drawn with
// Thumbnails recoloured by the merge tree's slider wait until it has been still this long: each costs a render
// and a read-back, and drawn during a drag they held up the main view's next partition (20-50 ms a move on
// horse-poses, where a thumbnail costs 35-165 ms in software WebGL).
const STILL_MS = 300;
let stillTimer = 0;
function drawThumbnailsWhenStill() {
  thumbsToken++; // a drawing in progress stops
  clearTimeout(stillTimer);
  stillTimer = setTimeout(drawThumbnails, STILL_MS);
}
function drawThumbnails() {
  clearTimeout(stillTimer);
  const token = ++thumbsToken;
  const canvases = [...$('pose-strip').querySelectorAll('canvas')];
  const colours = thumbnailColours();
  drawnWith = colours;
  // the population drawn: a drop while the strip is drawn (a minute for 399 frames in software WebGL) ends this
  // drawing, whose canvases, positions and colours are the old population's (the viewer has the new faces)
  const pop = state.pop;
  let i = 0;
  const next = () => {
    if (token !== thumbsToken || state.pop !== pop || !pop) return;
    if (i >= canvases.length) {
      $('pose-strip').dataset.drawn = String(token); // every thumbnail drawn (for the tests)
      return;
    }
    viewer.thumbnail(pop.positions[i], colours, canvases[i]);
    i++;
    setTimeout(next, 0);
  };
  next();
}

export function installPoses() {
  $('pose-select').addEventListener('change', (e) => choosePose(Number(e.target.value)));
  for (const id of ['pose-a', 'pose-b']) $(id).addEventListener('change', () => showPose(state.pose));
  $('pose-strip').addEventListener('keydown', (e) => {
    const step = { ArrowLeft: -1, ArrowRight: 1 }[e.key];
    if (!step || !state.pop) return;
    e.preventDefault();
    const i = (state.pose + step + state.pop.nShapes) % state.pop.nShapes;
    choosePose(i);
    $('pose-strip').children[i].focus();
  });
  subscribe((s, changed) => {
    if (changed.has('pop')) {
      thumbsToken++; // the old population's drawing stops (its strip is gone)
      fillPoseLists(s.pop.names);
    }
    if (changed.has('pose') || changed.has('mode') || changed.has('pop')) showPose(s.pose);
    if (changed.has('model') && s.model) setTimeout(drawThumbnails, 0);
    // the merge tree's slider recolours the main view: the thumbnails follow (and go back with it)
    else if (s.model && ['treeParts', 'mode', 'colours'].some((k) => changed.has(k)) && thumbnailColours() !== drawnWith) {
      if (changed.has('treeParts')) drawThumbnailsWhenStill();
      else drawThumbnails();
    }
  });
}
