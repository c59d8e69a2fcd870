// Reading speed in wasm beside native, measured in one run:
//   node scripts/bench-read-wasm.mjs INPUT... [--repeat N] [--rounds R]
// INPUT: a folder of pose files (OBJ, PLY, a .glb, a point cache with its base mesh) or single files, as for
// `cargo run --release --example bench_read`. The same example (examples/bench_read.rs: mesh::load, the reader
// each extension calls for) is built for wasm32-wasip1 and run in Node's WASI (V8, the engine of the page's
// Chromium), alternating R rounds with the native build so both see the same machine load. Prints one JSON
// line per round and target, then the medians: {input, bytes, nativeMs, wasmMs, nativeMBs, wasmMBs, ratio}.
// Needs the wasm32-wasip1 target (`rustup target add wasm32-wasip1`; the script adds it when missing).
import { execFileSync } from 'node:child_process';
import { readFileSync, statSync, mkdtempSync, rmSync, openSync, closeSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { resolve, dirname, basename } from 'node:path';
import { fileURLToPath } from 'node:url';
import { WASI } from 'node:wasi';

const ROOT = resolve(fileURLToPath(new URL('..', import.meta.url)));
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 ? args.splice(i, 2)[1] : dflt;
};
const repeat = Number(opt('--repeat', '5'));
const rounds = Number(opt('--rounds', '3'));
if (!args.length || args.some((a) => a.startsWith('--'))) {
  console.error('usage: node scripts/bench-read-wasm.mjs INPUT... [--repeat N] [--rounds R]');
  process.exit(2);
}
const inputs = args.map((a) => resolve(a));

const run = (cmd, argv) => execFileSync(cmd, argv, { cwd: ROOT, stdio: ['ignore', 'inherit', 'inherit'] });
const installed = execFileSync('rustup', ['target', 'list', '--installed'], { encoding: 'utf8' });
if (!installed.split('\n').includes('wasm32-wasip1')) run('rustup', ['target', 'add', 'wasm32-wasip1']);
run('cargo', ['build', '--quiet', '--release', '--example', 'bench_read']);
run('cargo', ['build', '--quiet', '--release', '--target', 'wasm32-wasip1', '--example', 'bench_read']);
const nativeBin = resolve(ROOT, 'target/release/examples/bench_read');
const wasmModule = await WebAssembly.compile(readFileSync(resolve(ROOT, 'target/wasm32-wasip1/release/examples/bench_read.wasm')));

// The example prints one JSON line; WASI's stdout goes to a pipe read back here.
function native(input) {
  return JSON.parse(execFileSync(nativeBin, [input, '--repeat', String(repeat)], { encoding: 'utf8' }));
}
async function wasm(input) {
  const isDir = statSync(input).isDirectory();
  const dir = isDir ? input : dirname(input);
  const arg = isDir ? '/in' : `/in/${basename(input)}`;
  const out = mkdtempSync(resolve(tmpdir(), 'bench-read-wasm-'));
  const fd = openSync(resolve(out, 'stdout'), 'w');
  const wasi = new WASI({ version: 'preview1', args: ['bench_read', arg, '--repeat', String(repeat)], preopens: { '/in': dir }, stdout: fd, returnOnExit: true });
  const instance = await WebAssembly.instantiate(wasmModule, wasi.getImportObject());
  const code = wasi.start(instance);
  closeSync(fd);
  const text = readFileSync(resolve(out, 'stdout'), 'utf8');
  rmSync(out, { recursive: true });
  if (code !== 0) throw new Error(`bench_read in wasm exited with ${code}: ${text}`);
  return JSON.parse(text);
}

const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];
for (const input of inputs) {
  const n = [];
  const w = [];
  let bytes = 0;
  for (let r = 0; r < rounds; r++) {
    const a = native(input);
    const b = await wasm(input);
    bytes = a.bytes;
    n.push(a.median_ms);
    w.push(b.median_ms);
    console.log(JSON.stringify({ round: r + 1, input, native: a.median_ms, wasm: b.median_ms }));
  }
  const nativeMs = median(n);
  const wasmMs = median(w);
  const mbs = (ms) => Math.round(bytes / 1e6 / (ms / 1e3));
  console.log(JSON.stringify({ input, bytes, repeat, rounds, nativeMs, wasmMs, nativeMBs: mbs(nativeMs), wasmMBs: mbs(wasmMs), ratio: +(wasmMs / nativeMs).toFixed(2) }));
}
