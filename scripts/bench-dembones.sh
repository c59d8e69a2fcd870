#!/usr/bin/env bash
# posemfa's fit against Dem Bones (SSDR, Le & Deng 2012) on the same folder, one thread each, runs alternating:
#   scripts/bench-dembones.sh DIR [--bones 23] [--influences 1] [--runs 3]
# posemfa: the fit time `posemfa fit` prints (reading the files not counted), release build, default parameters.
# Dem Bones: py-dem-bones 0.13.1 (PyPI; benchmark only, never a dependency of posemfa) in a throwaway venv under
# /tmp (scripts/dembones-venv.sh), OMP_NUM_THREADS=1, the time of its solve call alone (scripts/bench-dembones.py).
# Prints one JSON line per run and tool, then the medians and their ratio.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export PATH="$HOME/.cargo/bin:$PATH"
data= bones=23 influences=1 runs=3
while [ $# -gt 0 ]; do
  case "$1" in
    --bones) bones=$2; shift 2 ;;
    --influences) influences=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    -*) echo "bench-dembones.sh: unknown option $1 (--bones N --influences K --runs R)" >&2; exit 2 ;;
    *) data=$1; shift ;;
  esac
done
[ -d "$data" ] || { echo "usage: scripts/bench-dembones.sh DIR [--bones 23] [--influences 1] [--runs 3] (DIR: a folder of OBJ files)" >&2; exit 2; }
source scripts/dembones-venv.sh   # sets $venv
cargo build --release --quiet --bin posemfa
out=$(mktemp /tmp/posemfa-dembones.XXXXXX)
trap 'rm -f "$out"' EXIT
for r in $(seq 1 "$runs"); do
  # "... | RMSE 0.00334 (unit box; E_RMS 1.234) | 160 ms (load 90 ms)"
  line=$(target/release/posemfa fit "$data" --quiet | head -1)
  ms=$(sed -E 's/.*\| ([0-9.]+) ms \(load.*/\1/' <<< "$line")
  parts=$(sed -E 's/.*final ([0-9]+) \|.*/\1/' <<< "$line")
  echo "{\"tool\": \"posemfa\", \"run\": $r, \"parts\": $parts, \"seconds\": $(awk "BEGIN { print $ms / 1000 }")}" | tee -a "$out"
  OMP_NUM_THREADS=1 "$venv/bin/python" scripts/bench-dembones.py "$data" "$bones" "$influences" | tee -a "$out"
done
python3 - "$out" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
p = statistics.median(r["seconds"] for r in rows if r["tool"] == "posemfa")
d = statistics.median(r["seconds"] for r in rows if r["tool"] == "dem-bones")
print(json.dumps({"posemfa_seconds_median": p, "dem_bones_seconds_median": d, "ratio_dem_bones_over_posemfa": d / p}))
PY
