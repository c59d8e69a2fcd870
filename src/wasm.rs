//! The wasm-bindgen surface: thin wrappers that convert typed arrays, plain objects and errors, nothing
//! else. camelCase at the JS boundary. Every error is thrown as a JS `Error` whose message is the Rust
//! error's text and which carries the same as data: `kind`, `file`, `line` (or null) and `problems`
//! ([{kind, file, line, message}], one per problem: a population refused lists every file's).
//! Objects passed in (fit parameters, generator specs, interpolation options, shown-mesh descriptors) refuse
//! unknown fields, with an error naming the field.

use crate::error::{Error, Problem};
use crate::export::shown::{obj_in_original_units, Shown};
use crate::mesh::{Population, ReadOptions, Sources};
use crate::mfa::{FitStart, FlatParams, Model, Params};
use crate::parts::hierarchy::{FitResult, Pipeline};
use js_sys::{Array, Float32Array, Float64Array, Uint32Array, Uint8Array};
use std::rc::Rc;
use wasm_bindgen::prelude::*;

/// A JS Error carrying the problems as data (see the module doc).
fn thrown(problems: &[Problem]) -> JsValue {
    let text: Vec<String> = problems
        .iter()
        .map(|p| match (&p.file, p.line) {
            (Some(f), Some(l)) => format!("file {f}, line {l}: {}", p.message),
            (Some(f), None) => format!("file {f}: {}", p.message),
            _ => p.message.clone(),
        })
        .collect();
    let err = js_sys::Error::new(&text.join("\n"));
    let first = problems.first();
    let set = |k: &str, v: JsValue| {
        let _ = js_sys::Reflect::set(&err, &JsValue::from_str(k), &v);
    };
    set("kind", first.map_or(JsValue::NULL, |p| JsValue::from_str(p.kind)));
    set("file", first.and_then(|p| p.file.as_deref()).map_or(JsValue::NULL, JsValue::from_str));
    set("line", first.and_then(|p| p.line).map_or(JsValue::NULL, |l| JsValue::from(l as u32)));
    set("problems", to_js(&problems).unwrap_or(JsValue::NULL));
    err.into()
}

impl From<Error> for JsValue {
    fn from(e: Error) -> JsValue {
        thrown(&[e.problem()])
    }
}

/// An invalid request that the core did not see (wrong index, unknown option value...).
fn js_err(e: impl std::fmt::Display) -> JsValue {
    thrown(&[Problem { kind: "request", file: None, line: None, message: e.to_string() }])
}

/// A plain JS object as `T` (missing fields take defaults; unknown fields are refused, naming the field). It
/// goes through JSON text: serde-wasm-bindgen reads only the fields a struct declares, so it cannot see a
/// misspelled one.
fn from_js<T: serde::de::DeserializeOwned + Default>(v: JsValue, what: &str) -> Result<T, JsValue> {
    if v.is_undefined() || v.is_null() {
        return Ok(T::default());
    }
    descriptor(v, what)
}

/// A plain JS object as `T`, through JSON text (see [`from_js`]); every field required unless `T` says not.
fn descriptor<T: serde::de::DeserializeOwned>(v: JsValue, what: &str) -> Result<T, JsValue> {
    let invalid = |m: String| {
        thrown(&[Problem { kind: "params", file: None, line: None, message: format!("invalid {what}: {m}") }])
    };
    let text: String = js_sys::JSON::stringify(&v).map_err(|_| invalid("not a plain object".into()))?.into();
    serde_json::from_str(&text).map_err(|e| invalid(e.to_string()))
}

fn flat_f32(points: &[[f64; 3]]) -> Float32Array {
    let v: Vec<f32> = points.iter().flat_map(|p| p.map(|c| c as f32)).collect();
    Float32Array::from(v.as_slice())
}

fn to_js<T: serde::Serialize + ?Sized>(v: &T) -> Result<JsValue, JsValue> {
    v.serialize(&serde_wasm_bindgen::Serializer::json_compatible()).map_err(js_err)
}

/// A loaded population (unit-box coordinates inside).
#[wasm_bindgen(js_name = Population)]
pub struct WasmPopulation {
    inner: Rc<Population>,
}

#[wasm_bindgen(js_class = Population)]
impl WasmPopulation {
    /// Reads and validates the files of one population, each by its extension (`mesh::load`: OBJ or PLY per
    /// pose, one .glb / .gltf with its .bin files, a .pc2 / .mdd point cache with its base mesh; any other
    /// extension is refused by name, .mtl ignored). Throws an Error with one problem per file that has one (`problems`,
    /// each {kind, file, line, message}; the message has one line per problem).
    /// `animation`: for a glTF, the animation to read (a name of `clips`; default the one with the most
    /// keyframes).
    #[wasm_bindgen(constructor)]
    pub fn new(
        names: Vec<String>,
        files: Vec<Uint8Array>,
        animation: Option<String>,
    ) -> Result<WasmPopulation, JsValue> {
        if names.len() != files.len() {
            return Err(js_err("names and files differ in length"));
        }
        // poses of one mesh file each are copied in and read one at a time (their text is most of the memory)
        use crate::mesh::load::FileKind;
        let one_each = names.iter().all(|n| matches!(FileKind::of(n), FileKind::Obj | FileKind::Ply));
        let read = if one_each {
            let mut fetch = |i: usize, buffer: &mut Vec<u8>| {
                // the last file's bytes go before the next one's come (a buffer kept for the largest file, grown
                // by doubling, held 7 bytes per vertex-pose more at the peak on horse-poses subdivided)
                *buffer = Vec::new();
                *buffer = files[i].to_vec();
                Ok(())
            };
            Population::read(Sources::MeshFiles { names: &names, fetch: &mut fetch }, &ReadOptions::default())
        } else {
            let gltf = crate::mesh::gltf::Options { animation, ..Default::default() };
            let files = names.into_iter().zip(files.iter().map(|f| f.to_vec())).collect();
            Population::read(Sources::Files(files), &ReadOptions { gltf })
        };
        match read {
            // poses with no motion are refused as a bad file is: the page keeps what it had
            Ok(p) => match p.still_error() {
                Some(e) => Err(thrown(&[e.problem()])),
                None => Ok(WasmPopulation { inner: Rc::new(p) }),
            },
            Err(errors) => Err(thrown(&errors.iter().map(Error::problem).collect::<Vec<_>>())),
        }
    }

    /// Where the poses came from, for people: "11 OBJ files", "6 frames of animation 'Walk' (...) of mesh
    /// 'horse' in horse.glb; ...", "48 frames of the point cache gallop.pc2 (...), faces from rest.obj".
    #[wasm_bindgen(getter)]
    pub fn source(&self) -> String {
        self.inner.source.clone()
    }

    /// A glTF's animations that move its mesh, {names, read} (`read`: the index of the one the poses came
    /// from), or null for poses of another source.
    #[wasm_bindgen(getter)]
    pub fn clips(&self) -> Result<JsValue, JsValue> {
        match &self.inner.clips {
            None => Ok(JsValue::NULL),
            Some(c) => {
                let obj = js_sys::Object::new();
                js_sys::Reflect::set(&obj, &"names".into(), &to_js(&c.names)?)?;
                js_sys::Reflect::set(&obj, &"read".into(), &JsValue::from(c.read as u32))?;
                Ok(obj.into())
            }
        }
    }

    #[wasm_bindgen(getter, js_name = nShapes)]
    pub fn n_shapes(&self) -> usize {
        self.inner.n_shapes()
    }

    #[wasm_bindgen(getter, js_name = nVertices)]
    pub fn n_vertices(&self) -> usize {
        self.inner.n_vertices()
    }

    pub fn names(&self) -> Array {
        self.inner.names.iter().map(|n| JsValue::from_str(n)).collect()
    }

    pub fn faces(&self) -> Uint32Array {
        let v: Vec<u32> = self.inner.faces.iter().flatten().copied().collect();
        Uint32Array::from(v.as_slice())
    }

    /// Shape i's vertices, unit box, flat xyz.
    pub fn positions(&self, shape: usize) -> Result<Float32Array, JsValue> {
        let s = self.inner.get_shape(shape).ok_or_else(|| js_err(format!("no shape {shape}")))?;
        // the stored f32 coordinates as they are
        Ok(Float32Array::from(s.as_f32().as_flattened()))
    }

