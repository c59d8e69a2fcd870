"""posemfa's Python API on a generated population: arrays, reconstruction, interpolation, rig, model file,
progress and cancel, the GIL."""

import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import posemfa
from posemfa.glb import Rig, e_rms


@pytest.fixture(scope="module")
def poses(quadruped):
    return posemfa.read(quadruped)


@pytest.fixture(scope="module")
def model(poses):
    return posemfa.fit(poses)


def test_read_gives_original_units_and_faces(poses, quadruped):
    names = sorted(f for f in os.listdir(quadruped) if f.endswith(".obj"))
    assert poses.n_poses == len(names) == 10 and poses.names == names
    first = [l.split()[1:4] for l in open(os.path.join(quadruped, poses.names[0])) if l.startswith("v ")]
    first = np.array(first, dtype=np.float64)
    pts = poses.points
    assert pts.shape == (10, poses.n_vertices, 3) and pts.dtype == np.float64
    # original units, within the f32 the population stores (unit box: 6e-8 of its side)
    side = np.ptp(pts.reshape(-1, 3), axis=0).max()
    assert np.abs(pts[0] - first).max() < 1e-6 * side
    f = poses.faces
    assert f.ndim == 2 and f.shape[1] == 3 and f.dtype == np.int64 and f.max() < poses.n_vertices


def test_model_arrays_reconstruct_the_poses(model, poses):
    n_s, n_v = poses.n_poses, poses.n_vertices
    labels, R, t, latent = model.labels, model.rotations, model.translations, model.latent
    assert labels.shape == (n_v,) and R.shape == (model.n_parts, n_s, 3, 3) and t.shape == (model.n_parts, n_s, 3)
    assert latent.shape == (n_v, 3)
    # pose i vertex j ~ R[l_j, i] @ latent_j + t[l_j, i]: the RMSE recomputed here is the model's
    recon = np.einsum("jiab,jb->ija", R[labels], latent) + t[labels].transpose(1, 0, 2)
    rmse = np.sqrt(np.mean(np.sum((recon - poses.points) ** 2, axis=2)))
    assert rmse == pytest.approx(model.rmse, rel=1e-6)
    assert model.rmse_unit == pytest.approx(model.rmse * poses.normalization[1], rel=1e-12)
    assert np.allclose(np.einsum("kiab,kicb->kiac", R, R), np.eye(3), atol=1e-9)
    d = model.diagnosis
    assert d["articulated"] is True and isinstance(d["reason"], str)
    tree = model.merge_tree
    assert tree is not None and len(tree["leaves"]) == n_v


def test_interpolate_ends_and_middle(model, poses):
    a, b, mid = model.interpolate(0, 1, 0.0), model.interpolate(0, 1, 1.0), model.interpolate(0, 1, 0.5)
    pts = poses.points
    side = np.ptp(pts.reshape(-1, 3), axis=0).max()
    # exact ends with the residual: the poses themselves (to f32 of the unit box)
    assert np.abs(a - pts[0]).max() < 1e-5 * side and np.abs(b - pts[1]).max() < 1e-5 * side
    assert np.abs(mid - pts[0]).max() > 1e-3 * side and np.abs(mid - pts[1]).max() > 1e-3 * side
    with pytest.raises(posemfa.Error, match="poses are numbered 0 to 9"):
        model.interpolate(0, 10, 0.5)


def test_rig_played_from_the_file_matches_rig_report(model, poses, tmp_path, quadruped, cli):
    path = tmp_path / "rig.glb"
    info = model.export_gltf(path, weights="fitted", joints="fixed", influences=4)
    rig = Rig(path.read_bytes())
    played = np.stack([rig.play(k) for k in range(rig.n_keys)])
    assert rig.n_keys == poses.n_poses and info["bones"] == len(rig.names) == model.n_parts
    assert e_rms(poses.points, played, info["bind"]) == pytest.approx(info["e_rms"], rel=1e-3)
    # the CLI's rig-report on the same files and options
    out = subprocess.run([cli, "rig-report", quadruped, "--weights", "fitted", "--joints", "fixed"],
                         check=True, capture_output=True, text=True).stdout
    report = json.loads(out.strip().splitlines()[-1])
    assert info["e_rms"] == report["e_rms"]
    # fixed joints: only the root's translation is animated
    assert rig.animated_translation.sum() == 1 and rig.parents[rig.animated_translation][0] == -1


