// Starts the worker (www/worker.js) as early as possible: main.js imports this module first, so the wasm
// module downloads and compiles while the rest of the page (three.js) is still being evaluated.
export const startWorker = () => new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
export const worker = startWorker();
