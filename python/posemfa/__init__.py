"""posemfa from Python: read registered poses, fit the parts and their motions, export a rig.

    import posemfa
    poses = posemfa.read("horse-poses/")            # every format `posemfa fit` reads
    model = posemfa.fit(poses, bones=20)            # or posemfa.fit(points, faces)
    print(model.labels, model.rmse, model.diagnosis)
    model.export_gltf("horse.glb", weights="fitted")

Coordinates are in the poses' own units throughout (the core's unit box stays inside; ``*_unit`` figures are
the ones ``posemfa fit --json`` prints). Every refusal is a :class:`posemfa.Error` (a ``ValueError``) with the
CLI's message. See docs/python.md.
"""

import json
import os

import numpy as np

from . import _posemfa as _native
from ._posemfa import Error, Poses, formats_read

__version__ = _native.__version__
__all__ = ["Error", "Cancelled", "Poses", "Model", "read", "poses", "generate", "fit", "load", "formats_read"]


class Cancelled(Error):
    """The progress callback returned False: the fit stopped. ``.partial`` is the best model so far
    (``partial.complete`` is False; its labels and motions are usable, its verdict is None)."""

    def __init__(self, message, partial):
        super().__init__(message)
        self.partial = partial


def _paths(path):
    if isinstance(path, (str, bytes, os.PathLike)):
        return [os.fsdecode(path)]
    return [os.fsdecode(p) for p in path]


def read(path, *, object=None, animation=None, frames=None, poses_from=None):
    """Reads poses as ``posemfa fit DIR_OR_FILES`` does: a folder of mesh files (poses in natural order of the
    names), a list of files, a .zip, or one animated glTF / FBX / USD file or point cache.

    object: glTF / FBX / USD, the mesh or object (name or index; default the animated one with most vertices).
    animation: glTF / FBX, the clip or take (default the one with most keyframes). frames: sample N evenly spaced
    times (default the keyframes). poses_from: 'animation' or 'morph-targets' (default: the animation if one
    moves the mesh). Returns :class:`Poses` (``.points`` (n_poses, n_vertices, 3) float64 in the file's units,
    ``.faces`` (n_faces, 3) int64, ``.names``, ``.source``)."""
    return _native.read(_paths(path), object, animation, frames, poses_from)


def poses(points, faces, names=None):
    """:class:`Poses` from arrays: ``points`` (n_poses, n_vertices, 3) in any units, ``faces`` (n_faces, 3)
    vertex indices shared by every pose; ``names`` one per pose in natural order (default "pose 1", ...)."""
    try:
        p = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise Error(f"points cannot be read as an array of numbers: {e}") from None
    if p.ndim != 3 or p.shape[2] != 3:
        raise Error(f"points has shape {p.shape}: it must be (poses, vertices, 3), x y z per vertex")
    try:
        f = np.asarray(faces)
    except (TypeError, ValueError) as e:
        raise Error(f"faces cannot be read as an array: {e}") from None
    if f.size == 0:
        f = f.reshape(0, 3).astype(np.int64)
    if f.dtype.kind not in "iu":
        raise Error(f"faces has dtype {f.dtype}: it must hold whole numbers (vertex indices)")
    if f.ndim != 2 or f.shape[1] != 3:
        raise Error(f"faces has shape {f.shape}: it must be (triangles, 3), three vertex indices per triangle")
    if f.dtype.kind == "u" and f.size and f.max() > np.iinfo(np.int64).max:
        raise Error(f"faces holds the index {f.max()}, past any vertex of points ({p.shape[1]} vertices)")
    names = None if names is None else [str(n) for n in names]
    return _native.poses_from_arrays(p, f.astype(np.int64, copy=False), names)


def generate(preset="quadruped", vertices=10_000, poses=20, seed=0):
    """A generated population, as ``posemfa generate PRESET --vertices N --poses P --seed S`` writes it."""
    return _native.generate(preset, vertices, poses, seed)


