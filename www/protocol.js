// The worker client: the page's only way to talk to www/worker.js (which owns the wasm instance). Every
// request gets an id and one promise, settled by the worker's final answer for that id; the messages in
// between (fit progress, teaching steps) go to the request's `onEvent`. The messages are listed in worker.js.
//
//   final answers      loaded | fitted | reply                -> the promise resolves with the message
//                      load-error | fit-error | reply.error    -> it rejects with a WorkerError
//   events             progress | teach                       -> onEvent(message)
//   worker-wide        ready -> onReady (first worker only); fatal -> onFatal; crashed -> restart policy
//
// Faults: when the wasm instance traps (the worker says 'crashed') or the worker dies after it was ready, the
// worker is replaced and the page's `onRestart` gives the new one the work again, at most MAX_RESTARTS times
// for the same job (a population with its fit parameters, named by the `job` key of the request that started
// it). After that no worker is started until the next request, and `onGiveUp` is told. Every request still
// waiting is rejected with kind 'crashed'.

export const MAX_RESTARTS = 2;

/** An error answered by the worker: kind ('load' | 'fit' | 'query' | 'crashed'), message, and problems
 *  [{ kind, file, line, message }] as the core threw them (src/wasm.rs). */
export class WorkerError extends Error {
  constructor(kind, message, problems = null) {
    super(message);
    this.kind = kind;
    this.problems = problems ?? [{ file: null, line: null, kind, message }];
  }
}

const FINAL = new Set(['loaded', 'load-error', 'fitted', 'fit-error', 'reply']);

export class WorkerClient {
  /** start(): a new Worker; first: an already started one (optional). Callbacks: see the file's comment. */
  constructor({ start, first = null, onReady, onFatal, onRestart, onGiveUp }) {
    Object.assign(this, { start, onReady, onFatal, onRestart, onGiveUp });
    this.nextId = 1;
    this.waiting = new Map(); // id -> { resolve, reject, onEvent }
    this.job = null; // key of the work in hand
    this.restarts = new Map(); // job key -> restarts made for it
    this.restartCount = 0;
    this.readySeen = false;
    this.attach(first ?? start());
  }

  attach(w) {
    this.worker = w;
    this.ready = false;
    w.onmessage = ({ data }) => w === this.worker && this.receive(data);
    w.onerror = (e) => w === this.worker && this.failed(e.message || String(e));
  }

  /** A new request id (for a fit that a load starts: { fit: { id, params } }). */
  id() {
    return this.nextId++;
  }

  /** Sends a message that gets no answer of its own (cancel, teach-pause). */
  post(msg, transfer = []) {
    if (!this.worker) this.attach(this.start()); // given up earlier: a new request gets a new worker
    this.worker.postMessage(msg, transfer);
  }

  /**
   * Sends `msg` with a new id (or msg.id); returns { id, done }: done settles with the final answer.
   * opts: transfer (ArrayBuffers), onEvent(message), job (key of the work this request starts).
   */
  request(msg, { transfer = [], onEvent = null, job } = {}) {
    const id = msg.id ?? this.id();
    const done = this.expect(id, { onEvent });
    if (job !== undefined) this.job = job;
    this.post({ ...msg, id }, transfer);
    return { id, done };
  }

  /** A promise for the final answer to `id` (a request sent inside another, e.g. the fit of a load). */
  expect(id, { onEvent = null } = {}) {
    return new Promise((resolve, reject) => this.waiting.set(id, { resolve, reject, onEvent }));
  }

  /** Stops waiting for `id` (a fit that will not start: its load failed). */
  forget(id) {
    this.waiting.delete(id);
  }

  receive(m) {
    if (m.type === 'crashed') return this.failed(m.message);
    if (m.type === 'ready') {
      this.ready = true;
      if (!this.readySeen) {
        this.readySeen = true;
        this.onReady(m);
      }
      return;
    }
    if (m.type === 'fatal') return this.onFatal(m.message);
    const w = this.waiting.get(m.id);
    if (!w) return; // an answer nobody waits for any more (superseded)
    if (!FINAL.has(m.type)) {
      w.onEvent?.(m);
      return;
    }
    this.waiting.delete(m.id);
    if (m.type === 'load-error') w.reject(new WorkerError('load', problemsText(m.problems), m.problems));
    else if (m.type === 'fit-error') w.reject(new WorkerError('fit', m.message, m.problems));
    else if (m.type === 'reply' && m.error !== undefined) w.reject(new WorkerError('query', m.error, m.problems));
    else w.resolve(m);
  }

  // The worker trapped or died. Before it was ever ready, the page cannot run (onFatal).
  failed(message) {
    if (!this.ready && !this.readySeen) return this.onFatal(`the worker failed: ${message}`);
    this.worker.terminate();
    this.worker = null;
    const pending = [...this.waiting.values()];
    this.waiting.clear();
    for (const w of pending) w.reject(new WorkerError('crashed', `the worker stopped (${message})`));
    const made = this.restarts.get(this.job) ?? 0;
    if (made >= MAX_RESTARTS) {
      this.onGiveUp({ message, restarts: made });
      return;
    }
    this.restarts.set(this.job, made + 1);
    this.restartCount++;
    this.attach(this.start());
    this.onRestart({ message, attempt: made + 1 });
  }
}

const problemsText = (problems) => problems.map((p) => (p.file ? `${p.file}${p.line ? `, line ${p.line}` : ''}: ` : '') + p.message).join('\n');