    /// [offset x, y, z, scale]: unit = (original - offset) * scale.
    pub fn normalization(&self) -> Float64Array {
        let n = self.inner.normalization;
        Float64Array::from(&[n.offset[0], n.offset[1], n.offset[2], n.scale][..])
    }

    /// Where every vertex of shape i lies along the longest side of its bounding box, 0 to 1
    /// (`geometry::along_longest_axis`).
    #[wasm_bindgen(js_name = alongLongestAxis)]
    pub fn along_longest_axis(&self, shape: usize) -> Result<Float32Array, JsValue> {
        let s = self.inner.get_shape(shape).ok_or_else(|| js_err(format!("no shape {shape}")))?;
        let t: Vec<f32> = crate::geometry::along_longest_axis(&s.to_vec()).iter().map(|&x| x as f32).collect();
        Ok(Float32Array::from(t.as_slice()))
    }

    /// Unit-box lengths in the population's original units.
    #[wasm_bindgen(js_name = originalLengths)]
    pub fn original_lengths(&self, unit: Vec<f64>) -> Float64Array {
        let v: Vec<f64> = unit.iter().map(|&x| self.inner.normalization.length_to_original(x)).collect();
        Float64Array::from(v.as_slice())
    }

    /// Plain linear vertex blending of poses i and j (0-based) at t, unit box, flat xyz.
    #[wasm_bindgen(js_name = linearInterpolate)]
    pub fn linear_interpolate(&self, i: usize, j: usize, t: f64) -> Result<Float32Array, JsValue> {
        Ok(flat_f32(&Shown::Linear { from: i, to: j, t }.positions(&self.inner, None, None)?))
    }

    /// OBJ text, in the original units, of a mesh that needs no model: `what` is {kind: "pose", pose} or
    /// {kind: "linear", from, to, t} (`posemfa::export::shown::Shown`); `header` becomes its comment lines.
    #[wasm_bindgen(js_name = objText)]
    pub fn obj_text(&self, what: JsValue, header: &str) -> Result<String, JsValue> {
        let what: Shown = descriptor(what, "mesh descriptor")?;
        Ok(obj_in_original_units(&self.inner, &what.positions(&self.inner, None, None)?, header))
    }

    /// OBJ text of the meshes a view shows side by side that need no model (see `FitModel.objScene`; `parts` must
    /// be null here).
    #[wasm_bindgen(js_name = objScene)]
    pub fn obj_scene(&self, meshes: JsValue, header: &str) -> Result<String, JsValue> {
        obj_scene(&self.inner, None, meshes, header)
    }

    /// A palette index (< `n_colours`) for every part of `labels` (one per vertex): parts that share a mesh
    /// edge differ while the palette allows (`posemfa::articulate::graph::colour_parts`).
    #[wasm_bindgen(js_name = partColours)]
    pub fn part_colours(&self, labels: Vec<u32>, n_colours: usize) -> Result<Uint32Array, JsValue> {
        if labels.len() != self.inner.n_vertices() {
            return Err(js_err(format!("{} labels for {} vertices", labels.len(), self.inner.n_vertices())));
        }
        Ok(Uint32Array::from(
            crate::articulate::graph::colour_parts(&labels, self.inner.graph_faces(), n_colours).as_slice(),
        ))
    }

    /// [`Population::part_colours`] keeping the colours of earlier partitions where a part is the same (more
    /// than half of each in the other): `previous` is their labels one after the other (one per vertex each, the
    /// newest first) and `previous_colours` their colours one after the other (one per part each: a
    /// partition's count of parts is its largest label + 1) (`posemfa::articulate::graph::colour_parts_like`).
    #[wasm_bindgen(js_name = partColoursLike)]
    pub fn part_colours_like(
        &self,
        labels: Vec<u32>,
        n_colours: usize,
        previous: Vec<u32>,
        previous_colours: Vec<u32>,
    ) -> Result<Uint32Array, JsValue> {
        let n = self.inner.n_vertices();
        if labels.len() != n {
            return Err(js_err(format!("{} labels for {} vertices", labels.len(), n)));
        }
        if n == 0 || previous.len() % n != 0 {
            return Err(js_err(format!(
                "{} earlier labels are not whole partitions of {} vertices",
                previous.len(),
                n
            )));
        }
        let mut earlier = Vec::new();
        let mut at = 0;
        for part in previous.chunks(n) {
            let parts = part.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
            let Some(colours) = previous_colours.get(at..at + parts) else {
                return Err(js_err(format!(
                    "{} earlier colours for earlier partitions of more parts",
                    previous_colours.len()
                )));
            };
            earlier.push((part, colours));
            at += parts;
        }
        Ok(Uint32Array::from(
            crate::articulate::graph::colour_parts_like(&labels, self.inner.graph_faces(), n_colours, &earlier)
                .as_slice(),
        ))
    }
}

/// A fit in progress (the merge tree's rule, or Algorithm 1 with the other part rules and in a lesson). `step()` is
/// one AECM iteration; `run(budgetMs)` steps until the budget is spent.
#[wasm_bindgen]
pub struct Fitter {
    pipe: Pipeline,
    pop: Rc<Population>,
    params: Rc<Params>,
}

impl Fitter {
    /// The parameters (and the start, `startLabels`) read from JS and the pipeline `make` builds from them.
    fn with(
        population: &WasmPopulation,
        params: JsValue,
        make: fn(&Population, &Params, &FitStart) -> crate::error::Result<Pipeline>,
    ) -> Result<Fitter, JsValue> {
        let (params, start) = from_js::<FlatParams>(params, "parameters")?.split();
        // the fit needs the memory more than a view of the last model does (rebuilt when asked again)
        forget_articulation(None);
        let pipe = make(&population.inner, &params, &start)?;
        Ok(Fitter { pipe, pop: population.inner.clone(), params: Rc::new(params) })
    }
}

#[wasm_bindgen]
impl Fitter {
    /// `params`: a plain object with any of the fields of `Params` in camelCase (parts, seed, tol, maxIter,
    /// varianceFloor, lambdaRule: "exact" | "paper-eq18", restarts, refine, ...); missing fields take defaults.
    #[wasm_bindgen(constructor)]
    pub fn new(population: &WasmPopulation, params: JsValue) -> Result<Fitter, JsValue> {
        Fitter::with(population, params, Pipeline::starting)
    }

    /// The fit a step-by-step lesson shows (`Pipeline::for_teaching`: the paper's Algorithm 1, whatever
    /// `partRule` says); `params` as for the constructor.
    #[wasm_bindgen(js_name = forTeaching)]
    pub fn for_teaching(population: &WasmPopulation, params: JsValue) -> Result<Fitter, JsValue> {
        Fitter::with(population, params, Pipeline::for_teaching)
    }

    /// One AECM iteration; returns the progress object {stage, iteration, totalIterations, logLikelihood,
    /// parts, runFinished}.
    pub fn step(&mut self) -> Result<JsValue, JsValue> {
        let p = self.pipe.step()?;
        to_js(&p)
    }

    /// Steps until `budget_ms` has passed, a run of the pipeline has finished or the fit is done; returns the
    /// progress objects of every iteration made (each `stage` names the run it belongs to). A slice never goes on
    /// past the end of a run, so a page that shows the last step of every slice names every run, however fast it
    /// is.
    pub fn run(&mut self, budget_ms: f64) -> Result<Array, JsValue> {
        let t0 = crate::clock::now_ms();
        let out = Array::new();
        while !self.pipe.is_done() {
            let p = self.pipe.step()?;
            out.push(&to_js(&p)?);
            if p.run_finished || crate::clock::now_ms() - t0 >= budget_ms {
                break;
            }
        }
        Ok(out)
    }

    #[wasm_bindgen(js_name = isDone)]
    pub fn is_done(&self) -> bool {
        self.pipe.is_done()
    }

    /// The run in progress (`Stage` in src/parts/hierarchy/result.rs): {kind: "coarse"} | {kind: "refine",
    /// part, of, subParts} | {kind: "final", rule: "mergeTree" | "algorithm1", run: "first" | "settle" | "round"
    /// | "count" | "allVertices", number, coarseVertices} | {kind: "done"}.
    pub fn stage(&self) -> Result<JsValue, JsValue> {
        to_js(&self.pipe.stage())
    }

    /// Labels of the AECM run in progress over ALL vertices (during the refinement: the coarse labels).
    #[wasm_bindgen(js_name = currentLabels)]
    pub fn current_labels(&self) -> Uint32Array {
        Uint32Array::from(self.pipe.current_labels().as_slice())
    }

