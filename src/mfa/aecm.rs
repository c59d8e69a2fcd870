//! A fit in progress: Alternating Expectation-Conditional Maximisation with two cycles (paper section 3.2).
//!
//! One iteration ([`Fit::step`]): CM cycle 1 (π, b) on the current responsibilities, E-step, CM cycle 2
//! (Λ, R, Φ), E-step. The last E-step gives the log-likelihood of the new parameters (the trace) and the
//! responsibilities of the next cycle 1. Convergence: |ΔL| / n_v < tol over one plain iteration; the
//! iteration cap is reported as not converged and the best state seen is still returned.
//!
//! With `Params::accelerate` (default), every second iteration ends with a SQUAREM extrapolation from the last
//! three states ([`super::squarem`]): its E-step gives the log-likelihood of the extrapolated state, which is
//! kept only when that is at least the plain iteration's; so the trace never decreases. Convergence is still
//! judged on the plain iteration's own |ΔL| (a converged iteration is never extrapolated), so the final state
//! is a plain AECM iterate at the same tolerance.
//!
//! Extrapolation starts only once a plain iteration changes L by less than [`SQUAREM_START`] per vertex. Early
//! on, an iteration still moves vertices between components, and an extrapolated step (up to |α| times the
//! plain one) can carry the fit into another basin: the safeguard keeps L monotone, not the basin. Extrapolating
//! from the start, horse-gallop's fit at seed 4 ended at 20 parts, RMSE 0.00450, and the same poses rounded to
//! float32 (as a .glb stores them) at 21 parts, 0.00394; with the start delayed the two agree at every seed 0-4,
//! as they do without acceleration.

use super::cm;
use super::component::Component;
use super::data::Data;
use super::estep::{e_step, Blocked, EStep};
use super::init;
use super::params::{InFit, LambdaRule, RunParams};
use super::result::Model;
use super::squarem;
use crate::error::{Error, Result};
use crate::geometry::Vec3;
use crate::memory;
use serde::Serialize;

/// What one iteration did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    pub iteration: usize,
    pub log_likelihood: f64,
    pub parts: usize,
    pub dropped: usize,
    pub converged: bool,
}

/// SQUAREM's longest step |α| at the start of a run (grows by 4 when used in full and kept).
const SQUAREM_FIRST_STEP_MAX: f64 = 4.0;

/// SQUAREM extrapolates only after a plain iteration whose |ΔL| / n_v is below this (10 x the default `tol`;
/// a difference of log-likelihoods per vertex, so free of the shape's scale). See the module doc.
pub const SQUAREM_START: f64 = 1e-2;

#[derive(Debug, Clone)]
pub struct Fit {
    data: Data,
    estep: EStep,
    comps: Vec<Component>,
    /// The responsibilities, sparse (every γ_kj >= 1e-14), as the CM steps use them.
    members: cm::Members,
    trace: Vec<f64>,
    initial_ll: f64,
    converged: bool,
    tol: f64,
    max_iter: usize,
    floor: f64,
    rule: LambdaRule,
    px: bool,
    min_mass: f64,
    best: Option<(f64, Vec<Component>)>,
    /// SQUAREM state: on, the states before the last one and two plain iterations, the longest step allowed.
    accelerate: bool,
    sq_prev: Vec<Vec<Component>>,
    sq_step_max: f64,
    /// Scratch responsibilities for the extrapolated state's E-step.
    sq_members: cm::Members,
    /// Extrapolations tried and kept (for benchmarks).
    pub extrapolations_tried: usize,
    pub extrapolations_kept: usize,
    /// Floating-point operations and milliseconds spent in E-steps (for benchmarks).
    pub estep_flops: f64,
    /// The part of `estep_flops` done in f32 (the screen).
    pub estep_flops_f32: f64,
    pub estep_ms: f64,
}

impl Fit {
    /// Starts from k-means++ (m = `params.parts`) with the per-cluster Procrustes initialisation.
    pub fn new(data: Data, params: &impl InFit) -> Result<Fit> {
        let params = &floor_for(&data, params);
        params.validate()?;
        let a = &params.algorithm1;
        let most = memory::max_components(a.parts, params.refine, a.max_subparts, data.n_vertices);
        check_population(&data, a.parts, most)?;
        let labels = init::kmeans(&data, a.parts, params.seed, params.restarts);
        Fit::from_labels(data, &labels, params)
    }

