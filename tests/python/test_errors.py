"""Bad input from Python raises posemfa.Error (a ValueError) with a clear message, never a crash; the messages
are the CLI's."""

import os
import subprocess

import numpy as np
import pytest

import posemfa


@pytest.fixture(scope="module")
def small():
    return posemfa.generate("quadruped", 1200, 4)


def test_error_is_a_value_error():
    assert issubclass(posemfa.Error, ValueError) and issubclass(posemfa.Cancelled, posemfa.Error)


@pytest.mark.parametrize("shape", [(4, 100), (4, 100, 2), (100, 3), (2, 3, 4, 3)])
def test_wrong_shape(shape):
    with pytest.raises(posemfa.Error, match=r"must be \(poses, vertices, 3\)"):
        posemfa.fit(np.zeros(shape), np.zeros((1, 3), dtype=np.int64))


def test_nan_names_the_pose_and_vertex(small):
    pts = small.points.copy()
    pts[2, 17, 1] = np.nan
    with pytest.raises(posemfa.Error) as e:
        posemfa.fit(pts, small.faces)
    msg = str(e.value)
    # the core's message (the CLI's), which counts vertices from 1 as a file's lines do
    assert "pose 3: vertex 18 has a non-finite coordinate" in msg, msg


def test_faces_outside_the_vertices(small):
    f = small.faces.copy()
    f[5, 1] = small.n_vertices + 3
    with pytest.raises(posemfa.Error, match=r"faces\[5\].*outside 0\.\.1"):
        posemfa.fit(small.points, f)
    f[5, 1] = -1
    with pytest.raises(posemfa.Error, match="outside"):
        posemfa.fit(small.points, f)


def test_faces_of_floats_or_wrong_width(small):
    with pytest.raises(posemfa.Error, match="whole numbers"):
        posemfa.fit(small.points, small.faces.astype(np.float64))
    with pytest.raises(posemfa.Error, match=r"\(triangles, 3\)"):
        posemfa.fit(small.points, small.faces[:, :2])


def test_one_pose_is_not_a_population(small):
    with pytest.raises(posemfa.Error, match="at least 2 shapes"):
        posemfa.fit(small.points[:1], small.faces)


def test_ragged_points():
    with pytest.raises(posemfa.Error, match="cannot be read as an array"):
        posemfa.fit([[[0, 0, 0]], [[0, 0, 0], [1, 1, 1]]], [[0, 0, 0]])


def test_parameters(small):
    with pytest.raises(posemfa.Error, match="unknown parameter 'partz'"):
        posemfa.fit(small, partz=3)
    with pytest.raises(posemfa.Error, match="parts = -1: '-1' is negative"):
        posemfa.fit(small, parts=-1)
    with pytest.raises(posemfa.Error, match="max_iter = abc"):
        posemfa.fit(small, max_iter="abc")
    with pytest.raises(posemfa.Error, match="part_rule = 'best'"):
        posemfa.fit(small, part_rule="best")
    with pytest.raises(posemfa.Error, match="weights = 'heavy'"):
        posemfa.fit(small).export_gltf("/nonexistent/x.glb", weights="heavy")


def test_names_out_of_natural_order(small):
    with pytest.raises(posemfa.Error, match="not in natural order"):
        posemfa.fit(small.points, small.faces, names=["b", "a", "c", "d"])


def test_unreadable_path_has_the_clis_message(tmp_path, cli):
    d = tmp_path / "poses"
    d.mkdir()
    (d / "a.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (d / "b.obj").write_text("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n")
    run = subprocess.run([cli, "fit", str(d)], capture_output=True, text=True)
    assert run.returncode != 0
    with pytest.raises(posemfa.Error) as e:
        posemfa.read(d)
    assert str(e.value) in run.stderr, (str(e.value), run.stderr)
    with pytest.raises(posemfa.Error) as e:
        posemfa.read(tmp_path / "absent")
    assert "absent" in str(e.value)


def test_write_to_a_missing_folder(small):
    m = posemfa.fit(small)
    with pytest.raises(posemfa.Error, match="cannot write"):
        m.save("/nonexistent-folder/m.posemfa")
