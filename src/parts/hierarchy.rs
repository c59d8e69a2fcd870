//! The driver of a fit, resumable (so a page can step it, show progress and cancel between iterations without
//! threads): it runs the AECM ([`crate::mfa`]), keeps each run's statistics, lifts results from a coarse mesh to
//! every vertex and reports every iteration ([`Progress`]). Which run comes next is the rule's to say: once a
//! run finished, `Pipeline::next_run` hands its model to the rule, which answers with the next run or that the
//! fit is done. There are two rules ([`Rule`]), each in its own module:
//!
//! - `tree_rule`, the merge tree (the default, [`PartRule::Tree`]): the start is the patches' merge tree cut
//!   ([`super::merge_tree`]: no random draw), its flesh dissolved; after the first final-stage run, the count
//!   is read off a merge tree of the fitted parts, and the parts left are refitted. A large population's
//!   parts are decided on a coarse mesh ([`super::coarse_mesh`]) and fitted on all vertices last.
//! - `algorithm1`, the paper's Algorithm 1 ([`PartRule::Distinct`], [`PartRule::Threshold`], the refinement
//!   off, and the step-by-step lesson): a coarse AECM from k-means++, each coarse part refined with m_k = 1, 2,
//!   ... components (err is the mass-weighted mean variance of the sub-components, as the paper's plain average
//!   is fragile: docs/method.md, item 8), then the final AECM from the refined labels; with
//!   [`PartRule::Distinct`] the part rule's rounds after it ([`super::distinct`]). With
//!   `Algorithm1Params::subset_vertices` (multi-resolution, [`super::multires`]) the coarse and refinement runs
//!   are on a well-spread subset of the vertices.
//!
//! `rounds` holds the steps after a final-stage run that both rules take (motion labels, connected parts,
//! flesh dissolved, the exact count asked for, [`super::part_count`]); `result` what a fit reports.

use crate::error::Result;
use crate::mesh::Population;
pub use crate::mfa::aecm::StageStats;
use crate::mfa::aecm::{Fit, StepInfo};
use crate::mfa::component::Component;
use crate::mfa::data::Data;
use crate::mfa::estep::Blocked;
use crate::mfa::params::{FitStart, Params, PartRule, RunParams};
use crate::mfa::result::Model;

mod algorithm1;
mod result;
mod rounds;
#[cfg(test)]
mod tests;
mod tree_rule;

pub use result::{FinalRun, FitResult, PartRound, Progress, Rule, RuleReport, Stage, StageParts};

pub use algorithm1::{merge_rigid_neighbours, SUBSET_FACTOR};
use algorithm1::{placeholder_fit, Refinement};
use tree_rule::check_start_labels;
pub use tree_rule::{
    coarse_target, COARSE_FACTOR, COARSE_POSES, TREE_COUNT_START_RATIO, TREE_CUT_LEAVES, TREE_START_RATIO,
};

/// Data and their E-step layout (which depends on the data alone, so one serves every run on them).
fn lay_out(data: Data) -> (Data, Blocked) {
    let layout = Blocked::new(&data);
    (data, layout)
}

/// The whole population's data and their E-step layout, kept in `full` (built on first use).
fn full_data<'a>(full: &'a mut Option<(Data, Blocked)>, pop: &Population) -> &'a (Data, Blocked) {
    full.get_or_insert_with(|| lay_out(Data::from_population(pop)))
}

enum State {
    Coarse(Fit),
    Refine(Box<Refinement>),
    Final(Fit),
    Done,
}

/// The rule a fit with `params` follows: the merge tree with [`PartRule::Tree`] (the default), Algorithm 1 with
/// the other part rules. With the refinement off (`refine` false) it is Algorithm 1's coarse stage alone,
/// whatever `part_rule` says: the merge tree has no stage without its rule, and the result says which rule ran
/// ([`FitResult::from_merge_tree`], the JSON's `stage_stats`).
pub fn rule_of(params: &Params) -> Rule {
    if params.part_rule == PartRule::Tree && params.refine {
        Rule::MergeTree
    } else {
        Rule::Algorithm1
    }
}