    /// Responsibilities of the run in progress, `[j * parts + k]` for the run's vertices (see
    /// `currentVertices`), and the number of parts: {parts, gamma: Float32Array, vertices: Uint32Array|null}.
    #[wasm_bindgen(js_name = currentResponsibilities)]
    pub fn current_responsibilities(&self) -> Result<JsValue, JsValue> {
        let obj = js_sys::Object::new();
        if let Some(f) = self.pipe.current_fit() {
            let g: Vec<f32> = f.responsibilities().iter().map(|&v| v as f32).collect();
            js_sys::Reflect::set(&obj, &"parts".into(), &JsValue::from(f.n_parts() as u32))
                .map_err(|_| js_err("reflect"))?;
            js_sys::Reflect::set(&obj, &"gamma".into(), &Float32Array::from(g.as_slice()))
                .map_err(|_| js_err("reflect"))?;
            let verts = match self.pipe.current_vertices() {
                Some(v) => Uint32Array::from(v.iter().map(|&x| x as u32).collect::<Vec<_>>().as_slice()).into(),
                None => JsValue::NULL,
            };
            js_sys::Reflect::set(&obj, &"vertices".into(), &verts).map_err(|_| js_err("reflect"))?;
        }
        Ok(obj.into())
    }

    /// A palette index (< `n_colours`) for every component of the AECM run in progress, such that
    /// components whose vertices share a mesh edge differ (the vertices outside the run, during the
    /// refinement, count as one more part); empty before the first run.
    #[wasm_bindgen(js_name = currentColours)]
    pub fn current_colours(&self, n_colours: usize) -> Uint32Array {
        let Some(f) = self.pipe.current_fit() else { return Uint32Array::new_with_length(0) };
        let k = f.n_parts();
        let mut labels = if self.pipe.on_coarse_mesh() { self.pipe.current_labels() } else { f.labels() };
        if let Some(vertices) = self.pipe.current_vertices().filter(|_| !self.pipe.on_coarse_mesh()) {
            let mut all = vec![k as u32; self.pop.n_vertices()];
            for (&v, &l) in vertices.iter().zip(&labels) {
                all[v] = l;
            }
            labels = all;
        }
        let c = crate::articulate::graph::colour_parts(&labels, self.pop.graph_faces(), n_colours);
        let per_component: Vec<u32> =
            (0..k).map(|p| c.get(p).copied().unwrap_or((p % n_colours.max(1)) as u32)).collect();
        Uint32Array::from(per_component.as_slice())
    }

    /// Log-likelihood trace of the AECM run in progress (after every iteration).
    #[wasm_bindgen(js_name = currentTrace)]
    pub fn current_trace(&self) -> Float64Array {
        let t = self.pipe.current_fit().map(|f| f.trace().to_vec()).unwrap_or_default();
        Float64Array::from(t.as_slice())
    }

    /// The result so far (final model when done; otherwise the best available).
    pub fn result(&self) -> FitModel {
        let about = Rc::new(About { params: (*self.params).clone(), saved: None, has_data: true, rig: None });
        FitModel { result: Rc::new(self.pipe.result()), pop: self.pop.clone(), about }
    }
}

/// A fitted model with its population.
#[wasm_bindgen]
pub struct FitModel {
    result: Rc<FitResult>,
    pop: Rc<Population>,
    about: Rc<About>,
}

/// What a model was fitted with; for one opened from a model file, the figures measured on its poses when it was
/// saved (shown as they are: the same numbers, not measured again), and whether the file held the poses (else
/// its population's poses are the model's reconstructions).
struct About {
    params: Params,
    saved: Option<crate::model_file::Summary>,
    has_data: bool,
    /// The rig a model file kept (`fit --save --with-rig`): the Rig panel and pose mode take it when it is the
    /// one they ask for, instead of solving its weights again.
    rig: Option<crate::model_file::SavedRig>,
}

impl FitModel {
    fn model(&self) -> &Model {
        &self.result.model
    }

    /// The figures of the fit: those a model file was saved with, else measured on the poses now.
    fn figures(&self) -> std::borrow::Cow<'_, crate::model_file::Summary> {
        match &self.about.saved {
            Some(saved) => std::borrow::Cow::Borrowed(saved),
            None => std::borrow::Cow::Owned(crate::model_file::Summary::measure(&self.pop, &self.result)),
        }
    }

    /// Refuses `what` (a view of the data) for a model opened without its poses.
    fn needs_data(&self, what: &str) -> Result<(), JsValue> {
        if self.about.has_data {
            return Ok(());
        }
        Err(js_err(format!(
            "{what} needs the poses, and this model file was saved without them: open it together with the poses it \
             was fitted to (drop both at once), or save it with its poses"
        )))
    }

    fn shape(&self, i: usize) -> Result<(), JsValue> {
        if i < self.model().n_shapes {
            Ok(())
        } else {
            Err(js_err(format!("no pose {i}: the population has {} poses", self.model().n_shapes)))
        }
    }
}

#[wasm_bindgen]
impl FitModel {
    #[wasm_bindgen(getter, js_name = nParts)]
    pub fn n_parts(&self) -> usize {
        self.model().n_parts()
    }

    pub fn labels(&self) -> Uint32Array {
        Uint32Array::from(self.model().labels.as_slice())
    }

    /// The partitions of the default part rule's merge tree ([`TreeCuts`]); undefined with Algorithm 1's rules.
    #[wasm_bindgen(js_name = treeCuts)]
    pub fn tree_cuts(&self) -> Option<TreeCuts> {
        self.result.tree_cuts().map(TreeCuts)
    }

    #[wasm_bindgen(js_name = coarseLabels)]
    pub fn coarse_labels(&self) -> Uint32Array {
        Uint32Array::from(self.result.coarse_labels.as_slice())
    }

    #[wasm_bindgen(js_name = refinedLabels)]
    pub fn refined_labels(&self) -> Uint32Array {
        Uint32Array::from(self.result.refined_labels.as_slice())
    }

    /// Latent reference shape (eq 21), flat xyz.
    pub fn latent(&self) -> Float32Array {
        flat_f32(&self.model().latent)
    }

    /// The latent shape with every part moved to its place in shape i but not turned (v_j^ref + b^i_{l_j}),
    /// unit box, flat xyz.
    #[wasm_bindgen(js_name = latentPlaced)]
    pub fn latent_placed(&self, shape: usize) -> Result<Float32Array, JsValue> {
        self.shape(shape)?;
        Ok(flat_f32(&self.model().latent_placed(shape)))
    }

    /// Shape i rebuilt from the latent shape (eq 22), unit box, flat xyz.
    pub fn reconstruct(&self, shape: usize) -> Result<Float32Array, JsValue> {
        self.shape(shape)?;
        Ok(flat_f32(&self.model().reconstruct(shape)))
    }

    /// |original - reconstruction| per vertex of shape i (unit box).
    #[wasm_bindgen(js_name = vertexErrors)]
    pub fn vertex_errors(&self, shape: usize) -> Result<Float32Array, JsValue> {
        self.shape(shape)?;
        self.needs_data("the reconstruction error")?;
        let e: Vec<f32> = self.model().vertex_errors(&self.pop, shape).iter().map(|&v| v as f32).collect();
        Ok(Float32Array::from(e.as_slice()))
    }

    /// P(k | h_j) for every part (eq 12).
    pub fn responsibilities(&self, vertex: usize) -> Result<Float64Array, JsValue> {
        if vertex >= self.model().n_vertices {
            return Err(js_err(format!("no vertex {vertex}")));
        }
        self.needs_data("the responsibilities")?;
        Ok(Float64Array::from(self.model().responsibilities(&self.pop, vertex).as_slice()))
    }

    /// Rotation angle (degrees) of part k in every pose, relative to pose `reference`.
    #[wasm_bindgen(js_name = rotationAngles)]
    pub fn rotation_angles(&self, part: usize, reference: usize) -> Result<Float64Array, JsValue> {
        let c = self.model().parts.get(part).ok_or_else(|| js_err(format!("no part {part}")))?;
        self.shape(reference)?;
        let a: Vec<f64> = c
            .rotations
            .iter()
            .map(|r| crate::geometry::rotation::angle_between(&c.rotations[reference], r).to_degrees())
            .collect();
        Ok(Float64Array::from(a.as_slice()))
    }

