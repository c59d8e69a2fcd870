// posemfa without an iframe: `mount(element, options)` puts a minimal view (the mesh coloured by its fitted
// parts, a one-line caption) into any element of another page; `unmount()` takes it away again. It runs its
// own worker (www/worker.js, the same protocol as the page), so several mounts and the page do not share
// state. Built to dist/mount.js (stable name, relative URLs). Usage:
//
//   import { mount } from './posemfa/mount.js';
//   const view = mount(document.querySelector('#creature'), { example: 'arm' });
//   view.ready.then((summary) => console.log(summary.parts, summary.groundTruth?.ari));
//   view.unmount();
//
// options: url (a model file .posemfa, a .zip of pose files, a .glb, a point cache in a .zip with its base mesh:
// fetched with its progress in the caption and a Cancel button, www/fetch-source.js; the server must allow this
// page to read it, docs/embed.md), or example (id of a built-in example; default: the first, the quadruped), or
// spec (a generator spec, see Synthetic in src/wasm.rs); params (fit parameters over the example's); pose (0-based, default 0);
// view: 'parts' (default) | 'truth' (the generator's ground truth); flat (unlit colours, default false);
// worker: a Worker-like object that speaks www/worker.js's protocol, used instead of a worker of its own (the
// article's shared pool, www/explain/pool.js, hands out such channels; unmount() terminates it).
// The element gets data-state = loading | fitting | fitted | error.
// Besides ready / summary / unmount, the handle gives what a page that builds on the view needs: viewer (the
// www/viewer.js Viewer), population() and model() (as the worker sent them), post(msg, transfer) to the
// worker, query(method, ...args) (a promise of the worker's reply) and on(f) (f(msg) for every message).
import { Viewer } from './viewer.js';
import { paletteColours } from './colors.js';
import { fetchSource } from './fetch-source.js';

