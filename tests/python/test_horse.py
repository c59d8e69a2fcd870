"""Fitting ../shared/data/horse-poses from Python gives exactly the CLI's labels and RMSE."""

import json
import os
import subprocess

import numpy as np
import pytest

import posemfa
from conftest import missing


def test_horse_poses_match_the_cli(cli, shared_data, tmp_path):
    data = os.path.join(shared_data, "horse-poses")
    if not os.path.isdir(data):
        missing(f"{data} (research data, ../shared or POSEMFA_SHARED)")
    out = tmp_path / "fit.json"
    subprocess.run([cli, "fit", data, "--quiet", "--json", str(out)], check=True, capture_output=True)
    ref = json.loads(out.read_text())
    model = posemfa.fit(posemfa.read(data))
    assert model.labels.tolist() == ref["labels"]
    assert model.rmse_unit == ref["rmse"]
    assert model.rmse == ref["rmse"] / ref["normalization"]["scale"]
    assert model.e_rms == ref["e_rms"]
    assert model.n_parts == len(ref["parts"])
    rot = np.array([p["rotations"] for p in ref["parts"]]).reshape(model.rotations.shape)
    assert np.array_equal(rot, model.rotations)
    print(f"horse-poses: {model.n_parts} parts, RMSE {model.rmse_unit!r} (unit box) = CLI {ref['rmse']!r}")