    /// {shapes, vertices, parts, partsFrom: "merge tree" | "Algorithm 1", coarseParts (the merge tree's start, or
    /// Algorithm 1's coarse parts), refinedParts, refine (the refinement ran), partsAsked (the exact count asked
    /// for, or null), rmse, rmseOriginal (in the original units), eRms (the
    /// rig's measure, [`crate::export::rig_report::fit_e_rms`]),
    /// iterations, converged, complete,
    /// logLikelihood: [...], stageStats: [...],
    /// diagnosis: {articulated, reason, singleBodyRmse, partsRmse, explained, parts} or null for a fit stopped
    /// early, unfinished: null or the words to show instead of the verdict,
    /// partCurve: [{parts, score, variance}] (the part rule's last round of merge decisions, most parts first),
    /// partRounds: [{parts, dissolved, after}] (every round of the part rule), startParts: the merge tree's start
    /// once its flesh was dissolved (null without)}
    pub fn summary(&self) -> Result<JsValue, JsValue> {
        let m = self.model();
        let s = &self.result.stages;
        let figures = self.figures();
        let figures = &*figures;
        let rmse = figures.rmse;
        let v = serde_json::json!({
            "hasData": self.about.has_data,
            "shapes": m.n_shapes, "vertices": m.n_vertices, "parts": m.n_parts(),
            "partsFrom": if self.result.from_merge_tree() { "merge tree" } else { "Algorithm 1" },
            "coarseParts": s.coarse_parts, "refinedParts": s.refined_parts,
            "refine": self.result.refined(), "partsAsked": self.result.parts_asked,
            "rmse": rmse, "rmseOriginal": self.pop.normalization.length_to_original(rmse),
            "eRms": figures.e_rms,
            "iterations": m.iterations, "converged": m.converged,
            "complete": self.result.complete, "logLikelihood": m.log_likelihood,
            "stageStats": self.result.stats,
            "diagnosis": figures.diagnosis,
            "unfinished": (!self.result.complete).then_some(crate::parts::diagnosis::UNFINISHED),
            "partCurve": self.result.part_curve,
            "partRounds": self.result.part_rounds,
            "startParts": self.result.start_parts(),
        });
        to_js(&v)
    }

    /// The machine's limit for the E-step's arithmetic, measured for at least `min_ms` per kernel on this
    /// model's components and its population, against this fit's E-step figures
    /// ([`crate::mfa::limit::limit_report`]): {f64: {gflop, ms, gflopsPerS}, f32: {...}, stageFractions,
    /// fraction}.
    #[wasm_bindgen(js_name = kernelLimit)]
    pub fn kernel_limit(&self, min_ms: f64) -> Result<JsValue, JsValue> {
        let data = crate::mfa::data::Data::from_population(&self.pop);
        to_js(&crate::mfa::limit::limit_report(&data, &self.model().parts, &self.result.stats, min_ms))
    }

    /// The full result as JSON text (same format as the CLI's --json).
    #[wasm_bindgen(js_name = toJson)]
    pub fn to_json(&self) -> Result<String, JsValue> {
        self.needs_data("the JSON export (its RMSE, islands and diagnosis are measured on the poses)")?;
        Ok(crate::export::json::fit_to_json(&self.pop, &self.result))
    }

    /// The model file (.posemfa) of this fit ([`crate::model_file`]); with `with_poses`, the population's
    /// points too (a model opened without them is saved without them).
    pub fn save(&self, with_poses: bool) -> Uint8Array {
        let summary = self.figures();
        let summary = &*summary;
        let fit = crate::model_file::Borrowed {
            result: &self.result,
            params: &self.about.params,
            population: &self.pop,
            summary,
        };
        Uint8Array::from(fit.to_bytes(with_poses && self.about.has_data).as_slice())
    }

    /// The parameters of the fit, as a plain object (camelCase, as the Fitter takes them; `startLabels` when
    /// the fit started from a partition).
    pub fn params(&self) -> Result<JsValue, JsValue> {
        to_js(&FlatParams::new(&self.about.params, &FitStart { labels: self.result.start_labels.clone() }))
    }
}

/// A finished model set aside while a new fit runs ([`FitModel::park`]): its per-vertex arrays (labels, latent
/// points, the stages' labels, the merge tree's leaves: 44 bytes a vertex) wait in JS typed arrays, outside the
/// wasm memory, and come back with [`ParkedModel::restore`] when the new fit is cancelled and the old model stays,
/// or when it is asked something meanwhile. Wasm memory never shrinks: held through a new fit's tree stage, those
/// arrays and the holes they leave raised a refit's peak on the generated 42 k x 11 population from 56.9 to 61.1
/// and 67.1 bytes per vertex-pose.
#[wasm_bindgen]
pub struct ParkedModel {
    kept: Parked,
    pop: Rc<Population>,
    about: Rc<About>,
}

enum Parked {
    /// The result with its per-vertex arrays taken out, and those arrays in JS.
    Taken {
        result: FitResult,
        labels: Uint32Array,
        latent: Float64Array,
        coarse: Uint32Array,
        refined: Uint32Array,
        decided: Option<Uint32Array>,
        leaves: Option<Uint32Array>,
    },
    /// Another holder shares the result, so taking its arrays out would free nothing: it is kept as it is.
    Shared(Rc<FitResult>),
}

/// The partitions of a fit's merge tree, one for every count ([`crate::parts::merge_tree::TreeCuts`]): its own
/// object, so that the page keeps the tree of the fit a Refine started from after that fit is gone.
#[wasm_bindgen]
pub struct TreeCuts(crate::parts::merge_tree::TreeCuts);

#[wasm_bindgen]
impl TreeCuts {
    /// {most, fewest, decided}: the part counts the tree holds, and the count the part rule read off it (null
    /// with a count asked for).
    pub fn counts(&self) -> Result<JsValue, JsValue> {
        let (most, fewest) = self.0.counts();
        to_js(&serde_json::json!({ "most": most, "fewest": fewest, "decided": self.0.decided() }))
    }

    /// The partition with `count` parts, one label per vertex (clamped to the tree's counts); at the decided
    /// count, the fit's own labels.
    pub fn labels(&self, count: usize) -> Uint32Array {
        Uint32Array::from(self.0.labels(count).as_slice())
    }
}

fn take_u32(v: &mut Vec<u32>) -> Uint32Array {
    let a = Uint32Array::from(v.as_slice());
    *v = Vec::new();
    a
}

#[wasm_bindgen]
impl FitModel {
    /// Sets this model aside while a new fit runs (see [`ParkedModel`]); this object is spent, the parked one
    /// gives it back.
    pub fn park(self) -> ParkedModel {
        let rc = self.result.clone();
        let pop = self.pop.clone();
        let about = self.about.clone();
        drop(self); // its articulation goes with it
        let kept = match Rc::try_unwrap(rc) {
            Ok(mut result) => {
                let latent = Float64Array::from(result.model.latent.as_flattened());
                result.model.latent = Vec::new();
                Parked::Taken {
                    labels: take_u32(&mut result.model.labels),
                    latent,
                    coarse: take_u32(&mut result.coarse_labels),
                    refined: take_u32(&mut result.refined_labels),
                    decided: result.decided_labels.as_mut().map(take_u32),
                    leaves: result.merge_tree_mut().map(|t| take_u32(&mut t.leaves)),
                    result,
                }
            }
            Err(shared) => Parked::Shared(shared),
        };
        ParkedModel { kept, pop, about }
    }
}

#[wasm_bindgen]
impl ParkedModel {
    /// The model as it was before [`FitModel::park`]; this object is spent.
    pub fn restore(self) -> FitModel {
        let result = match self.kept {
            Parked::Shared(rc) => rc,
            Parked::Taken { mut result, labels, latent, coarse, refined, decided, leaves } => {
                result.model.labels = labels.to_vec();
                let mut points = vec![[0.0; 3]; latent.length() as usize / 3];
                latent.copy_to(points.as_flattened_mut());
                result.model.latent = points;
                result.coarse_labels = coarse.to_vec();
                result.refined_labels = refined.to_vec();
                if let (Some(d), Some(a)) = (result.decided_labels.as_mut(), decided) {
                    *d = a.to_vec();
                }
                if let (Some(t), Some(a)) = (result.merge_tree_mut(), leaves) {
                    t.leaves = a.to_vec();
                }
                Rc::new(result)
            }
        };
        FitModel { result, pop: self.pop, about: self.about }
    }
}