def fit(points, faces=None, *, names=None, progress=None, **params):
    """Fits the parts and their motions.

    points: a :class:`Poses` (from :func:`read`: the CLI's population bit for bit) or an array (n_poses,
    n_vertices, 3) with ``faces`` (n_faces, 3). params: the CLI's fit options with ``_`` for ``-`` (defaults as
    ``posemfa fit --help`` prints them): parts=11, seed=0, tol=1e-3, max_iter=300, floor=1e-7,
    literal_eq18=False, no_px=False, no_accel=False, part_rule='tree', distinct_ratio=4.0, blend_ratio=0.1,
    refine_threshold=None, max_subparts=6, refine_tol=1e-2, no_refine=False, subset=2000, coarse=8000,
    bones=None (auto) or N, start_labels=None.

    progress(step) -> bool is called between AECM iterations with a dict (stage 'coarse' | 'refine' | 'final',
    part, of, sub_parts, iteration, total_iterations, log_likelihood, parts, run_finished); returning False stops
    the fit and raises :class:`Cancelled` (its ``.partial`` holds the model so far). An exception raised in the
    callback stops the fit and is raised. The fit runs without the GIL; the callback runs with it.
    """
    if isinstance(points, Poses):
        if faces is not None or names is not None:
            raise Error("fit(poses): faces and names come with the Poses; give either Poses or points and faces")
        p = points
    else:
        if faces is None:
            raise Error("fit(points, faces): the faces are missing (or give the Poses that posemfa.read returns)")
        p = poses(points, faces, names)
    native, stopped = _native.fit(p, progress, **params)
    model = Model(native)
    if stopped:
        raise Cancelled(
            f"the fit was stopped by its progress callback (stage parts so far: {model.n_parts}); "
            "the model so far is this exception's .partial", model)
    return model


def load(path, poses=None):
    """Reads a model file (``posemfa fit --save``, :meth:`Model.save`, the page's Save model). ``poses``: the
    poses it was fitted to, for a file saved without them (checked to be its mesh)."""
    return Model(_native.load(os.fsdecode(path), poses))


