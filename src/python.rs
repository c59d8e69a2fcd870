//! The Python extension module `posemfa._posemfa` (cargo feature `python`; built by maturin from
//! `pyproject.toml`). Conversion only, as in [`crate::wasm`]: the core reads, fits, articulates and writes; this
//! module turns numpy arrays and keyword arguments into its types and its results into numpy arrays. The
//! pure-Python layer (`python/posemfa/`) gives the documented API (`posemfa.read`, `posemfa.fit`, ...) on top.
//!
//! Coordinates handed to Python are in the population's original units (the unit box is the core's working
//! frame: [`crate::mesh::Normalization`]); the `*_unit` getters give the unit-box figures the CLI's JSON holds.
//! Errors are `posemfa.Error` (a `ValueError`) with the core's messages, the words the CLI prints. The GIL is
//! released while reading and fitting; a progress callback runs with it held again, between AECM iterations.

use crate::export::gltf::{GltfOptions, Joints, Morphs, Weights};
use crate::mesh::gltf::PoseSource;
use crate::mesh::{Mesh, Population, ReadOptions, Sources};
use crate::mfa::{FitStart, FlatParams, LambdaRule, Params, PartRule};
use crate::model_file::{Borrowed, ModelFile, Summary};
use crate::parts::hierarchy::{FitResult, Pipeline, Progress, Stage};
use numpy::ndarray::{Array1, Array2, Array3, Array4};
use numpy::{PyArray1, PyArray2, PyArray3, PyArray4, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

pyo3::create_exception!(
    posemfa,
    Error,
    PyValueError,
    "What posemfa refuses: bad input, a file it cannot read, parameters out of range (the CLI's messages)."
);

fn err(message: impl std::fmt::Display) -> PyErr {
    Error::new_err(message.to_string())
}

fn core<T>(r: crate::Result<T>) -> PyResult<T> {
    r.map_err(err)
}

fn array2<'py, T: numpy::Element>(py: Python<'py>, v: Vec<T>, cols: usize) -> PyResult<Bound<'py, PyArray2<T>>> {
    let rows = v.len() / cols.max(1);
    let a = Array2::from_shape_vec((rows, cols), v).map_err(err)?;
    Ok(PyArray2::from_owned_array(py, a))
}

fn array3<'py, T: numpy::Element>(
    py: Python<'py>,
    v: Vec<T>,
    shape: (usize, usize, usize),
) -> PyResult<Bound<'py, PyArray3<T>>> {
    Ok(PyArray3::from_owned_array(py, Array3::from_shape_vec(shape, v).map_err(err)?))
}

// ---------------------------------------------------------------- poses

/// Registered poses of one mesh (the core's population): unit-box points in f32 and how to map them back.
#[pyclass(module = "posemfa._posemfa", name = "Poses", frozen)]
#[derive(Clone)]
pub struct PyPoses {
    pop: Population,
}

#[pymethods]
impl PyPoses {
    /// (n_poses, n_vertices, 3) float64, original units.
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let (ns, nv) = (self.pop.n_shapes(), self.pop.n_vertices());
        let norm = self.pop.normalization;
        let mut v = Vec::with_capacity(ns * nv * 3);
        for s in self.pop.shapes() {
            for p in s.iter() {
                v.extend(norm.to_original(p));
            }
        }
        array3(py, v, (ns, nv, 3))
    }

    /// (n_poses, n_vertices, 3) float32, unit-box coordinates as the fit sees them.
    #[getter]
    fn unit_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let (ns, nv) = (self.pop.n_shapes(), self.pop.n_vertices());
        let v: Vec<f32> = self.pop.shapes().flat_map(|s| s.as_f32().iter().flatten().copied()).collect();
        array3(py, v, (ns, nv, 3))
    }

    /// (n_faces, 3) int64 vertex indices.
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        array2(py, self.pop.faces.iter().flatten().map(|&i| i as i64).collect(), 3)
    }

    #[getter]
    fn names(&self) -> Vec<String> {
        self.pop.names.clone()
    }

    #[getter]
    fn source(&self) -> String {
        self.pop.source.clone()
    }

    /// (offset, scale): unit = (original - offset) * scale.
    #[getter]
    fn normalization(&self) -> ([f64; 3], f64) {
        (self.pop.normalization.offset, self.pop.normalization.scale)
    }

    #[getter]
    fn n_poses(&self) -> usize {
        self.pop.n_shapes()
    }

    #[getter]
    fn n_vertices(&self) -> usize {
        self.pop.n_vertices()
    }

    fn __len__(&self) -> usize {
        self.pop.n_shapes()
    }

    fn __repr__(&self) -> String {
        format!(
            "<posemfa.Poses: {} poses x {} vertices, {} triangles; {}>",
            self.pop.n_shapes(),
            self.pop.n_vertices(),
            self.pop.faces.len(),
            self.pop.source
        )
    }
}

