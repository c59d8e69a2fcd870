// The page's whole state in location.hash, so that reloading or sharing the link restores it, and the
// embedding flags. Keys (all optional; in this order when written):
//
//   ex=ID                      a built-in example (posemfa::synth::presets), or
//   gen=PRESET,VERTICES,POSES,SEED   a generated population, or
//   src=files                  opened or dropped files (not in the link: the default example is shown), or
//   src=URL                    a file fetched from URL (a model file .posemfa, a .zip of poses, a .glb...;
//                              www/fetch-source.js): a shared link fetches it again
//   parts, bones=N|auto, seed, tol, floor, lambda=exact|paper-eq18, refine=0|1   fit parameters (the form's;
//                              bones: "Parts in the end", targetParts; absent = auto, the part rule's own count)
//   cut=N                      the parts were refined from the N-part partition of that fit's merge tree
//                              ("Refine N parts"): the link makes the fit, then the Refine
//   teach=N, stage=coarse|refine|final   a teaching fit N steps in (and the Algorithm 1 stage it was in): the
//                              link opens on the same step (the steps are deterministic)
//   view=parts|stages|recon|latent|interp|pose|truth   flat=0|1   pose=I (0-based)
//   a=I, b=J, t=0..1, side=0|1, skin=rigid|smooth, residual=0|1     interpolation
//   cam=PX,PY,PZ,TX,TY,TZ      camera position and target (exact numbers)
//   embed=1                    minimal view for an iframe (hides header, panel, toolbar, poses, interpolation
//                              controls, the pose panel: parts are still dragged on the mesh); hide=NAME,...
//                              hides more; show=NAME,... brings some back. Names: header, panel, toolbar, modes,
//                              caption, poses, interp, posepanel, info, presets, teach
import './embed.css';
import { state, subscribe } from './state.js';

export const CONTROLS = ['header', 'panel', 'toolbar', 'modes', 'caption', 'poses', 'interp', 'posepanel', 'info', 'presets', 'teach'];
const EMBED_HIDES = ['header', 'panel', 'toolbar', 'poses', 'interp', 'posepanel'];
const MODES = ['parts', 'stages', 'recon', 'latent', 'interp', 'pose', 'truth'];
const STAGES = ['coarse', 'refine', 'final', 'done'];
const ORDER = ['ex', 'gen', 'src', 'parts', 'bones', 'seed', 'tol', 'floor', 'lambda', 'refine', 'cut', 'teach', 'stage', 'view', 'flat', 'pose', 'a', 'b', 't', 'side', 'skin', 'residual', 'cam', 'embed', 'hide', 'show'];

const num = (v) => (v === null || v === undefined || v === '' || !Number.isFinite(Number(v)) ? undefined : Number(v));
const bool = (v) => (v === '1' ? true : v === '0' ? false : undefined);
const list = (v) => (v ? v.split(',').filter((x) => CONTROLS.includes(x)) : []);