/// Opens a model file (.posemfa) without fitting: `names` / `files` hold exactly one .posemfa and, optionally, the
/// pose files it was fitted to (read as the Population constructor reads them, `animation` likewise; checked to be
/// the model's mesh, else refused by name). Returns {population: Population, model: FitModel, params, hasData}.
/// Whether the zip archive `bytes` holds a model file (`.posemfa`), from its listing alone (nothing unpacked).
#[wasm_bindgen(js_name = zipHoldsModel)]
pub fn zip_holds_model(bytes: &[u8]) -> bool {
    crate::mesh::zip_archive::holds_model(bytes)
}

/// The files of the zip archive `name` that the page reads (mesh files and model files), checked as the CLI
/// checks an archive (zip bombs, damage, encryption: src/mesh/zip_archive.rs): {names, files}, natural-sorted,
/// named ARCHIVE/PATH. The worker opens an archive itself only when it holds a model file; the population's
/// loader opens any other.
#[wasm_bindgen(js_name = openZip)]
pub fn open_zip(name: &str, bytes: &[u8]) -> Result<JsValue, JsValue> {
    let budget = crate::memory::budget_bytes()? / 2;
    let archive = crate::mesh::zip_archive::open_with(name, bytes, budget, true)?;
    let names = js_sys::Array::new();
    let files = js_sys::Array::new();
    for (n, b) in &archive.files {
        names.push(&JsValue::from_str(n));
        files.push(&Uint8Array::from(b.as_slice()));
    }
    let obj = js_sys::Object::new();
    js_sys::Reflect::set(&obj, &"names".into(), &names).map_err(|_| js_err("reflect"))?;
    js_sys::Reflect::set(&obj, &"files".into(), &files).map_err(|_| js_err("reflect"))?;
    Ok(obj.into())
}

#[wasm_bindgen(js_name = openModel)]
pub fn open_model(names: Vec<String>, files: Vec<Uint8Array>, animation: Option<String>) -> Result<JsValue, JsValue> {
    if names.len() != files.len() {
        return Err(js_err("names and files differ in length"));
    }
    let is_model = |n: &str| n.to_ascii_lowercase().ends_with(&format!(".{}", crate::model_file::EXTENSION));
    let Some(k) = names.iter().position(|n| is_model(n)) else {
        return Err(js_err("no .posemfa model file among the files"));
    };
    if let Some(other) = names.iter().skip(k + 1).find(|n| is_model(n)) {
        return Err(thrown(&[Error::ModelFile {
            file: other.clone(),
            message: format!("a second model file beside {}: open one model at a time", names[k]),
        }
        .problem()]));
    }
    let mut saved = crate::model_file::ModelFile::from_bytes(&names[k], &files[k].to_vec())?;
    let (rest_names, rest_files): (Vec<String>, Vec<Uint8Array>) = names
        .iter()
        .zip(files.iter())
        .enumerate()
        .filter(|(i, _)| *i != k)
        .map(|(_, (n, f))| (n.clone(), f.clone()))
        .unzip();
    if !rest_names.is_empty() {
        let pop = WasmPopulation::new(rest_names, rest_files, animation)?;
        let pop = Rc::try_unwrap(pop.inner).unwrap_or_else(|rc| (*rc).clone());
        saved = saved.with_population(&names[k], pop)?;
    }
    let has_data = saved.has_data;
    let pop = Rc::new(saved.population);
    let about = Rc::new(About { params: saved.params, saved: Some(saved.summary), has_data, rig: saved.rig });
    let params = to_js(&about.params)?;
    let model = FitModel { result: Rc::new(saved.result), pop: pop.clone(), about };
    let obj = js_sys::Object::new();
    let set =
        |k: &str, v: JsValue| js_sys::Reflect::set(&obj, &k.into(), &v).map(|_| ()).map_err(|_| js_err("reflect"));
    set("population", WasmPopulation { inner: pop }.into())?;
    set("model", model.into())?;
    set("params", params)?;
    set("hasData", JsValue::from(has_data))?;
    Ok(obj.into())
}

/// Bytes of wasm linear memory: it only grows, so this is the peak of the instance so far.
#[wasm_bindgen(js_name = memoryBytes)]
pub fn memory_bytes() -> f64 {
    (core::arch::wasm32::memory_size(0) * 65536) as f64
}

/// The fit form's fields, as typed (an object of text values: any of parts, targetParts, seed, tol,
/// varianceFloor), read over `base` (fit parameters as a plain object; missing fields take defaults) and every
/// field checked (`Params::with_fields`): {params, problems: []} or {params: null, problems: [{field, message}]},
/// one problem per field that cannot be used, naming what is allowed. With `vertices` (the population's vertex
/// count, when one is loaded) a part count the population cannot hold is refused too, naming the limit.
#[wasm_bindgen(js_name = formParams)]
pub fn form_params(base: JsValue, fields: JsValue, vertices: Option<u32>) -> Result<JsValue, JsValue> {
    // (a start in `base` is kept as it is: the form has no field of it)
    let (base, start) = from_js::<FlatParams>(base, "fit parameters")?.split();
    let fields: std::collections::BTreeMap<String, String> = descriptor(fields, "form fields")?;
    let pairs: Vec<(&str, &str)> = fields.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    let v = match base.with_fields_for(&pairs, vertices.map(|n| n as usize)) {
        Ok(p) => serde_json::json!({ "params": FlatParams::new(&p, &start), "problems": [] }),
        Err(problems) => serde_json::json!({ "params": null, "problems": problems }),
    };
    to_js(&v)
}

/// The rig panel's fields as typed (an object of text values: influences), each checked by the core
/// (`RigRequest::with_fields`): {problems: []} or {problems: [{field, message}]}, one per field that cannot be
/// used, naming what was typed and what is allowed.
#[wasm_bindgen(js_name = rigFields)]
pub fn rig_fields(fields: JsValue) -> Result<JsValue, JsValue> {
    let fields: std::collections::BTreeMap<String, String> = descriptor(fields, "rig fields")?;
    let pairs: Vec<(&str, &str)> = fields.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    let v = match crate::export::rig_report::RigRequest::default().with_fields(&pairs) {
        Ok(_) => serde_json::json!({ "problems": [] }),
        Err(problems) => serde_json::json!({ "problems": problems }),
    };
    to_js(&v)
}

/// The verdict's threshold (`parts::diagnosis::MIN_EXPLAINED`): the least fraction of the motion that rigid
/// parts explain for "articulated", which the page and the article print.
#[wasm_bindgen(js_name = minExplained)]
pub fn min_explained() -> f64 {
    crate::parts::diagnosis::MIN_EXPLAINED
}

/// The default fit parameters as a plain object (camelCase fields of `Params`), for the page's form.
#[wasm_bindgen(js_name = defaultParams)]
pub fn default_params() -> Result<JsValue, JsValue> {
    to_js(&Params::default())
}

/// A generated population and its ground truth (`posemfa::synth`).
#[wasm_bindgen]
pub struct Synthetic {
    inner: crate::synth::Generated,
}

#[wasm_bindgen]
impl Synthetic {
    /// `spec`: a plain object with any of the fields of `synth::Spec` in camelCase (preset: "quadruped" |
    /// "arm" | "snake" | "blob", vertices, poses, seed, jointBand, noise, maxAngleDeg, rootMotion, tied);
    /// missing fields take defaults. Throws an Error naming the invalid field.
    #[wasm_bindgen(constructor)]
    pub fn new(spec: JsValue) -> Result<Synthetic, JsValue> {
        let spec: crate::synth::Spec = from_js(spec, "generator spec")?;
        Ok(Synthetic { inner: crate::synth::generate(&spec)? })
    }

    /// The generated shapes as a population (unit box; its normalisation is the identity).
    pub fn population(&self) -> WasmPopulation {
        WasmPopulation { inner: Rc::new(self.inner.population.clone()) }
    }

    /// Ground-truth part names, in part-index order.
    #[wasm_bindgen(js_name = partNames)]
    pub fn part_names(&self) -> Array {
        self.inner.part_names.iter().map(|n| JsValue::from_str(n)).collect()
    }

    /// Ground-truth part of every vertex.
    #[wasm_bindgen(js_name = partOfVertex)]
    pub fn part_of_vertex(&self) -> Uint32Array {
        Uint32Array::from(self.inner.part_of_vertex.as_slice())
    }

