// Reading speed in wasm beside native, measured in one run:
//   node scripts/bench-read-wasm.mjs INPUT... [--repeat N] [--rounds R] [--formats F,F,...]
// INPUT: a folder of pose files (OBJ, PLY, a .glb, a point cache with its base mesh) or single files.
// --formats (e.g. obj,ply-ascii,ply,pc2,mdd,glb): each INPUT is also written in each format first
// (`bench_read INPUT --write FORMAT DIR`, into a temporary folder, removed at the end; `obj` of an OBJ folder is
// the folder itself) and every format is timed in turn, so each reader gets the same poses.
// Times what the page runs on a drop, `new Population(names, files)` of the wasm module (pkg-node: the same
// Rust readers, checks and unit box, in Node's V8, the engine of the page's Chromium), against the native
// `Population::from_files` (`cargo run --release --example bench_read -- INPUT --population`), alternating R
// rounds so both see the same machine load. Each round prints one JSON line (medians of N reads); the last
// line per input gives the medians over rounds: {input, bytes, nativeMs, wasmMs, nativeMBs, wasmMBs, ratio}.
// Needs `npm run build:wasm` (pkg-node/). Honours CARGO_TARGET_DIR as cargo does.
import { execFileSync } from 'node:child_process';
import { readFileSync, readdirSync, statSync, existsSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { resolve, join, basename } from 'node:path';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';

const ROOT = resolve(fileURLToPath(new URL('..', import.meta.url)));
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : dflt;
};
const repeat = Number(opt('--repeat', '5'));
const rounds = Number(opt('--rounds', '3'));
const formats = opt('--formats', '').split(',').filter(Boolean);
const FORMATS = ['obj', 'ply-ascii', 'ply', 'pc2', 'mdd', 'glb'];
if (!args.length || args.some((a) => a.startsWith('--')) || formats.some((f) => !FORMATS.includes(f))
    || !(repeat >= 1) || !(rounds >= 1)) {
  console.error(`usage: node scripts/bench-read-wasm.mjs INPUT... [--repeat N] [--rounds R] [--formats ${FORMATS.join(',')}]`);
  process.exit(2);
}
const pkg = join(ROOT, 'pkg-node/posemfa.js');
if (!existsSync(pkg)) {
  console.error('bench-read-wasm: pkg-node/ is missing; run `npm run build:wasm` first');
  process.exit(1);
}
const wasm = createRequire(import.meta.url)(pkg);
execFileSync('cargo', ['build', '--quiet', '--release', '--example', 'bench_read'], { cwd: ROOT, stdio: 'inherit' });
const nativeBin = join(process.env.CARGO_TARGET_DIR ? resolve(ROOT, process.env.CARGO_TARGET_DIR) : join(ROOT, 'target'), 'release/examples/bench_read');

// The files bench_read reads: a folder's files (sorted, .mtl left out) or the file itself.
function filesOf(input) {
  if (!statSync(input).isDirectory()) return [{ name: basename(input), bytes: readFileSync(input) }];
  return readdirSync(input).sort().filter((n) => !/\.mtl$/i.test(n) && statSync(join(input, n)).isFile())
    .map((name) => ({ name, bytes: readFileSync(join(input, name)) }));
}

const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];

function inWasm(files) {
  const names = files.map((f) => f.name);
  const times = [];
  for (let r = 0; r < repeat; r++) {
    const arrays = files.map((f) => new Uint8Array(f.bytes)); // as the worker gets them
    const t0 = performance.now();
    const pop = new wasm.Population(names, arrays);
    times.push(performance.now() - t0);
    pop.free();
  }
  return median(times);
}

function natively(input) {
  const out = execFileSync(nativeBin, [input, '--repeat', String(repeat), '--population'], { encoding: 'utf8' });
  return JSON.parse(out).median_ms;
}

// What to time: each INPUT as it is, or with --formats each INPUT in each format.
function jobsOf(tmp) {
  const jobs = [];
  for (const arg of args) {
    if (!tmp) {
      jobs.push({ label: arg, input: resolve(arg) });
      continue;
    }
    const isObjFolder = statSync(resolve(arg)).isDirectory() && filesOf(resolve(arg)).every((f) => /\.obj$/i.test(f.name));
    for (const format of formats) {
      if (format === 'obj' && isObjFolder) {
        jobs.push({ label: arg, format, input: resolve(arg) });
        continue;
      }
      const dir = join(tmp, `${jobs.length}-${format}`);
      execFileSync(nativeBin, [resolve(arg), '--write', format, dir], { stdio: ['ignore', 'ignore', 'inherit'] });
      jobs.push({ label: arg, format, input: dir });
    }
  }
  return jobs;
}

function measure({ label, format, input }) {
  const files = filesOf(input);
  const bytes = files.reduce((n, f) => n + f.bytes.length, 0);
  const n = [];
  const w = [];
  for (let r = 0; r < rounds; r++) {
    n.push(natively(input));
    w.push(inWasm(files));
    console.log(JSON.stringify({ round: r + 1, input: label, format, nativeMs: +n[r].toFixed(1), wasmMs: +w[r].toFixed(1) }));
  }
  const nativeMs = median(n);
  const wasmMs = median(w);
  const mbs = (ms) => Math.round(bytes / 1e6 / (ms / 1e3));
  console.log(JSON.stringify({
    input: label, format, files: files.length, bytes, repeat, rounds, nativeMs: +nativeMs.toFixed(1), wasmMs: +wasmMs.toFixed(1),
    nativeMBs: mbs(nativeMs), wasmMBs: mbs(wasmMs), ratio: +(wasmMs / nativeMs).toFixed(2),
  }));
}

const tmp = formats.length ? mkdtempSync(join(tmpdir(), 'bench-read-')) : null;
try {
  for (const job of jobsOf(tmp)) measure(job);
} finally {
  if (tmp) rmSync(tmp, { recursive: true, force: true });
}