/// The population whose parts a [`Pipeline`] decides on a coarse mesh, and that mesh.
struct Fine {
    pop: Population,
    mesh: super::coarse_mesh::CoarseMesh,
    /// The whole population's data and E-step layout for the last run, made before the coarse mesh: the
    /// largest block of the fit is then taken first, and the blocks of the coarse mesh and its runs, freed
    /// before the last run, do not leave it to be placed above them (in wasm, where linear memory only grows,
    /// made last they raised the peak memory per vertex-pose: docs/decisions.md).
    full: (Data, Blocked),
}

pub struct Pipeline {
    pop: Population,
    /// The fit's parameters, with the variance floor scaled for the whole population (also while the runs are on
    /// a subset or a coarse mesh of it).
    params: RunParams,
    /// The partition the fit started from ([`FitStart`]), when one was given.
    start_labels: Option<Vec<u32>>,
    state: State,
    coarse: Option<Model>,
    coarse_labels: Vec<u32>,
    refined_labels: Vec<u32>,
    final_model: Option<Model>,
    stats: Vec<StageStats>,
    stage_started_ms: f64,
    total_iterations: usize,
    /// Vertices of the coarse and refinement stages (multi-resolution), None = all.
    subset: Option<Vec<usize>>,
    /// Times the part count was made exact (`target_parts`).
    count_rounds: usize,
    /// [`PartRule::Distinct`]: times parts were dissolved and merged after a final AECM (at most
    /// [`DECIDE_ROUNDS`]; the final AECM runs again after each round that removed parts).
    decide_rounds: usize,
    /// [`PartRule::Distinct`]: the merge decisions ([`super::distinct::merge_indistinct`]).
    part_curve: Vec<super::distinct::CurvePoint>,
    /// See [`FitResult::part_rounds`] and [`FitResult::start_parts`].
    part_rounds: Vec<PartRound>,
    start_parts: Option<usize>,
    /// See [`FitResult::decided_labels`].
    decided_labels: Option<Vec<u32>>,
    /// See [`FitResult::merge_tree`] and [`FitResult::tree_count`].
    merge_tree: Option<super::merge_tree::MergeTree>,
    tree_count: Option<usize>,
    /// [`PartRule::Tree`]: the current final-stage run is the first, at the refinement's loose tolerance (its
    /// parts are decided on, then the AECM runs again at `tol` whatever the decision).
    loose_start: bool,
    /// The loose first run's components, while the part rule decides on its parts: when it leaves them as they
    /// are, the AECM goes on from them at `tol` ([`Pipeline::go_on`]) instead of starting again from labels.
    loose_components: Option<Vec<Component>>,
    /// The whole population's data and their E-step layout, built once: a run on all vertices takes them and
    /// hands them back when it finishes (no second copy), the label fits read them.
    full: Option<(Data, Blocked)>,
    /// [`PartRule::Tree`] on a large population: while the parts are decided, `pop` is the coarse mesh's
    /// population and this holds the whole one; the last AECM runs on all vertices ([`Pipeline::finish_on_all_vertices`]).
    fine: Option<Box<Fine>>,
    /// The final stage's runs opened so far, in order (the last is the one in progress while in [`State::Final`]).
    final_runs: Vec<FinalRun>,
    /// The model of the last final-stage AECM run (the run's components, in the unit box, and its labels): on a
    /// coarse mesh the next run goes on from it ([`Pipeline::refit_warm`], [`Pipeline::finish_on_all_vertices`]).
    last_run: Option<Model>,
}