    /// The shapes as OBJ files: [[name, text], ...] in order.
    #[wasm_bindgen(js_name = objFiles)]
    pub fn obj_files(&self) -> Array {
        crate::synth::obj_files(&self.inner)
            .into_iter()
            .map(|(n, t)| -> JsValue {
                [JsValue::from_str(&n), JsValue::from_str(&t)].iter().collect::<Array>().into()
            })
            .collect()
    }
}

/// The built-in examples (`posemfa::synth::presets`): [{id, title, note, failsOnPurpose, spec, params}], the
/// default (the quadruped) first. `spec` goes to `new Synthetic(spec)`, `params` to `new Fitter(pop, params)`.
#[wasm_bindgen]
pub fn examples() -> Result<JsValue, JsValue> {
    to_js(&crate::synth::presets::examples())
}

// ---------------------------------------------------------------- articulation

thread_local! {
    /// The articulation of the last FitModel asked (graph, joints, weights are computed once per fit).
    static ARTICULATION: std::cell::RefCell<Option<(std::rc::Weak<FitResult>, Rc<crate::articulate::Articulation>)>> =
        const { std::cell::RefCell::new(None) };
}

fn articulate_options(opts: JsValue) -> Result<crate::articulate::Options, JsValue> {
    from_js(opts, "interpolation options")
}

/// Lets go of the cached articulation (its model's copy, graph, joints and skinning weights: per vertex, not per
/// vertex-pose, since it shares the population's points). Wasm memory never shrinks, so what is held while a
/// large block is asked for raises the peak for good: the cache goes before a new articulation is built, when a
/// fit starts and with the model it belongs to. On horse-poses subdivided (Node), an interpolation after each of
/// three fits took the instance to 162.8 bytes per vertex-pose with the cache kept (when the articulation still
/// held the shapes in f64), 94.4 with it let go, and 58.3, the fit's own peak, once it read the population.
fn forget_articulation(only_of: Option<&Rc<FitResult>>) {
    ARTICULATION.with(|cache| {
        let mut cache = cache.borrow_mut();
        let ours = |weak: &std::rc::Weak<FitResult>| only_of.is_none_or(|r| std::ptr::eq(weak.as_ptr(), Rc::as_ptr(r)));
        if cache.as_ref().is_some_and(|(weak, _)| ours(weak)) {
            *cache = None;
        }
    });
}

impl FitModel {
    fn articulation(&self) -> Result<Rc<crate::articulate::Articulation>, JsValue> {
        let cached = ARTICULATION.with(|cache| {
            cache
                .borrow()
                .as_ref()
                .filter(|(weak, _)| weak.upgrade().is_some_and(|r| Rc::ptr_eq(&r, &self.result)))
                .map(|(_, art)| art.clone())
        });
        if let Some(art) = cached {
            return Ok(art);
        }
        forget_articulation(None);
        let art = Rc::new(crate::articulate::Articulation::new(&self.result.model, &self.pop)?);
        ARTICULATION.with(|cache| *cache.borrow_mut() = Some((Rc::downgrade(&self.result), art.clone())));
        Ok(art)
    }
}

impl Drop for FitModel {
    fn drop(&mut self) {
        forget_articulation(Some(&self.result));
    }
}

#[wasm_bindgen]
impl FitModel {
    /// The shape at t in [0, 1] between poses i and j (0-based), unit box, flat xyz. `opts`: {residual: bool,
    /// skin: "rigid" | "smooth", exactEnds: bool, root: "anchor" | "paper", tree: "strongest" |
    /// "breadth-first", blend: "dual-quaternion" | "linear", edgeBlend: bool}; missing fields take defaults.
    pub fn interpolate(&self, i: usize, j: usize, t: f64, opts: JsValue) -> Result<Float32Array, JsValue> {
        let o = articulate_options(opts)?;
        Ok(flat_f32(&self.articulation()?.interpolate(i, j, t, &o)?))
    }

    /// The shape at time s in [0, keys.length - 1] along the poses `keys` (0-based), unit box, flat xyz.
    pub fn keyframes(&self, keys: Vec<u32>, s: f64, opts: JsValue) -> Result<Float32Array, JsValue> {
        let o = articulate_options(opts)?;
        let keys: Vec<usize> = keys.iter().map(|&k| k as usize).collect();
        Ok(flat_f32(&self.articulation()?.keyframes(&keys, s, &o)?))
    }

    /// Plain linear vertex interpolation of poses i and j (the baseline), unit box, flat xyz.
    #[wasm_bindgen(js_name = linearInterpolate)]
    pub fn linear_interpolate(&self, i: usize, j: usize, t: f64) -> Result<Float32Array, JsValue> {
        Ok(flat_f32(&self.articulation()?.linear(i, j, t)?))
    }

    /// Per vertex, the distance of the interpolation at t (`opts` as [`FitModel::interpolate`]) from the plain
    /// linear blend of the two poses at t (unit box): at t = 0 and 1 the blend is the end pose itself, so this
    /// is the interpolation's end error there.
    #[wasm_bindgen(js_name = distancesToLinear)]
    pub fn distances_to_linear(&self, i: usize, j: usize, t: f64, opts: JsValue) -> Result<Float32Array, JsValue> {
        let o = articulate_options(opts)?;
        let art = self.articulation()?;
        let d = crate::geometry::distances(&art.interpolate(i, j, t, &o)?, &art.linear(i, j, t)?);
        Ok(Float32Array::from(d.iter().map(|&x| x as f32).collect::<Vec<f32>>().as_slice()))
    }

    /// Skinning weights, dense: `[vertex * nParts + part]`. `skin`: "smooth" (default) or "rigid".
    #[wasm_bindgen(js_name = skinWeights)]
    pub fn skin_weights(&self, skin: Option<String>) -> Result<Float32Array, JsValue> {
        let s = match skin.as_deref() {
            None | Some("smooth") => crate::articulate::Skin::Smooth,
            Some("rigid") => crate::articulate::Skin::Rigid,
            Some(o) => return Err(js_err(format!("skin '{o}': use rigid or smooth"))),
        };
        let art = self.articulation()?;
        let w: Vec<f32> = art.weights(s).dense(art.n_parts()).iter().map(|&x| x as f32).collect();
        Ok(Float32Array::from(w.as_slice()))
    }

    /// The skeleton in pose `shape`: {root, parents: [part or -1 per part], positions: Float32Array (xyz per
    /// part, NaN for parts without vertices)}.
    pub fn skeleton(&self, shape: usize) -> Result<JsValue, JsValue> {
        let sk = self.articulation()?.skeleton(shape)?;
        let parents: Vec<i32> = sk.tree.parent.iter().map(|p| p.map_or(-1, |p| p as i32)).collect();
        let pos: Vec<[f64; 3]> = sk.positions.iter().map(|p| p.unwrap_or([f64::NAN; 3])).collect();
        let obj = js_sys::Object::new();
        let set =
            |k: &str, v: &JsValue| js_sys::Reflect::set(&obj, &k.into(), v).map(|_| ()).map_err(|_| js_err("reflect"));
        set("root", &JsValue::from(sk.tree.root as u32))?;
        set("parents", &js_sys::Int32Array::from(parents.as_slice()).into())?;
        set("positions", &flat_f32(&pos).into())?;
        Ok(obj.into())
    }

