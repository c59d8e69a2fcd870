// The page's one state, and the only way to change it: `update(patch)` copies the patch's fields in and then
// tells every subscriber which fields changed. `state` is read-only (writing a field throws), so every change
// is visible in one place. Fields (all set through update):
//
//   phase        'loading' | 'idle' | 'fitting' | 'teaching' | 'fitted' | 'error' (body[data-state] shows it;
//                'teaching' is shown as 'fitting' with body[data-teaching=1])
//   defaults     the fit parameters' defaults (from the core); baseParams: the parameters the form does not
//                show come from here (the defaults, or an example's parameters over them)
//   examples     the core's built-in examples [{ id, title, note, failsOnPurpose, spec, params }]
//   pop          the population shown: { names, nShapes, nVertices, faces, positions[], truth, source }
//   source       what `pop` came from: { label, example, spec } or { label, names, bytes } (kept for a
//                restarted worker)
//   loading      the load in flight: { id, source, fit: { id, params }, notes } or null
//   model        the fitted model: { summary, labels, coarseLabels, refinedLabels, latent, ... } or null
//   gen          bumped whenever pop or model changes: answers to older questions are dropped
//   colours      per-vertex colourings: { grey, live, final, coarse, refined, truth }
//   fitId        request id of the fit in progress (a teaching fit's too), else null
//   lastStep     the progress object of the last AECM iteration seen
//   mode, pose   the view ('parts' | 'stages' | 'recon' | 'latent' | 'interp' | 'truth') and the pose shown
//   shown        what the viewer shows, left to right: [{ positions, colours, name }]
//   pick         the clicked vertex { slot, vertex } or null; hoverPart: the part under the pointer or null
//   teach        the teaching fit: { id, running, iteration, stage, values, runs } (see teach.js)
//   keptAfter    'cancel' / 'failure': the last fit was cancelled (worker.js finishFit) or failed, and the
//                finished model before it stays; null otherwise
//   fitCount, loadErrorCount, restartCount   fits ended, loads refused, workers replaced (test contract)

const data = {
  phase: 'loading',
  defaults: null,
  baseParams: null,
  examples: [],
  pop: null,
  source: null,
  loading: null,
  model: null,
  gen: 0,
  colours: {},
  fitId: null,
  lastStep: null,
  mode: 'parts',
  pose: 0,
  shown: [],
  pick: null,
  hoverPart: null,
  teach: null,
  problems: null,
  fitCount: 0,
  loadErrorCount: 0,
  restartCount: 0,
  // the merge tree's part count shown by its slider (controls/tree.js); null: the fitted parts
  treeParts: null,
  // 'cancel' / 'failure': the last fit was cancelled or failed, and the finished model before it is still shown
  keptAfter: null,
};

export const state = new Proxy(data, {
  set(_, key) {
    throw new Error(`page state: set ${String(key)} through update({ ${String(key)} }) (www/state.js)`);
  },
  deleteProperty(_, key) {
    throw new Error(`page state: ${String(key)} cannot be deleted (www/state.js)`);
  },
});

const subscribers = new Set();

/** Copies the patch's fields into the state; subscribers hear of the fields whose value changed. */
export function update(patch) {
  const changed = [];
  for (const [k, v] of Object.entries(patch)) {
    if (!(k in data)) throw new Error(`page state has no field ${k} (www/state.js lists them)`);
    if (data[k] !== v) {
      data[k] = v;
      changed.push(k);
    }
  }
  if (changed.length) {
    const set = new Set(changed);
    for (const f of [...subscribers]) f(state, set);
  }
}

/** fn(state, changedFields: Set) after every update that changed something; returns the unsubscribe. */
export function subscribe(fn) {
  subscribers.add(fn);
  return () => subscribers.delete(fn);
}