impl Pipeline {
    /// The pipeline a step-by-step lesson shows: the paper's Algorithm 1 (coarse AECM, refinement of each part,
    /// final AECM) with the scale-free part rule ([`PartRule::Distinct`]), whatever part rule `params` name: the
    /// default merge tree starts from its own partition and has no coarse or refinement stage to step through.
    /// A `start` is refused as with Algorithm 1 (it starts from its own k-means++ draw).
    pub fn for_teaching(pop: &Population, params: &Params, start: &FitStart) -> Result<Pipeline> {
        Pipeline::starting(pop, &Params { part_rule: PartRule::Distinct, ..params.clone() }, start)
    }

    /// Validates the parameters and the data and makes the rule's start (the merge tree's cut, or Algorithm 1's
    /// k-means++ draw).
    pub fn new(pop: &Population, params: &Params) -> Result<Pipeline> {
        Pipeline::starting(pop, params, &FitStart::default())
    }

    /// [`Pipeline::new`] from `start` when it gives a partition ([`FitStart`]): it is checked against `pop` and
    /// `params`, and the count is exactly its number of parts unless `target_parts` says otherwise.
    pub fn starting(pop: &Population, params: &Params, start: &FitStart) -> Result<Pipeline> {
        params.validate()?;
        // the variance floor follows the whole population's size, in every run of the fit (subsets included)
        let mut params = params.for_radius(pop.mean_squared_radius());
        if let Some(start) = &start.labels {
            let n = check_start_labels(start, pop, &params)?;
            params = params.map(|p| p.target_parts = Some(p.target_parts.unwrap_or(n)));
        }
        let params = &params;
        if let Some(n) = params.target_parts {
            super::part_count::check_target(n, pop.n_vertices(), params.min_part_vertices)?;
        }
        let t0 = crate::clock::now_ms();
        if params.part_rule == PartRule::Tree && !params.refine && crate::trace::enabled() {
            crate::trace_line!("refinement off: Algorithm 1's coarse stage alone (the merge tree always refines)");
        }
        match rule_of(params) {
            Rule::MergeTree => Pipeline::from_tree(pop, params, start.labels.as_deref(), t0),
            Rule::Algorithm1 => Pipeline::from_algorithm1(pop, params, t0),
        }
    }

    /// The population fitted (all its vertices, also while the parts are decided on a coarse mesh).
    pub fn population(&self) -> &Population {
        self.fine.as_ref().map_or(&self.pop, |f| &f.pop)
    }

    /// Whether the run in progress is on a coarse mesh's vertices ([`super::coarse_mesh`]; then
    /// [`Pipeline::current_vertices`] are its seeds).
    pub fn on_coarse_mesh(&self) -> bool {
        self.fine.is_some()
    }

    pub fn params(&self) -> &Params {
        self.params.params()
    }

    /// Which run the pipeline is in: Algorithm 1's coarse or refinement runs, or which of the final stage's runs.
    pub fn stage(&self) -> Stage {
        match &self.state {
            State::Coarse(_) => Stage::Coarse,
            State::Refine(r) => Stage::Refine { part: r.part, of: r.members.len(), sub_parts: r.sub_parts },
            State::Final(_) => {
                let run = *self.final_runs.last().expect("a final run is opened before it runs");
                Stage::Final {
                    rule: self.rule(),
                    run,
                    number: self.final_runs.iter().filter(|&&r| r == run).count(),
                    coarse_vertices: self.fine.as_ref().map(|f| f.mesh.seeds.len()),
                }
            }
            State::Done => Stage::Done,
        }
    }

    pub fn is_done(&self) -> bool {
        matches!(self.state, State::Done)
    }

    /// The rule deciding the parts ([`rule_of`] the fit's parameters).
    pub fn rule(&self) -> Rule {
        rule_of(&self.params)
    }

    /// The AECM run in progress (None when done).
    pub fn current_fit(&self) -> Option<&Fit> {
        match &self.state {
            State::Coarse(f) | State::Final(f) => Some(f),
            State::Refine(r) => Some(&r.fit),
            State::Done => None,
        }
    }

