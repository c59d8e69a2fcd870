// The article's one worker pool, page side (www/explain/pool-worker.js is the worker side). Every figure gets a
// *channel*: an object that looks like a Worker to www/mount.js (postMessage, onmessage, terminate) but is a
// session on one of the pool's workers. A channel first waits for its turn: at most one fit per worker at a
// time, figures in view first, then the others in the order of the article (they are small: the whole article
// is fitted in a few seconds, so a reader who jumps ahead finds the figure ready). Its turn ends with 'fitted'
// (or an error); from then on the channel talks to its worker directly (queries, teaching steps).
//
// Size: one worker per core beyond the page's own, at least one and at most two (see POOL_SIZE). On the
// 2-core machines this project is tested on that is one worker: the page's thread also renders WebGL in
// software (SwiftShader), and a second worker would take its core; the figures each fit in a few hundred ms,
// so one worker fits them one after another within the article's budget. Every worker holds its own wasm
// instance (compile, about 15 MB of memory), so more than two buys nothing for an article whose screen shows
// two or three figures at a time.

export const POOL_SIZE = (() => {
  const asked = Number(new URLSearchParams(location.search).get('workers'));
  if (Number.isInteger(asked) && asked >= 1 && asked <= 8) return asked; // for measuring (README)
  return Math.min(2, Math.max(1, (navigator.hardwareConcurrency || 2) - 1));
})();

export class Pool {
  constructor(size = POOL_SIZE) {
    this.size = size;
    this.workers = [];
    this.channels = new Map();
    this.nextSession = 1;
    this.waiting = []; // channels waiting for their turn
    this.info = null;
    this.failed = null;
    this.ready = new Promise((resolve) => { this.resolveReady = resolve; });
    for (let w = 0; w < size; w++) this.startWorker(w);
  }

  startWorker(w) {
    const worker = new Worker(new URL('./pool-worker.js', import.meta.url), { type: 'module' });
    const entry = { worker, busy: 0, sessions: 0, up: false };
    this.workers[w] = entry;
    worker.onmessage = ({ data }) => {
      if (data.type === 'pool-ready') {
        entry.up = true;
        entry.upAt = performance.now();
        if (!this.info) {
          this.info = { defaults: data.defaults, examples: data.examples, minExplained: data.minExplained };
          this.resolveReady(this.info);
        }
        this.schedule();
      } else if (data.type === 'pool-fatal') {
        this.failed = data.message;
        for (const c of this.channels.values()) c.deliver({ type: 'fatal', message: data.message });
      } else {
        this.channels.get(data.session)?.deliver(data.msg);
      }
    };
    worker.onerror = (e) => {
      const message = `a worker of the pool failed: ${e.message || e}`;
      for (const c of this.channels.values()) if (c.worker === entry) c.deliver({ type: 'fatal', message });
    };
  }

  /**
   * A Worker-like channel for one figure; `priority()` is read whenever a turn is given (lower goes first);
   * `onTurn(channel)` is called when its turn comes, before the channel says 'ready' (the figure makes its
   * mount() there, so that no WebGL context is made before it is needed).
   */
  channel(priority = () => 0, onTurn = null) {
    const c = new Channel(this, this.nextSession++, priority, onTurn);
    this.channels.set(c.session, c);
    this.waiting.push(c);
    queueMicrotask(() => this.schedule());
    return c;
  }

  /** Gives free workers to the waiting channels, most urgent first. */
  schedule() {
    if (this.failed) return;
    for (;;) {
      const free = this.workers.filter((w) => w.up && w.busy === 0);
      if (!free.length || !this.waiting.length) return;
      this.waiting.sort((a, b) => a.priority() - b.priority() || a.session - b.session);
      const c = this.waiting.shift();
      const w = free.sort((a, b) => a.sessions - b.sessions)[0];
      w.busy++;
      w.sessions++;
      c.bind(w);
    }
  }

  release(c) {
    if (!c.holding) return;
    c.holding = false;
    c.worker.busy--;
    this.schedule();
  }

  /** Re-sorts the waiting channels (a figure came into view). */
  reprioritise() {
    this.schedule();
  }

  /** How many channels wait, and how many workers are busy (for the test contract and the README). */
  status() {
    return { workers: this.size, upAt: this.workers.map((w) => w.upAt ?? null), up: this.workers.filter((w) => w.up).length, waiting: this.waiting.length, busy: this.workers.reduce((a, w) => a + w.busy, 0) };
  }
}

class Channel {
  constructor(pool, session, priority, onTurn) {
    Object.assign(this, { pool, session, priority, onTurn });
    this.worker = null;
    this.holding = false;
    this.onmessage = null;
    this.onerror = null;
    this.listeners = new Set();
    this.closed = false;
  }

  // Its turn: tell mount() the "worker" is ready (it then sends 'generate' with a 'fit').
  bind(w) {
    this.worker = w;
    this.holding = true;
    this.onTurn?.(this);
    const { defaults, examples } = this.pool.info;
    this.deliver({ type: 'ready', defaults, examples, features: { synth: true } });
  }

  deliver(msg) {
    if (this.closed) return;
    if (['fitted', 'fit-error', 'load-error', 'fatal'].includes(msg.type)) this.pool.release(this);
    this.onmessage?.({ data: msg });
    for (const f of this.listeners) f(msg);
  }

  /** Also told every message (besides onmessage, which mount() sets). */
  listen(f) {
    this.listeners.add(f);
    return () => this.listeners.delete(f);
  }

  postMessage(msg, transfer = []) {
    if (this.closed) return;
    if (!this.worker) throw new Error('this figure has no worker yet (wait for its ready message)');
    this.worker.worker.postMessage({ session: this.session, msg }, transfer);
  }

  terminate() {
    if (this.closed) return;
    this.pool.release(this);
    this.pool.waiting = this.pool.waiting.filter((c) => c !== this);
    if (this.worker) {
      this.worker.worker.postMessage({ session: this.session, msg: { type: 'close' } });
      this.worker.sessions--;
    }
    this.closed = true;
    this.pool.channels.delete(this.session);
  }
}
