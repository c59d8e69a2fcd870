//! Algorithm 1's own stages ([`PartRule::Distinct`] and [`PartRule::Threshold`], and the step-by-step lesson):
//! the coarse AECM from k-means++, then every coarse part refined on its own with m_k = 1, 2, ... components,
//! each trial split of the worst sub-part by positions (retried by residuals), kept while err drops; with the
//! paper's rule, adjacent parts that one rigid motion explains are merged before the final AECM
//! ([`merge_rigid_neighbours`]). The driver ([`super::Pipeline`]) runs the AECM; this says which run comes next
//! ([`Pipeline::refine_next`], [`Pipeline::algorithm1_next`]).
//!
//! What decides the count besides the part rule's own numbers (listed in `tree_rule`'s module documentation,
//! which the scale-free rule [`PartRule::Distinct`] shares): its own parameters, in
//! [`crate::mfa::Algorithm1Params`] with their defaults (the coarse parts m, the refinement's stops, the paper's
//! threshold, multi-resolution's subset, used from [`SUBSET_FACTOR`] times as many vertices), and the seed and
//! restarts of the k-means++ draw ([`Params`]).

use super::rounds::Tail;
use super::{lay_out, FinalRun, Pipeline, StageStats, State};
use crate::error::Result;
use crate::mesh::Population;
use crate::mfa::aecm::Fit;
use crate::mfa::data::Data;
use crate::mfa::estep::Blocked;
use crate::mfa::params::{Params, PartRule, RunParams};
use crate::mfa::result::Model;
use crate::parts::labels::compact;

/// Multi-resolution runs only on populations with at least this many times `subset_vertices` vertices (10 000 at the
/// default 2 000). A subset of more than a fifth of the mesh saves little and costs accuracy (fewer parts, a larger
/// RMSE, a small part lost on some seeds: docs/decisions.md, "Figures behind src/parts", `examples/speed_accuracy.rs`).
/// Without a subset the fit does not depend on the frame the file is written in (the subset's grid is axis-aligned;
/// every other step uses distances only).
pub const SUBSET_FACTOR: usize = 5;

