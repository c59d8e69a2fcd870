"""Type hints of the posemfa package (docs/python.md). Defaults are those of the CLI (`posemfa fit --help`)."""

import os
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, bytes, "os.PathLike[str]"]
Step = Dict[str, Any]
"""What the progress callback gets after every AECM iteration: stage ('coarse' | 'refine' | 'final' | 'done'),
part / of / sub_parts (the refinement's part, 0-based, of how many, trying how many sub-parts; else None),
iteration, total_iterations, log_likelihood, parts (components of the current run), run_finished."""

class Error(ValueError):
    """Everything posemfa refuses (bad arrays, unreadable files, parameters out of range), with the CLI's
    message."""

class Cancelled(Error):
    """The progress callback returned False. ``partial``: the best model so far (``complete`` False)."""

    partial: "Model"
    def __init__(self, message: str, partial: "Model") -> None: ...

class Poses:
    """Registered poses of one mesh, as the fit sees them (stored as float32 in a unit box)."""

    @property
    def points(self) -> npt.NDArray[np.float64]:
        """(n_poses, n_vertices, 3), the poses' own units."""
    @property
    def unit_points(self) -> npt.NDArray[np.float32]:
        """(n_poses, n_vertices, 3), unit-box coordinates exactly as fitted."""
    @property
    def faces(self) -> npt.NDArray[np.int64]:
        """(n_faces, 3) vertex indices."""
    @property
    def names(self) -> List[str]:
        """The poses' names in the order used (natural order of file names)."""
    @property
    def source(self) -> str:
        """Where the poses came from ("11 OBJ files", ...)."""
    @property
    def normalization(self) -> Tuple[Tuple[float, float, float], float]:
        """(offset, scale): unit = (original - offset) * scale."""
    @property
    def n_poses(self) -> int: ...
    @property
    def n_vertices(self) -> int: ...
    def __len__(self) -> int: ...

class Model:
    """A fitted model: numpy arrays, coordinates in the poses' units."""

    @property
    def labels(self) -> npt.NDArray[np.uint32]:
        """(n_vertices,): each vertex's part (eq 20)."""
    @property
    def coarse_labels(self) -> npt.NDArray[np.uint32]: ...
    @property
    def refined_labels(self) -> npt.NDArray[np.uint32]: ...
    @property
    def rotations(self) -> npt.NDArray[np.float64]:
        """(n_parts, n_poses, 3, 3): each part's rotation in each pose."""
    @property
    def translations(self) -> npt.NDArray[np.float64]:
        """(n_parts, n_poses, 3): pose i vertex j ~ rotations[l, i] @ latent[j] + translations[l, i], l = labels[j]."""
    @property
    def latent(self) -> npt.NDArray[np.float64]:
        """(n_vertices, 3): the latent shape (eq 21), each part in its own frame."""
    @property
    def variances(self) -> npt.NDArray[np.float64]:
        """(n_parts, n_poses): per-pose variances (unit box units^2)."""
    @property
    def weights(self) -> npt.NDArray[np.float64]:
        """(n_parts,): mixing weights."""
    @property
    def log_likelihood(self) -> npt.NDArray[np.float64]:
        """After every iteration of the final AECM run."""
    @property
    def n_parts(self) -> int: ...
    @property
    def rmse(self) -> float:
        """Reconstruction RMSE in the poses' units."""
    @property
    def rmse_unit(self) -> float:
        """The same in the unit box: `rmse` of `posemfa fit --json`."""
    @property
    def e_rms(self) -> float:
        """The fit's error in the rig's measure (thousandths of the bind pose's diagonal)."""
    @property
    def iterations(self) -> int: ...
    @property
    def converged(self) -> bool: ...
    @property
    def complete(self) -> bool:
        """False for a fit stopped by its progress callback."""
    @property
    def poses(self) -> Poses: ...
    @property
    def has_data(self) -> bool:
        """False for a model file saved without its poses."""
    @property
    def diagnosis(self) -> Optional[Dict[str, Any]]:
        """articulated, undecided, reason, singleBodyRmse, partsRmse, explained, parts; None if stopped early."""
    @property
    def merge_tree(self) -> Optional[Dict[str, Any]]:
        """leaves, n_leaves, merges [{a, b, parts, rise, score, variance}], typical; None with Algorithm 1's rules."""
    @property
    def params(self) -> Dict[str, Any]: ...
    def fit_json(self) -> Dict[str, Any]:
        """`posemfa fit --json`'s document."""
    def interpolate(self, i: int, j: int, t: float) -> npt.NDArray[np.float64]:
        """(n_vertices, 3): the shape at t between poses i and j (0-based; negative counts from the end)."""
    def rig_glb(self, *, weights: str = "rigid", bones: Optional[int] = None, influences: int = 4,
                joints: str = "free", morphs: str = "none", bind: Optional[int] = None, bone_motion: str = "rigid",
                candidate_rings: int = 1, alternations: int = 30,
                progress: Optional[Callable[[Step], bool]] = None) -> Tuple[bytes, Dict[str, Any]]:
        """The rig's .glb bytes and rig-report's figures (e_rms, bones, bind, report)."""
    def export_gltf(self, path: PathLike, *, weights: str = "rigid", bones: Optional[int] = None,
                    influences: int = 4, joints: str = "free", morphs: str = "none", bind: Optional[int] = None,
                    bone_motion: str = "rigid", candidate_rings: int = 1, alternations: int = 30,
                    progress: Optional[Callable[[Step], bool]] = None) -> Dict[str, Any]:
        """Writes the rigged .glb. weights 'rigid' | 'smooth' | 'fitted'; bones None = this model's parts (N refits
        with bones=N); influences 1-8; joints 'free' | 'fixed'; morphs 'none' | 'residual'; bind default the pose
        named 'reference', else 0; bone_motion 'rigid' | 'scale' | 'affine' and candidate_rings 1-3 (fitted weights,
        free joints); alternations 1-10000. Returns e_rms, bones, bind, report."""
    def to_bytes(self, with_poses: bool = True) -> bytes: ...
    def save(self, path: PathLike, with_poses: bool = True) -> None:
        """Writes the model file (.posemfa)."""