/// Reads poses as `posemfa fit DIR_OR_FILES` does: a folder, files, a zip, or one glTF / FBX / USD / point cache.
#[pyfunction]
#[pyo3(signature = (paths, object=None, animation=None, frames=None, poses_from=None))]
fn read(
    py: Python<'_>,
    paths: Vec<std::path::PathBuf>,
    object: Option<String>,
    animation: Option<String>,
    frames: Option<usize>,
    poses_from: Option<String>,
) -> PyResult<PyPoses> {
    let source = match poses_from.as_deref() {
        None => PoseSource::Auto,
        Some("animation") => PoseSource::Animation,
        Some("morph-targets") => PoseSource::MorphTargets,
        Some(other) => {
            return Err(err(format!("poses_from = '{other}': use 'animation' or 'morph-targets' (or None: either)")))
        }
    };
    if paths.is_empty() {
        return Err(err("no files were given"));
    }
    let gltf = crate::mesh::gltf::Options { mesh: object, animation, frames, source };
    let pop = py.detach(|| Population::read(Sources::paths(&paths), &ReadOptions { gltf }));
    Ok(PyPoses { pop: core(pop.map_err(|mut e| e.swap_remove(0)))? })
}

/// Poses from arrays: `points` (n_poses, n_vertices, 3) float64 in any units, `faces` (n_faces, 3) int64,
/// `names` one per pose in natural order (default "pose 1", "pose 2", ...).
#[pyfunction]
#[pyo3(signature = (points, faces, names=None))]
fn poses_from_arrays(
    py: Python<'_>,
    points: PyReadonlyArray3<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    names: Option<Vec<String>>,
) -> PyResult<PyPoses> {
    let p = points.as_array();
    let (ns, nv, three) = p.dim();
    if three != 3 {
        return Err(err(format!(
            "points has shape ({ns}, {nv}, {three}): it must be (poses, vertices, 3), x y z per vertex"
        )));
    }
    if nv == 0 {
        return Err(err("points has no vertices: it must be (poses, vertices, 3) with at least one vertex"));
    }
    let f = faces.as_array();
    if f.dim().1 != 3 {
        return Err(err(format!(
            "faces has shape ({}, {}): it must be (triangles, 3), three vertex indices per triangle",
            f.dim().0,
            f.dim().1
        )));
    }
    let mut tris = Vec::with_capacity(f.dim().0);
    for (t, row) in f.outer_iter().enumerate() {
        let mut tri = [0u32; 3];
        for (c, &i) in row.iter().enumerate() {
            if i < 0 || i as u64 >= nv as u64 {
                return Err(err(format!(
                    "faces[{t}] = [{}, {}, {}]: vertex index {i} is outside 0..{} (points has {nv} vertices); faces \
                     and points must come from the same mesh",
                    row[0],
                    row[1],
                    row[2],
                    nv - 1
                )));
            }
            tri[c] = i as u32;
        }
        tris.push(tri);
    }
    let names = match names {
        Some(n) => {
            if n.len() != ns {
                return Err(err(format!("{} names for {ns} poses: give one name per pose", n.len())));
            }
            for w in n.windows(2) {
                if crate::mesh::population::natural_cmp(&w[0], &w[1]) != std::cmp::Ordering::Less {
                    return Err(err(format!(
                        "names '{}' and '{}' are not in natural order: posemfa orders poses by name as it orders \
                         files (\"2\" before \"10\"), so give the poses in that order (or no names)",
                        w[0], w[1]
                    )));
                }
            }
            n
        }
        None => (1..=ns).map(|i| format!("pose {i}")).collect(),
    };
    let mut meshes = Vec::with_capacity(ns);
    for (name, shape) in names.into_iter().zip(p.outer_iter()) {
        let positions: Vec<[f64; 3]> = shape.outer_iter().map(|v| [v[0], v[1], v[2]]).collect();
        meshes.push((name, Mesh { positions, faces: tris.clone() }));
    }
    let pop = py.detach(|| Population::new(crate::mesh::Sources::Meshes(meshes)));
    let mut pop = core(pop)?;
    pop.source = format!("{ns} poses from arrays");
    Ok(PyPoses { pop })
}

