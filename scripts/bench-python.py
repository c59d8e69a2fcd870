"""Times a fit from Python against the CLI's on the same files (the binding's overhead is meant to stay
within 10 %). Prints figures; asserts
nothing (CONTRIBUTING.md: timing goals are benchmarks).

  .venv-python/bin/python scripts/bench-python.py [DIR] [--runs N] [--cli target/release/posemfa]

DIR: a population folder; default the generated quadruped of 50 000 vertices x 20 poses, written once with
`posemfa generate quadruped --vertices 50000 --poses 20` into a temporary folder. Each run times the CLI
(`posemfa fit DIR --quiet`: the fit's own time, as it prints it) and Python (`posemfa.fit(poses)` on the poses
read once, wall clock), alternating; medians and their ratio are printed.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import posemfa

ap = argparse.ArgumentParser()
ap.add_argument("dir", nargs="?")
ap.add_argument("--runs", type=int, default=3)
ap.add_argument("--cli", default=os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                              "target", "release", "posemfa"))
a = ap.parse_args()
if not os.access(a.cli, os.X_OK):
    sys.exit(f"no CLI at {a.cli}: cargo build --release (or --cli PATH)")
tmp = None
data = a.dir
if data is None:
    tmp = tempfile.TemporaryDirectory()
    data = tmp.name
    subprocess.run([a.cli, "generate", "quadruped", "--vertices", "50000", "--poses", "20", "--out", data],
                   check=True, capture_output=True)
poses = posemfa.read(data)
print(f"{data}: {poses.n_poses} poses x {poses.n_vertices} vertices; {a.runs} runs, alternating")
cli_ms, py_ms = [], []
for run in range(a.runs):
    out = subprocess.run([a.cli, "fit", data, "--quiet"], check=True, capture_output=True, text=True).stdout
    m = re.search(r"\| ([0-9.]+) ms \(load", out)
    if m is None:
        sys.exit(f"cannot find the fit time in the CLI's output:\n{out}")
    cli_ms.append(float(m.group(1)))
    t = time.perf_counter()
    model = posemfa.fit(poses)
    py_ms.append(1e3 * (time.perf_counter() - t))
    print(f"  run {run + 1}: CLI {cli_ms[-1]:.0f} ms, Python {py_ms[-1]:.0f} ms ({model.n_parts} parts)")
c, p = statistics.median(cli_ms), statistics.median(py_ms)
print(f"median: CLI {c:.0f} ms, Python {p:.0f} ms, Python / CLI = {p / c:.3f}")