pub(super) struct Refinement {
    pub(super) members: Vec<Vec<usize>>,
    pub(super) part: usize,
    /// Current trial: m_k and its fit.
    pub(super) sub_parts: usize,
    pub(super) fit: Fit,
    /// Best accepted fit so far for this part.
    best: Option<Best>,
    /// [`PartRule::Distinct`]: the labelling kept for this part so far (err, local labels): the first fit, then
    /// every accepted fit whose err is at most 1 / `distinct_ratio` of the kept one's.
    kept: Option<(f64, Vec<u32>)>,
    /// The split of the current best was already retried with the other rule.
    retried: bool,
    /// Refined labels accumulated over parts (global ids), u32::MAX = not yet assigned.
    refined: Vec<u32>,
    next_label: u32,
    /// The current coarse part's data and E-step layout while no trial runs on them (a trial takes them and
    /// hands them back when it finishes, as the final-stage runs do with [`Pipeline`]'s `full`).
    laid: Option<(Data, Blocked)>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SplitRule {
    Positions,
    Residuals,
}

struct Best {
    err: f64,
    /// Labels renumbered 0.. (what is kept).
    local: Vec<u32>,
    /// Labels as the fit numbers its components (what the next split starts from).
    raw: Vec<u32>,
    /// The worst sub-part: its local vertex ids, and their residual vectors (3 n_s each, flat).
    worst: (Vec<usize>, Vec<f64>),
}

/// The residual h_j - (R Λ E[z|h_j] + b) of vertex `j` of `fit`'s data under component `c`, appended to `out`
/// (3 n_s values).
fn push_residual(
    fit: &Fit,
    c: &crate::mfa::component::Component,
    wb: &crate::mfa::component::Woodbury,
    j: usize,
    out: &mut Vec<f64>,
) {
    let h = fit.data().vertex(j).to_vec();
    let e = c.posterior_mean(wb, &h);
    let v = [c.lambda[0] * e[0], c.lambda[1] * e[1], c.lambda[2] * e[2]];
    for (i, p) in h.iter().enumerate() {
        let q = c.place(i, v);
        out.extend_from_slice(&[p[0] - q[0], p[1] - q[1], p[2] - q[2]]);
    }
}

/// The component with the largest mass x mean variance, its vertices (local ids) and their residuals
/// ([`push_residual`]).
fn worst_component(fit: &Fit) -> (Vec<usize>, Vec<f64>) {
    let comps = fit.components();
    let labels = fit.labels();
    let score = |k: usize| comps[k].weight * comps[k].variances.iter().sum::<f64>();
    let worst = (0..comps.len())
        .max_by(|&a, &b| score(a).partial_cmp(&score(b)).unwrap_or(std::cmp::Ordering::Equal))
        .unwrap_or(0);
    let c = &comps[worst];
    let wb = c.woodbury();
    let mut members = Vec::new();
    let mut residuals = Vec::new();
    for (j, &l) in labels.iter().enumerate() {
        if l as usize == worst {
            members.push(j);
            push_residual(fit, c, &wb, j, &mut residuals);
        }
    }
    (members, residuals)
}

/// The squared residuals of `vertices` (local ids of `fit`'s data), each under the component that owns it.
fn residual_ss(fit: &Fit, vertices: &[usize]) -> f64 {
    let comps = fit.components();
    let labels = fit.labels();
    let wbs: Vec<_> = comps.iter().map(|c| c.woodbury()).collect();
    let mut r = Vec::new();
    let mut ss = 0.0;
    for &j in vertices {
        let k = labels[j] as usize;
        r.clear();
        push_residual(fit, &comps[k], &wbs[k], j, &mut r);
        ss += r.iter().map(|x| x * x).sum::<f64>();
    }
    ss
}

impl Pipeline {
    /// Algorithm 1's start: the coarse AECM from k-means++ on all vertices, or with multi-resolution on a
    /// well-spread subset of them ([`SUBSET_FACTOR`]).
    pub(super) fn from_algorithm1(pop: &Population, params: &RunParams, t0: f64) -> Result<Pipeline> {
        // the coarse and refinement runs stop at a loose tolerance and only pass labels on: they run plain AECM
        // (SQUAREM would move where they stop); the final run is accelerated
        let coarse = if params.refine {
            params.map(|p| {
                p.tol = p.refine_tol;
                p.accelerate = false;
            })
        } else {
            params.clone()
        };
        let a = &params.algorithm1;
        let subset = (params.refine && a.subset_vertices > 0 && pop.n_vertices() >= SUBSET_FACTOR * a.subset_vertices)
            .then(|| crate::parts::multires::spread_subset(pop, a.subset_vertices));
        let data = match &subset {
            Some(s) => {
                // the final stage runs on every vertex: the budget is checked for all of them first
                let most = crate::memory::max_components(a.parts, params.refine, a.max_subparts, pop.n_vertices());
                crate::memory::check(pop.n_vertices(), pop.n_shapes(), most, crate::memory::budget_bytes()?)?;
                Data::from_population_subset(pop, s)
            }
            None => Data::from_population(pop),
        };
        let fit = Fit::new(data, &coarse)?;
        Ok(Pipeline {
            pop: pop.clone(),
            params: params.clone(),
            start_labels: None,
            state: State::Coarse(fit),
            coarse: None,
            coarse_labels: Vec::new(),
            refined_labels: Vec::new(),
            final_model: None,
            stats: vec![StageStats { name: "coarse".into(), ..Default::default() }],
            stage_started_ms: t0,
            total_iterations: 0,
            subset,
            count_rounds: 0,
            decide_rounds: 0,
            part_curve: Vec::new(),
            part_rounds: Vec::new(),
            start_parts: None,
            decided_labels: None,
            merge_tree: None,
            tree_count: None,
            loose_start: false,
            loose_components: None,
            full: None,
            fine: None,
            final_runs: Vec::new(),
            last_run: None,
        })
    }

    pub(super) fn sub_params(&self) -> RunParams {
        self.params.for_refinement()
    }

    /// The coarse stage's model of all vertices (with multi-resolution: its components' E-step on all of them).
    pub(super) fn coarse_model(&self, fit: &Fit) -> Model {
        match &self.subset {
            None => fit.model(),
            Some(_) => crate::parts::multires::model_everywhere(&self.pop, &fit.model(), &self.params),
        }
    }

    pub(super) fn start_refinement(&mut self) -> Result<State> {
        let labels = &self.coarse_labels;
        let m = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        let mut members = vec![Vec::new(); m];
        match &self.subset {
            None => labels.iter().enumerate().for_each(|(j, &l)| members[l as usize].push(j)),
            Some(s) => s.iter().for_each(|&j| members[labels[j] as usize].push(j)),
        }
        members.retain(|m| !m.is_empty());
        let (data, layout) = lay_out(Data::from_population_subset(&self.pop, &members[0]));
        let fit = Fit::from_labels_laid_out(data, layout, &vec![0; members[0].len()], &self.sub_params())?;
        Ok(State::Refine(Box::new(Refinement {
            laid: None,
            refined: vec![u32::MAX; labels.len()],
            members,
            part: 0,
            sub_parts: 1,
            fit,
            best: None,
            retried: false,
            next_label: 0,
            kept: None,
        })))
    }