    /// Vertex ids (global) of the vertices of the current AECM run (all of them except in the refinement).
    pub fn current_vertices(&self) -> Option<&[usize]> {
        match &self.state {
            State::Refine(r) => Some(&r.members[r.part]),
            State::Coarse(_) => self.subset.as_deref(),
            State::Final(_) => self.fine.as_ref().map(|f| f.mesh.seeds.as_slice()),
            State::Done => None,
        }
    }

    /// Labels of every vertex under the run in progress: the run's own; on a coarse mesh, each patch's label on
    /// all of the patch's vertices; during the refinement, the coarse stage's.
    pub fn current_labels(&self) -> Vec<u32> {
        match self.current_fit() {
            Some(f) if self.current_vertices().is_none() => f.labels(),
            Some(f) if self.fine.is_some() => self.everywhere(&f.labels()),
            _ => self.current_model().labels,
        }
    }

    /// Labels (or any per-vertex values) of the coarse mesh's vertices carried to every vertex of their patch;
    /// as they are when the pipeline is on all vertices.
    fn everywhere<T: Copy>(&self, per_vertex: &[T]) -> Vec<T> {
        match &self.fine {
            Some(f) if per_vertex.len() == f.mesh.seeds.len() => f.mesh.to_fine(per_vertex),
            _ => per_vertex.to_vec(),
        }
    }

    /// A model of the coarse mesh's vertices as a model of every vertex: each vertex takes its patch's part,
    /// and its latent position is its own positions brought back by that part's motions (mean over the poses).
    /// The model as it is on all vertices.
    fn model_everywhere(&self, model: Model) -> Model {
        let Some(f) = self.fine.as_ref().filter(|f| model.n_vertices == f.mesh.seeds.len()) else { return model };
        let labels = f.mesh.to_fine(&model.labels);
        let ns = f.pop.n_shapes();
        let latent = labels
            .iter()
            .enumerate()
            .map(|(j, &l)| {
                let part = &model.parts[l as usize];
                let mut v = [0.0; 3];
                for i in 0..ns {
                    let p = part.unplace(i, f.pop.point(i, j));
                    (0..3).for_each(|c| v[c] += p[c] / ns as f64);
                }
                v
            })
            .collect();
        Model { n_vertices: labels.len(), labels, latent, ..model }
    }

    fn account(&mut self, fit: &Fit) {
        let s = self.stats.last_mut().expect("a stage is always open");
        s.iterations += fit.iterations();
        s.aecm_runs += 1;
        s.estep_ms += fit.estep_ms;
        s.estep_flops += fit.estep_flops;
        s.estep_flops_f32 += fit.estep_flops_f32;
    }

    fn close_stage(&mut self, next: Option<&str>) {
        let now = crate::clock::now_ms();
        if let Some(s) = self.stats.last_mut() {
            s.ms = now - self.stage_started_ms;
        }
        self.stage_started_ms = now;
        if let Some(n) = next {
            self.stats.push(StageStats { name: n.into(), ..Default::default() });
        }
    }

    /// One AECM iteration of the current stage; stage transitions happen inside when a run finishes.
    pub fn step(&mut self) -> Result<Progress> {
        let stage = self.stage();
        let info: StepInfo = match &mut self.state {
            State::Coarse(f) | State::Final(f) => f.step(),
            State::Refine(r) => r.fit.step(),
            State::Done => {
                return Ok(Progress {
                    stage,
                    iteration: 0,
                    total_iterations: self.total_iterations,
                    log_likelihood: self
                        .final_model
                        .as_ref()
                        .and_then(|m| m.log_likelihood.last().copied())
                        .unwrap_or(f64::NAN),
                    parts: self.final_model.as_ref().map_or(0, |m| m.n_parts()),
                    run_finished: true,
                })
            }
        };
        self.total_iterations += 1;
        let finished = self.current_fit().is_some_and(|f| f.is_finished());
        let progress = Progress {
            stage,
            iteration: info.iteration,
            total_iterations: self.total_iterations,
            log_likelihood: info.log_likelihood,
            parts: info.parts,
            run_finished: finished,
        };
        if finished {
            self.advance()?;
        }
        Ok(progress)
    }