/// A generated population (`posemfa generate PRESET`): the poses only.
#[pyfunction]
#[pyo3(signature = (preset="quadruped", vertices=10_000, poses=20, seed=0))]
fn generate(py: Python<'_>, preset: &str, vertices: usize, poses: usize, seed: u64) -> PyResult<PyPoses> {
    let names: Vec<&str> = crate::synth::Preset::ALL.iter().map(|p| p.name()).collect();
    let p = crate::synth::Preset::ALL
        .iter()
        .find(|p| p.name() == preset)
        .copied()
        .ok_or_else(|| err(format!("unknown preset '{preset}': use one of {}", names.join(", "))))?;
    let spec = crate::synth::Spec { preset: p, vertices, poses, seed, ..Default::default() };
    let g = py.detach(|| crate::synth::generate(&spec));
    Ok(PyPoses { pop: core(g)?.population })
}

// ---------------------------------------------------------------- parameters

const PARAM_NAMES: &[&str] = &[
    "parts",
    "seed",
    "tol",
    "max_iter",
    "floor",
    "literal_eq18",
    "no_px",
    "no_accel",
    "part_rule",
    "distinct_ratio",
    "blend_ratio",
    "refine_threshold",
    "max_subparts",
    "refine_tol",
    "no_refine",
    "subset",
    "coarse",
    "bones",
    "start_labels",
];