    /// The rig as a .glb and its error measured on the file, as `posemfa export-gltf` writes it and
    /// `posemfa rig-report` measures it (`export::rig_report::export_rig`). `opts`: {weights: "rigid" | "smooth" |
    /// "fitted", influences: 1..8, joints: "free" | "fixed", morphs: "none" | "residual", bindPose}; missing fields
    /// take defaults (bindPose: the pose named reference, else the first). Returns {glb: Uint8Array, bones, eRms,
    /// maxError, maxErrorOverDiagonal, diagonal, poseErms: Float64Array, clips: [names of the file's animation clips],
    /// rigMs, writeMs, evaluateMs}.
    pub fn rig(&self, opts: JsValue) -> Result<JsValue, JsValue> {
        self.needs_data("the rig (its weights are fitted and its error measured on the poses)")?;
        let req: crate::export::rig_report::RigRequest = from_js(opts, "rig options")?;
        let g = req.options(&self.pop)?;
        let r = crate::export::rig_report::export_rig(&*self.articulation()?, &self.pop, &g, self.about.rig.as_ref())?;
        let obj = js_sys::Object::new();
        let set =
            |k: &str, v: &JsValue| js_sys::Reflect::set(&obj, &k.into(), v).map(|_| ()).map_err(|_| js_err("reflect"));
        let per_pose: Vec<f64> = r.error.poses.iter().map(|p| p.e_rms).collect();
        set("glb", &Uint8Array::from(r.glb.as_slice()).into())?;
        set("bones", &JsValue::from(r.bones as u32))?;
        set("clips", &to_js(&r.clips)?)?;
        set("eRms", &JsValue::from(r.error.e_rms))?;
        set("source", &JsValue::from_str(r.source.word()))?;
        set("maxError", &JsValue::from(r.error.max_error))?;
        set("maxErrorOverDiagonal", &JsValue::from(r.error.max_error_over_diagonal))?;
        set("diagonal", &JsValue::from(r.error.diagonal))?;
        set("poseErms", &Float64Array::from(per_pose.as_slice()).into())?;
        set("rigMs", &JsValue::from(r.rig_ms))?;
        set("writeMs", &JsValue::from(r.write_ms))?;
        set("evaluateMs", &JsValue::from(r.evaluate_ms))?;
        Ok(obj.into())
    }

    /// Pose mode: the rig of `opts` (rig options as for [`FitModel::rig`]; default fitted weights),
    /// written and read back, its training poses solved onto it and their pose space.
    pub fn poser(&self, opts: JsValue) -> Result<WasmPoser, JsValue> {
        self.needs_data("pose mode (its rig's weights are fitted to the poses)")?;
        let mut req: crate::export::rig_report::RigRequest = from_js(opts.clone(), "pose options")?;
        let given =
            !opts.is_undefined() && !opts.is_null() && js_sys::Reflect::has(&opts, &"weights".into()).unwrap_or(false);
        if !given {
            req.weights = crate::export::gltf::Weights::Fitted;
        }
        let g = req.options(&self.pop)?;
        let p = crate::export::pose_glb::Poser::new(&*self.articulation()?, &self.pop, &g, self.about.rig.as_ref())?;
        Ok(WasmPoser { inner: p, names: self.pop.names.clone(), bind_pose: g.bind_pose })
    }

    /// Endpoint errors, volume and edge stretch at t of every interpolation method, poses i -> j (0-based).
    #[wasm_bindgen(js_name = articulationReport)]
    pub fn articulation_report(&self, i: usize, j: usize, t: f64) -> Result<JsValue, JsValue> {
        to_js(&crate::articulate::report::report(&*self.articulation()?, i, j, t)?)
    }
}

// ---------------------------------------------------------------- ground-truth accuracy

#[wasm_bindgen]
impl Synthetic {
    /// Accuracy of a fit of this population against the generator's truth (`posemfa::metrics`):
    /// {ari: adjusted Rand index of the fitted labels, rotationErrorDeg: median over the true parts of their
    /// mean rotation error (degrees, relative to pose 1), rotationErrorDegMax, rotationErrorsDeg: [per true
    /// part], trueParts}.
    #[wasm_bindgen(js_name = groundTruth)]
    pub fn ground_truth(&self, model: &FitModel) -> Result<JsValue, JsValue> {
        to_js(&crate::metrics::ground_truth_accuracy(model.model(), &self.inner)?)
    }
}

#[wasm_bindgen]
impl FitModel {
    /// OBJ text, in the original units, of a mesh of this model or its population: `what` is {kind: "pose" |
    /// "reconstruction", pose} | {kind: "latent"} | {kind: "interpolation", from, to, t, options} | {kind:
    /// "linear", from, to, t} (`posemfa::export::shown::Shown`); `header` becomes its comment lines.
    #[wasm_bindgen(js_name = objText)]
    pub fn obj_text(&self, what: JsValue, header: &str) -> Result<String, JsValue> {
        let what: Shown = descriptor(what, "mesh descriptor")?;
        let art = if matches!(what, Shown::Interpolation { .. }) { Some(self.articulation()?) } else { None };
        Ok(obj_in_original_units(&self.pop, &what.positions(&self.pop, Some(self.model()), art.as_deref())?, header))
    }

    /// OBJ text of the meshes a view shows side by side, one object each (`posemfa::export::shown::obj_of_meshes`):
    /// `meshes` is [{name, what, parts}], `what` as in [`FitModel::obj_text`], `parts` "final" | "coarse" |
    /// "refined" (the faces in one group per part of that stage) or null.
    #[wasm_bindgen(js_name = objScene)]
    pub fn obj_scene(&self, meshes: JsValue, header: &str) -> Result<String, JsValue> {
        obj_scene(&self.pop, Some(self), meshes, header)
    }
}

/// One mesh of `objScene`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneMesh {
    name: String,
    what: Shown,
    #[serde(default)]
    parts: Option<String>,
}

fn obj_scene(pop: &Population, fit: Option<&FitModel>, meshes: JsValue, header: &str) -> Result<String, JsValue> {
    use crate::export::shown::{obj_of_meshes, NamedMesh};
    let meshes: Vec<SceneMesh> = descriptor(meshes, "mesh list")?;
    let mut named = Vec::with_capacity(meshes.len());
    for m in &meshes {
        let art = match (fit, &m.what) {
            (Some(f), Shown::Interpolation { .. }) => Some(f.articulation()?),
            _ => None,
        };
        let positions = m.what.positions(pop, fit.map(FitModel::model), art.as_deref())?;
        let labels: Option<&[u32]> = match (fit, m.parts.as_deref()) {
            (_, None) => None,
            (None, Some(_)) => return Err(js_err(format!("mesh {}: parts need a fitted model", m.name))),
            (Some(f), Some("final")) => Some(f.model().labels.as_slice()),
            (Some(f), Some("coarse")) => Some(f.result.coarse_labels.as_slice()),
            (Some(f), Some("refined")) => Some(f.result.refined_labels.as_slice()),
            (_, Some(o)) => return Err(js_err(format!("mesh {}: parts '{o}': use final, coarse or refined", m.name))),
        };
        // a fit cancelled before a stage has no labels of it: that mesh is written without groups
        named.push(NamedMesh { name: m.name.clone(), positions, labels: labels.filter(|l| !l.is_empty()) });
    }
    Ok(obj_of_meshes(pop, &named, header)?)
}

/// Test-only fault injection for the page's fault tests (reached only when the page is opened with
/// `?faultInjection=1`): `"panic"` panics, which aborts (the release profile's panic = "abort"): the wasm
/// instance traps with `unreachable`, as on any bug that panics.
#[wasm_bindgen(js_name = faultInjection)]
pub fn fault_injection(kind: &str) -> Result<(), JsValue> {
    match kind {
        "panic" => panic!("fault injection: a deliberate panic (page test)"),
        other => Err(js_err(format!("fault injection '{other}': the only kind is panic"))),
    }
}

// ---------------------------------------------------------------- pose mode

/// A rig being posed ([`crate::export::pose_glb::Poser`]); positions in the population's original units.
#[wasm_bindgen(js_name = Poser)]
pub struct WasmPoser {
    inner: crate::export::pose_glb::Poser,
    names: Vec<String>,
    /// The training pose the rig is bound in (its rest pose: every bone the identity).
    bind_pose: usize,
}

fn vec3(v: &[f64]) -> Result<[f64; 3], JsValue> {
    match v {
        [x, y, z] => Ok([*x, *y, *z]),
        _ => Err(js_err(format!("expected 3 numbers, got {}", v.len()))),
    }
}