    /// Starts from a labelling (one component per distinct label).
    pub fn from_labels(data: Data, labels: &[u32], params: &impl InFit) -> Result<Fit> {
        let layout = Blocked::new(&data);
        Fit::from_labels_laid_out(data, layout, labels, params)
    }

    /// [`Fit::from_labels`] with the E-step's layout of `data` (`Blocked::new(&data)`) already built.
    pub fn from_labels_laid_out(data: Data, layout: Blocked, labels: &[u32], params: &impl InFit) -> Result<Fit> {
        let params = &floor_for(&data, params);
        params.validate()?;
        let most = labels.iter().max().map_or(1, |&l| l as usize + 1).min(data.n_vertices);
        check_data(&data, 1, most)?;
        if labels.len() != data.n_vertices {
            return Err(Error::Request(format!("{} labels for {} vertices", labels.len(), data.n_vertices)));
        }
        let comps = init::components_from_labels(&data, labels, params.floor());
        // the labels' components are evaluated first in the first E-step (they are its best guess)
        let owners = (comps.len() == labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0)).then_some(labels);
        Ok(Fit::from_components_owned(data, EStep::with_layout(layout), comps, params, owners))
    }

    /// [`Fit::from_components`] with the E-step's layout of `data` already built (a run that goes on from
    /// another run's components on the same data).
    pub fn from_components_laid_out(data: Data, layout: Blocked, comps: Vec<Component>, params: &impl InFit) -> Fit {
        Fit::from_components_owned(data, EStep::with_layout(layout), comps, params, None)
    }

    pub fn from_components(data: Data, comps: Vec<Component>, params: &impl InFit) -> Fit {
        let estep = EStep::new(&data);
        Fit::from_components_owned(data, estep, comps, params, None)
    }

    /// [`Fit::from_components`] with each vertex's likeliest component, if known, for the first E-step's order.
    fn from_components_owned(
        data: Data,
        estep: EStep,
        comps: Vec<Component>,
        params: &impl InFit,
        owners: Option<&[u32]>,
    ) -> Fit {
        let params = &floor_for(&data, params);
        let floor = params.floor();
        let mut fit = Fit {
            estep,
            data,
            comps,
            members: Vec::new(),
            trace: Vec::new(),
            initial_ll: f64::NEG_INFINITY,
            converged: false,
            tol: params.tol,
            max_iter: params.max_iter,
            floor,
            rule: params.lambda_rule,
            px: params.px_em,
            min_mass: params.min_part_vertices as f64,
            best: None,
            accelerate: params.accelerate,
            sq_prev: Vec::new(),
            sq_step_max: SQUAREM_FIRST_STEP_MAX,
            sq_members: Vec::new(),
            extrapolations_tried: 0,
            extrapolations_kept: 0,
            estep_flops: 0.0,
            estep_flops_f32: 0.0,
            estep_ms: 0.0,
        };
        if let Some(labels) = owners {
            fit.estep.set_owner_labels(labels, fit.comps.len());
        }
        fit.initial_ll = fit.run_e_step();
        fit
    }

    /// E-step with exact pruning of negligible components ([`EStep::run`]).
    fn run_e_step(&mut self) -> f64 {
        let t0 = crate::clock::now_ms();
        let (ll, _shape_evals) = self.estep.run(&self.data, &self.comps, &mut self.members);
        self.estep_ms += crate::clock::now_ms() - t0;
        self.estep_flops += self.estep.flops_f64 + self.estep.flops_f32;
        self.estep_flops_f32 += self.estep.flops_f32;
        ll
    }

    /// One AECM iteration. Does nothing but report once converged or at the cap.
    pub fn step(&mut self) -> StepInfo {
        if self.is_finished() {
            return self.info(0);
        }
        if self.accelerate {
            self.sq_prev.push(self.comps.clone());
        }
        cm::cycle1(&self.data, &self.members, &mut self.comps);
        self.run_e_step();
        let masses = cm::cycle2(&self.data, &self.members, &mut self.comps, self.rule, self.floor, self.px);
        // drop components whose responsibility mass fell below a few vertices (never the last one)
        let before = self.comps.len();
        if self.comps.len() > 1 {
            let keep: Vec<bool> = masses.iter().map(|&n| n >= self.min_mass).collect();
            if keep.iter().any(|&k| k) && keep.iter().any(|&k| !k) {
                let mut idx = 0;
                self.comps.retain(|_| {
                    let k = keep[idx];
                    idx += 1;
                    k
                });
                let total: f64 = self.comps.iter().map(|c| c.weight).sum();
                self.comps.iter_mut().for_each(|c| c.weight /= total);
            }
        }
        let dropped = before - self.comps.len();
        if dropped > 0 {
            // component indices changed: no hint for the next E-step
            self.estep.forget_owners();
        }
        let ll = self.run_e_step();
        let prev = self.trace.last().copied().unwrap_or(self.initial_ll);
        self.trace.push(ll);
        if ll.is_finite() && self.best.as_ref().is_none_or(|b| ll > b.0) {
            self.best = Some((ll, self.comps.clone()));
        }
        if ((ll - prev) / self.data.n_vertices as f64).abs() < self.tol && dropped == 0 {
            self.converged = true;
        }
        if self.is_finished() && self.accelerate && crate::trace::enabled() {
            crate::trace_line!(
                "AECM finished after {} iterations; SQUAREM kept {} of {} extrapolations (step_max {})",
                self.trace.len(),
                self.extrapolations_kept,
                self.extrapolations_tried,
                self.sq_step_max
            );
        }
        if self.accelerate {
            if dropped > 0 || self.converged {
                self.sq_prev.clear();
            } else if self.sq_prev.len() == 2 {
                if ((ll - prev) / self.data.n_vertices as f64).abs() < SQUAREM_START {
                    self.try_extrapolation(ll);
                }
                self.sq_prev.clear();
            }
        }
        self.info(dropped)
    }

    /// SQUAREM from θ0, θ1 (`sq_prev`) and θ2 (the current state, log-likelihood `ll2`): keeps the extrapolated
    /// state when its log-likelihood is at least `ll2`, else stays at θ2.
    fn try_extrapolation(&mut self, ll2: f64) {
        let Some((theta, a)) =
            squarem::extrapolate(&self.sq_prev[0], &self.sq_prev[1], &self.comps, self.sq_step_max, self.floor)
        else {
            // α = -1 (θ2 itself): let the next cycle try a longer step
            self.sq_step_max *= 4.0;
            return;
        };
        self.extrapolations_tried += 1;
        let t0 = crate::clock::now_ms();
        let (ll, _) = self.estep.run(&self.data, &theta, &mut self.sq_members);
        self.estep_ms += crate::clock::now_ms() - t0;
        self.estep_flops += self.estep.flops_f64 + self.estep.flops_f32;
        self.estep_flops_f32 += self.estep.flops_f32;
        if ll.is_finite() && ll >= ll2 {
            self.extrapolations_kept += 1;
            self.comps = theta;
            std::mem::swap(&mut self.members, &mut self.sq_members);
            if let Some(last) = self.trace.last_mut() {
                *last = ll;
            }
            if self.best.as_ref().is_none_or(|b| ll > b.0) {
                self.best = Some((ll, self.comps.clone()));
            }
            if a >= self.sq_step_max {
                self.sq_step_max *= 4.0;
            }
        } else {
            // the E-step's owner hints now belong to θ'; they only order the work, the result is exact
            self.sq_step_max = (self.sq_step_max / 4.0).max(1.0);
        }
    }

    fn info(&self, dropped: usize) -> StepInfo {
        StepInfo {
            iteration: self.trace.len(),
            log_likelihood: self.trace.last().copied().unwrap_or(self.initial_ll),
            parts: self.comps.len(),
            dropped,
            converged: self.converged,
        }
    }

    pub fn is_finished(&self) -> bool {
        self.converged || self.trace.len() >= self.max_iter
    }

    /// Steps until converged or at the cap; `observer` sees every iteration and returns false to stop.
    pub fn run(&mut self, observer: &mut dyn FnMut(&StepInfo) -> bool) -> StepInfo {
        let mut last = self.info(0);
        while !self.is_finished() {
            last = self.step();
            if !observer(&last) {
                break;
            }
        }
        last
    }

    /// The fit's data and E-step layout, for another run on the same vertices.
    pub fn into_laid_out(self) -> (Data, Blocked) {
        (self.data, self.estep.into_layout())
    }

    pub fn converged(&self) -> bool {
        self.converged
    }

    pub fn iterations(&self) -> usize {
        self.trace.len()
    }

    /// Log-likelihood after every iteration.
    pub fn trace(&self) -> &[f64] {
        &self.trace
    }

    /// Log-likelihood of the starting parameters.
    pub fn initial_log_likelihood(&self) -> f64 {
        self.initial_ll
    }

    pub fn components(&self) -> &[Component] {
        &self.comps
    }

    pub fn n_parts(&self) -> usize {
        self.comps.len()
    }

    pub fn data(&self) -> &Data {
        &self.data
    }

    /// Current responsibilities, dense: `gamma[j * parts + k]` (those below 1e-14 are 0).
    pub fn responsibilities(&self) -> Vec<f64> {
        cm::dense_responsibilities(&self.members, self.data.n_vertices, self.comps.len())
    }

    /// Mean variance of the components, weighted by their mass (Algorithm 1's err, mass-weighted).
    pub fn mean_variance(&self) -> f64 {
        let mut num = 0.0;
        let mut den = 0.0;
        for c in &self.comps {
            num += c.weight * c.mean_variance();
            den += c.weight;
        }
        num / den.max(f64::MIN_POSITIVE)
    }

    /// Labels of the current state: I_j = argmax_k γ_kj (eq 20).
    pub fn labels(&self) -> Vec<u32> {
        labels_from_members(&self.members, self.data.n_vertices, self.comps.len())
    }

    /// The model of the current state (converged) or of the best state seen (not converged, e.g. the literal
    /// eq 18 cycling). Translations are returned in unit-box coordinates.
    pub fn model(&self) -> Model {
        let current_is_best =
            self.converged || self.best.as_ref().is_none_or(|b| self.trace.last().is_some_and(|&l| l >= b.0));
        if current_is_best {
            self.model_of(&self.comps, self.labels())
        } else {
            let comps = self.best.as_ref().map(|b| b.1.clone()).unwrap_or_default();
            let mut gamma = Vec::new();
            e_step(&self.data, &comps, &mut gamma);
            let labels = labels_from_gamma(&gamma, comps.len());
            self.model_of(&comps, labels)
        }
    }

    fn model_of(&self, comps: &[Component], labels: Vec<u32>) -> Model {
        Model {
            log_likelihood: self.trace.clone(),
            iterations: self.trace.len(),
            converged: self.converged,
            ..model_of(&self.data, comps, labels)
        }
    }
}