export function mount(element, options = {}) {
  const box = document.createElement('div');
  box.className = 'posemfa-mount';
  box.style.cssText = 'position:relative;width:100%;height:100%;min-height:200px;display:flex;flex-direction:column;font:13px system-ui,sans-serif';
  const view = document.createElement('div');
  view.style.cssText = 'position:relative;flex:1;min-height:0';
  const caption = document.createElement('div');
  caption.className = 'posemfa-caption';
  caption.style.cssText = 'padding:2px 4px;color:#5b6475';
  box.append(view, caption);
  element.append(box);

  const setState = (s) => { element.dataset.state = s; };
  setState('loading');
  caption.textContent = 'Loading…';
  const viewer = new Viewer(view);
  if (options.flat) viewer.setFlat(true);
  const worker = options.worker ?? new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  let pop = null;
  let summary = null;
  let fittedModel = null;
  let title = '';
  const listeners = new Set();
  const replies = new Map();
  let nextId = 1000;
  let resolveReady;
  let rejectReady;
  const ready = new Promise((ok, fail) => { resolveReady = ok; rejectReady = fail; });
  ready.catch(() => {}); // a failure is also shown in the caption and data-state

  const fail = (message) => {
    setState('error');
    caption.textContent = message;
    rejectReady(new Error(message));
  };

  worker.onmessage = ({ data: m }) => {
    if (m.type === 'reply' && replies.has(m.id)) {
      const r = replies.get(m.id);
      replies.delete(m.id);
      if (m.error) r.fail(new Error(m.error));
      else r.ok(m.result);
    }
    handle(m);
    for (const f of listeners) f(m);
  };
  const abort = new AbortController();
  // A file from options.url: fetched, then loaded as a drop of it is (a model file opens without fitting).
  async function fromUrl(defaults) {
    const url = options.url;
    const cancel = document.createElement('button');
    cancel.type = 'button';
    cancel.textContent = 'Cancel';
    cancel.onclick = () => abort.abort();
    const status = document.createElement('span');
    status.textContent = `Fetching ${url}…`;
    caption.replaceChildren(status, ' ', cancel);
    let got;
    try {
      got = await fetchSource(url, {
        signal: abort.signal,
        onProgress: (n, total) => { status.textContent = `Fetching ${url}: ${(n / 1e6).toFixed(1)}${total ? ` of ${(total / 1e6).toFixed(1)}` : ''} MB`; },
      });
    } catch (e) {
      return fail(abort.signal.aborted ? `Cancelled: ${url} was not opened` : `Cannot open ${url}: ${e.problems?.[0]?.message ?? e.message}`);
    }
    if (!got.files.length) return fail(`Cannot open ${url}: no mesh or model file in it`);
    title = url.split('/').pop();
    caption.textContent = title;
    const files = got.files.map((f) => f.bytes.buffer.slice(f.bytes.byteOffset, f.bytes.byteOffset + f.bytes.byteLength));
    const params = { ...defaults, ...(options.params ?? {}) };
    worker.postMessage({ type: 'load', id: 1, names: got.files.map((f) => f.name), files, fit: { id: 2, params } }, files);
  }

  const handle = (m) => {
    if (m.type === 'ready' && options.url) {
      fromUrl(m.defaults);
    } else if (m.type === 'ready') {
      const ex = options.spec ? null : (m.examples.find((e) => e.id === options.example) ?? m.examples[0]);
      if (options.example && ex && ex.id !== options.example) return fail(`no example "${options.example}"`);
      const params = { ...m.defaults, ...(ex?.params ?? {}), ...(options.params ?? {}) };
      worker.postMessage({ type: 'generate', id: 1, spec: options.spec ?? ex.spec, fit: { id: 2, params } });
      title = ex ? ex.title : `generated ${options.spec.preset ?? ''}`;
      caption.textContent = title;
    } else if (m.type === 'loaded') {
      pop = m.population;
      viewer.setTopology(pop.faces, pop.positions[0]);
      setState('fitting');
    } else if (m.type === 'fitted') {
      const first = !summary; // a later fit (a teaching run's end) keeps the camera where the reader put it
      summary = m.model.summary;
      fittedModel = m.model;
      const pose = Math.min(Math.max(Number(options.pose) || 0, 0), pop.nShapes - 1);
      const truth = options.view === 'truth' && pop.truth;
      const colours = truth ? paletteColours(pop.truth.partOfVertex, pop.truth.colours) : paletteColours(m.model.labels, m.model.colours.final);
      viewer.show([{ positions: pop.positions[pose], colours: colours.vertexColours }], { frame: first });
      const acc = summary.groundTruth ? `, adjusted Rand ${summary.groundTruth.ari.toFixed(3)}` : '';
      const how = summary.opened ? `opened from ${summary.opened}` : `fitted in ${Math.round(summary.fitMs)} ms`;
      caption.textContent = title + (truth
        ? ` — ground truth, ${pop.truth.partNames.length} parts`
        : ` — ${summary.parts} parts ${how}${acc}`);
      setState('fitted');
      resolveReady({ ...summary });
    } else if (m.type === 'load-error') {
      fail(m.problems.map((p) => p.message).join('; '));
    } else if (m.type === 'fit-error' || m.type === 'fatal') {
      fail(m.message);
    }
  };
  worker.onerror = (e) => fail(`the worker failed: ${e.message || e}`);

  let mounted = true;
  return {
    /** Resolves to the fit's summary ({parts, rmse, fitMs, groundTruth: {ari, rotationErrorDeg}, ...}). */
    ready,
    summary: () => (summary ? { ...summary } : null),
    viewer,
    caption,
    population: () => pop,
    model: () => fittedModel,
    post: (msg, transfer) => worker.postMessage(msg, transfer),
    /** The worker's answer to a query (see QUERIES in www/worker.js). */
    query(method, ...args) {
      const id = nextId++;
      return new Promise((ok, fail) => {
        replies.set(id, { ok, fail });
        worker.postMessage({ type: 'query', id, method, args });
      });
    },
    on(f) {
      listeners.add(f);
      return () => listeners.delete(f);
    },
    /** Stops the worker, frees the WebGL context and removes what mount() added. */
    /** Stops fetching options.url (the caption says it was cancelled). */
    cancel: () => abort.abort(),
    unmount() {
      if (!mounted) return;
      mounted = false;
      abort.abort();
      worker.terminate();
      viewer.dispose();
      box.remove();
      delete element.dataset.state;
    },
  };
}
