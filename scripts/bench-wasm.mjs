// Benchmark of the whole pipeline in wasm, one thread, in headless Chromium (default) or in Node:
//   node scripts/bench-wasm.mjs [INPUT...] [--node] [--repeat N] [--seed S] [--kernel-ms MS] [--refits N]
//                               [--interpolate] [--rig rigid|smooth|fitted|pose] [--baseline DIR]
// INPUT: a folder of registered OBJ files, or synth:PRESET[:VERTICES[:POSES[:SEED]]] (a generated population).
// Default inputs: ../shared/data/horse-poses, ../shared/data/horse-gallop, synth:quadruped:50000:20 (a folder
// that is absent is reported and skipped). Prints one JSON object per input (the same figures as
// `posemfa bench`): time per stage, AECM iterations, E-step GFLOP/s, the measured kernel limit and the E-step's
// fraction of it, peak wasm memory (linear memory only grows, and every input runs in a fresh instance): after
// the load (peak_memory_bytes_load), after the first fit and its summary as the page's worker does them
// (peak_memory_bytes_fit) and at the end, after the kernel limits (peak_memory_bytes; --kernel-ms 0: none);
// with --refits N, after each of N more fits made as the page fits again, the last model parked meanwhile
// (peak_memory_bytes_refits); with --interpolate, after an interpolation viewed after the first fit and after
// each refit (peak_memory_bytes_view, peak_memory_bytes_refit_views); with --rig, after the rig the page
// exports with those weights (or pose mode's poser) made after the first fit (peak_memory_bytes_rig).
// Needs `npm run build:wasm` (www/pkg for Chromium, pkg-node for Node).
// --baseline DIR: DIR is another checkout (e.g. today's main, `git archive main | tar -x -C DIR`) with its own
// `npm run build:wasm` done; each input is then fitted alternately by DIR's module and by this one, in the same
// browser, `--repeat` times each, and the output per input is {input, baseline, current, ratio} with ratio =
// current / baseline of the median fit times (one run, one machine: the ratio is the figure to quote).
import { readFileSync, readdirSync, existsSync, statSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { benchOne, synthSpec } from './bench-core.mjs';

const ROOT = resolve(fileURLToPath(new URL('..', import.meta.url)));
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : dflt;
};
const flag = (name) => {
  const i = args.indexOf(name);
  return i >= 0 ? (args.splice(i, 1), true) : false;
};
const settings = {
  repeat: Number(opt('--repeat', '3')),
  seed: Number(opt('--seed', '0')),
  kernelMs: Number(opt('--kernel-ms', '300')),
  refits: Number(opt('--refits', '0')),
  interpolate: flag('--interpolate'),
  rig: opt('--rig', null),
};
if (settings.rig && !['rigid', 'smooth', 'fitted', 'pose'].includes(settings.rig)) {
  console.error(`bench-wasm: --rig ${settings.rig}: use rigid, smooth, fitted or pose`);
  process.exit(2);
}
const baselineDir = opt('--baseline', null);
const inNode = flag('--node');
const inputs = args.length ? args : [
  resolve(ROOT, '../shared/data/horse-poses'), resolve(ROOT, '../shared/data/horse-gallop'), 'synth:quadruped:50000:20',
];
for (const a of args) {
  if (a.startsWith('--')) {
    console.error(`bench-wasm: unknown option ${a} (options: --node --repeat N --seed S --kernel-ms MS --refits N --interpolate --rig W --baseline DIR)`);
    process.exit(2);
  }
}

/** Input descriptors; folders as lists of .obj names (natural order, as the page sorts them). */
const collator = new Intl.Collator('en', { numeric: true });
const described = [];
for (const a of inputs) {
  const spec = synthSpec(a);
  if (spec) {
    described.push({ label: a, synth: spec });
    continue;
  }
  const dir = resolve(a);
  if (!existsSync(dir) || !statSync(dir).isDirectory()) {
    console.error(`bench-wasm: ${dir} is absent (skipped); pass a folder of registered OBJ files or synth:PRESET:V:P`);
    continue;
  }
  const names = readdirSync(dir).filter((f) => f.toLowerCase().endsWith('.obj')).sort(collator.compare);
  described.push({ label: dir, dir, names });
}
if (!described.length) process.exit(2);