/// The model of components `comps` (frame of `data`) with the given labels, before any AECM iteration: every
/// vertex's latent point v_j = Λ_{I_j} E[z | h_j] under its label's component (eq 21), translations in unit-box
/// coordinates.
pub fn model_of(data: &Data, comps: &[Component], labels: Vec<u32>) -> Model {
    let wbs: Vec<_> = comps.iter().map(|c| c.woodbury()).collect();
    let mut h = Vec::new();
    let latent: Vec<Vec3> = (0..data.n_vertices)
        .map(|j| {
            let k = labels[j] as usize;
            let e = comps[k].posterior_mean(&wbs[k], data.vertex_into(j, &mut h));
            [comps[k].lambda[0] * e[0], comps[k].lambda[1] * e[1], comps[k].lambda[2] * e[2]]
        })
        .collect();
    Model {
        n_shapes: data.n_shapes,
        n_vertices: data.n_vertices,
        parts: super::data::from_frame(data, comps),
        labels,
        latent,
        log_likelihood: Vec::new(),
        iterations: 0,
        converged: false,
    }
}

/// [`labels_from_gamma`] of [`cm::dense_responsibilities`]`(members, n, m)`, without building the dense matrix:
/// the same comparisons (a component's γ against the best so far, the first of equal ones kept; a vertex
/// missing from a component's list has γ = 0 there, which never wins against γ >= 0).
fn labels_from_members(members: &cm::Members, n: usize, m: usize) -> Vec<u32> {
    if m == 0 {
        return Vec::new();
    }
    let mut labels = vec![0u32; n];
    let mut best = vec![0.0; n];
    for (k, list) in members.iter().enumerate().take(m) {
        for mb in list {
            let j = mb.j as usize;
            if k == 0 {
                best[j] = mb.g;
            } else if mb.g > best[j] {
                labels[j] = k as u32;
                best[j] = mb.g;
            }
        }
    }
    labels
}

