"""Dem Bones side of scripts/bench-rig.sh (benchmark only; runs inside the throwaway venv that script makes).

Reads a folder of OBJ files (same vertices, natural order), takes the file whose stem is `reference` (or,
without one, the first file) as the rest pose and every other file as a frame, solves with
py_dem_bones.solve_skinning (bone count N, 4 influences, its default 30 iterations), plays the result by
linear blend skinning and prints one JSON line: bones found, E_RMS (Kavan et al. 2010: 1000 ||V - V'||_F /
sqrt(3 n_v n_frames) / diagonal of the rest pose's bounding box), per-frame E_RMS, max error / diagonal,
and the solve time (compute() alone; reading and evaluating are not counted).

Usage: python bench-rig-dembones.py DIR BONES [INFLUENCES]
"""
import json
import os
import re
import sys
import time

import numpy as np
import py_dem_bones


def natural_key(s):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return np.array(verts, dtype=np.float64), faces


def main():
    folder, bones = sys.argv[1], int(sys.argv[2])
    influences = int(sys.argv[3]) if len(sys.argv) > 3 else 4
    names = sorted((n for n in os.listdir(folder) if n.lower().endswith(".obj")), key=natural_key)
    rest_name = next((n for n in names if os.path.splitext(n)[0] == "reference"), names[0])
    rest, faces = read_obj(os.path.join(folder, rest_name))
    frame_names = [n for n in names if n != rest_name]
    frames = np.stack([read_obj(os.path.join(folder, n))[0] for n in frame_names])
    t0 = time.perf_counter()
    result = py_dem_bones.solve_skinning(rest, frames, bones, faces=faces, max_influences=influences)
    solve_s = time.perf_counter() - t0
    w = result.weights  # (B, V)
    m = result.transforms  # (F, B, 4, 4), column vectors
    rest_h = np.concatenate([rest, np.ones((rest.shape[0], 1))], axis=1)
    diag = float(np.linalg.norm(rest.max(axis=0) - rest.min(axis=0)))
    sq, per_frame, worst = 0.0, [], 0.0
    for f in range(frames.shape[0]):
        moved = np.einsum("bij,vj->bvi", m[f][:, :3, :], rest_h)  # (B, V, 3)
        pred = np.einsum("bv,bvi->vi", w, moved)
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
    }))


if __name__ == "__main__":
    main()
