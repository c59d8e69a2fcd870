#!/usr/bin/env bash
# Builds the wasm library and its JS bindings:
#   www/pkg/   --target web (ES module for the page; .wasm optimised by wasm-opt -O3 from npm binaryen)
#   pkg-node/  --target nodejs (CommonJS, for Node scripts and benchmarks; not optimised)
# Needs what scripts/setup.sh installs.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
export PATH="$HOME/.cargo/bin:$PATH"
export CARGO_TERM_PROGRESS_WHEN=never

say() { printf '[build:wasm] %s\n' "$*"; }
die() { printf '[build:wasm] ERROR: %s\n' "$*" >&2; exit 1; }
size() { stat -c %s "$1" | awk '{ printf "%.0f KB", $1 / 1024 }'; }

crate=posemfa
target_dir="${CARGO_TARGET_DIR:-target}"
raw="$target_dir/wasm32-unknown-unknown/release/$crate.wasm"
wasm_opt=node_modules/.bin/wasm-opt

command -v wasm-bindgen >/dev/null || die "wasm-bindgen not found: run npm run setup"
[ -x "$wasm_opt" ] || die "$wasm_opt not found: run npm run setup"

# One build at a time: two builds at once would overwrite each other's www/pkg and pkg-node.
mkdir -p "$target_dir"
exec 9>"$target_dir/.posemfa-build-wasm.lock"
if ! flock -n 9; then
  say "another wasm build is running in this checkout; waiting for it (up to 20 minutes)"
  flock -w 1200 9 || die "timed out waiting for the other wasm build (lock $target_dir/.posemfa-build-wasm.lock)"
fi

t0=$(date +%s)
say "cargo build --release --target wasm32-unknown-unknown --lib"
cargo build --release --target wasm32-unknown-unknown --lib
[ -f "$raw" ] || die "$raw was not produced"

say "wasm-bindgen --target web -> www/pkg, --target nodejs -> pkg-node"
rm -rf www/pkg pkg-node
wasm-bindgen --target web --out-dir www/pkg "$raw"
wasm-bindgen --target nodejs --out-dir pkg-node "$raw"
# the repo is "type": "module" and the nodejs glue is CommonJS: mark pkg-node/ as CommonJS for Node
echo '{ "type": "commonjs" }' > pkg-node/package.json

web_wasm="www/pkg/${crate}_bg.wasm"
bound_size=$(size "$web_wasm")
# Features of the wasm32-unknown-unknown target of current Rust (1.82+: multivalue, reference-types;
# 1.87+: bulk-memory, nontrapping-fptoint) that wasm-bindgen's output keeps, and simd128 (.cargo/config.toml);
# wasm-opt rejects the module without them.
say "wasm-opt -O3 $web_wasm"
"$wasm_opt" -O3 \
  --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
  --enable-reference-types --enable-multivalue --enable-mutable-globals --enable-simd \
  "$web_wasm" -o "$web_wasm.opt"
mv "$web_wasm.opt" "$web_wasm"

# The optimised module must still validate and link against its own JS glue.
node --input-type=module -e "
  import { readFileSync } from 'node:fs';
  const bytes = readFileSync('$web_wasm');
  if (!WebAssembly.validate(bytes)) { console.error('optimised module does not validate'); process.exit(1); }
  const glue = await import('./www/pkg/$crate.js');
  glue.initSync({ module: bytes });
" || die "the optimised $web_wasm does not load with www/pkg/$crate.js"
node -e "require('./pkg-node/$crate.js')" || die "pkg-node/$crate.js does not load in Node"

say "sizes: cargo $(size "$raw") -> wasm-bindgen $bound_size -> wasm-opt $(size "$web_wasm") (node build $(size "pkg-node/${crate}_bg.wasm"))"
say "done in $(( $(date +%s) - t0 )) s"
