// Benchmark of the whole pipeline in wasm under Node (one thread), same figures as `posemfa bench`:
//   node scripts/bench-wasm.mjs [DIR] [--repeat N] [--seed S]
// DIR defaults to ../shared/data/horse-poses. Needs `npm run build:wasm` (pkg-node/).
import { readFileSync, readdirSync, existsSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : dflt;
};
const repeat = Number(opt('--repeat', '3'));
const seed = Number(opt('--seed', '0'));
const dir = resolve(args[0] ?? '../shared/data/horse-poses');
if (!existsSync(dir)) {
  console.error(`bench-wasm: data folder ${dir} is absent; pass a folder of registered OBJ files`);
  process.exit(2);
}
const pkg = resolve(process.env.POSEMFA_PKG ?? 'pkg-node/posemfa.js');
if (!existsSync(pkg)) {
  console.error('bench-wasm: pkg-node/ is missing; run `npm run build:wasm` first');
  process.exit(2);
}
const wasm = require(pkg);
const names = readdirSync(dir).filter((f) => f.toLowerCase().endsWith('.obj'));
const files = names.map((f) => new Uint8Array(readFileSync(join(dir, f))));

const t0 = performance.now();
const pop = new wasm.Population(names, files);
const loadMs = performance.now() - t0;

const runs = [];
let summary;
for (let r = 0; r < repeat; r++) {
  const t = performance.now();
  const fitter = new wasm.Fitter(pop, { seed });
  while (!fitter.isDone()) fitter.run(1e9);
  const model = fitter.result();
  runs.push(performance.now() - t);
  summary = model.summary();
  model.free();
  fitter.free();
}
const sorted = [...runs].sort((a, b) => a - b);
const stages = summary.stageStats.map((s) => ({
  stage: s.name,
  ms: s.ms,
  iterations: s.iterations,
  aecm_runs: s.aecmRuns,
  estep_ms: s.estepMs,
  estep_gflop: s.estepFlops / 1e9,
  estep_gflops_per_s: s.estepMs > 0 ? s.estepFlops / s.estepMs / 1e6 : 0,
}));
console.log(JSON.stringify({
  runtime: `wasm (node ${process.version})`,
  inputs: [dir], shapes: pop.nShapes, vertices: pop.nVertices,
  load_ms: loadMs, fit_ms_median: sorted[Math.floor(sorted.length / 2)], fit_ms_all: runs,
  parts: summary.parts, rmse: summary.rmse, stages,
}, null, 2));