def test_affine_bones_play_from_the_file_and_beat_rigid_ones(model, poses, tmp_path):
    rigid = model.export_gltf(tmp_path / "rigid.glb", weights="fitted")
    info = model.export_gltf(tmp_path / "affine.glb", weights="fitted", bone_motion="affine", candidate_rings=2,
                             influences=8)
    # the skin's joints are the leaves under each joint; the file plays what rig-report measured
    rig = Rig((tmp_path / "affine.glb").read_bytes())
    assert all(n.endswith(" skin") for n in rig.names) and len(rig.names) == info["bones"]
    played = np.stack([rig.play(k) for k in range(rig.n_keys)])
    assert e_rms(poses.points, played, info["bind"]) == pytest.approx(info["e_rms"], rel=1e-3)
    assert info["e_rms"] < rigid["e_rms"], (info["e_rms"], rigid["e_rms"])
    assert info["report"]["e_rms_his_centred_half_diagonal"] > 0
    with pytest.raises(posemfa.Error, match="bone_motion = 'shear': use 'rigid', 'scale' or 'affine'"):
        model.rig_glb(weights="fitted", bone_motion="shear")
    with pytest.raises(posemfa.Error, match="affine bones need fitted weights"):
        model.rig_glb(bone_motion="affine")
    with pytest.raises(posemfa.Error, match="alternations"):
        model.rig_glb(weights="fitted", alternations=0)


def test_rig_with_another_bone_count_refits(model, tmp_path):
    info = model.export_gltf(tmp_path / "six.glb", bones=6)
    assert info["bones"] == 6


def test_model_file_round_trip(model, poses, tmp_path):
    p = tmp_path / "m.posemfa"
    model.save(p)
    back = posemfa.load(p)
    assert np.array_equal(back.labels, model.labels) and back.rmse == model.rmse and back.has_data
    assert np.array_equal(back.rotations, model.rotations)
    q = tmp_path / "bare.posemfa"
    model.save(q, with_poses=False)
    assert os.path.getsize(q) < os.path.getsize(p)
    bare = posemfa.load(q)
    assert not bare.has_data and bare.rmse == model.rmse
    with pytest.raises(posemfa.Error, match="saved without its poses"):
        bare.rig_glb()
    again = posemfa.load(q, poses=poses)
    assert again.has_data and again.rmse == model.rmse
    other = posemfa.generate("snake", 500, 4)
    with pytest.raises(posemfa.Error, match="another mesh"):
        posemfa.load(q, poses=other)


def test_progress_sees_every_stage_and_cancel_keeps_the_partial_model(poses):
    steps = []
    posemfa.fit(poses, progress=lambda s: steps.append(s) or True)
    stages = {s["stage"] for s in steps}
    assert "final" in stages and stages <= {"coarse", "refine", "final", "done"} and all(isinstance(s["log_likelihood"], float) for s in steps)
    seen = []
    with pytest.raises(posemfa.Cancelled) as e:
        posemfa.fit(poses, progress=lambda s: seen.append(s) or len(seen) < 5)
    assert len(seen) == 5 and e.value.partial.complete is False and e.value.partial.diagnosis is None
    assert e.value.partial.labels.shape == (poses.n_vertices,)
    assert isinstance(e.value, posemfa.Error)


def test_an_exception_in_the_callback_stops_the_fit_and_is_raised(poses):
    def boom(step):
        raise KeyError("from the callback")
    with pytest.raises(KeyError, match="from the callback"):
        posemfa.fit(poses, progress=boom)


def test_the_gil_is_released_while_fitting():
    big = posemfa.generate("quadruped", 40000, 16)
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)
    t = threading.Thread(target=tick)
    t.start()
    time.sleep(0.02)
    t0 = time.perf_counter()
    posemfa.fit(big)
    t1 = time.perf_counter()
    done.set()
    t.join()
    # the other thread kept running during the fit: no gap between its ticks near the fit's length (with the GIL
    # held for the whole fit there would be one gap of all of it)
    during = [t0] + [x for x in ticks if t0 < x < t1] + [t1]
    gap = max(np.diff(during))
    assert t1 - t0 > 0.05 and gap < 0.25 * (t1 - t0), (t1 - t0, gap, len(during))


def test_arrays_in_keep_the_given_order_and_units():
    g = posemfa.generate("quadruped", 1500, 6)
    pts = g.points * 100.0 + 7.0          # centimetres, moved: any units
    m = posemfa.fit(pts, g.faces)
    assert m.poses.names == [f"pose {i}" for i in range(1, 7)]
    assert np.abs(m.poses.points - pts).max() < 1e-5 * np.ptp(pts)
    assert m.rmse == pytest.approx(posemfa.fit(g).rmse * 100.0, rel=1e-3)


def test_the_stubs_defaults_are_the_fits(model):
    """__init__.pyi states the defaults of fit: they are the parameters a fit without options used."""
    import ast
    stub = ast.parse(open(os.path.join(os.path.dirname(posemfa.__file__), "__init__.pyi")).read())
    fit = next(f for f in stub.body if isinstance(f, ast.FunctionDef) and f.name == "fit")
    defaults = {a.arg: ast.literal_eval(d) for a, d in zip(fit.args.kwonlyargs, fit.args.kw_defaults) if d is not None}
    names = {"parts": "parts", "seed": "seed", "tol": "tol", "max_iter": "maxIter", "floor": "varianceFloor",
             "distinct_ratio": "distinctRatio", "blend_ratio": "blendRatio", "max_subparts": "maxSubparts",
             "refine_tol": "refineTol", "subset": "subsetVertices", "coarse": "coarseVertices"}
    used = model.params
    for py, field in names.items():
        assert defaults[py] == used[field], (py, defaults[py], used[field])