class Model:
    """A fitted model. Arrays are numpy; coordinates in the poses' units.

    labels (n_vertices,) each vertex's part; rotations (n_parts, n_poses, 3, 3); translations (n_parts, n_poses,
    3) and latent (n_vertices, 3), so that pose i's vertex j ~ rotations[l, i] @ latent[j] + translations[l, i]
    with l = labels[j]; rmse (the poses' units), rmse_unit (unit box, as ``fit --json``), e_rms; diagnosis
    (dict or None); merge_tree (dict or None)."""

    def __init__(self, native):
        self._m = native

    def __repr__(self):
        return repr(self._m)

    # the arrays and figures
    labels = property(lambda self: self._m.labels)
    coarse_labels = property(lambda self: self._m.coarse_labels)
    refined_labels = property(lambda self: self._m.refined_labels)
    rotations = property(lambda self: self._m.rotations)
    translations = property(lambda self: self._m.translations)
    latent = property(lambda self: self._m.latent)
    variances = property(lambda self: self._m.variances)
    weights = property(lambda self: self._m.weights)
    log_likelihood = property(lambda self: self._m.log_likelihood)
    n_parts = property(lambda self: self._m.n_parts)
    rmse = property(lambda self: self._m.rmse)
    rmse_unit = property(lambda self: self._m.rmse_unit)
    e_rms = property(lambda self: self._m.e_rms)
    iterations = property(lambda self: self._m.iterations)
    converged = property(lambda self: self._m.converged)
    complete = property(lambda self: self._m.complete)
    poses = property(lambda self: self._m.poses)
    has_data = property(lambda self: self._m.has_data)

    @property
    def diagnosis(self):
        """Whether the poses look articulated and why (dict), None for a fit stopped early."""
        return json.loads(self._m.diagnosis_json())

    @property
    def merge_tree(self):
        """The default part rule's merge tree of the fitted parts (dict), None with Algorithm 1's rules."""
        return json.loads(self._m.merge_tree_json())

    @property
    def params(self):
        """The fit parameters (camelCase, every field, as the model file stores them)."""
        return json.loads(self._m.params_json())

    def fit_json(self):
        """``posemfa fit --json``'s document (dict)."""
        return json.loads(self._m.fit_json())

    def interpolate(self, i, j, t):
        """The shape at ``t`` between poses ``i`` and ``j`` (0-based; t = 0 is pose i, 1 pose j): Algorithm 2
        with the CLI's defaults (anchor root, exact ends, residual blending). (n_vertices, 3) float64."""
        return self._m.interpolate(int(i), int(j), float(t))

    def _rigged(self, bones, progress):
        if bones is None or bones == self.n_parts:
            return self
        native, stopped = self._m.refit(int(bones), progress)
        if stopped:
            raise Cancelled("the fit for the rig's bones was stopped by its progress callback", Model(native))
        return Model(native)

    def rig_glb(self, *, weights="rigid", bones=None, influences=4, joints="free", morphs="none", bind=None,
                bone_motion="rigid", candidate_rings=1, alternations=30, progress=None):
        """The rig's .glb bytes and what ``posemfa rig-report`` measures on them: (bytes, info) with info
        ``e_rms``, ``bones``, ``bind`` and ``report`` (dict: per pose errors, and
        ``e_rms_his_centred_half_diagonal``). Options as :meth:`export_gltf`."""
        m = self._rigged(bones, progress)
        glb, info = m._m.rig_glb(weights, int(influences), joints, morphs, bind, bone_motion, int(candidate_rings),
                                 int(alternations))
        info = dict(info)
        info["report"] = json.loads(info["report"])
        return glb, info

    def export_gltf(self, path, *, weights="rigid", bones=None, influences=4, joints="free", morphs="none",
                    bind=None, bone_motion="rigid", candidate_rings=1, alternations=30, progress=None):
        """Writes the rigged .glb (``posemfa export-gltf``) and returns what rig-report measures on it (dict:
        e_rms, bones, bind, report).

        weights: 'rigid' (default), 'smooth' or 'fitted'; bones: the rig's part count (default None: this
        model's parts; another N fits the poses again with bones=N, as ``export-gltf --bones N`` does);
        influences: most joints per vertex, 1-8 (default 4); joints: 'free' (default) or 'fixed' (constant bone
        lengths); morphs: 'none' (default) or 'residual' (one morph target per pose); bind: the pose the mesh is
        bound in, 0-based (default the pose named 'reference' if any, else 0). With fitted weights and free joints:
        bone_motion 'rigid' (default), 'scale' (``--bone-scale``: a scale along three fixed axes per bone) or
        'affine' (``--bone-affine``: any linear map of positive determinant, two leaf nodes per bone; Blender's
        bones cannot hold its shear); candidate_rings 1-3 (``--candidate-rings``, default 1); alternations (most
        alternations of the weight and bone solves, default 30)."""
        glb, info = self.rig_glb(weights=weights, bones=bones, influences=influences, joints=joints,
                                 morphs=morphs, bind=bind, bone_motion=bone_motion,
                                 candidate_rings=candidate_rings, alternations=alternations, progress=progress)
        try:
            with open(path, "wb") as f:
                f.write(glb)
        except OSError as e:
            raise Error(f"cannot write {os.fsdecode(path)}: {e.strerror}") from None
        return info

    def to_bytes(self, with_poses=True):
        """The model file's bytes (format: docs/formats.md, "The model file")."""
        return self._m.to_bytes(with_poses)

    def save(self, path, with_poses=True):
        """Writes the model file (.posemfa) that :func:`load`, ``posemfa --model`` and the page open;
        ``with_poses=False`` leaves the poses out (smaller; views of the data then need them)."""
        data = self._m.to_bytes(with_poses)
        try:
            with open(path, "wb") as f:
                f.write(data)
        except OSError as e:
            raise Error(f"cannot write {os.fsdecode(path)}: {e.strerror}") from None