    /// Moves to the next run or stage after the current run finished.
    fn advance(&mut self) -> Result<()> {
        let state = std::mem::replace(&mut self.state, State::Done);
        self.state = match state {
            State::Coarse(fit) => {
                self.account(&fit);
                let model = self.coarse_model(&fit);
                if self.subset.is_none() {
                    // the coarse run's data are the whole population's
                    self.full = Some(fit.into_laid_out());
                }
                self.coarse_labels = model.labels.clone();
                self.coarse = Some(model);
                if self.params.refine {
                    self.close_stage(Some("refine"));
                    self.start_refinement()?
                } else {
                    self.close_stage(None);
                    self.refined_labels = self.coarse_labels.clone();
                    let model = self.coarse.clone().expect("just set");
                    self.next_run(model)?
                }
            }
            State::Refine(mut r) => {
                let fit_done = std::mem::replace(&mut r.fit, placeholder_fit());
                self.account(&fit_done);
                self.refine_next(r, fit_done)?
            }
            State::Final(fit) => {
                self.account(&fit);
                self.close_stage(None);
                let model = fit.model();
                self.last_run = Some(model.clone());
                if self.fine.is_none() && self.loose_start {
                    self.loose_components = Some(fit.components().to_vec());
                }
                self.full = Some(fit.into_laid_out());
                self.next_run(model)?
            }
            State::Done => State::Done,
        };
        Ok(())
    }

    /// The rule's answer once a final-stage run finished (with the refinement off, the coarse run): given that
    /// run's model, the next run, or [`State::Done`] with the model kept as the fit's. Each rule says it in its
    /// own module: the merge tree's in `tree_rule` ([`Pipeline::tree_next`]), Algorithm 1's in `algorithm1`
    /// ([`Pipeline::algorithm1_next`]); the steps both take are in `rounds`.
    fn next_run(&mut self, model: Model) -> Result<State> {
        match self.rule() {
            Rule::MergeTree => self.tree_next(model),
            Rule::Algorithm1 => self.algorithm1_next(model),
        }
    }

    /// The part rule left the loose first run's parts as they were: the AECM goes on from that run's components
    /// at the fit's own tolerance (a new stage "final"; the run stopped at `refine_tol` was a few iterations short
    /// of `tol`, and a start again from its labels took many more: docs/decisions.md, "Figures behind src/parts"). From
    /// `labels` as [`Pipeline::refit`] when the motion labels have another number of parts than the run had
    /// components.
    fn go_on(&mut self, labels: &[u32]) -> Result<State> {
        let parts = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        let Some(comps) = self.loose_components.take().filter(|c| c.len() == parts) else {
            return self.refit(FinalRun::Settle, labels);
        };
        self.open_run(FinalRun::Settle);
        let (data, layout) = self.full.take().unwrap_or_else(|| lay_out(Data::from_population(&self.pop)));
        Ok(State::Final(Fit::from_components_laid_out(data, layout, comps, &self.params)))
    }