const median = (xs) => [...xs].sort((a, b) => a - b)[(xs.length - 1) >> 1];
/** Runs `one(which, repeatIndex)` alternately for the baseline and this build, and merges the figures. */
async function compared(label, one) {
  const runs = { baseline: [], current: [] };
  for (let r = 0; r < settings.repeat; r++) {
    for (const which of ['baseline', 'current']) runs[which].push(await one(which));
  }
  const merge = (rs) => ({ ...rs[rs.length - 1], fit_ms_all: rs.map((x) => x.fit_ms_median), fit_ms_median: median(rs.map((x) => x.fit_ms_median)) });
  const baseline = merge(runs.baseline);
  const current = merge(runs.current);
  const short = (x) => ({
    fit_ms_median: x.fit_ms_median, fit_ms_all: x.fit_ms_all, parts: x.parts, rmse: x.rmse, iterations: x.iterations,
    stages: x.stages.map((s) => ({ stage: s.stage, ms: s.ms, iterations: s.iterations, aecm_runs: s.aecm_runs, estep_ms: s.estep_ms, estep_fraction_of_limit: s.estep_fraction_of_limit })),
    estep_fraction_of_limit: x.estep_fraction_of_limit, peak_memory_bytes: x.peak_memory_bytes,
    peak_memory_bytes_load: x.peak_memory_bytes_load, peak_memory_bytes_fit: x.peak_memory_bytes_fit,
    peak_memory_bytes_refits: x.peak_memory_bytes_refits, peak_memory_bytes_view: x.peak_memory_bytes_view,
    peak_memory_bytes_refit_views: x.peak_memory_bytes_refit_views, peak_memory_bytes_rig: x.peak_memory_bytes_rig,
    ground_truth: x.ground_truth,
  });
  return { input: label, shapes: current.shapes, vertices: current.vertices, ratio: current.fit_ms_median / baseline.fit_ms_median, baseline: short(baseline), current: short(current) };
}
if (baselineDir && !existsSync(join(resolve(baselineDir), inNode ? 'pkg-node/posemfa.js' : 'www/pkg/posemfa.js'))) {
  console.error(`bench-wasm: ${baselineDir} has no built wasm; run \`npm run build:wasm\` there first`);
  process.exit(2);
}

const results = [];
if (inNode) {
  const pkg = resolve(process.env.POSEMFA_PKG ?? join(ROOT, 'pkg-node/posemfa.js'));
  if (!existsSync(pkg)) {
    console.error('bench-wasm: pkg-node/ is missing; run `npm run build:wasm` first');
    process.exit(2);
  }
  const require = createRequire(import.meta.url);
  for (const d of described) {
    // a fresh instance per input, so that its peak memory is its own
    delete require.cache[require.resolve(pkg)];
    const wasm = require(pkg);
    const input = d.synth ? d : { label: d.label, names: d.names, files: d.names.map((n) => new Uint8Array(readFileSync(join(d.dir, n)))) };
    if (baselineDir) {
      const bpkg = join(resolve(baselineDir), 'pkg-node/posemfa.js');
      const base = require(bpkg);
      const one = async (which) => benchOne(which === 'baseline' ? base : wasm, input, { ...settings, repeat: 1 });
      results.push({ runtime: `wasm (node ${process.version})`, ...(await compared(d.label, one)) });
      continue;
    }
    results.push({ runtime: `wasm (node ${process.version})`, ...benchOne(wasm, input, settings) });
  }
} else {
  if (!existsSync(join(ROOT, 'www/pkg/posemfa.js'))) {
    console.error('bench-wasm: www/pkg/ is missing; run `npm run build:wasm` first');
    process.exit(2);
  }
  const { serveStatic, launch } = await import(pathToFileURL(join(ROOT, 'tests/e2e/helpers.mjs')).href);
  const server = await serveStatic(ROOT);
  const browser = await launch();
  try {
    for (const d of described) {
      const context = await browser.newContext();
      const page = await context.newPage();
      const errors = [];
      page.on('pageerror', (e) => errors.push(String(e)));
      // the population's files come from disk through this route (they are outside the served folder)
      await page.route('**/__bench_data__/**', (route) => {
        const name = decodeURIComponent(new URL(route.request().url()).pathname.split('/').pop());
        route.fulfill({ body: readFileSync(join(d.dir, name)), contentType: 'text/plain' });
      });
      // the baseline's module, from its own checkout
      await page.route('**/__baseline__/**', (route) => {
        const name = decodeURIComponent(new URL(route.request().url()).pathname.split('/').pop());
        const type = name.endsWith('.wasm') ? 'application/wasm' : 'text/javascript';
        route.fulfill({ body: readFileSync(join(resolve(baselineDir), 'www/pkg', name)), contentType: type });
      });
      await page.goto(`${server.url}scripts/`).catch(() => {}); // any page of the origin; 404 is fine
      const version = await page.evaluate(() => navigator.userAgent.match(/Chrom(e|ium)\/[\d.]+/)?.[0] ?? 'Chromium');
      const run = (which, s) => page.evaluate(async ([d, settings, which]) => {
        const wasm = await import(which === 'baseline' ? '/__baseline__/posemfa.js' : '/www/pkg/posemfa.js');
        await wasm.default();
        const { benchOne } = await import('/scripts/bench-core.mjs');
        let input = d;
        if (!d.synth) {
          const files = await Promise.all(d.names.map(async (n) => new Uint8Array(await (await fetch(`/__bench_data__/${encodeURIComponent(n)}`)).arrayBuffer())));
          input = { label: d.label, names: d.names, files };
        }
        return benchOne(wasm, input, settings);
      }, [d, s, which]);
      const out = baselineDir ? await compared(d.label, (which) => run(which, { ...settings, repeat: 1 })) : await run('current', settings);
      if (errors.length) throw new Error(`page errors: ${errors.join('; ')}`);
      results.push({ runtime: `wasm (headless ${version})`, ...out });
      await context.close();
    }
  } finally {
    await browser.close();
    await server.close();
  }
}
console.log(JSON.stringify(results.length === 1 ? results[0] : results, null, 2));