    /// Decides after a refinement run: try one more sub-part, retry the split another way, or accept and go
    /// to the next coarse part.
    pub(super) fn refine_next(&mut self, mut r: Box<Refinement>, done: Fit) -> Result<State> {
        let err = done.mean_variance();
        let distinct = self.params.part_rule == PartRule::Distinct;
        let died = done.n_parts() < r.sub_parts;
        // The split's own gain: the squared residuals of the sub-part that was cut, before / after. The mean
        // variance over the whole coarse part understates it when another sub-part is still mixed (a few
        // vertices of a neighbour inflate its variance), so a true joint cut can lower err only 2-3 times.
        let split_gain = r.best.as_ref().map_or(f64::INFINITY, |b| {
            let before: f64 = b.worst.1.iter().map(|x| x * x).sum();
            before / residual_ss(&done, &b.worst.0).max(f64::MIN_POSITIVE)
        });
        if crate::trace::enabled() {
            crate::trace_line!(
                "refine part {} ({} vertices) m_k={} err={:.3e} split_gain={split_gain:.2} died={died} iterations={} retry={}",
                r.part,
                r.members[r.part].len(),
                r.sub_parts,
                err,
                done.iterations(),
                r.retried
            );
        }
        let improved = match &r.best {
            None => true,
            Some(b) => !died && err < (1.0 - self.params.algorithm1.refine_min_gain) * b.err,
        };
        let n_members = r.members[r.part].len();
        let room = r.sub_parts < self.params.algorithm1.max_subparts
            && n_members >= (r.sub_parts + 1) * 2 * self.params.min_part_vertices;
        let best_parts = improved.then(|| (done.labels(), worst_component(&done)));
        // the trial's data and layout serve the next trial on this part
        r.laid = Some(done.into_laid_out());
        if let Some((raw, worst)) = best_parts {
            let local = compact(&raw);
            let ratio = self.params.distinct.distinct_ratio;
            if distinct && r.kept.as_ref().is_none_or(|k| err * ratio <= k.0 || split_gain >= ratio) {
                r.kept = Some((err, local.clone()));
            }
            r.best = Some(Best { err, local, raw, worst });
            r.retried = false;
            if (distinct || err >= self.params.algorithm1.threshold.refine_threshold) && room {
                let labels = self.split(&r, SplitRule::Positions);
                r.sub_parts += 1;
                r.fit = self.sub_fit(&mut r, &labels)?;
                return Ok(State::Refine(r));
            }
        } else if !r.retried && r.sub_parts > 1 {
            // The split of the worst sub-part by positions did not pay: cut it by its rigid-fit residuals
            // instead (a different boundary) before giving up on this part.
            r.retried = true;
            let labels = self.split(&r, SplitRule::Residuals);
            r.fit = self.sub_fit(&mut r, &labels)?;
            return Ok(State::Refine(r));
        }
        // accept the best labelling of this part
        let best = r.best.take().expect("the first run of a part is always accepted");
        let local = r.kept.take().map_or(best.local, |k| k.1);
        let n_local = local.iter().map(|&l| l + 1).max().unwrap_or(1);
        for (&j, &l) in r.members[r.part].iter().zip(&local) {
            r.refined[j] = r.next_label + l;
        }
        r.next_label += n_local;
        r.part += 1;
        r.retried = false;
        if r.part < r.members.len() {
            r.sub_parts = 1;
            r.laid = Some(lay_out(Data::from_population_subset(&self.pop, &r.members[r.part])));
            let n = r.members[r.part].len();
            r.fit = self.sub_fit(&mut r, &vec![0; n])?;
            return Ok(State::Refine(r));
        }
        // all parts refined: final stage
        let refined = match &self.subset {
            None => std::mem::take(&mut r.refined),
            Some(s) => crate::parts::multires::extend_labels(&self.pop, s, &r.refined, self.params.floor()),
        };
        self.refined_labels = match self.params.part_rule {
            // parts are merged after the final AECM has cleaned the boundaries ([`Pipeline::algorithm1_next`])
            PartRule::Distinct | PartRule::Tree => compact(&refined),
            PartRule::Threshold => merge_rigid_neighbours(&self.pop, &refined, &self.params),
        };
        self.close_stage(None);
        self.begin_final(FinalRun::First);
        let labels = self.refined_labels.clone();
        Ok(State::Final(self.fit_all(&labels)?))
    }

