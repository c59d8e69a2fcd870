#!/usr/bin/env bash
# Every CLI command that fits first, run fitting and with --model (a model file saved by `fit --save`), side by
# side in one run: the outputs compared byte for byte, the wall times as medians of --runs alternating runs, and
# their ratio. Needs target/release/posemfa (built when missing).
# Usage: scripts/bench-model-cli.sh [FOLDER...] [--runs N]   (default: the three real populations of ../shared)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
runs=3
folders=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs=${2:?--runs needs a number}; shift ;;
    *) folders+=("$1") ;;
  esac
  shift
done
[ "${#folders[@]}" -gt 0 ] || folders=(../shared/data/horse-poses ../shared/data/lion-poses ../shared/data/horse-gallop)
for f in "${folders[@]}"; do [ -d "$f" ] || { echo "bench-model-cli: $f is absent" >&2; exit 2; }; done
[ -x target/release/posemfa ] || cargo build --release --quiet --bin posemfa
bin=$(pwd)/target/release/posemfa
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

now() { date +%s%N; }
median() { sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

# name | arguments after the inputs (OUT is replaced by the output file of each variant)
commands=(
  "interpolate|--from 1 --to 3 --t 0.4 --out OUT.obj"
  "export-gltf rigid|--out OUT.glb"
  "export-gltf fitted|--weights fitted --out OUT.glb"
  "rig-report|--weights fitted --out OUT.glb"
  "articulate-report|--from 1 --to 2"
  "fit --json|--quiet --json OUT.json"
)
printf '%-14s %-20s %10s %10s %7s  %s\n' population command fit_ms model_ms ratio output
for folder in "${folders[@]}"; do
  name=$(basename "$folder")
  # saved with the rig `--weights fitted` builds: export-gltf and rig-report with that option take it
  "$bin" fit "$folder" --quiet --save "$tmp/$name.posemfa" --with-rig >/dev/null
  for entry in "${commands[@]}"; do
    label=${entry%%|*}
    rest=${entry#*|}
    sub=${label%% *}
    [ "$sub" = "fit" ] && sub=fit
    fit_t=()
    model_t=()
    for r in $(seq 1 "$runs"); do
      t0=$(now); "$bin" $sub "$folder" ${rest//OUT/$tmp/a} > "$tmp/a.stdout"; t1=$(now)
      "$bin" $sub --model "$tmp/$name.posemfa" ${rest//OUT/$tmp/b} > "$tmp/b.stdout"; t2=$(now)
      fit_t+=($(( (t1 - t0) / 1000000 )))
      model_t+=($(( (t2 - t1) / 1000000 )))
    done
    same=same
    for ext in obj glb; do
      if [ -f "$tmp/a.$ext" ]; then cmp -s "$tmp/a.$ext" "$tmp/b.$ext" || same="DIFFERS ($ext)"; fi
    done
    if [ -f "$tmp/a.json" ]; then
      # a fit made now has timings of its own; the model file's are those of the fit that saved it (which
      # tests/model_file.rs compares byte for byte): the rest must agree
      untimed() { node -e 'const j = JSON.parse(require("fs").readFileSync(process.argv[1], "utf8")); delete j.timings_ms;
        for (const s of j.stage_stats) for (const k of ["ms", "estepMs"]) delete s[k]; console.log(JSON.stringify(j));' "$1"; }
      [ "$(untimed "$tmp/a.json")" = "$(untimed "$tmp/b.json")" ] || same="DIFFERS (json)"
      same="$same (timings aside)"
    fi
    if [ "$sub" = articulate-report ]; then
      # the report prints its own fit time and the inputs: the rest must agree
      strip() { grep -v '"fit_ms"\|"inputs"\|^    "\.\.\/\|^  \],\?$' "$1" | grep -v '^  "inputs"'; }
      diff -q <(strip "$tmp/a.stdout") <(strip "$tmp/b.stdout") >/dev/null || same="DIFFERS (report)"
    fi
    if [ "$sub" = rig-report ]; then
      # (timings, and where the rig came from: built, or kept in the model file)
      strip2() { sed 's/"timings_ms":{[^}]*}//; s/"rig_source":"[a-z ]*",\?//' "$1"; }
      diff -q <(strip2 "$tmp/a.stdout") <(strip2 "$tmp/b.stdout") >/dev/null || same="DIFFERS (report)"
    fi
    fm=$(printf '%s\n' "${fit_t[@]}" | median)
    mm=$(printf '%s\n' "${model_t[@]}" | median)
    printf '%-14s %-20s %10s %10s %7s  %s\n' "$name" "$label" "$fm" "$mm" "$(awk -v a="$mm" -v b="$fm" 'BEGIN { printf "%.3f", a / b }')" "$same"
    rm -f "$tmp"/a.* "$tmp"/b.*
  done
done