pub fn labels_from_gamma(gamma: &[f64], m: usize) -> Vec<u32> {
    if m == 0 {
        return Vec::new();
    }
    gamma
        .chunks_exact(m)
        .map(|row| {
            let mut best = 0;
            for k in 1..m {
                if row[k] > row[best] {
                    best = k;
                }
            }
            best as u32
        })
        .collect()
}

/// Refuses data that cannot be fitted, before anything is allocated for the fit: fewer than 2 shapes, no
/// vertex, more `parts` than vertices, non-finite coordinates, or a working set for `most_components`
/// components beyond the memory budget ([`memory`]).
/// What a whole population must be for a fit that may hold up to `most_components` components: at least 3
/// vertices and 2 poses, no more than `parts` asked for than vertices, finite coordinates, the memory budget,
/// and some motion ([`check_motion`]).
pub fn check_population(data: &Data, parts: usize, most_components: usize) -> Result<()> {
    if data.n_vertices < 3 {
        return Err(Error::Data(format!(
            "{} vertices; at least 3 are needed; use a mesh with more vertices",
            data.n_vertices
        )));
    }
    check_data(data, parts, most_components)?;
    check_motion(data)
}

fn check_data(data: &Data, parts: usize, most_components: usize) -> Result<()> {
    if data.n_shapes < 2 {
        return Err(Error::Data(format!(
            "{} shape(s); at least 2 poses are needed; add more poses of the same mesh",
            data.n_shapes
        )));
    }
    // (a whole population needs 3 vertices, see Fit::new; a part of it, fitted alone in the refinement, may
    // have fewer)
    if data.n_vertices == 0 {
        return Err(Error::Data("no vertices to fit; give the fit at least one vertex".into()));
    }
    if parts > data.n_vertices {
        return Err(Error::Params(format!(
            "parts = {parts} is more than the {} vertices of the mesh; ask for at most {} parts",
            data.n_vertices, data.n_vertices
        )));
    }
    if let Some((j, i, v)) = data.first_non_finite() {
        return Err(Error::Data(format!(
            "vertex {} of shape {} has a non-finite coordinate ({}); fix or remove that vertex",
            j + 1,
            i + 1,
            v
        )));
    }
    memory::check(data.n_vertices, data.n_shapes, most_components, memory::budget_bytes()?)
}