    /// Algorithm 1's rule after a final-stage run (or the coarse run, with the refinement off;
    /// [`Pipeline::next_run`]): the parts made connected; with the scale-free part rule ([`PartRule::Distinct`])
    /// the vertices labelled by motion first and, while a round is due, a round of the rule (flesh dissolved,
    /// parts without a distinct motion merged pair by pair, [`crate::parts::distinct::merge_indistinct`]), whose
    /// removals are refitted; then the count asked for, if any.
    pub(super) fn algorithm1_next(&mut self, mut model: Model) -> Result<State> {
        // the part rule decides after the refinement (a run without it is the coarse AECM as it is)
        let distinct = self.params.part_rule == PartRule::Distinct && self.params.refine;
        self.tidy(&mut model, distinct);
        let mut fitted = false;
        if distinct && self.round_due() {
            let (dissolved, before) = self.dissolve_round(&mut model);
            fitted = true;
            let (merged, curve) = crate::parts::distinct::merge_indistinct(&self.pop, &model.labels, &self.params);
            let after = self.record_round(&merged, curve, before, dissolved);
            if dissolved > 0 || after < before {
                self.refined_labels = merged.clone();
                if let Some(next) = self.count_after_round(&merged, after, |_, _| None)? {
                    return Ok(next);
                }
                return self.refit(FinalRun::Round, &merged);
            }
        }
        match self.exact_count(model, distinct && !fitted)? {
            Tail::Run(next) => Ok(next),
            Tail::Final(model) => Ok(self.done(model)),
        }
    }

    fn sub_fit(&self, r: &mut Refinement, labels: &[u32]) -> Result<Fit> {
        let (data, layout) =
            r.laid.take().unwrap_or_else(|| lay_out(Data::from_population_subset(&self.pop, &r.members[r.part])));
        Fit::from_labels_laid_out(data, layout, labels, &self.sub_params())
    }

    /// Labels of the best fit so far with its worst sub-part cut in two by 2-means (on the vertices'
    /// positions over all shapes, or on their residuals under that sub-part's rigid motion).
    fn split(&self, r: &Refinement, rule: SplitRule) -> Vec<u32> {
        let best = r.best.as_ref().expect("split needs an accepted fit");
        let mem = &r.members[r.part];
        let (worst, residuals) = (&best.worst.0, &best.worst.1);
        let mut labels = best.raw.clone();
        let new_label = labels.iter().copied().max().unwrap_or(0) + 1;
        if worst.len() < 2 * self.params.min_part_vertices {
            return labels;
        }
        let global: Vec<usize> = worst.iter().map(|&l| mem[l]).collect();
        let mut data = Data::from_population_subset(&self.pop, &global);
        if rule == SplitRule::Residuals {
            data = Data::from_f64(data.n_vertices, data.n_shapes, residuals, data.offsets);
        }
        let seed = self.params.seed.wrapping_add(1000 * r.part as u64 + r.sub_parts as u64);
        let halves = crate::mfa::init::kmeans(&data, 2, seed, self.params.restarts);
        for (&l, &half) in worst.iter().zip(&halves) {
            if half == 1 {
                labels[l] = new_label;
            }
        }
        labels
    }
}

pub(super) fn placeholder_fit() -> Fit {
    let data = Data::from_f64(0, 0, &[], Vec::new());
    Fit::from_components(data, Vec::new(), &Params::default())
}

/// Algorithm 1's own stopping rule, applied across coarse parts: two parts that share mesh edges and that one
/// rigid component explains with err (mean variance) below `merge_ratio * refine_threshold` are one part (they
/// would not have been split had they started in one coarse part). Merges the pair with the smallest joint err first,
/// until no pair qualifies. Keeps over-segmentation (a rigid piece cut in two by an unlucky coarse start or
/// split) out of the final stage. Labels are renumbered 0..
pub fn merge_rigid_neighbours(pop: &Population, labels: &[u32], params: &RunParams) -> Vec<u32> {
    let mut labels = compact(labels);
    let err_of = |members: &[usize]| crate::parts::distinct::rigid_variance(pop, members, params);
    let mut cache: std::collections::HashMap<(u32, u32), f64> = std::collections::HashMap::new();
    loop {
        let m = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        let mut members = vec![Vec::new(); m];
        for (j, &l) in labels.iter().enumerate() {
            members[l as usize].push(j);
        }
        let mut pairs = std::collections::BTreeSet::new();
        for f in pop.graph_faces().iter() {
            for e in 0..3 {
                let (a, b) = (labels[f[e] as usize], labels[f[(e + 1) % 3] as usize]);
                if a != b {
                    pairs.insert((a.min(b), a.max(b)));
                }
            }
        }
        let mut best: Option<((u32, u32), f64)> = None;
        for &(a, b) in &pairs {
            let key = (a, b);
            let err = *cache.entry(key).or_insert_with(|| {
                let mut union = members[a as usize].clone();
                union.extend_from_slice(&members[b as usize]);
                err_of(&union)
            });
            let t = &params.algorithm1.threshold;
            if err < t.merge_ratio * t.refine_threshold && best.is_none_or(|x| err < x.1) {
                best = Some((key, err));
            }
        }
        let Some(((a, b), _)) = best else { break };
        // merge b into a; labels above b shift down, so cached pairs are renumbered too
        cache = crate::parts::distinct::merge_pair(&mut labels, cache, a, b);
    }
    labels
}
