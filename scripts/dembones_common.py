"""What scripts/bench-dembones.py and scripts/bench-rig-dembones.py share (benchmark only; runs inside the
throwaway venv their shell scripts make): a folder of OBJ poses read as Dem Bones' rest pose and frames, the
timed solve, and the result played back by linear blend skinning.
"""
import os
import re
import time

import numpy as np
import py_dem_bones


def natural_key(s):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


def read_obj(path):
    """Vertices (n x 3) and faces (0-based, first index of each corner) of one OBJ file."""
    verts, faces = [], []
    with open(path, encoding="latin-1") as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return np.asarray(verts, dtype=np.float64), faces


def read_folder(folder):
    """The OBJ files of `folder` in natural order: the one whose stem is `reference` (else the first) is the rest
    pose, every other file a frame. Returns (rest_name, rest, faces, frame_names, frames as F x n x 3)."""
    names = sorted((n for n in os.listdir(folder) if n.lower().endswith(".obj")), key=natural_key)
    if len(names) < 2:
        raise SystemExit(f"{folder}: needs a rest pose and at least one frame (OBJ files), found {len(names)}")
    rest_name = next((n for n in names if os.path.splitext(n)[0] == "reference"), names[0])
    rest, faces = read_obj(os.path.join(folder, rest_name))
    frame_names = [n for n in names if n != rest_name]
    frames = np.stack([read_obj(os.path.join(folder, n))[0] for n in frame_names])
    return rest_name, rest, faces, frame_names, frames


def solve(rest, faces, frames, bones, influences):
    """py_dem_bones.solve_skinning (its default 30 iterations) and the wall time of that call alone (seconds)."""
    t0 = time.perf_counter()
    result = py_dem_bones.solve_skinning(rest, frames, bones, faces=faces, max_influences=influences)
    return result, time.perf_counter() - t0


def played(result, rest):
    """Each frame of the result by linear blend skinning of the rest pose: yields (F's index, n x 3)."""
    rest_h = np.hstack([rest, np.ones((len(rest), 1))])
    for f in range(len(result.transforms)):
        moved = np.einsum("bij,vj->bvi", result.transforms[f][:, :3, :], rest_h)  # (B, n, 3); column vectors
        yield f, np.einsum("bv,bvi->vi", result.weights, moved)