#[wasm_bindgen(js_class = Poser)]
impl WasmPoser {
    /// The skeleton: {parent: [bone or -1], order, names, jointPoints (flat xyz, bind pose), boneOfVertex,
    /// nModes, sd, range ([lo, hi] per mode), coords (per training pose), trainingNames, bindPose (the training
    /// pose the rig is bound in: its rest pose, as rebuilt from the parts), diagonal}.
    pub fn skeleton(&self) -> Result<JsValue, JsValue> {
        let r = &self.inner.rig.rig;
        let obj = js_sys::Object::new();
        let set =
            |k: &str, v: JsValue| js_sys::Reflect::set(&obj, &k.into(), &v).map(|_| ()).map_err(|_| js_err("reflect"));
        let parent: Vec<i32> = r.parent.iter().map(|p| p.map_or(-1, |p| p as i32)).collect();
        set("parent", to_js(&parent)?)?;
        set("order", to_js(&r.order)?)?;
        set("names", to_js(&self.inner.rig.names)?)?;
        set("jointPoints", flat_f32(&self.inner.to_unit(&r.joint_points)).into())?;
        set("boneOfVertex", Uint32Array::from(self.inner.bone_of_vertex.as_slice()).into())?;
        set("nModes", JsValue::from(self.inner.space.n_modes() as u32))?;
        set("sd", to_js(&self.inner.space.sd)?)?;
        set("range", to_js(&self.inner.space.range)?)?;
        set("coords", to_js(&self.inner.space.coords)?)?;
        set("trainingNames", to_js(&self.names)?)?;
        set("bindPose", JsValue::from(self.bind_pose as u32))?;
        // unit box, as the positions
        set("diagonal", JsValue::from(self.inner.diagonal * self.inner.normalization.scale))?;
        Ok(obj.into())
    }

    /// The mesh of the current pose (flat xyz, unit box as the population's positions).
    pub fn positions(&self) -> Float32Array {
        flat_f32(&self.inner.to_unit(&self.inner.positions()))
    }

    /// Turns bone k's subtree by `angle` radians about `axis` (3 numbers, world) through its joint.
    pub fn turn(&mut self, k: usize, axis: Vec<f64>, angle: f64) -> Result<(), JsValue> {
        Ok(self.inner.turn(k, vec3(&axis)?, angle)?)
    }

    /// Every bone's angle from the rest pose, degrees.
    pub fn angles(&self) -> Float64Array {
        Float64Array::from(self.inner.angles().as_slice())
    }

    /// Every bone's largest angle from the rest pose over the training poses, degrees.
    #[wasm_bindgen(js_name = trainingAngles)]
    pub fn training_angles(&self) -> Float64Array {
        Float64Array::from(self.inner.training_angles().as_slice())
    }

    /// Bone k in every training pose, degrees from the rest pose: {joint: at its joint, relative to its parent
    /// (as `angles`), whole: the bone's own rotation, the turns of the bones carrying it included}.
    #[wasm_bindgen(js_name = trainingAnglesOf)]
    pub fn training_angles_of(&self, k: usize) -> Result<JsValue, JsValue> {
        let (joint, whole) = self.inner.training_angles_of(k)?;
        let obj = js_sys::Object::new();
        js_sys::Reflect::set(&obj, &"joint".into(), &Float64Array::from(joint.as_slice()).into())
            .map_err(|_| js_err("reflect"))?;
        js_sys::Reflect::set(&obj, &"whole".into(), &Float64Array::from(whole.as_slice()).into())
            .map_err(|_| js_err("reflect"))?;
        Ok(obj.into())
    }

    /// Bone k's joint in the current pose (3 numbers, unit box).
    #[wasm_bindgen(js_name = jointPosition)]
    pub fn joint_position(&self, k: usize) -> Result<Float64Array, JsValue> {
        Ok(Float64Array::from(self.inner.to_unit(&[self.inner.joint_position(k)?])[0].as_slice()))
    }

    /// The pose of mode coefficients (the root stays where it is).
    #[wasm_bindgen(js_name = setModes)]
    pub fn set_modes(&mut self, coeffs: Vec<f64>) -> Result<(), JsValue> {
        Ok(self.inner.set_modes(&coeffs)?)
    }

    /// The current pose vector (log maps) and its mode coordinates: {vector, coords, mean, training}.
    #[wasm_bindgen(js_name = poseVector)]
    pub fn pose_vector(&self) -> Result<JsValue, JsValue> {
        let x = self.inner.vector();
        let c = self.inner.space.project(&x);
        to_js(
            &serde_json::json!({"vector": x, "coords": c, "mean": self.inner.space.mean, "training": self.inner.space.training}),
        )
    }

    /// Coefficients of a random pose within the training range (seeded).
    #[wasm_bindgen(js_name = randomCoords)]
    pub fn random_coords(&self, seed: f64) -> Float64Array {
        Float64Array::from(self.inner.space.random(seed as u64).as_slice())
    }

    /// Training pose i (0-based).
    #[wasm_bindgen(js_name = setTraining)]
    pub fn set_training(&mut self, i: usize) -> Result<(), JsValue> {
        Ok(self.inner.set_training(i)?)
    }

    /// The bones (12 numbers each), for undo.
    pub fn bones(&self) -> Float64Array {
        Float64Array::from(self.inner.bones_flat().as_slice())
    }

    #[wasm_bindgen(js_name = setBones)]
    pub fn set_bones(&mut self, flat: Vec<f64>) -> Result<(), JsValue> {
        Ok(self.inner.set_bones_flat(&flat)?)
    }

    /// Back to the rest pose.
    pub fn reset(&mut self) {
        self.inner.reset();
    }

    /// Per vertex 1 when a turn of bone k may move it (a weight on k or below), else 0.
    pub fn touches(&self, k: usize) -> Result<Uint8Array, JsValue> {
        let t: Vec<u8> = self.inner.touches(k)?.into_iter().map(u8::from).collect();
        Ok(Uint8Array::from(t.as_slice()))
    }

    /// The rig .glb with the current pose as a one-frame clip "pose".
    #[wasm_bindgen(js_name = poseGlb)]
    pub fn pose_glb(&self) -> Result<Uint8Array, JsValue> {
        Ok(Uint8Array::from(self.inner.pose_glb()?.as_slice()))
    }

    /// The current pose as OBJ text (original units, the population's faces).
    #[wasm_bindgen(js_name = objText)]
    pub fn obj_text(&self, header: &str) -> String {
        crate::export::obj::write_obj(&self.inner.positions(), &self.inner.rig.faces, header)
    }

    /// New frames of the same mesh (files as for a population) solved onto the rig: {names, eRms (per frame), eRmsAll,
    /// positions: [flat xyz per frame, skinned, unit box], bones: [per frame, 12 numbers a bone as `bones`], glb
    /// (the rig with clip "frames")}.
    #[wasm_bindgen(js_name = addFrames)]
    pub fn add_frames(&self, names: Vec<String>, files: Vec<Uint8Array>) -> Result<JsValue, JsValue> {
        if names.len() != files.len() {
            return Err(js_err("names and files differ in length"));
        }
        let mut pairs: Vec<(String, Vec<u8>)> = names.into_iter().zip(files.iter().map(|f| f.to_vec())).collect();
        pairs.sort_by(|a, b| crate::mesh::population::natural_cmp(&a.0, &b.0));
        let loaded = crate::mesh::load::load(pairs)
            .map_err(|errors| thrown(&errors.iter().map(Error::problem).collect::<Vec<_>>()))?;
        let frame_names: Vec<String> = loaded.poses.iter().map(|(n, _)| n.clone()).collect();
        let frames: Vec<Vec<[f64; 3]>> = loaded.poses.into_iter().map(|(_, m)| m.positions).collect();
        let sizes = frame_names.iter().zip(&frames).map(|(n, f)| (n.as_str(), f.len()));
        crate::articulate::pose::check_frame_sizes(sizes, self.inner.rig.rig.n_vertices(), None)
            .map_err(|e| thrown(&[e.problem()]))?;
        let (solved, e, glb) = self.inner.add_frames(&frames)?;
        let obj = js_sys::Object::new();
        let set =
            |k: &str, v: JsValue| js_sys::Reflect::set(&obj, &k.into(), &v).map(|_| ()).map_err(|_| js_err("reflect"));
        set("names", to_js(&frame_names)?)?;
        set("eRms", Float64Array::from(e.as_slice()).into())?;
        set("eRmsAll", JsValue::from(crate::articulate::pose::overall_e_rms(&e)))?;
        let positions = Array::new();
        for b in &solved.bones {
            positions.push(&flat_f32(&self.inner.to_unit(&self.inner.rig.rig.skin(b))).into());
        }
        set("positions", positions.into())?;
        // each frame's bones as `setBones` takes them: the page sets a frame shown to export it or read its
        // pose-space coordinates
        let bones = Array::new();
        for b in &solved.bones {
            bones.push(&Float64Array::from(crate::export::pose_glb::flat_bones(b).as_slice()).into());
        }
        set("bones", bones.into())?;
        set("glb", Uint8Array::from(glb.as_slice()).into())?;
        Ok(obj.into())
    }
}