/// The fit parameters of the CLI's fit options (`posemfa fit --help`), by their names with `_` for `-`, and
/// the start (`start_labels`).
fn params_from(kwargs: &Bound<'_, PyDict>, n_vertices: usize) -> PyResult<(Params, FitStart)> {
    let mut p = Params::default();
    let mut start = FitStart::default();
    let mut part_rule = None;
    let mut threshold = None;
    for (k, v) in kwargs.iter() {
        let key: String = k.extract().map_err(|_| err("parameter names must be strings"))?;
        if v.is_none() {
            continue;
        }
        let shown = v.str()?.to_string();
        let text = || -> PyResult<String> { Ok(shown.clone()) };
        let whole = |what: &str| -> PyResult<usize> {
            if v.is_instance_of::<pyo3::types::PyBool>() {
                return Err(err(format!("{key} = {}: it must be {what}, not True or False", text()?)));
            }
            v.extract::<usize>().map_err(|_| err(format!("{key} = {shown}: it must be {what}")))
        };
        let number = |what: &str| -> PyResult<f64> {
            let x = v.extract::<f64>().map_err(|_| err(format!("{key} = {shown}: it must be {what}")))?;
            if !x.is_finite() {
                return Err(err(format!("{key} = {x}: it must be {what}")));
            }
            Ok(x)
        };
        let flag = || -> PyResult<bool> {
            v.extract::<bool>().map_err(|_| err(format!("{key} = {shown}: it must be True or False")))
        };
        // the form's fields, read as the CLI reads them (the same words for a value it cannot use)
        let field = |p: &mut Params, name: &str| -> PyResult<()> {
            if v.is_instance_of::<pyo3::types::PyBool>() {
                return Err(err(format!("{key} = {}: it must be a number", text()?)));
            }
            p.set_field(name, &text()?).map_err(|e| err(format!("{key} = {shown}: {e}")))
        };
        match key.as_str() {
            "parts" => field(&mut p, "parts")?,
            "seed" => field(&mut p, "seed")?,
            "tol" => field(&mut p, "tol")?,
            "floor" => field(&mut p, "varianceFloor")?,
            "bones" => field(&mut p, "targetParts")?,
            "max_iter" => p.max_iter = whole("a whole number of iterations")?,
            "literal_eq18" => {
                if flag()? {
                    p.lambda_rule = LambdaRule::PaperEq18
                }
            }
            "no_px" => p.px_em = !flag()?,
            "no_accel" => p.accelerate = !flag()?,
            "no_refine" => p.refine = !flag()?,
            "part_rule" => {
                part_rule = Some(match text()?.as_str() {
                    "tree" => PartRule::Tree,
                    "distinct" => PartRule::Distinct,
                    "threshold" => PartRule::Threshold,
                    other => return Err(err(format!("part_rule = '{other}': use 'tree', 'distinct' or 'threshold'"))),
                })
            }
            "distinct_ratio" => p.distinct.distinct_ratio = number("a number")?,
            "blend_ratio" => p.distinct.blend_ratio = number("a number")?,
            "refine_threshold" => threshold = Some(number("a number")?),
            "max_subparts" => p.algorithm1.max_subparts = whole("a whole number")?,
            "refine_tol" => p.refine_tol = number("a number")?,
            "subset" => p.algorithm1.subset_vertices = whole("a whole number of vertices (0 = all)")?,
            "coarse" => p.tree.coarse_vertices = whole("a whole number of vertices (0 = decide on all)")?,
            "start_labels" => {
                let labels: Vec<u32> = v.extract().map_err(|_| {
                    err("start_labels: it must be a sequence of whole numbers, one part per vertex".to_string())
                })?;
                if labels.len() != n_vertices {
                    return Err(err(format!(
                        "start_labels has {} labels for {n_vertices} vertices: give one part per vertex",
                        labels.len()
                    )));
                }
                start.labels = Some(labels);
            }
            other => {
                return Err(err(format!("unknown parameter '{other}': the parameters are {}", PARAM_NAMES.join(", "))))
            }
        }
    }
    if let Some(rule) = part_rule {
        p.part_rule = rule;
    }
    if let Some(e) = threshold {
        if let Some(rule @ (PartRule::Distinct | PartRule::Tree)) = part_rule {
            let name = if rule == PartRule::Tree { "tree" } else { "distinct" };
            return Err(err(format!(
                "refine_threshold is the paper's part rule (threshold): leave out part_rule='{name}'"
            )));
        }
        p.algorithm1.threshold.refine_threshold = e;
        p.part_rule = PartRule::Threshold;
    }
    core(p.validate())?;
    Ok((p, start))
}

// ---------------------------------------------------------------- fitting

fn stage_dict<'py>(py: Python<'py>, p: &Progress) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let (name, part, of, sub_parts) = match p.stage {
        Stage::Coarse => ("coarse", None, None, None),
        Stage::Refine { part, of, sub_parts } => ("refine", Some(part), Some(of), Some(sub_parts)),
        Stage::Final { .. } => ("final", None, None, None),
        Stage::Done => ("done", None, None, None),
    };
    d.set_item("stage", name)?;
    d.set_item("part", part)?;
    d.set_item("of", of)?;
    d.set_item("sub_parts", sub_parts)?;
    d.set_item("iteration", p.iteration)?;
    d.set_item("total_iterations", p.total_iterations)?;
    d.set_item("log_likelihood", p.log_likelihood)?;
    d.set_item("parts", p.parts)?;
    d.set_item("run_finished", p.run_finished)?;
    Ok(d)
}