def read(path: Union[PathLike, Iterable[PathLike]], *, object: Optional[str] = None,
         animation: Optional[str] = None, frames: Optional[int] = None,
         poses_from: Optional[str] = None) -> Poses:
    """A folder, files, a .zip, or one glTF / FBX / USD / point cache, as `posemfa fit DIR_OR_FILES` reads them.
    object: the mesh (default the animated one with most vertices); animation: the clip (default the one with
    most keyframes); frames: N evenly spaced samples (default the keyframes); poses_from: 'animation' |
    'morph-targets' (default the animation if one moves the mesh)."""

def poses(points: npt.ArrayLike, faces: npt.ArrayLike, names: Optional[Sequence[str]] = None) -> Poses:
    """Poses from arrays (n_poses, n_vertices, 3) and (n_faces, 3); names in natural order (default "pose 1"...)."""

def generate(preset: str = "quadruped", vertices: int = 10000, poses: int = 20, seed: int = 0) -> Poses:
    """A generated population (`posemfa generate`)."""

def fit(points: Union[Poses, npt.ArrayLike], faces: Optional[npt.ArrayLike] = None, *,
        names: Optional[Sequence[str]] = None, progress: Optional[Callable[[Step], bool]] = None,
        parts: int = 11, seed: int = 0, tol: float = 1e-3, max_iter: int = 300, floor: float = 1e-7,
        literal_eq18: bool = False, no_px: bool = False, no_accel: bool = False, part_rule: str = "tree",
        distinct_ratio: float = 4.0, blend_ratio: float = 0.1, refine_threshold: Optional[float] = None,
        max_subparts: int = 6, refine_tol: float = 1e-2, no_refine: bool = False, subset: int = 2000,
        coarse: int = 8000, bones: Optional[int] = None, start_labels: Optional[Sequence[int]] = None) -> Model:
    """Fits (the GIL released); the parameters are `posemfa fit`'s options with `_` for `-`, with its defaults
    (refine_threshold None: the tree rule; a value implies part_rule='threshold'; bones None: auto).
    progress(step) -> bool between iterations; False raises Cancelled (with .partial), an exception in it is
    raised."""

def load(path: PathLike, poses: Optional[Poses] = None) -> Model:
    """Reads a model file; poses: those it was fitted to, for a file saved without them."""

def formats_read() -> str:
    """The formats `read` takes."""