    /// The parts decided on the coarse mesh go to every vertex: the decisions' labels and merge tree to every
    /// vertex of each patch, and the last AECM runs on all vertices from the coarse fit's components (a new stage
    /// "all vertices"; as [`Pipeline::go_on`], no new start from labels). After it the part rule does not decide
    /// again: [`Pipeline::tree_next`] only moves the boundaries by motion and makes the parts connected.
    fn finish_on_all_vertices(&mut self, model: Model) -> Result<State> {
        let (nv, ns) = (self.population().n_vertices(), self.population().n_shapes());
        let budget = crate::memory::budget_bytes();
        if let Err(e) = budget.and_then(|b| crate::memory::check(nv, ns, model.n_parts(), b)) {
            // the parts decided stay the result (on every vertex) when the last run does not fit
            self.final_model = Some(self.model_everywhere(model));
            return Err(e);
        }
        self.coarse_labels = self.everywhere(&self.coarse_labels);
        self.refined_labels = self.everywhere(&self.refined_labels);
        self.decided_labels = self.decided_labels.as_deref().map(|d| self.everywhere(d));
        if let Some(leaves) = self.merge_tree.as_ref().map(|t| self.everywhere(&t.leaves)) {
            self.merge_tree.as_mut().expect("just read").leaves = leaves;
        }
        let fine = self.fine.take().expect("called on a coarse mesh");
        // each part from the coarse AECM's own component (soft boundaries) where it is a part of that run
        // ([`super::labels::same_parts`]); a part the motion labels or the islands made, from the labels' rigid fit
        let mut comps = model.parts.clone();
        for (c, last) in comps.iter_mut().zip(self.last_run_parts(&model.labels)) {
            if let Some(last) = last {
                *c = last;
            }
        }
        self.pop = fine.pop;
        self.full = None;
        self.decide_rounds = usize::MAX;
        self.open_run(FinalRun::AllVertices);
        let (data, layout) = fine.full;
        let comps = crate::mfa::data::to_frame(&data, &comps);
        Ok(State::Final(Fit::from_components_laid_out(data, layout, comps, &self.params)))
    }

    /// On a coarse mesh, after a round of the part rule that removed parts: the AECM again from `labels`, each
    /// part that is still a part of the last run ([`super::labels::same_parts`]) from that run's component, the
    /// others (a merge's union) from their labels; a union that is mostly one of its sides is that side (rule 2
    /// merges parts that move alike): fewer iterations than from labels, and steadier counts over the standard
    /// runs of `posemfa robustness`. Not on all vertices: there it was faster but moved the skinned characters'
    /// parts away from their skeletons (the figures of both: docs/decisions.md).
    fn refit_warm(&mut self, run: FinalRun, labels: &[u32]) -> Result<State> {
        let last = self.last_run_parts(labels);
        self.open_run(run);
        let (data, layout) = self.full.take().unwrap_or_else(|| lay_out(Data::from_population(&self.pop)));
        let mut comps = crate::mfa::init::components_from_labels(&data, labels, self.params.floor());
        for (c, last) in comps.iter_mut().zip(last) {
            if let Some(last) = last {
                // (the weight stays the labels' share: the run's weights sum to one over its own parts)
                *c = Component { weight: c.weight, ..crate::mfa::data::component_to_frame(&data, last) };
            }
        }
        Ok(State::Final(Fit::from_components_laid_out(data, layout, comps, &self.run_params())))
    }

    /// The last AECM run's component (unit-box translations) of each part of `labels` that is still a part of
    /// that run ([`super::labels::same_parts`]: more than half of each in the other), None for the others (a
    /// merge's union, a part the motion labels or the islands made). The run is let go.
    fn last_run_parts(&mut self, labels: &[u32]) -> Vec<Option<Component>> {
        let parts = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        match self.last_run.take().filter(|m| m.labels.len() == labels.len()) {
            Some(last) => super::labels::same_parts(labels, &last.labels)
                .into_iter()
                .map(|same| same.map(|b| last.parts[b as usize].clone()))
                .collect(),
            None => vec![None; parts],
        }
    }

    /// A new final-stage run `run`: the final AECM again on all vertices, from `labels`.
    fn refit(&mut self, run: FinalRun, labels: &[u32]) -> Result<State> {
        self.open_run(run);
        Ok(State::Final(self.fit_all(labels)?))
    }

    /// A new run after the loose first one ([`Pipeline::go_on`], [`Pipeline::refit`]).
    fn open_run(&mut self, run: FinalRun) {
        self.loose_start = false;
        self.loose_components = None;
        self.begin_final(run);
    }

    /// Records that the final-stage run `run` starts: its [`StageStats`] entry and its place among the runs.
    fn begin_final(&mut self, run: FinalRun) {
        self.final_runs.push(run);
        self.stats.push(StageStats { name: run.stats_name().into(), ..Default::default() });
        self.stage_started_ms = crate::clock::now_ms();
    }