/// The parameters of a run on `data`: the fit's ([`RunParams`]), or, for a run on its own (plain [`super::Params`]),
/// with the variance floor scaled by this data's mean squared radius.
pub(crate) fn floor_for(data: &Data, params: &impl InFit) -> RunParams {
    params.in_fit(|| data.mean_squared_radius())
}

/// How far apart (unit-box units, per coordinate) two places of one vertex may be and still be the same place
/// ([`check_motion`]): the coordinates are stored in f32 and centred on that grid, each rounding at most 6e-8.
pub const SAME_PLACE: f64 = 1e-6;

/// Refuses a population whose shapes are all the same point set (up to rounding, after each is centred on
/// its centroid: identical shapes, or the whole mesh moved by a translation only): there is no motion, so no
/// parts, to learn. Only for the whole population: a part that does not move is fine inside a fit.
fn check_motion(data: &Data) -> Result<()> {
    for j in 0..data.n_vertices {
        let h = data.vertex(j);
        let first = h.get(0);
        if h.iter().skip(1).any(|p| (0..3).any(|d| (p[d] - first[d]).abs() > SAME_PLACE)) {
            return Ok(());
        }
    }
    Err(Error::Data(format!(
        "all {} shapes are the same: every vertex is at the same place in each of them (up to one translation \
         of the whole mesh), so there is no motion to learn; load poses in which the parts move",
        data.n_shapes
    )))
}

/// Time and work of one stage.
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct StageStats {
    pub name: String,
    pub iterations: usize,
    pub aecm_runs: usize,
    pub ms: f64,
    pub estep_ms: f64,
    pub estep_flops: f64,
    /// The part of `estep_flops` done in f32.
    pub estep_flops_f32: f64,
}
