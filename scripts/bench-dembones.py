"""Dem Bones side of scripts/bench-dembones.sh (benchmark only; runs in the throwaway venv that script makes).

Usage: python bench-dembones.py DIR BONES INFLUENCES

Reads the OBJ files of DIR (natural order; the one whose stem is `reference`, else the first, is the rest pose, the
others the frames), runs py_dem_bones.solve_skinning (its default 30 iterations) and prints one JSON line:
bones asked and found, the solve's wall time in seconds (the call alone: reading is not counted) and the
reconstruction RMSE in the input's units (linear blend skinning of the rest pose by the result).
Reading, solving and playing back: scripts/dembones_common.py (shared with bench-rig-dembones.py).
"""
import json
import sys

from dembones_common import played, read_folder, solve


def main():
    folder, bones, influences = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    _, rest, faces, _, frames = read_folder(folder)
    r, seconds = solve(rest, faces, frames, bones, influences)
    sq = sum(float(((pred - frames[f]) ** 2).sum()) for f, pred in played(r, rest))
    print(json.dumps({
        "tool": "dem-bones", "bones_asked": bones, "bones": int((r.weights.max(axis=1) > 0).sum()),
        "influences": influences, "frames": len(frames), "vertices": len(rest), "seconds": seconds,
        "rmse": (sq / (3 * len(rest) * len(frames))) ** 0.5,
    }))


if __name__ == "__main__":
    main()