    /// An AECM run on all vertices from `labels`, with the final stage's parameters.
    fn fit_all(&mut self, labels: &[u32]) -> Result<Fit> {
        let (data, layout) = self.full.take().unwrap_or_else(|| lay_out(Data::from_population(&self.pop)));
        Fit::from_labels_laid_out(data, layout, labels, &self.run_params())
    }

    /// The parameters of a run after the first: the fit's own, but on a coarse mesh, where every run only decides,
    /// at the loose tolerance (the last run, on all vertices, is at `tol`).
    fn run_params(&self) -> RunParams {
        match self.fine {
            Some(_) => self.params.at_loose_tolerance(),
            None => self.params.clone(),
        }
    }

    /// Runs to the end; `observer` sees every iteration and returns false to stop (the best state so far
    /// is kept).
    pub fn run(&mut self, observer: &mut dyn FnMut(&Progress) -> bool) -> Result<FitResult> {
        while !self.is_done() {
            let p = self.step()?;
            if !observer(&p) {
                break;
            }
        }
        Ok(self.result())
    }

    /// The result so far: the final model if done, else the best model available (the current final-stage
    /// fit, or the coarse model, or the current coarse fit).
    pub fn result(&self) -> FitResult {
        let model = match (&self.final_model, &self.state) {
            (Some(m), _) => m.clone(),
            (None, State::Final(f)) => f.model(),
            (None, State::Coarse(f)) => self.coarse_model(f),
            (None, _) => self.coarse.clone().expect("coarse model exists after the coarse stage"),
        };
        // (a fit stopped while deciding on a coarse mesh: its parts on every vertex)
        let model = self.model_everywhere(model);
        let merge_tree = self.merge_tree.clone().map(|mut t| {
            t.leaves = self.everywhere(&t.leaves);
            t
        });
        let n_distinct = |l: &[u32]| {
            let mut v = l.to_vec();
            v.sort_unstable();
            v.dedup();
            v.len()
        };
        FitResult {
            stages: StageParts {
                coarse_parts: n_distinct(&self.coarse_labels),
                refined_parts: n_distinct(&self.refined_labels),
                final_parts: model.n_parts(),
            },
            model,
            coarse_labels: self.everywhere(&self.coarse_labels),
            refined_labels: self.everywhere(&self.refined_labels),
            stats: self.stats.clone(),
            complete: self.is_done(),
            part_curve: self.part_curve.clone(),
            part_rounds: self.part_rounds.clone(),
            decided_labels: self.decided_labels.as_deref().map(|d| self.everywhere(d)),
            parts_asked: self.params.target_parts,
            count_unjudged: !self.params.refine || self.start_labels.is_some(),
            start_labels: self.start_labels.clone(),
            rule: match self.rule() {
                Rule::MergeTree => {
                    RuleReport::MergeTree { start_parts: self.start_parts, merge_tree, tree_count: self.tree_count }
                }
                Rule::Algorithm1 => RuleReport::Algorithm1 { refined: self.params.refine },
            },
        }
    }

    /// The model of the current state, for display while stepping (stage-local during the refinement: then
    /// the coarse model is shown).
    pub fn current_model(&self) -> Model {
        match &self.state {
            State::Coarse(f) => self.coarse_model(f),
            State::Final(f) => self.model_everywhere(f.model()),
            _ => self.result().model,
        }
    }
}

/// Runs a whole fit: every run the rule asks for, to the end (`observer` as in [`Pipeline::run`]).
pub fn fit(pop: &Population, params: &Params, observer: &mut dyn FnMut(&Progress) -> bool) -> Result<FitResult> {
    Pipeline::new(pop, params)?.run(observer)
}

/// [`fit`] from `start` ([`Pipeline::starting`]).
pub fn fit_from(
    pop: &Population,
    params: &Params,
    start: &FitStart,
    observer: &mut dyn FnMut(&Progress) -> bool,
) -> Result<FitResult> {
    Pipeline::starting(pop, params, start)?.run(observer)
}
