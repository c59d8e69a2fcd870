#!/usr/bin/env bash
# Coverage-guided fuzzing of the OBJ importer, the population assembly and a bounded fit (cargo-fuzz +
# libFuzzer, with AddressSanitizer). Not part of `npm test` (it runs for minutes); the crashers it found are
# kept as plain tests in tests/fuzz_regressions.rs, which are.
#
# Usage: scripts/fuzz.sh [TARGET|all] [--runs N] [--time SECONDS] [--sanitizer address|none] [--jobs N]
#   TARGET      obj_parse (default): bytes -> posemfa::mesh::obj::parse_obj
#               population: bytes split at NUL into files -> Population::from_files(_all_errors) -> bounded fit
#               shapes: bytes as coordinates -> Population::from_unit_shapes -> bounded fit
#               ply_parse: bytes -> posemfa::mesh::ply::parse_ply
#               point_cache: byte 0 (.pc2/.mdd) + bytes -> parse_pc2/parse_mdd, then mesh::load over a base mesh
#               gltf_read: byte 0 (options) + a .glb or .gltf -> posemfa::mesh::gltf::read
#               fbx_read: byte 0 (options) + an .fbx -> posemfa::mesh::fbx::read
#               usd_read: byte 0 (options) + a .usda, .usdc or .usdz -> posemfa::mesh::usd::read
#               model_file: a .posemfa model file -> posemfa::model_file::ModelFile::from_bytes, then used
#               zip_open: a .zip of pose files -> posemfa::mesh::zip_archive::open
#               pose_rig: a rig .glb -> posemfa::export::pose_glb::read_rig (posemfa pose), with_clip, play_glb_clip
#               formats: ply_parse, point_cache, gltf_read, fbx_read and usd_read in turn
#               all: each of them in turn, with the same limits
#   --runs N    stop after N executions (default 10000000); --time S: stop after S seconds (default: none)
#   --sanitizer address (default) or none (faster; still catches panics, overflow and debug assertions)
#   --jobs N    N fuzzing processes sharing the corpus (default 1; the machine has 2 cores)
#   Extra arguments after `--` go to libFuzzer (e.g. -- -max_len=65536).
#
# What it installs, each only when missing (so it is safe to run again), every network step under a timeout:
#   cargo-fuzz (cargo install, ~3 min), and a nightly toolchain for -Zsanitizer (rustup, minimal profile).
#   Without a nightly (rustup's server unreachable), it runs the stable toolchain with RUSTC_BOOTSTRAP=1, which
#   accepts the same flags (the stable toolchain ships the sanitizer runtimes for x86_64 Linux).
# Seed corpus: generated at every run into fuzz/corpus/TARGET/ (not committed) by fuzz/examples/gen_corpus.rs
#   from posemfa::synth meshes, hand-written OBJ files, small populations, and ../shared/objcorpus when present;
#   for the format targets also files from posemfa's writers (PLY, pc2, mdd, morph-target glb), hand-written
#   edge cases and the small Blender-written files committed in fuzz/seeds/.
# A crash stops the run (exit 1); libFuzzer writes the input to fuzz/artifacts/TARGET/crash-*: reproduce it with
#   (cd fuzz && cargo +nightly fuzz run TARGET artifacts/TARGET/crash-...), fix, and add it to
#   tests/fuzz_regressions.rs.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
root=$(pwd)
export PATH="$HOME/.cargo/bin:$PATH"
export CARGO_TERM_PROGRESS_WHEN=never

target=obj_parse
runs=10000000
time_limit=0
sanitizer=address
jobs=1
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    obj_parse|population|shapes|ply_parse|point_cache|gltf_read|fbx_read|usd_read|model_file|zip_open|pose_rig|formats|all) target=$1 ;;
    --runs) runs=${2:?--runs needs a number}; shift ;;
    --time) time_limit=${2:?--time needs seconds}; shift ;;
    --sanitizer) sanitizer=${2:?--sanitizer needs address or none}; shift ;;
    --jobs) jobs=${2:?--jobs needs a number}; shift ;;
    --) shift; extra=("$@"); break ;;
    *) echo "fuzz.sh: unknown argument '$1' (targets: obj_parse population shapes ply_parse point_cache gltf_read fbx_read usd_read model_file zip_open pose_rig formats all; options: --runs N --time S --sanitizer address|none --jobs N)" >&2; exit 2 ;;
  esac
  shift
done
case "$sanitizer" in address|none) ;; *) echo "fuzz.sh: --sanitizer must be address or none" >&2; exit 2 ;; esac