/** The state written in a hash string ("#..." or "..."), as a plain object (absent keys left out). */
export function parseHash(hash) {
  const q = new URLSearchParams(String(hash).replace(/^#/, ''));
  const s = {};
  if (q.has('ex')) s.ex = q.get('ex');
  if (q.has('gen')) {
    const [preset, vertices, poses, seed] = q.get('gen').split(',');
    s.gen = { preset, vertices: num(vertices) ?? 2500, poses: num(poses) ?? 8, seed: num(seed) ?? 0 };
  }
  if (q.get('src')) s.src = q.get('src') === 'files' ? 'files' : q.get('src');
  const params = {};
  if (num(q.get('parts')) !== undefined) params.parts = num(q.get('parts'));
  if (q.get('bones') === 'auto') params.targetParts = null;
  else if (Number.isInteger(num(q.get('bones')))) params.targetParts = num(q.get('bones'));
  if (num(q.get('seed')) !== undefined) params.seed = num(q.get('seed'));
  if (num(q.get('tol')) !== undefined) params.tol = num(q.get('tol'));
  if (num(q.get('floor')) !== undefined) params.varianceFloor = num(q.get('floor'));
  if (['exact', 'paper-eq18'].includes(q.get('lambda'))) params.lambdaRule = q.get('lambda');
  if (bool(q.get('refine')) !== undefined) params.refine = bool(q.get('refine'));
  if (Object.keys(params).length) s.params = params;
  const cut = num(q.get('cut'));
  if (Number.isInteger(cut) && cut >= 1) s.cut = cut;
  const steps = num(q.get('teach'));
  if (steps !== undefined && Number.isInteger(steps) && steps >= 1) {
    s.teach = { steps, stage: STAGES.includes(q.get('stage')) ? q.get('stage') : undefined };
  }
  const view = {};
  if (MODES.includes(q.get('view'))) view.mode = q.get('view');
  if (bool(q.get('flat')) !== undefined) view.flat = bool(q.get('flat'));
  for (const k of ['pose', 'a', 'b', 't']) if (num(q.get(k)) !== undefined) view[k] = num(q.get(k));
  if (bool(q.get('side')) !== undefined) view.side = bool(q.get('side'));
  if (['rigid', 'smooth'].includes(q.get('skin'))) view.skin = q.get('skin');
  if (bool(q.get('residual')) !== undefined) view.residual = bool(q.get('residual'));
  const cam = (q.get('cam') ?? '').split(',').map(Number);
  if (cam.length === 6 && cam.every(Number.isFinite)) view.cam = cam;
  if (Object.keys(view).length) s.view = view;
  if (q.get('embed') === '1') s.embed = true;
  if (list(q.get('hide')).length) s.hide = list(q.get('hide'));
  if (list(q.get('show')).length) s.show = list(q.get('show'));
  return s;
}

/** The hash string (without "#") of a state object as parseHash returns it. */
export function formatHash(s) {
  const q = {};
  if (s.ex) q.ex = s.ex;
  if (s.gen) q.gen = [s.gen.preset, s.gen.vertices, s.gen.poses, s.gen.seed].join(',');
  if (s.src) q.src = s.src;
  const p = s.params ?? {};
  if (p.parts !== undefined) q.parts = p.parts;
  if (Number.isInteger(p.targetParts)) q.bones = p.targetParts; // auto (null) is the default: left out
  if (p.seed !== undefined) q.seed = p.seed;
  if (p.tol !== undefined) q.tol = p.tol;
  if (p.varianceFloor !== undefined) q.floor = p.varianceFloor;
  if (p.lambdaRule !== undefined) q.lambda = p.lambdaRule;
  if (p.refine !== undefined) q.refine = p.refine ? 1 : 0;
  if (s.cut) q.cut = s.cut;
  if (s.teach) {
    q.teach = s.teach.steps;
    if (s.teach.stage) q.stage = s.teach.stage;
  }
  const v = s.view ?? {};
  if (v.mode) q.view = v.mode;
  if (v.flat !== undefined) q.flat = v.flat ? 1 : 0;
  for (const k of ['pose', 'a', 'b', 't']) if (v[k] !== undefined) q[k] = v[k];
  if (v.side !== undefined) q.side = v.side ? 1 : 0;
  if (v.skin) q.skin = v.skin;
  if (v.residual !== undefined) q.residual = v.residual ? 1 : 0;
  if (v.cam) q.cam = v.cam.map(String).join(','); // shortest exact decimal of every number
  if (s.embed) q.embed = 1;
  if (s.hide?.length) q.hide = s.hide.join(',');
  if (s.show?.length) q.show = s.show.join(',');
  return ORDER.filter((k) => k in q).map((k) => `${k}=${encodeURIComponent(q[k]).replace(/%2C/g, ',')}`).join('&');
}

/** What a hash holds that parseHash did not take ("parts=abc", "view=wat", an unknown key), as "key=value". */
export function unreadInHash(hash) {
  const kept = new Set(new URLSearchParams(formatHash(parseHash(hash))).keys());
  const given = [...new URLSearchParams(String(hash).replace(/^#/, ''))];
  return given.filter(([k, v]) => !kept.has(k) && !(k === 'bones' && v === 'auto')).map(([k, v]) => `${k}=${v}`);
}

/** Hides the controls the flags name (body classes hide-NAME; see embed.css). */
export function applyEmbedFlags(s, body = document.body) {
  const hidden = new Set([...(s.embed ? EMBED_HIDES : []), ...(s.hide ?? [])]);
  for (const c of s.show ?? []) hidden.delete(c);
  body.classList.toggle('embed', !!s.embed);
  for (const c of CONTROLS) body.classList.toggle(`hide-${c}`, hidden.has(c));
}

// Applied as soon as this module runs (before the page's first fit), so an embedded page never shows its
// controls.
applyEmbedFlags(parseHash(location.hash));

/**
 * ctx (from main.js): { viewer, readParams, fillParams, renderView, runExample, generate, openUrl(url) (a promise of
 *   null, or of what went wrong when the fetch failed), note, teach(count), refine(n) (the merge tree's Refine: a promise of false when
 *   the tree cannot give n parts) }.
 * Returns { start(): true when the hash chose what to load (and loaded it) }.
 */
export function installUrlState(ctx) {
  const { viewer } = ctx;
  const $ = (id) => document.getElementById(id);
  let restoring = null; // view state waiting for the fit to end
  let source = null; // { ex } | { gen } | { src: 'files' } of the population shown
  let fitParams = null; // the form's fit parameters when the shown model was fitted (a Refine's: its tree's fit's)
  let cut = null; // the count of the tree's partition the shown model was refined from (Refine), or null
  let flags = parseHash(location.hash);
  let written = location.hash.replace(/^#/, '');
  let timer = 0;
  let note = null; // shown once the first population is in
  let lastTeachId = null;

  function current() {
    const s = { ...source };
    const linkable = s.src !== 'files'; // a URL is fetched again; dropped files cannot be
    if (fitParams && linkable) {
      const { parts, targetParts, seed, tol, varianceFloor, lambdaRule, refine } = fitParams;
      s.params = { parts, targetParts, seed, tol, varianceFloor, lambdaRule, refine };
      if (cut) s.cut = cut;
    }
    const t = state.teach;
    if (t && state.fitId === t.id && t.iteration > 0 && linkable) s.teach = { steps: t.iteration, stage: t.stage?.kind ?? 'coarse' };
    if (state.pop && linkable) {
      s.view = {
        mode: state.mode,
        flat: $('flat').checked,
        pose: state.pose,
        a: Number($('pose-a').value),
        b: Number($('pose-b').value),
        t: Number($('interp-t').value),
        side: $('side-by-side').checked,
        skin: $('interp-skin').value,
        residual: $('interp-residual').checked,
      };
      if (viewer.framed) s.view.cam = [...viewer.camera.position.toArray(), ...viewer.controls.target.toArray()];
    }
    if (flags.embed) s.embed = true;
    if (flags.hide) s.hide = flags.hide;
    if (flags.show) s.show = flags.show;
    return s;
  }

  function write() {
    timer = 0;
    if (restoring || !source) return; // not before the state in the link has been applied
    const h = formatHash(current());
    if (h === written) return;
    written = h;
    history.replaceState(history.state, '', `#${h}`);
  }
  // Written at most every 150 ms while things change, and once more 300 ms after the last change (a camera
  // still gliding after a drag changes without telling).
  let trailing = 0;
  const schedule = () => {
    if (!timer) timer = setTimeout(write, 150);
    clearTimeout(trailing);
    trailing = setTimeout(write, 300);
  };
  for (const ev of ['change', 'input', 'click', 'keyup']) document.addEventListener(ev, schedule, true);
  viewer.onCameraChange(schedule);

  // The view of a state: the form controls set and their handlers run (main.js), then the camera.
  async function applyView(v) {
    const set = (id, prop, value, ev) => {
      if (value === undefined) return;
      $(id)[prop] = value;
      $(id).dispatchEvent(new Event(ev, { bubbles: true }));
    };
    const n = state.pop.nShapes;
    const pose = (i) => (i === undefined ? undefined : String(Math.min(Math.max(Math.round(i), 0), n - 1)));
    set('flat', 'checked', v.flat, 'change');
    set('pose-a', 'value', pose(v.a), 'input');
    set('pose-b', 'value', pose(v.b), 'input');
    set('interp-t', 'value', v.t === undefined ? undefined : String(v.t), 'input');
    set('interp-skin', 'value', v.skin, 'input');
    set('interp-residual', 'checked', v.residual, 'input');
    set('side-by-side', 'checked', v.side, 'change');
    set('pose-select', 'value', pose(v.pose), 'change');
    const radio = document.querySelector(`#modes input[value=${v.mode}]`);
    if (v.mode && radio && !radio.parentElement.hidden) {
      radio.checked = true;
      radio.dispatchEvent(new Event('change', { bubbles: true }));
    }
    await ctx.renderView({ frame: true }); // the last render wins: the camera goes on after it
    if (v.cam) {
      viewer.camera.position.fromArray(v.cam, 0);
      viewer.controls.target.fromArray(v.cam, 3);
      viewer.camera.updateMatrixWorld();
      viewer.userMoved = true; // a resize keeps this camera
      viewer.requestRender();
    }
  }

  // Loads what a state names; its view waits for the fit. False when the state names no population.
  function load(s) {
    const examples = state.examples;
    // A teaching link: the population is loaded without a fit, then the teaching fit makes its steps.
    const opts = { fit: !s.teach };
    if (s.ex) {
      const ex = examples.find((e) => e.id === s.ex);
      if (!ex) return false;
      restoring = { ...s.view, teach: s.teach, cut: s.teach ? null : s.cut };
      ctx.runExample(ex, s.params, opts);
      return true;
    }
    if (s.gen) {
      restoring = { ...s.view, teach: s.teach, cut: s.teach ? null : s.cut };
      ctx.generate(s.gen, null, s.params, opts);
      return true;
    }
    if (s.src && s.src !== 'files') {
      restoring = { ...s.view, teach: s.teach, cut: s.teach ? null : s.cut };
      if (s.params) ctx.fillParams({ ...state.baseParams, ...s.params });
      ctx.openUrl(s.src).then((failed) => {
        if (!failed) return;
        restoring = null;
        if (state.pop || flags.embed) return;
        // the page stays useful behind the message, and says it again once the example is in
        note = `${failed} Showing the default example.`;
        ctx.runExample(state.examples[0]);
      });
      return true;
    }
    return false;
  }

  window.addEventListener('hashchange', () => {
    const h = location.hash.replace(/^#/, '');
    if (h === written) return;
    written = h;
    const s = parseHash(h);
    flags = s;
    applyEmbedFlags(s);
    const sameSource = formatHash({ ex: s.ex, gen: s.gen, src: s.src, params: s.params, cut: s.cut }) === formatHash({ ...source, params: current().params, cut });
    if (sameSource && state.model) applyView(s.view ?? {});
    else load(s);
  });

  /** The state now (as parseHash returns it), and whether a link's view is still waiting for its fit. */
  window.posemfa.urlState = () => current();
  window.posemfa.restoring = () => !!restoring;

  // A teaching link's view applies once its steps are made.
  function restored() {
    const v = restoring;
    queueMicrotask(async () => { // after the views have shown the model or the step
      try {
        await applyView(v);
        const stage = state.teach?.stage?.kind ?? 'coarse';
        if (v.teach?.stage && state.model === null && stage !== v.teach.stage) {
          ctx.note(`This link was made in the stage “${v.teach.stage}”; ${v.teach.steps} steps lead to “${stage}” here.`);
        }
      } finally {
        restoring = null;
        schedule();
      }
    });
  }

  // A link's Refine once its fit is in; its view waits for the refined fit.
  async function refineLink(n, tree) {
    restoring = { ...restoring, cut: null };
    await Promise.resolve(); // after every view has taken the fit (the slider takes its tree)
    if (await ctx.refine(n)) return;
    const has = tree ? `its merge tree holds ${tree.fewest}-${tree.most} parts` : 'it has no merge tree';
    ctx.note(`This link’s parts were refined from ${n} parts of the merge tree, but ${has} here: showing the fit’s own parts.`);
    restored();
  }

  subscribe((st, changed) => {
    if (changed.has('pop') && restoring?.teach) queueMicrotask(() => ctx.teach(restoring.teach.steps));
    if (changed.has('teach') && restoring?.teach && st.teach && st.teach.iteration >= restoring.teach.steps) {
      restored();
      return;
    }
    if (changed.has('teach') && !restoring) schedule(); // a Run makes steps without a click
    if (changed.has('pop')) {
      const src = st.source;
      source = src?.example ? { ex: src.example.id } : src?.spec ? { gen: src.spec } : { src: src?.url ?? 'files' };
      fitParams = null;
      if (note) {
        const text = note;
        note = null;
        queueMicrotask(() => ctx.note(text)); // after the load's own notes
      }
    }
    const newTeachingFit = changed.has('teach') && st.teach && st.teach.id !== lastTeachId;
    if (newTeachingFit) lastTeachId = st.teach.id;
    if ((changed.has('model') && st.model) || newTeachingFit) {
      const refined = changed.has('model') && !!st.model?.refinedFromTree;
      // a Refine's parts are the link's fit and its count of the tree: the parameters stay that fit's
      if (refined) cut = st.model.summary.parts;
      else [fitParams, cut] = [ctx.readParams(), null];
      if (changed.has('model') && st.model && restoring?.cut && !refined) {
        refineLink(restoring.cut, st.model.tree);
      } else if (changed.has('model') && restoring) {
        restored();
      } else {
        schedule();
      }
    } else if (restoring && (changed.has('loadErrorCount') || (changed.has('fitCount') && !changed.has('model')))) {
      restoring = null;
    }
  });

  return {
    /** At the worker's 'ready': loads the population the hash names. False: the page's default applies. */
    start() {
      const s = parseHash(location.hash);
      const said = [];
      if (s.src === 'files') said.push('This link was made from opened files, which a link cannot carry: open them again. Showing the default example.');
      const ids = state.examples.map((e) => e.id);
      if (s.ex && !ids.includes(s.ex)) said.push(`This link names the example “${s.ex}”, which is not one of the built-in examples (${ids.join(', ')}): showing the default example.`);
      const unread = unreadInHash(location.hash).filter((kv) => !kv.startsWith('ex='));
      if (unread.length) said.push(`Ignored in this link (not values this page reads): ${unread.join(', ')}.`);
      if (said.length) note = said.join(' ');
      return load(s);
    },
  };
}
