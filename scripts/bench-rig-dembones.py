"""Dem Bones side of scripts/bench-rig.sh (benchmark only; runs inside the throwaway venv that script makes).

Reads a folder of OBJ files (same vertices, natural order), takes the file whose stem is `reference` (or,
without one, the first file) as the rest pose and every other file as a frame, solves with
py_dem_bones.solve_skinning (bone count N, 4 influences, its default 30 iterations), plays the result by
linear blend skinning and prints one JSON line: bones found, E_RMS (Kavan et al. 2010: 1000 ||V - V'||_F /
sqrt(3 n_v n_frames) / diagonal of the rest pose's bounding box), per-frame E_RMS, max error / diagonal,
and the solve time, wall clock and CPU (compute() alone; reading and evaluating are not counted).
Reading, solving and playing back: scripts/dembones_common.py (shared with bench-dembones.py).

Usage: python bench-rig-dembones.py DIR BONES [INFLUENCES]
"""
import json
import sys
import time

import numpy as np
import py_dem_bones

from dembones_common import played, read_folder, solve


def main():
    folder, bones = sys.argv[1], int(sys.argv[2])
    influences = int(sys.argv[3]) if len(sys.argv) > 3 else 4
    rest_name, rest, faces, frame_names, frames = read_folder(folder)
    c0 = time.process_time()
    result, solve_s = solve(rest, faces, frames, bones, influences)
    solve_cpu_s = time.process_time() - c0  # the same call's CPU time (one thread: OMP_NUM_THREADS=1)
    w = result.weights  # (B, V)
    diag = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
    sq, per_frame, worst = 0.0, [], 0.0
    for f, pred in played(result, rest):
        d = pred - frames[f]
        s = float((d * d).sum())
        sq += s
        per_frame.append(1000 * np.sqrt(s / (3 * rest.shape[0])) / diag)
        worst = max(worst, float(np.sqrt((d * d).sum(axis=1)).max()))
    n = frames.shape[0] * rest.shape[0]
    print(json.dumps({
        "tool": "dem-bones",
        "version": getattr(py_dem_bones, "__version__", "?"),
        "bones_asked": bones,
        "bones": int((w.max(axis=1) > 0).sum()),
        "influences": influences,
        "max_nonzero": int((w > 0).sum(axis=0).max()),
        "rest": rest_name,
        "frames": frame_names,
        "e_rms": 1000 * np.sqrt(sq / (3 * n)) / diag,
        "max_error_over_diagonal": worst / diag,
        "per_frame_e_rms": per_frame,
        "solve_s": solve_s,
        "solve_cpu_s": solve_cpu_s,
    }))


if __name__ == "__main__":
    main()
