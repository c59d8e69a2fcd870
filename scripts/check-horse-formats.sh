#!/usr/bin/env bash
# The readers' checks on the real horses (each format fits as the OBJ poses do), with files written by Blender
# (into a temporary folder, removed at the end: nothing from ../shared is kept or committed), at each seed given:
#   1. horse-gallop's 48 frames as Blender shape keys (one .glb, animated one key per frame) fit like the OBJ
#      folder at the same seed: part count within +-3 and RMSE within 10 % of the OBJ fit's; the poses read from
#      the animation (49 frames) and from the morph targets (`--poses-from morph-targets`: 48 targets + base).
#   2. horse-poses rigged by `posemfa export-gltf`, imported by Blender and exported again flat (every vertex
#      split per face corner, as Blender does for a mesh without smooth normals): welded back to the OBJ
#      folder's vertex count, and it fits.
#   3. PLY ASCII / binary and .pc2 versions of horse-poses fit like the OBJ folder at the same seed: same part
#      count, adjusted Rand index >= 0.99 (`cargo test --test formats horse` with POSEMFA_SEEDS set to the
#      seeds; its lines are printed here).
#
# Usage: scripts/check-horse-formats.sh [--seeds S[,S...]] [DATA_DIR]
#        (seeds default 0; DATA_DIR default ../shared/data; needs Blender: apt-get install -y blender
#        python3-numpy). Prints one line per check and seed with its figures; exits 1 when a check fails, 2 when
#        the arguments are wrong or Blender or the data are missing.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
usage() { sed -n '/^# Usage:/,/^$/p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
seeds=0
data=../shared/data
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) [ $# -ge 2 ] || usage; seeds=$2; shift 2 ;;
    --seeds=*) seeds=${1#--seeds=}; shift ;;
    -h|--help) usage ;;
    -*) echo "check-horse-formats: unknown option '$1'" >&2; usage ;;
    *) data=$1; shift ;;
  esac
done
[[ $seeds =~ ^[0-9]+(,[0-9]+)*$ ]] \
  || { echo "check-horse-formats: --seeds takes whole numbers separated by commas (e.g. 0,1,2), not '$seeds'" >&2; exit 2; }
for d in horse-gallop horse-poses; do
  [ -d "$data/$d" ] || { echo "check-horse-formats: $data/$d is absent (give the data folder as the argument)" >&2; exit 2; }
done
data=$(realpath "$data")   # Blender is given absolute paths
command -v blender >/dev/null || { echo "check-horse-formats: blender is missing (apt-get install -y blender python3-numpy)" >&2; exit 2; }
cargo build --release --quiet --bin posemfa
posemfa=$(realpath "${CARGO_TARGET_DIR:-target}")/release/posemfa   # cargo honours CARGO_TARGET_DIR too
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
source scripts/fixtures/blender.sh   # blender_py

echo "[check] Blender: horse-gallop as shape keys; horse-poses rigged by posemfa, re-exported flat"
blender_py shapekeys "$data/horse-gallop" "$tmp/gallop-shapekeys.glb"
"$posemfa" export-gltf "$data/horse-poses" --out "$tmp/horse-posemfa.glb" >/dev/null
blender_py reexport "$tmp/horse-posemfa.glb" "$tmp/horse-skinned-flat.glb" --flat

ok=0
for seed in ${seeds//,/ }; do
  echo "[check] seed $seed: fits of the OBJ folders and of Blender's files"
  fit() { "$posemfa" fit "$1" --seed "$seed" --quiet --json "$tmp/$2.json" "${@:3}" >/dev/null; }
  fit "$data/horse-gallop" gallop-obj
  fit "$tmp/gallop-shapekeys.glb" gallop-glb
  fit "$tmp/gallop-shapekeys.glb" gallop-targets --poses-from morph-targets
  fit "$data/horse-poses" poses-obj
  fit "$tmp/horse-skinned-flat.glb" poses-skinned
  node - "$tmp" "$seed" <<'JS' || ok=1
const { readFileSync } = require('node:fs');
const [dir, seed] = process.argv.slice(2);
const r = (n) => JSON.parse(readFileSync(`${dir}/${n}.json`, 'utf8'));
const parts = (j) => j.parts.length;
let ok = true;
const check = (pass, line) => { console.log(`${pass ? 'ok  ' : 'FAIL'} seed ${seed}: ${line}`); ok &&= pass; };
const go = r('gallop-obj');
for (const [name, what] of [['gallop-glb', 'animation'], ['gallop-targets', 'morph targets']]) {
  const gg = r(name);
  const rel = Math.abs(gg.rmse - go.rmse) / go.rmse;
  check(gg.shapes.length === go.shapes.length && gg.n_vertices === go.n_vertices
    && Math.abs(parts(gg) - parts(go)) <= 3 && rel <= 0.1,
    `horse-gallop, Blender shape-key .glb (${what}): ${gg.shapes.length} poses x ${gg.n_vertices} vertices, ${parts(gg)} parts, RMSE ${gg.rmse.toFixed(5)}`
    + ` | OBJ folder: ${go.shapes.length} x ${go.n_vertices}, ${parts(go)} parts, RMSE ${go.rmse.toFixed(5)}`
    + ` (parts within 3, RMSE ${(100 * rel).toFixed(1)} % apart <= 10 %) | ${gg.source}`);
}
const [po, ps] = [r('poses-obj'), r('poses-skinned')];
const welded = /(\d+) vertices welded to (\d+)/.exec(ps.source);
check(ps.n_vertices === po.n_vertices && welded !== null && Number(welded[1]) > ps.n_vertices && parts(ps) >= 2
  && Number.isFinite(ps.rmse),
  `horse-poses, Blender skinned .glb with seams: ${welded ? `${welded[1]} vertices in the file welded to ${welded[2]}` : 'no weld reported'}`
  + ` (OBJ: ${po.n_vertices}), ${ps.shapes.length} frames, ${parts(ps)} parts, RMSE ${ps.rmse.toFixed(5)} | ${ps.source}`);
process.exit(ok ? 0 : 1);
JS
done

echo "[check] horse-poses as ASCII PLY, binary PLY and .pc2 against the OBJ folder (cargo test --test formats horse)"
mkdir "$tmp/shared" && ln -s "$data" "$tmp/shared/data"   # the test reads POSEMFA_SHARED/data/horse-poses
if POSEMFA_SHARED=$tmp/shared POSEMFA_SEEDS=$seeds cargo test --quiet --test formats horse_as_ply_and_pc2 -- --nocapture >"$tmp/test.log" 2>&1; then
  grep -E '^(ok  |FAIL) seed' "$tmp/test.log"
  grep -q '^ok   seed' "$tmp/test.log" || { cat "$tmp/test.log" >&2; echo "check-horse-formats: the test printed no figures" >&2; ok=1; }
else
  cat "$tmp/test.log" >&2
  ok=1
fi
exit $ok
