"""Dem Bones side of scripts/bench-dembones.sh (benchmark only; runs in the throwaway venv that script makes).

Usage: python bench-dembones.py DIR BONES INFLUENCES

Reads the OBJ files of DIR (natural order; the one named reference.obj, else the first, is the rest pose, the
others the frames), runs py_dem_bones.solve_skinning (its default 30 iterations) and prints one JSON line:
bones asked and found, the solve's wall time in seconds (the call alone: reading is not counted) and the
reconstruction RMSE in the input's units (linear blend skinning of the rest pose by the result).
"""
import json
import os
import re
import sys
import time

import numpy as np
import py_dem_bones


def natural(name):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", name)]


def obj(path):
    v, f = [], []
    for line in open(path, encoding="latin-1"):
        if line.startswith("v "):
            v.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            f.append([int(w.split("/")[0]) - 1 for w in line.split()[1:]])
    return np.asarray(v, dtype=np.float64), f


def main():
    folder, bones, influences = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    names = sorted((n for n in os.listdir(folder) if n.lower().endswith(".obj")), key=natural)
    rest_name = "reference.obj" if "reference.obj" in names else names[0]
    rest, faces = obj(os.path.join(folder, rest_name))
    frames = np.stack([obj(os.path.join(folder, n))[0] for n in names if n != rest_name])
    t0 = time.perf_counter()
    r = py_dem_bones.solve_skinning(rest, frames, bones, faces=faces, max_influences=influences)
    seconds = time.perf_counter() - t0
    rest_h = np.hstack([rest, np.ones((len(rest), 1))])
    sq = 0.0
    for f in range(len(frames)):
        moved = np.einsum("bij,vj->bvi", r.transforms[f][:, :3, :], rest_h)
        d = np.einsum("bv,bvi->vi", r.weights, moved) - frames[f]
        sq += float((d * d).sum())
    print(json.dumps({
        "tool": "dem-bones", "bones_asked": bones, "bones": int((r.weights.max(axis=1) > 0).sum()),
        "influences": influences, "frames": len(frames), "vertices": len(rest), "seconds": seconds,
        "rmse": (sq / (3 * len(rest) * len(frames))) ** 0.5,
    }))


if __name__ == "__main__":
    main()