/// Fits with the GIL released; `progress(step) -> bool` between iterations (False stops, keeping the best model
/// so far). Returns the result and whether the callback stopped it; an exception the callback raised is raised.
fn run_fit(
    py: Python<'_>,
    pop: &Population,
    params: &Params,
    start: &FitStart,
    progress: Option<Py<PyAny>>,
) -> PyResult<(FitResult, bool)> {
    let mut raised: Option<PyErr> = None;
    let mut stopped = false;
    let result = py.detach(|| -> crate::Result<FitResult> {
        let mut pipe = Pipeline::starting(pop, params, start)?;
        let mut observer = |p: &Progress| -> bool {
            let Some(cb) = &progress else { return true };
            Python::attach(|py| {
                let answer = stage_dict(py, p).and_then(|d| cb.call1(py, (d,))).and_then(|r| r.is_truthy(py));
                match answer {
                    Ok(true) => true,
                    Ok(false) => {
                        stopped = true;
                        false
                    }
                    Err(e) => {
                        raised = Some(e);
                        false
                    }
                }
            })
        };
        pipe.run(&mut observer)
    });
    if let Some(e) = raised {
        return Err(e);
    }
    Ok((core(result)?, stopped))
}

/// Fits `poses` with the CLI's fit options as keyword arguments; returns (model, stopped by the callback).
#[pyfunction]
#[pyo3(signature = (poses, progress=None, **params))]
fn fit(
    py: Python<'_>,
    poses: &PyPoses,
    progress: Option<Py<PyAny>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<(PyModel, bool)> {
    let (params, start) = match params {
        Some(d) => params_from(d, poses.pop.n_vertices())?,
        None => params_from(&PyDict::new(py), poses.pop.n_vertices())?,
    };
    let (result, stopped) = run_fit(py, &poses.pop, &params, &start, progress)?;
    Ok((PyModel::fitted(poses.pop.clone(), result, params), stopped))
}

/// Reads a model file (`posemfa fit --save`, `Model.save`, the page's Save model); with `poses`, those are put
/// under it after checking they are its mesh.
#[pyfunction]
#[pyo3(signature = (path, poses=None))]
fn load(py: Python<'_>, path: std::path::PathBuf, poses: Option<&PyPoses>) -> PyResult<PyModel> {
    let name = path.display().to_string();
    let pop = poses.map(|p| p.pop.clone());
    let file = py.detach(|| -> crate::Result<ModelFile> {
        let bytes =
            std::fs::read(&path).map_err(|e| crate::Error::Io(format!("cannot read model file {name}: {e}")))?;
        let m = ModelFile::from_bytes(&name, &bytes)?;
        match pop {
            Some(pop) => m.with_population(&name, pop),
            None => Ok(m),
        }
    });
    Ok(PyModel::from_file(core(file)?))
}

// ---------------------------------------------------------------- the model

/// A fit (or a model file read back): its population, result and parameters. The figures measured on the poses
/// (RMSE, E_RMS, the verdict: [`Summary`]) are measured when first asked for, so that `fit` takes the time the
/// CLI's fit takes (its summary is measured after its timer too).
#[pyclass(module = "posemfa._posemfa", name = "Model", frozen)]
pub struct PyModel {
    result: FitResult,
    params: Params,
    pop: Population,
    has_data: bool,
    summary: std::sync::OnceLock<Summary>,
    /// The rig kept in the model file it was read from, if any (`rig_glb` takes it when it is the one asked for).
    rig: Option<crate::model_file::SavedRig>,
    /// Built on first use (interpolate, export).
    art: std::sync::OnceLock<crate::articulate::Articulation>,
}

impl PyModel {
    fn fitted(pop: Population, result: FitResult, params: Params) -> PyModel {
        PyModel {
            result,
            params,
            pop,
            has_data: true,
            summary: std::sync::OnceLock::new(),
            rig: None,
            art: std::sync::OnceLock::new(),
        }
    }

    fn from_file(f: ModelFile) -> PyModel {
        let summary = std::sync::OnceLock::new();
        let _ = summary.set(f.summary);
        PyModel {
            result: f.result,
            params: f.params,
            pop: f.population,
            has_data: f.has_data,
            summary,
            rig: f.rig,
            art: std::sync::OnceLock::new(),
        }
    }

    fn pop(&self) -> &Population {
        &self.pop
    }

    fn summary(&self) -> &Summary {
        self.summary.get_or_init(|| Summary::measure(&self.pop, &self.result))
    }

    fn needs_data(&self, what: &str) -> PyResult<()> {
        if self.has_data {
            return Ok(());
        }
        Err(err(format!(
            "this model was saved without its poses, and {what} needs them: posemfa.load(path, poses=posemfa.read(...)) \
             with the poses it was fitted to"
        )))
    }

    fn articulation(&self) -> PyResult<&crate::articulate::Articulation> {
        if let Some(a) = self.art.get() {
            return Ok(a);
        }
        let a = core(crate::articulate::Articulation::new(&self.result.model, self.pop()))?;
        Ok(self.art.get_or_init(|| a))
    }

    fn pose_index(&self, name: &str, i: i64) -> PyResult<usize> {
        let n = self.pop().n_shapes() as i64;
        let k = if i < 0 { i + n } else { i };
        if k < 0 || k >= n {
            return Err(err(format!("{name} = {i}: poses are numbered 0 to {} (or from the end, -1 ...)", n - 1)));
        }
        Ok(k as usize)
    }
}

/// The rig's options from rig_glb's arguments (`bones` the bone motion, `more` the candidate rings and the most
/// alternations), checked.
fn rig_options(
    pop: &Population,
    (weights, influences, joints, morphs, bind): (&str, usize, &str, &str, Option<usize>),
    bones: &str,
    (rings, alternations): (usize, usize),
) -> PyResult<GltfOptions> {
    let weights = match weights {
        "rigid" => Weights::Rigid,
        "smooth" => Weights::Smooth,
        "fitted" => Weights::Fitted,
        other => return Err(err(format!("weights = '{other}': use 'rigid', 'smooth' or 'fitted'"))),
    };
    let joints = match joints {
        "free" => Joints::Free,
        "fixed" => Joints::Fixed,
        other => return Err(err(format!("joints = '{other}': use 'free' or 'fixed'"))),
    };
    let morphs = match morphs {
        "none" => Morphs::None,
        "residual" => Morphs::Residual,
        other => return Err(err(format!("morphs = '{other}': use 'none' or 'residual'"))),
    };
    let n = pop.n_shapes();
    let bind_pose = match bind {
        None => crate::export::rig_report::default_bind_pose(pop),
        Some(b) if b < n => b,
        Some(b) => return Err(err(format!("bind = {b}: poses are numbered 0 to {}", n - 1))),
    };
    let bones = crate::export::rig_report::BoneMotion::from_word(bones).map_err(err)?;
    let mut g = GltfOptions {
        weights,
        influences,
        joints,
        morphs,
        bind_pose,
        rings,
        iterations: alternations,
        ..Default::default()
    };
    bones.apply(&mut g);
    core(g.rig_options().validate(n))?;
    Ok(g)
}

#[pymethods]
impl PyModel {
    /// The poses (the data, or for a model file saved without them the model's reconstructions).
    #[getter]
    fn poses(&self) -> PyPoses {
        PyPoses { pop: self.pop().clone() }
    }

    /// Whether the poses are the fitted data (False: a model file saved without them).
    #[getter]
    fn has_data(&self) -> bool {
        self.has_data
    }

    /// (n_vertices,) uint32: each vertex's part.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_vec(py, self.result.model.labels.clone())
    }

    #[getter]
    fn coarse_labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_vec(py, self.result.coarse_labels.clone())
    }

    #[getter]
    fn refined_labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_vec(py, self.result.refined_labels.clone())
    }

    #[getter]
    fn n_parts(&self) -> usize {
        self.result.model.n_parts()
    }

    /// (n_parts, n_poses, 3, 3): R_k^i (the same in either frame: the unit box is a uniform scale).
    #[getter]
    fn rotations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray4<f64>>> {
        let m = &self.result.model;
        let mut v = Vec::with_capacity(m.n_parts() * m.n_shapes * 9);
        for c in &m.parts {
            for r in &c.rotations {
                v.extend(crate::geometry::row_major(r));
            }
        }
        let a = Array4::from_shape_vec((m.n_parts(), m.n_shapes, 3, 3), v).map_err(err)?;
        Ok(PyArray4::from_owned_array(py, a))
    }

    /// (n_parts, n_poses, 3), original units: pose i's vertex j ≈ rotations[l, i] @ latent[j] + translations[l, i]
    /// with l = labels[j].
    #[getter]
    fn translations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let m = &self.result.model;
        let norm = self.pop().normalization;
        let v: Vec<f64> =
            m.parts.iter().flat_map(|c| c.translations.iter().flat_map(|&b| norm.to_original(b))).collect();
        array3(py, v, (m.n_parts(), m.n_shapes, 3))
    }

    /// (n_vertices, 3), original units (scaled only: every part's latent frame is centred on its own origin).
    #[getter]
    fn latent<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let s = self.pop().normalization.scale;
        array2(py, self.result.model.latent.iter().flat_map(|p| p.map(|c| c / s)).collect(), 3)
    }

    /// (n_parts, n_poses): the per-pose variances s_k^i, unit-box units².
    #[getter]
    fn variances<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = &self.result.model;
        array2(py, m.parts.iter().flat_map(|c| c.variances.iter().copied()).collect(), m.n_shapes)
    }

    /// (n_parts,): the mixing weights π_k.
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_owned_array(py, Array1::from_iter(self.result.model.parts.iter().map(|c| c.weight)))
    }

    /// RMSE of the reconstruction, original units (as measured when saved, for a model file without poses).
    #[getter]
    fn rmse(&self) -> f64 {
        self.pop().normalization.length_to_original(self.summary().rmse)
    }

    /// RMSE in the unit box: `rmse` of `posemfa fit --json`.
    #[getter]
    fn rmse_unit(&self) -> f64 {
        self.summary().rmse
    }

    /// The fit's E_RMS (the rig's measure: thousandths of the bind pose's bounding-box diagonal).
    #[getter]
    fn e_rms(&self) -> f64 {
        self.summary().e_rms
    }

    #[getter]
    fn iterations(&self) -> usize {
        self.result.model.iterations
    }

    #[getter]
    fn converged(&self) -> bool {
        self.result.model.converged
    }

    /// False for a fit stopped by its progress callback.
    #[getter]
    fn complete(&self) -> bool {
        self.result.complete
    }

    #[getter]
    fn log_likelihood<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.result.model.log_likelihood.clone())
    }

    /// The verdict as JSON (null for a fit stopped early).
    fn diagnosis_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.summary().diagnosis).map_err(err)
    }

    /// The merge tree as JSON (null with Algorithm 1's rules).
    fn merge_tree_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.result.merge_tree()).map_err(err)
    }

    /// The parameters as JSON (camelCase, every field; `startLabels` when the fit started from a partition).
    fn params_json(&self) -> PyResult<String> {
        let start = FitStart { labels: self.result.start_labels.clone() };
        serde_json::to_string(&FlatParams::new(&self.params, &start)).map_err(err)
    }

    /// `posemfa fit --json`'s document.
    fn fit_json(&self) -> PyResult<String> {
        self.needs_data("the fit JSON")?;
        Ok(crate::export::json::fit_to_json(self.pop(), &self.result))
    }

    /// The shape at t between poses i and j (0-based), original units: Algorithm 2 with the CLI's defaults.
    fn interpolate<'py>(&self, py: Python<'py>, i: i64, j: i64, t: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (i, j) = (self.pose_index("i", i)?, self.pose_index("j", j)?);
        if !t.is_finite() {
            return Err(err(format!("t = {t}: it must be a finite number (0 = pose i, 1 = pose j)")));
        }
        let art = self.articulation()?;
        let shape = core(py.detach(|| art.interpolate(i, j, t, &crate::articulate::Options::default())))?;
        let shape = art.to_original(&shape);
        array2(py, shape.into_iter().flatten().collect(), 3)
    }

    /// A fit of the same poses with these parameters, `bones` parts in the end (`export-gltf --bones N`).
    #[pyo3(signature = (bones, progress=None))]
    fn refit(&self, py: Python<'_>, bones: usize, progress: Option<Py<PyAny>>) -> PyResult<(PyModel, bool)> {
        self.needs_data("fitting again")?;
        let mut params = self.params.clone();
        let d = PyDict::new(py);
        d.set_item("bones", bones)?;
        params.target_parts = params_from(&d, self.pop().n_vertices())?.0.target_parts;
        core(params.validate())?;
        // (from the same start as this fit, if it had one)
        let start = FitStart { labels: self.result.start_labels.clone() };
        let (result, stopped) = run_fit(py, self.pop(), &params, &start, progress)?;
        Ok((PyModel::fitted(self.pop().clone(), result, params), stopped))
    }

    /// The rigged .glb (`posemfa export-gltf`): its bytes and the figures rig-report measures on it.
    #[pyo3(signature = (weights="rigid", influences=4, joints="free", morphs="none", bind=None,
                        bone_motion="rigid", candidate_rings=1, alternations=30))]
    #[allow(clippy::too_many_arguments)]
    fn rig_glb<'py>(
        &self,
        py: Python<'py>,
        weights: &str,
        influences: usize,
        joints: &str,
        morphs: &str,
        bind: Option<usize>,
        bone_motion: &str,
        candidate_rings: usize,
        alternations: usize,
    ) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyDict>)> {
        self.needs_data("a rig (its weights and error are fitted to the poses)")?;
        let g = rig_options(
            self.pop(),
            (weights, influences, joints, morphs, bind),
            bone_motion,
            (candidate_rings, alternations),
        )?;
        let art = self.articulation()?;
        let pop = self.pop();
        let kept = self.rig.as_ref();
        let out = core(py.detach(|| crate::export::rig_report::export_rig(art, pop, &g, kept)))?;
        let d = PyDict::new(py);
        d.set_item("e_rms", out.error.e_rms)?;
        d.set_item("rig_source", out.source.word())?;
        d.set_item("bones", out.bones)?;
        d.set_item("bind", g.bind_pose)?;
        d.set_item("report", serde_json::to_string(&out.error).map_err(err)?)?;
        Ok((PyBytes::new(py, &out.glb), d))
    }

    /// The model file's bytes (with or without the poses).
    #[pyo3(signature = (with_poses=true))]
    fn to_bytes<'py>(&self, py: Python<'py>, with_poses: bool) -> Bound<'py, PyBytes> {
        let summary = self.summary();
        let file = Borrowed { result: &self.result, params: &self.params, population: &self.pop, summary };
        let bytes = py.detach(|| file.to_bytes(with_poses && self.has_data));
        PyBytes::new(py, &bytes)
    }

    fn __repr__(&self) -> String {
        format!(
            "<posemfa.Model: {} parts, {} poses x {} vertices, RMSE {:.5} (unit box){}>",
            self.result.model.n_parts(),
            self.pop().n_shapes(),
            self.pop().n_vertices(),
            self.summary().rmse,
            if self.result.complete { "" } else { ", stopped early" }
        )
    }
}

/// The formats `read` takes (as `posemfa fit --help` lists them).
#[pyfunction]
fn formats_read() -> String {
    crate::mesh::load::formats_read()
}

#[pymodule]
#[pyo3(name = "_posemfa")]
fn posemfa_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("Error", m.py().get_type::<Error>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyPoses>()?;
    m.add_class::<PyModel>()?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(poses_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(generate, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(formats_read, m)?)?;
    Ok(())
}
