#!/usr/bin/env bash
# posemfa's fitted rig against Dem Bones (SSDR, Le & Deng 2012) on the same data: same bone counts, 4 influences,
# one thread, runs alternating between the two tools. Prints a table (E_RMS, max error, time) and the raw JSON.
#
# Usage: scripts/bench-rig.sh DIR [--bones 10,20,30] [--runs R] [--influences K]
#   a bone count `auto` runs posemfa with its own part count and Dem Bones with as many bones as posemfa found.
#
# - posemfa: `posemfa export-gltf DIR --out X.glb --weights fitted --influences K --bones N` (release build), timed as a
#   whole command (reading, fit, skinning, writing), wall clock and CPU (user + system); its E_RMS is measured on the written .glb by
#   `posemfa rig-report DIR --glb X.glb` (the clip played by linear blend skinning from the file's own numbers).
# - Dem Bones: the PyPI package py-dem-bones (benchmark only, never a dependency of posemfa), installed into a
#   throwaway venv under /tmp (scripts/dembones-venv.sh); scripts/bench-rig-dembones.py times its solve alone
#   (wall clock and CPU). On a shared machine the CPU times are the steadier ratio: the wall clock counts the waits.
# - Both rigs use the file named reference.obj (else the first file) as the rest pose, and their E_RMS
#   (Kavan et al. 2010) is taken over the other files (the frames), with the rest pose's bounding-box diagonal.
# - Times are medians over the runs (default 1); OMP_NUM_THREADS=1 for Dem Bones.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root=$(pwd)
export PATH="$HOME/.cargo/bin:$PATH"

data=
bones=10,20,30
runs=1
influences=4
while [ $# -gt 0 ]; do
  case "$1" in
    --bones) bones=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --influences) influences=$2; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    -*) echo "bench-rig.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) data=$1; shift ;;
  esac
done
[ -n "$data" ] || { echo "usage: scripts/bench-rig.sh DIR [--bones 10,20,30] [--runs R]" >&2; exit 2; }
[ -d "$data" ] || { echo "bench-rig.sh: $data is not a folder of OBJ files" >&2; exit 2; }

source scripts/dembones-venv.sh   # sets $venv

cargo build --release --quiet --bin posemfa
bin=$root/target/release/posemfa
work=$(mktemp -d /tmp/posemfa-bench-rig.XXXXXX)
trap 'rm -rf "$work"' EXIT
results=$work/results.jsonl
: > "$results"

now() { date +%s.%N; }
IFS=, read -r -a counts <<< "$bones"
for n in "${counts[@]}"; do
  for r in $(seq 1 "$runs"); do
    count=(--bones "$n")
    [ "$n" = auto ] && count=()
    t0=$(now)
    # CPU seconds (user + system) of the command, beside its wall clock
    cpu=$(python3 - "$work/export.log" "$bin" export-gltf "$data" --out "$work/rig-$n.glb" --weights fitted \
      --influences "$influences" "${count[@]}" <<'PY'
import resource, subprocess, sys
with open(sys.argv[1], "w") as log:
    subprocess.run(sys.argv[2:], stdout=log, check=True)
r = resource.getrusage(resource.RUSAGE_CHILDREN)
print(r.ru_utime + r.ru_stime)
PY
)
    t1=$(now)
    "$bin" rig-report "$data" --glb "$work/rig-$n.glb" > "$work/report.json"
    found=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["bones"])' "$work/report.json")
    python3 - "$n" "$r" "$t0" "$t1" "$work/report.json" "$cpu" >> "$results" <<'PY'
import json, sys
n, r, t0, t1, path, cpu = sys.argv[1:]
rep = json.load(open(path))
rest = rep["rest"]
frames = [p for p in rep["poses"] if p["name"] != rest]
e = (sum(p["e_rms"] ** 2 for p in frames) / len(frames)) ** 0.5
mx = max(p["max_error"] for p in frames) / rep["diagonal"]
print(json.dumps({"tool": "posemfa", "bones_asked": n, "bones": rep["bones"], "run": int(r), "e_rms": e,
                  "max_error_over_diagonal": mx, "seconds": float(t1) - float(t0), "cpu_seconds": float(cpu),
                  "frames": len(frames)}))
PY
    # auto: Dem Bones gets as many bones as posemfa found
    db_n=$n
    [ "$n" = auto ] && db_n=$found
    OMP_NUM_THREADS=1 "$venv/bin/python" scripts/bench-rig-dembones.py "$data" "$db_n" "$influences" > "$work/db.json"
    python3 - "$r" "$work/db.json" "$n" >> "$results" <<'PY'
import json, sys
d = json.load(open(sys.argv[2]))
print(json.dumps({"tool": "dem-bones", "bones_asked": sys.argv[3], "bones": d["bones"], "run": int(sys.argv[1]),
                  "e_rms": d["e_rms"], "max_error_over_diagonal": d["max_error_over_diagonal"],
                  "seconds": d["solve_s"], "cpu_seconds": d["solve_cpu_s"], "frames": len(d["frames"])}))
PY
    tail -n 2 "$results" >&2
  done
done

python3 - "$results" "$influences" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
print(f"\n| bones | posemfa E_RMS | Dem Bones E_RMS | ratio | posemfa max err / diag | Dem Bones max err / diag "
      f"| posemfa export-gltf (s) | Dem Bones solve (s) | time ratio | posemfa CPU (s) | Dem Bones CPU (s) | CPU ratio |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for n in sorted({r["bones_asked"] for r in rows}, key=lambda x: (not x.isdigit(), int(x) if x.isdigit() else 0)):
    p = [r for r in rows if r["bones_asked"] == n and r["tool"] == "posemfa"]
    d = [r for r in rows if r["bones_asked"] == n and r["tool"] == "dem-bones"]
    med = lambda xs, k: statistics.median(x[k] for x in xs)
    pe, de = med(p, "e_rms"), med(d, "e_rms")
    pt, dt = med(p, "seconds"), med(d, "seconds")
    pc, dc = med(p, "cpu_seconds"), med(d, "cpu_seconds")
    print(f"| {n} ({p[0]['bones']} / {d[0]['bones']}) | {pe:.3f} | {de:.3f} | {pe / de:.2f} "
          f"| {med(p, 'max_error_over_diagonal'):.4f} | {med(d, 'max_error_over_diagonal'):.4f} "
          f"| {pt:.2f} | {dt:.2f} | {pt / dt:.3f} | {pc:.2f} | {dc:.2f} | {pc / dc:.3f} |")
n_counts = len({r["bones_asked"] for r in rows})
print(f"\n{len(rows) // 2 // n_counts} runs per tool and count (medians), {sys.argv[2]} influences, E_RMS over {rows[0]['frames']} frames; "
      "bones: asked (posemfa / Dem Bones found)")
PY