step() { printf '[fuzz] %s\n' "$*"; }
die() { printf '[fuzz] ERROR: %s\n' "$*" >&2; exit 1; }

command -v cargo >/dev/null || die "cargo not found; install Rust with rustup first"

# ------------------------------------------------------------------ cargo-fuzz
if cargo fuzz --version >/dev/null 2>&1; then
  step "cargo-fuzz: present ($(cargo fuzz --version 2>/dev/null))"
else
  step "cargo-fuzz: installing (cargo install cargo-fuzz, a few minutes)"
  mkdir -p "$HOME/.cargo"
  (
    flock -w 3600 9 || die "timed out waiting for another cargo-fuzz install"
    cargo fuzz --version >/dev/null 2>&1 || timeout 2400 cargo install cargo-fuzz || die "cargo install cargo-fuzz failed"
  ) 9>"$HOME/.cargo/.posemfa-cargo-fuzz-install.lock"
fi

# ------------------------------------------------------------------ toolchain with -Z flags
toolchain=nightly
bootstrap=()
if rustup run nightly rustc --version >/dev/null 2>&1; then
  step "toolchain: $(rustup run nightly rustc --version)"
else
  step "toolchain: installing nightly (rustup toolchain install nightly --profile minimal)"
  if timeout 900 rustup toolchain install nightly --profile minimal </dev/null && rustup run nightly rustc --version >/dev/null 2>&1; then
    step "toolchain: $(rustup run nightly rustc --version)"
  else
    toolchain=stable
    bootstrap=(env RUSTC_BOOTSTRAP=1)
    step "toolchain: no nightly (rustup could not install it); using stable with RUSTC_BOOTSTRAP=1: $(rustc --version)"
  fi
fi

# ------------------------------------------------------------------ seed corpus
cd "$root/fuzz"
extra_objs="$root/../shared/objcorpus"
step "seed corpus: generating into fuzz/corpus/ (fuzz/examples/gen_corpus.rs)"
timeout 1800 cargo run --quiet --release --example gen_corpus -- corpus "$extra_objs" || die "generating the seed corpus failed"

# ------------------------------------------------------------------ run
max_len_of() {
  case "$1" in
    obj_parse) echo 8192 ;;
    population) echo 16384 ;;
    shapes) echo 4096 ;;
    ply_parse) echo 16384 ;;
    point_cache) echo 8192 ;;
    gltf_read) echo 65536 ;;
    fbx_read) echo 65536 ;;
    usd_read) echo 65536 ;;
    model_file) echo 65536 ;;
    zip_open) echo 65536 ;;
    pose_rig) echo 65536 ;;
  esac
}
run_one() {
  local t=$1 dict=() opts
  [ -f "$t.dict" ] && dict=("-dict=$t.dict")
  mkdir -p "corpus/$t" "artifacts/$t"
  opts=(-runs="$runs" -max_len="$(max_len_of "$t")" -timeout=20 -rss_limit_mb=3072 -print_final_stats=1)
  [ "$time_limit" != 0 ] && opts+=(-max_total_time="$time_limit")
  [ "$jobs" -gt 1 ] && opts+=(-jobs="$jobs" -workers="$jobs")
  step "running $t: ${opts[*]} ${dict[*]} ${extra[*]}"
  local t0=$(date +%s)
  set +e
  "${bootstrap[@]}" timeout $(( time_limit > 0 ? time_limit + 1200 : 86400 )) \
    cargo "+$toolchain" fuzz run --release --sanitizer "$sanitizer" "$t" "corpus/$t" -- "${opts[@]}" "${dict[@]}" "${extra[@]}"
  local rc=$?
  set -e
  step "$t: exit $rc after $(( $(date +%s) - t0 )) s; corpus now $(find "corpus/$t" -type f | wc -l) inputs"
  if [ "$rc" != 0 ]; then
    ls -1 "artifacts/$t" 2>/dev/null | sed 's/^/[fuzz]   artifact: fuzz\/artifacts\/'"$t"'\//'
    die "$t failed (a crash, a timeout or an out-of-memory; see above)"
  fi
}

if [ "$target" = all ]; then
  for t in obj_parse population shapes ply_parse point_cache gltf_read fbx_read usd_read model_file zip_open pose_rig; do run_one "$t"; done
elif [ "$target" = formats ]; then
  for t in ply_parse point_cache gltf_read fbx_read usd_read; do run_one "$t"; done
else
  run_one "$target"
fi
step "done: no crash"
