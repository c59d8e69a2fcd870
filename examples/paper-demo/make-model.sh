#!/usr/bin/env bash
# Writes quadruped.posemfa, the model file the example paper page embeds: a generated quadruped (posemfa::synth,
# no research data), fitted at the defaults and saved with its poses. Run again after a change of the model
# file's format version (src/model_file.rs). Usage: examples/paper-demo/make-model.sh
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
root=$(cd ../.. && pwd)
[ -x "$root/target/release/posemfa" ] || (cd "$root" && cargo build --release --quiet --bin posemfa)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$root/target/release/posemfa" generate quadruped --vertices 2000 --poses 10 --seed 2 --out "$tmp/quadruped" >/dev/null
"$root/target/release/posemfa" fit "$tmp/quadruped" --quiet --save quadruped.posemfa
