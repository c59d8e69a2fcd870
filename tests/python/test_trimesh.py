"""docs/python.md's example: meshes read with trimesh, fitted from arrays."""

import glob

import numpy as np

import posemfa


def test_docs_example_with_trimesh(quadruped):
    import trimesh
    meshes = [trimesh.load(f, process=False) for f in sorted(glob.glob(f"{quadruped}/*.obj"))]
    points = np.stack([m.vertices for m in meshes])
    model = posemfa.fit(points, meshes[0].faces)
    print(model.n_parts, "parts, RMSE", model.rmse)
    # the same population as the CLI reads from the files: the same parts
    ref = posemfa.fit(posemfa.read(quadruped))
    assert model.n_parts == ref.n_parts
    assert np.array_equal(model.labels, ref.labels)
    assert abs(model.rmse - ref.rmse) <= 1e-6 * ref.rmse
