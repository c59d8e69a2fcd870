//! Algorithm 1, hierarchical optimisation, as a resumable pipeline (so a page can step it, show progress
//! and cancel between iterations without threads):
//!
//! 1. Coarse: AECM with m parts from k-means++.
//! 2. Refine: for every coarse part k, AECM on its vertices alone with m_k = 1, 2, ... components; err is
//!    the mass-weighted mean variance of the sub-components (the paper's plain average is fragile,
//!    METHOD_NOTES item 8). Stop when m_k does not lower err by at least the fraction `refine_min_gain`, when a
//!    component died, or at `max_subparts`, and with [`PartRule::Threshold`] when err < `refine_threshold`. Keep
//!    the best m_k; with [`PartRule::Distinct`], the last m_k that lowered err `distinct_ratio` times, or whose
//!    split lowered the squared residuals of the sub-part it cut `distinct_ratio` times.
//! 3. Final: AECM on all vertices started from the refined labels. With [`PartRule::Distinct`], every vertex is
//!    then labelled by rigid motion ([`super::motion_labels`]), every part is made one connected piece of the
//!    mesh ([`super::islands`]) and the parts are fitted to those labels ([`super::label_fit`]); then flesh
//!    between parts is dissolved and parts without a distinct motion are merged ([`super::distinct`]); if that
//!    removed parts, the final AECM runs again from those labels (at most [`DECIDE_ROUNDS`] times).
//! 4. Only with `target_parts` = N: parts are split or merged until there are exactly N ([`super::part_count`]),
//!    then the final AECM runs again from those labels.
//!
//! Every stage is kept (coarse labels, refined labels, final model).
//!
//! With `Params::subset_vertices` (multi-resolution, [`super::multires`]) stages 1 and 2 run on a well-spread
//! subset of the vertices; the coarse and refined labels of all vertices come from the E-step of those stages'
//! components on the whole population, and stage 3 runs on all vertices.

use super::labels::compact;
use crate::error::{Error, Result};
use crate::mesh::Population;
pub use crate::mfa::aecm::StageStats;
use crate::mfa::aecm::{Fit, StepInfo};
use crate::mfa::component::Component;
use crate::mfa::data::Data;
use crate::mfa::estep::Blocked;
use crate::mfa::params::{Params, PartRule};
use crate::mfa::result::Model;
use serde::Serialize;

/// Where the pipeline is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "camelCase", rename_all_fields = "camelCase")]
pub enum Stage {
    Coarse,
    /// Refining coarse part `part` (0-based) of `of`, trying `sub_parts` components.
    Refine {
        part: usize,
        of: usize,
        sub_parts: usize,
    },
    Final,
    Done,
}

/// Reported after every AECM iteration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Progress {
    pub stage: Stage,
    /// Iteration within the current AECM run.
    pub iteration: usize,
    /// Iterations over all runs so far.
    pub total_iterations: usize,
    pub log_likelihood: f64,
    /// Components of the current AECM run.
    pub parts: usize,
    /// The current run's iteration was its last (converged or capped).
    pub run_finished: bool,
}

/// Part counts of the three stages.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageParts {
    pub coarse_parts: usize,
    pub refined_parts: usize,
    pub final_parts: usize,
}

/// One decision round of the part rule ([`PartRule::Distinct`] or [`PartRule::Tree`], after a final AECM): the
/// parts it judged (the AECM's, each made one connected piece), how many of them it dissolved as flesh, and how
/// many were left after its merges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "camelCase", deny_unknown_fields)]
pub struct PartRound {
    pub parts: usize,
    pub dissolved: usize,
    pub after: usize,
}

/// Everything Algorithm 1 produced.
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The final model (or the best available if the fit was stopped early).
    pub model: Model,
    pub coarse_labels: Vec<u32>,
    pub refined_labels: Vec<u32>,
    pub stages: StageParts,
    pub stats: Vec<StageStats>,
    /// False if the fit was stopped before the final stage converged or hit its cap.
    pub complete: bool,
    /// [`PartRule::Distinct`]: the merge decisions, from the most parts down to the count kept (empty otherwise).
    pub part_curve: Vec<super::distinct::CurvePoint>,
    /// Every round of the part rule, in order (`part_curve` is the last one's merges; empty without the rule).
    pub part_rounds: Vec<PartRound>,
    /// [`PartRule::Tree`]: the start's parts once its flesh was dissolved, before the first AECM (the cut's own
    /// count is `stages.coarse_parts`).
    pub start_parts: Option<usize>,
    /// With `target_parts` and [`PartRule::Distinct`]: the labels the part rule decided, before the count was made
    /// exact (what auto would have kept), for the diagnosis ([`super::diagnosis::diagnose_fit`]).
    pub decided_labels: Option<Vec<u32>>,
    /// [`PartRule::Tree`]: the merge tree of the fitted parts the part rule read its count from (its leaves are
    /// the parts of the first final AECM, its merges go down to one part): a partition for every count.
    pub merge_tree: Option<super::merge_tree::MergeTree>,
    /// [`PartRule::Tree`]: the count the part rule read off `merge_tree`.
    pub tree_count: Option<usize>,
    /// The parts came from the merge tree ([`PartRule::Tree`] with the refinement on), not from Algorithm 1 (the
    /// other part rules, `refine` off, and a step-by-step lesson): what the page names the stages after.
    pub from_merge_tree: bool,
    /// The part count is the user's own, with no rule behind it (`refine` off: Algorithm 1's coarse stage alone,
    /// m = `parts`; or a partition given to start from, [`Params::start_labels`]), so too few parts cannot be
    /// told from a shape that is no articulated one ([`super::diagnosis::diagnose_fit`]).
    pub count_unjudged: bool,
    /// The refinement ran (`refine` on): Algorithm 1's refined stage is its own, not the coarse one again.
    pub refined: bool,
    /// The exact part count asked for (`target_parts`), if one was.
    pub parts_asked: Option<usize>,
}

impl FitResult {
    /// The partitions of the merge tree ([`PartRule::Tree`]; none with Algorithm 1's rules).
    pub fn tree_cuts(&self) -> Option<super::merge_tree::TreeCuts> {
        let tree = self.merge_tree.clone()?;
        Some(super::merge_tree::TreeCuts::new(tree, self.tree_count, &self.model.labels))
    }
}

struct Refinement {
    members: Vec<Vec<usize>>,
    part: usize,
    /// Current trial: m_k and its fit.
    sub_parts: usize,
    fit: Fit,
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

/// Data and their E-step layout (which depends on the data alone, so one serves every run on them).
fn lay_out(data: Data) -> (Data, Blocked) {
    let layout = Blocked::new(&data);
    (data, layout)
}

/// The whole population's data and their E-step layout, kept in `full` (built on first use).
fn full_data<'a>(full: &'a mut Option<(Data, Blocked)>, pop: &Population) -> &'a (Data, Blocked) {
    full.get_or_insert_with(|| lay_out(Data::from_population(pop)))
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

enum State {
    Coarse(Fit),
    Refine(Box<Refinement>),
    Final(Fit),
    Done,
}

/// Multi-resolution runs only on populations with at least this many times `subset_vertices` vertices (10 000
/// at the default 2 000). A subset of more than a fifth of the mesh saves little and costs accuracy: on
/// horse-gallop (8 431 vertices) a 2 000-vertex subset saved a quarter of the fit's time but gave 20 parts and
/// RMSE 0.00450 against 21 and 0.00395 without it, and on the 3 000-vertex quadruped example a subset lost a tail
/// piece on some seeds (`examples/speed_accuracy.rs`). Without a subset the fit does not depend on the frame the
/// file is written in (the subset's grid is axis-aligned; every other step uses distances only).
pub const SUBSET_FACTOR: usize = 5;

/// [`PartRule::Tree`] decides on a coarse mesh ([`super::coarse_mesh`]) only on populations with at least this
/// many times its size ([`coarse_target`]; 16 000 vertices at the default 8 000 and 20 poses or more): below that the decisions on all
/// vertices cost little more, and horse-gallop (8 431 vertices), the lion and the generated 12 000-vertex
/// creatures decide on every vertex as before.
pub const COARSE_FACTOR: usize = 2;

/// With fewer poses than this, the coarse mesh has more vertices ([`coarse_target`]).
pub const COARSE_POSES: usize = 20;

/// The coarse mesh's size for `coarse_vertices` ([`Params::coarse_vertices`]) and `n_shapes` poses: at least
/// `coarse_vertices x COARSE_POSES` vertex-poses, i.e. `coarse_vertices` from 20 poses on and more below (16 000
/// at 10 poses by default). The decisions read the poses' motion at the coarse vertices, and a population of few
/// poses gives them less to read per vertex; the runs' cost goes with the vertex-poses, so it stays bounded. On
/// 10-11 poses at 8 000 vertices the decisions moved more than on all vertices over the 9 standard runs of
/// `posemfa robustness` (the lion subdivided twice 18-22 parts, once 17-20, horse-poses subdivided 23-26); at
/// this size 19-20, 19-20 (on all vertices: under 2 x 16 000) and 26-27.
pub fn coarse_target(coarse_vertices: usize, n_shapes: usize) -> usize {
    if n_shapes >= COARSE_POSES {
        coarse_vertices
    } else {
        coarse_vertices * COARSE_POSES / n_shapes.max(1)
    }
}

/// The population whose parts a [`Pipeline`] decides on a coarse mesh, and that mesh.
struct Fine {
    pop: Population,
    mesh: super::coarse_mesh::CoarseMesh,
    /// The whole population's data and E-step layout for the last run, made before the coarse mesh: the
    /// largest block of the fit is then taken first, and the blocks of the coarse mesh and its runs, freed
    /// before the last run, do not leave it to be placed above them (in wasm, where linear memory only grows,
    /// made last they raised the generated 42 k x 11 quadruped's peak from 59 to 69 bytes per vertex-pose).
    full: (Data, Blocked),
}

pub struct Pipeline {
    pop: Population,
    params: Params,
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
    /// The model of the last final-stage AECM run (the run's components, in the unit box, and its labels): on a
    /// coarse mesh the next run goes on from it ([`Pipeline::refit_warm`], [`Pipeline::finish_on_all_vertices`]).
    last_run: Option<Model>,
}

/// [`PartRule::Tree`]'s start when the part rule chooses the count: the patches' tree is cut where a merge first
/// costs the smaller side, per vertex, this many times what merging two pieces of one part typically costs
/// ([`MergeTree::merge_yardstick`]). A generous over-segmentation: the part rule decides after the first AECM.
/// With every pose dropped in turn, the lion's start then moves by 4 parts where the patches' typical variance
/// as the yardstick (the median of 400 tiny fits, [`TREE_COUNT_START_RATIO`]) moved it by 22; 16, 24, 32 and 40
/// were measured too (docs/decisions.md, nineteenth session).
pub const TREE_START_RATIO: f64 = 28.0;

/// [`PartRule::Tree`]'s start with an exact part count (`target_parts`): the cut where a merge first costs 64
/// times the patches' typical variance ([`MergeTree::typical`]), and no flesh dissolved before the first AECM.
/// The count's steadiness does not matter there, and this start rigs better: horse-gallop at 10 bones E_RMS
/// 3.13 against 3.91 from the part rule's start (20 bones 1.035 and 1.036, 30 bones 0.613 and 0.556).
pub const TREE_COUNT_START_RATIO: f64 = 64.0;

/// A patch tree with fewer leaves than this (a mesh of under about 384 vertices) starts from every patch, uncut.
/// There a patch of about 6 vertices spans much of a part, so most patches straddle a joint and their typical
/// variance is not a rigid patch's: on Blender's 174-vertex skinned character (18 parts) it was 24 times the
/// 692-vertex one's, the cut at [`TREE_START_RATIO`] kept 6 of its 29 patches and the fit ended at 5 parts
/// (adjusted Rand 0.447 against the skeleton); from all 29 it ends at 18 (0.856). The AECM from at most 63 parts
/// on so few vertices is cheap.
pub const TREE_CUT_LEAVES: usize = 64;

/// The least typical variance of the patches (unit-box units²; the data are in the unit box), against 0 on
/// exactly rigid data.
const PATCH_VARIANCE_FLOOR: f64 = 1e-14;

/// Most times [`Pipeline`] makes the part count exact and refits.
const COUNT_ROUNDS: usize = 3;

/// Most times [`PartRule::Distinct`] dissolves and merges parts and refits (a refit moves boundaries, which can
/// leave a new sliver of flesh or a new island part).
const DECIDE_ROUNDS: usize = 3;

impl Pipeline {
    /// The pipeline a step-by-step lesson shows: the paper's Algorithm 1 (coarse AECM, refinement of each part,
    /// final AECM) with the scale-free part rule ([`PartRule::Distinct`]), whatever part rule `params` name: the
    /// default merge tree starts from its own partition and has no coarse or refinement stage to step through.
    pub fn for_teaching(pop: &Population, params: &Params) -> Result<Pipeline> {
        Pipeline::new(pop, &Params { part_rule: PartRule::Distinct, ..params.clone() })
    }

    /// Validates the parameters and the data and runs the coarse initialisation (k-means++).
    pub fn new(pop: &Population, params: &Params) -> Result<Pipeline> {
        params.validate()?;
        // the variance floor follows the whole population's size, in every run of the fit (subsets included)
        let mut params = params.for_radius(pop.mean_squared_radius());
        if let Some(start) = &params.start_labels {
            params.target_parts = Some(params.target_parts.unwrap_or(check_start_labels(start, pop, &params)?));
        }
        let params = &params;
        if let Some(n) = params.target_parts {
            super::part_count::check_target(n, pop.n_vertices(), params.min_part_vertices)?;
        }
        let t0 = crate::clock::now_ms();
        if params.part_rule == PartRule::Tree && params.refine {
            return Pipeline::from_tree(pop, params, t0);
        }
        // the coarse and refinement runs stop at a loose tolerance and only pass labels on: they run plain AECM
        // (SQUAREM would move where they stop); the final run is accelerated
        let coarse = if params.refine {
            Params { tol: params.refine_tol, accelerate: false, ..params.clone() }
        } else {
            params.clone()
        };
        let subset =
            (params.refine && params.subset_vertices > 0 && pop.n_vertices() >= SUBSET_FACTOR * params.subset_vertices)
                .then(|| super::multires::spread_subset(pop, params.subset_vertices));
        let data = match &subset {
            Some(s) => {
                // the final stage runs on every vertex: the budget is checked for all of them first
                let most =
                    crate::memory::max_components(params.parts, params.refine, params.max_subparts, pop.n_vertices());
                crate::memory::check(pop.n_vertices(), pop.n_shapes(), most, crate::memory::budget_bytes()?)?;
                Data::from_population_subset(pop, s)
            }
            None => Data::from_population(pop),
        };
        let fit = Fit::new(data, &coarse)?;
        Ok(Pipeline {
            pop: pop.clone(),
            params: params.clone(),
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
            last_run: None,
        })
    }

    /// [`PartRule::Tree`]: the patches' merge tree gives the start ([`super::merge_tree`]: no random draw), cut
    /// where a merge first costs the smaller side [`TREE_START_RATIO`] times the tree's typical merge within a
    /// part; the start's flesh goes ([`dissolve_start_flesh`]) and the final AECM runs from what is left. With
    /// an exact part count, the cut at [`TREE_COUNT_START_RATIO`] instead, flesh and all.
    fn from_tree(pop: &Population, params: &Params, t0: f64) -> Result<Pipeline> {
        // (an exact count the coarse mesh cannot hold is made on all vertices)
        let target = coarse_target(params.coarse_vertices, pop.n_shapes());
        let on_coarse = params.coarse_vertices > 0
            && pop.n_vertices() >= COARSE_FACTOR * target
            && params
                .target_parts
                .is_none_or(|n| super::part_count::check_target(n, target, params.min_part_vertices).is_ok());
        // (the last run's data first: see [`Fine::full`]); the data are judged on every vertex (a motion of a few
        // vertices no seed holds is still motion)
        let full = on_coarse.then(|| lay_out(Data::from_population(pop)));
        if let Some((data, _)) = &full {
            crate::mfa::aecm::check_population(data, 1, 1)?;
        }
        let coarse = on_coarse.then(|| super::coarse_mesh::CoarseMesh::build(pop, target));
        if let Some(c) = coarse.as_ref().filter(|_| crate::trace::enabled()) {
            let ms = crate::clock::now_ms() - t0;
            crate::trace_line!(
                "coarse mesh: {} vertices, {} triangles ({ms:.1} ms)",
                c.pop.n_vertices(),
                c.pop.faces.len()
            );
        }
        let work = coarse.as_ref().map_or_else(|| pop.clone(), |c| c.pop.clone());
        let data = Data::from_population(&work);
        // (the memory for the start's count is checked once the tree gives it)
        if full.is_none() {
            crate::mfa::aecm::check_population(&data, 1, 1)?;
        }
        let (cut, labels) = match &params.start_labels {
            // on the coarse mesh each coarse vertex takes its seed's part (a part no seed holds is made again by
            // the exact count's split)
            Some(start) => {
                let on_work = match &coarse {
                    Some(c) => compact(&c.seeds.iter().map(|&v| start[v]).collect::<Vec<_>>()),
                    None => compact(start),
                };
                let most = on_work.iter().max().map_or(1, |&l| l as usize + 1).max(params.target_parts.unwrap_or(0));
                crate::memory::check(work.n_vertices(), work.n_shapes(), most, crate::memory::budget_bytes()?)?;
                (on_work.clone(), on_work)
            }
            None => tree_start(&work, &data, params)?,
        };
        let start_parts = (cut != labels).then(|| labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0));
        if coarse.is_some() {
            // the last run is on every vertex: its memory, for at most the cut's count, before any run
            let most = cut.iter().max().map_or(1, |&l| l as usize + 1).max(params.target_parts.unwrap_or(0));
            crate::memory::check(pop.n_vertices(), pop.n_shapes(), most, crate::memory::budget_bytes()?)?;
        }
        let mut p = Pipeline {
            pop: work,
            params: params.clone(),
            state: State::Done,
            coarse: None,
            coarse_labels: cut,
            refined_labels: labels.clone(),
            final_model: None,
            stats: vec![StageStats { name: "tree".into(), ..Default::default() }],
            stage_started_ms: t0,
            total_iterations: 0,
            subset: None,
            count_rounds: 0,
            decide_rounds: 0,
            part_curve: Vec::new(),
            part_rounds: Vec::new(),
            start_parts,
            decided_labels: None,
            merge_tree: None,
            tree_count: None,
            loose_start: true,
            loose_components: None,
            full: None,
            fine: coarse.zip(full).map(|(mesh, full)| Box::new(Fine { pop: pop.clone(), mesh, full })),
            last_run: None,
        };
        p.close_stage(Some("final"));
        // the first run only feeds the part rule's decisions: at the refinement's loose tolerance (from a
        // generous over-segmentation a converged run took 64 iterations on the 12 k hand, the loose one 10)
        let loose = params.at_loose_tolerance();
        let (data, layout) = lay_out(data);
        p.state = State::Final(Fit::from_labels_laid_out(data, layout, &labels, &loose)?);
        Ok(p)
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
        &self.params
    }

    pub fn stage(&self) -> Stage {
        match &self.state {
            State::Coarse(_) => Stage::Coarse,
            State::Refine(r) => Stage::Refine { part: r.part, of: r.members.len(), sub_parts: r.sub_parts },
            State::Final(_) => Stage::Final,
            State::Done => Stage::Done,
        }
    }

    pub fn is_done(&self) -> bool {
        matches!(self.state, State::Done)
    }

    /// The stage of [`StageStats`] in progress (the last one opened: "coarse", "refine", "final", "distinct",
    /// "parts"), how many stages of that name have been opened so far (1 for the first), and whether the fit
    /// started from the merge tree's cut (stage "tree") rather than Algorithm 1's coarse stage, for a page to say
    /// which run it is in.
    pub fn current_stage_name(&self) -> (&str, usize, bool) {
        let name = self.stats.last().map_or("", |s| s.name.as_str());
        let from_tree = self.stats.first().is_some_and(|s| s.name == "tree");
        (name, self.stats.iter().filter(|s| s.name == name).count(), from_tree)
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
                    self.finish(model)?
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
                self.finish(model)?
            }
            State::Done => State::Done,
        };
        Ok(())
    }

    /// Algorithm 1's model made of connected parts ([`super::islands`]); with `target_parts`, the part count is
    /// then made exact ([`super::part_count`]) and the final AECM runs again from those labels (at most
    /// [`COUNT_ROUNDS`] times, in case the AECM drops a part).
    fn finish(&mut self, mut model: Model) -> Result<State> {
        let rounds = self.count_rounds;
        // (not once the count is forced: parts split to meet it can share one motion, and would empty each other)
        // the part rule decides after Algorithm 1's refinement (a run without it is the coarse AECM as it is)
        let distinct = matches!(self.params.part_rule, PartRule::Distinct | PartRule::Tree) && self.params.refine;
        if distinct && rounds == 0 {
            super::motion_labels::label_by_motion(&mut model, &self.pop);
            super::motion_labels::drop_empty_parts(&mut model);
        }
        // an island becomes a part of its own only after the first final AECM (later ones are boundary shifts)
        let new_parts = rounds == 0 && self.decide_rounds == 0;
        super::islands::connect_parts(&mut model, &self.pop, new_parts, self.params.min_part_vertices);
        if distinct {
            super::motion_labels::drop_empty_parts(&mut model);
        }
        // with `target_parts` the part rule decides once: its later rounds would refit counts the exact part count
        // then changes anyway
        let decide_rounds = if self.params.target_parts.is_some() { 1 } else { DECIDE_ROUNDS };
        // whether the parts were fitted to the motion labels in this call (a model the part rule leaves as it
        // is stays fitted)
        let mut fitted = false;
        if distinct && rounds == 0 && self.decide_rounds == 0 && self.params.start_labels.is_some() {
            // a partition given to start from (the page's Refine) is the user's: the part rule does not change
            // it, but its tree of the fitted parts is made as on any fit (the page's slider, the JSON)
            self.decide_rounds += 1;
            super::label_fit::fit_to_labels(&mut model, &full_data(&mut self.full, &self.pop).0, &self.params);
            fitted = true;
            let (_, curve) = self.decide_on_tree(&model.labels);
            self.part_curve = curve;
        } else if distinct && rounds == 0 && self.decide_rounds < decide_rounds {
            self.decide_rounds += 1;
            // rule 1 judges each part by the motion of its own labelled vertices (the mixture's component of a
            // short band part leans toward its neighbours' vertices; see label_fit)
            super::label_fit::fit_to_labels(&mut model, &full_data(&mut self.full, &self.pop).0, &self.params);
            fitted = true;
            let dissolved = super::distinct::dissolve_flesh(&mut model, &self.pop, self.params.blend_ratio);
            if dissolved > 0 {
                super::islands::connect_parts(&mut model, &self.pop, false, self.params.min_part_vertices);
            }
            let before = model.n_parts();
            let (merged, curve) = if self.params.part_rule == PartRule::Tree {
                self.decide_on_tree(&model.labels)
            } else {
                super::distinct::merge_indistinct(&self.pop, &model.labels, &self.params)
            };
            self.part_curve = curve;
            if self.params.target_parts.is_some() {
                self.decided_labels = Some(merged.clone());
            }
            let after = merged.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
            self.part_rounds.push(PartRound { parts: before + dissolved, dissolved, after });
            if crate::trace::enabled() {
                crate::trace_line!(
                    "part rule, round {}: {dissolved} parts dissolved as flesh, merges {before} -> {after} parts",
                    self.decide_rounds
                );
            }
            if dissolved > 0 || after < before {
                self.refined_labels = merged.clone();
                if let Some(n) = self.params.target_parts.filter(|&n| n != after) {
                    // the count is made exact on the decided labels at once (a refit first would be changed anyway)
                    self.count_rounds += 1;
                    // more parts than decided: the tree's finer partition; fewer: merged from the decided parts
                    // (the tree's own 10-part cut of horse-gallop rigged at E_RMS 3.40, the merges at 3.27)
                    let labels = match self.tree_partition(n).filter(|_| n > after) {
                        Some(l) => l,
                        None => super::part_count::labels_with_count(&self.pop, &merged, n, &self.params)?.0,
                    };
                    return self.refit("parts", &labels);
                }
                if self.fine.is_some() {
                    return self.refit_warm("distinct", &merged);
                }
                return self.refit("distinct", &merged);
            }
            if self.fine.is_some() && self.params.target_parts.is_none_or(|n| n == model.n_parts()) {
                // nothing to remove, on a coarse mesh: the last run, on all vertices, goes on from these parts
                // (with another count asked for, it is made below, on the coarse mesh)
                return self.finish_on_all_vertices(model);
            }
            if self.loose_start {
                // nothing to remove: the first run goes on at the fit's own tolerance
                return self.go_on(&merged);
            }
        }
        let n = match self.params.target_parts {
            Some(n)
                if !(model.n_parts() == n
                    && compact(&model.labels).iter().max().map_or(0, |&l| l as usize + 1) == n) =>
            {
                n
            }
            _ => {
                // the model is final: with the part rule's motion labels, its parts are fitted to them
                if distinct && rounds == 0 && !fitted {
                    super::label_fit::fit_to_labels(&mut model, &full_data(&mut self.full, &self.pop).0, &self.params);
                }
                if self.fine.is_some() {
                    return self.finish_on_all_vertices(model);
                }
                self.final_model = Some(model);
                // the data are not read any more: free them before the caller reads the result
                self.full = None;
                return Ok(State::Done);
            }
        };
        if rounds == COUNT_ROUNDS {
            return Err(crate::error::Error::Data(format!(
                "cannot keep exactly {n} parts: the final AECM dropped parts {rounds} times (each part needs the \
                 weight of at least {} vertices, the smallest part a fit keeps); ask for fewer parts",
                self.params.min_part_vertices
            )));
        }
        self.count_rounds += 1;
        let (labels, _) = super::part_count::labels_with_count(&self.pop, &model.labels, n, &self.params)?;
        self.refit("parts", &labels)
    }

    /// [`PartRule::Tree`]'s rule 2: the merge tree of the fitted parts ([`super::merge_tree::MergeTree::from_leaves`],
    /// every merge down to one part), cut where a merge first scores `distinct_ratio`. The first round's tree is
    /// the one kept in the result (its leaves are the parts of the first final AECM). Returns the labels at the
    /// count read off the tree and the curve of decisions (as [`super::distinct::merge_indistinct`]'s).
    fn decide_on_tree(&mut self, labels: &[u32]) -> (Vec<u32>, Vec<super::distinct::CurvePoint>) {
        let leaves = compact(labels);
        let mut tree = super::merge_tree::MergeTree::from_leaves(&self.pop, leaves, self.params.floor());
        // the first round's typical variance stays the yardstick: a refit's larger parts have larger variances,
        // and with its own yardstick every round would merge a few more (lion-poses: 43 -> 40 -> 36 -> 34)
        let yardstick = self.merge_tree.as_ref().map_or_else(|| tree.middle_typical(), |first| first.typical);
        tree.rescore(yardstick);
        let count = tree.decided_count(self.params.distinct_ratio);
        let merged = tree.labels_at(count);
        let curve = tree.curve(count);
        if self.merge_tree.is_none() {
            self.merge_tree = Some(tree);
            self.tree_count = Some(count);
        }
        (merged, curve)
    }

    /// [`PartRule::Tree`] with `target_parts`: the merge tree's partition with `n` parts, when the tree holds that
    /// count (the fitted parts' tree: from the first final AECM's parts down to one).
    fn tree_partition(&self, n: usize) -> Option<Vec<u32>> {
        let t = self.merge_tree.as_ref()?;
        let (most, fewest) = t.counts();
        (fewest..=most).contains(&n).then(|| t.labels_at(n))
    }

    /// The part rule left the loose first run's parts as they were: the AECM goes on from that run's components
    /// at the fit's own tolerance (a new stage "final"; the run stopped at `refine_tol` was a few iterations short
    /// of `tol`, and a start again from its labels took 17 iterations on horse-poses, 39 on lion-poses). From
    /// `labels` as [`Pipeline::refit`] when the motion labels have another number of parts than the run had
    /// components.
    fn go_on(&mut self, labels: &[u32]) -> Result<State> {
        let parts = labels.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
        let Some(comps) = self.loose_components.take().filter(|c| c.len() == parts) else {
            return self.refit("final", labels);
        };
        self.open_run("final");
        let (data, layout) = self.full.take().unwrap_or_else(|| lay_out(Data::from_population(&self.pop)));
        Ok(State::Final(Fit::from_components_laid_out(data, layout, comps, &self.params)))
    }

    /// The parts decided on the coarse mesh go to every vertex: the decisions' labels and merge tree to every
    /// vertex of each patch, and the last AECM runs on all vertices from the coarse fit's components (a new stage
    /// "all vertices"; as [`Pipeline::go_on`], no new start from labels). After it the part rule does not decide
    /// again: [`Pipeline::finish`] only moves the boundaries by motion and makes the parts connected.
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
        self.open_run("all vertices");
        let (data, layout) = fine.full;
        let comps = crate::mfa::data::to_frame(&data, &comps);
        Ok(State::Final(Fit::from_components_laid_out(data, layout, comps, &self.params)))
    }

    /// On a coarse mesh, after a round of the part rule that removed parts: the AECM again from `labels`, each
    /// part that is still a part of the last run ([`super::labels::same_parts`]) from that run's component, the
    /// others (a merge's union) from their labels; a union that is mostly one of its sides is that side (rule 2
    /// merges parts that move alike). The subdivided horse-gallop's refit took 22 iterations from labels, 10 from
    /// there; over the 9 standard runs of the subdivided lion, 16-20 parts (adjusted Rand min 0.843) from labels,
    /// 17-20 (0.949) from there. Not on all vertices: there it made horse-gallop's fit 341 -> 280 ms but moved the
    /// skinned characters' parts away from their skeletons (adjusted Rand 0.811 / 0.830 / 0.878 -> 0.779 / 0.785
    /// / 0.846).
    fn refit_warm(&mut self, stage: &str, labels: &[u32]) -> Result<State> {
        let last = self.last_run_parts(labels);
        self.open_run(stage);
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

    /// A new stage `stage`: the final AECM again on all vertices, from `labels`.
    fn refit(&mut self, stage: &str, labels: &[u32]) -> Result<State> {
        self.open_run(stage);
        Ok(State::Final(self.fit_all(labels)?))
    }

    /// The stage of a new run after the loose first one ([`Pipeline::go_on`], [`Pipeline::refit`]).
    fn open_run(&mut self, stage: &str) {
        self.loose_start = false;
        self.loose_components = None;
        self.stats.push(StageStats { name: stage.into(), ..Default::default() });
        self.stage_started_ms = crate::clock::now_ms();
    }

    /// An AECM run on all vertices from `labels`, with the final stage's parameters.
    fn fit_all(&mut self, labels: &[u32]) -> Result<Fit> {
        let (data, layout) = self.full.take().unwrap_or_else(|| lay_out(Data::from_population(&self.pop)));
        Fit::from_labels_laid_out(data, layout, labels, &self.run_params())
    }

    /// The parameters of a run after the first: the fit's own, but on a coarse mesh, where every run only decides,
    /// at the loose tolerance (the last run, on all vertices, is at `tol`).
    fn run_params(&self) -> Params {
        match self.fine {
            Some(_) => self.params.at_loose_tolerance(),
            None => self.params.clone(),
        }
    }

    fn sub_params(&self) -> Params {
        self.params.for_refinement()
    }

    /// The coarse stage's model of all vertices (with multi-resolution: its components' E-step on all of them).
    fn coarse_model(&self, fit: &Fit) -> Model {
        match &self.subset {
            None => fit.model(),
            Some(_) => super::multires::model_everywhere(&self.pop, &fit.model(), &self.params),
        }
    }

    fn start_refinement(&mut self) -> Result<State> {
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
    fn refine_next(&mut self, mut r: Box<Refinement>, done: Fit) -> Result<State> {
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
            Some(b) => !died && err < (1.0 - self.params.refine_min_gain) * b.err,
        };
        let n_members = r.members[r.part].len();
        let room = r.sub_parts < self.params.max_subparts
            && n_members >= (r.sub_parts + 1) * 2 * self.params.min_part_vertices;
        let best_parts = improved.then(|| (done.labels(), worst_component(&done)));
        // the trial's data and layout serve the next trial on this part
        r.laid = Some(done.into_laid_out());
        if let Some((raw, worst)) = best_parts {
            let local = compact(&raw);
            let ratio = self.params.distinct_ratio;
            if distinct && r.kept.as_ref().is_none_or(|k| err * ratio <= k.0 || split_gain >= ratio) {
                r.kept = Some((err, local.clone()));
            }
            r.best = Some(Best { err, local, raw, worst });
            r.retried = false;
            if (distinct || err >= self.params.refine_threshold) && room {
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
            Some(s) => super::multires::extend_labels(&self.pop, s, &r.refined, self.params.floor()),
        };
        self.refined_labels = match self.params.part_rule {
            // parts are merged after the final AECM has cleaned the boundaries ([`Pipeline::finish`])
            PartRule::Distinct | PartRule::Tree => compact(&refined),
            PartRule::Threshold => merge_rigid_neighbours(&self.pop, &refined, &self.params),
        };
        self.close_stage(Some("final"));
        let labels = self.refined_labels.clone();
        Ok(State::Final(self.fit_all(&labels)?))
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
            start_parts: self.start_parts,
            decided_labels: self.decided_labels.as_deref().map(|d| self.everywhere(d)),
            merge_tree,
            refined: self.params.refine,
            parts_asked: self.params.target_parts,
            tree_count: self.tree_count,
            from_merge_tree: self.params.part_rule == PartRule::Tree && self.params.refine,
            count_unjudged: !self.params.refine || self.params.start_labels.is_some(),
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

/// The number of parts of [`Params::start_labels`], once they are found to be a start for `pop`: one label per
/// vertex, with the merge tree's part rule.
fn check_start_labels(start: &[u32], pop: &Population, params: &Params) -> Result<usize> {
    if start.len() != pop.n_vertices() {
        return Err(Error::Params(format!(
            "startLabels has {} labels for a population of {} vertices: give one label per vertex",
            start.len(),
            pop.n_vertices()
        )));
    }
    if params.part_rule != PartRule::Tree || !params.refine {
        return Err(Error::Params(
            "startLabels needs the merge tree's part rule (partRule \"tree\", refine on): Algorithm 1 starts from its own k-means++ draw".into(),
        ));
    }
    // (the count is checked against the population with any count asked for, in Pipeline::new)
    Ok(compact(start).iter().max().map_or(0, |&l| l as usize + 1))
}

/// [`PartRule::Tree`]'s start ([`Pipeline::from_tree`]): the patches' tree cut at [`TREE_START_RATIO`] times its
/// [`MergeTree::merge_yardstick`] (with `target_parts`: at [`TREE_COUNT_START_RATIO`] times its typical variance),
/// not cut when it has fewer than [`TREE_CUT_LEAVES`] patches; then, when the part rule decides the count, the
/// start's flesh dissolved ([`dissolve_start_flesh`]). Returns the cut and the start (compact labels).
fn tree_start(pop: &Population, data: &Data, params: &Params) -> Result<(Vec<u32>, Vec<u32>)> {
    // the patches' own yardstick, not the variance floor: on clean data the patches fit far below the floor,
    // and the floor as the yardstick merged the generated hand's fingertips before the AECM
    let t0 = crate::clock::now_ms();
    let mut tree = super::merge_tree::MergeTree::build(pop, PATCH_VARIANCE_FLOOR);
    if crate::trace::enabled() {
        crate::trace_line!("tree built ({:.1} ms)", crate::clock::now_ms() - t0);
    }
    let exact = params.target_parts.is_some();
    let ratio = if exact { TREE_COUNT_START_RATIO } else { TREE_START_RATIO };
    if !exact {
        tree.rescore(tree.merge_yardstick().max(PATCH_VARIANCE_FLOOR));
    }
    let uncut = tree.n_leaves < TREE_CUT_LEAVES;
    let count = if uncut { tree.n_leaves } else { tree.decided_count(ratio) };
    let start = count.max(params.target_parts.unwrap_or(1));
    let cut = tree.labels_at(start);
    let most = start.max(params.target_parts.unwrap_or(0));
    crate::memory::check(pop.n_vertices(), pop.n_shapes(), most, crate::memory::budget_bytes()?)?;
    if crate::trace::enabled() {
        crate::trace_line!("tree: {} patches, start at {start} parts", tree.n_leaves);
    }
    // (uncut, the start's parts are single patches of about 6 vertices, too few to tell a slice of a band from a
    // part of its own: on the skinned characters the flesh rule there moved the parts' agreement with the
    // skeleton by -0.05 to +0.04)
    let labels =
        if params.refine && !uncut && !exact { dissolve_start_flesh(pop, data, &cut, params) } else { cut.clone() };
    Ok((cut, labels))
}

/// [`PartRule::Tree`]: the part rule's first rule ([`super::distinct::dissolve_flesh`]) on the start, before any
/// AECM: each start part's component in closed form ([`crate::mfa::init::components_from_labels`]), and a part
/// whose motion is a blend of two neighbours' goes to them. A start cut from the patches has slices of the
/// skinning bands between bones; left in, the first AECM makes each a band part of its own, how many depending on
/// small changes of the data (horse-gallop with one of 49 frames dropped: 7-15 dissolved after the AECM), and
/// the decided count with them (23-29 parts). Dissolved on the start, 11-13 go on the horses and the lion, the
/// AECM starts with fewer components and the rounds after it find next to no flesh. Compact labels.
fn dissolve_start_flesh(pop: &Population, data: &Data, labels: &[u32], params: &Params) -> Vec<u32> {
    let t0 = crate::clock::now_ms();
    let comps = crate::mfa::init::components_from_labels(data, labels, params.floor());
    let mut model = crate::mfa::aecm::model_of(data, &comps, compact(labels));
    let dissolved = super::distinct::dissolve_flesh(&mut model, pop, params.blend_ratio);
    if dissolved > 0 {
        super::islands::connect_parts(&mut model, pop, false, params.min_part_vertices);
    }
    if crate::trace::enabled() {
        crate::trace_line!(
            "start: {dissolved} parts dissolved as flesh before the first AECM ({:.1} ms)",
            crate::clock::now_ms() - t0
        );
    }
    compact(&model.labels)
}

fn placeholder_fit() -> Fit {
    let data = Data::from_f64(0, 0, &[], Vec::new());
    Fit::from_components(data, Vec::new(), &Params::default())
}

/// Runs the whole of Algorithm 1.
pub fn fit(pop: &Population, params: &Params, observer: &mut dyn FnMut(&Progress) -> bool) -> Result<FitResult> {
    Pipeline::new(pop, params)?.run(observer)
}

/// Algorithm 1's own stopping rule, applied across coarse parts: two parts that share mesh edges and that one
/// rigid component explains with err (mean variance) below `merge_ratio * refine_threshold` are one part (they
/// would not have been split had they started in one coarse part). Merges the pair with the smallest joint err first,
/// until no pair qualifies. Keeps over-segmentation (a rigid piece cut in two by an unlucky coarse start or
/// split) out of the final stage. Labels are renumbered 0..
pub fn merge_rigid_neighbours(pop: &Population, labels: &[u32], params: &Params) -> Vec<u32> {
    let mut labels = compact(labels);
    let err_of = |members: &[usize]| super::distinct::rigid_variance(pop, members, params);
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
            if err < params.merge_ratio * params.refine_threshold && best.is_none_or(|x| err < x.1) {
                best = Some((key, err));
            }
        }
        let Some(((a, b), _)) = best else { break };
        // merge b into a; labels above b shift down, so cached pairs are renumbered too
        cache = super::distinct::merge_pair(&mut labels, cache, a, b);
    }
    labels
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::adjusted_rand_index;
    use crate::synth::{generate, part_index, Preset, Spec};

    #[test]
    fn the_start_loses_a_band_slice_and_keeps_the_limbs() {
        // the arm with a wide blend band at the elbow, the band a start part of its own (label 3)
        let g = generate(&Spec { preset: Preset::Arm, vertices: 1500, poses: 8, joint_band: 0.10, ..Spec::default() })
            .unwrap();
        let pop = &g.population;
        let idx = |name| part_index(Preset::Arm, name).unwrap() as u32;
        let (upper, forearm) = (idx("upper_arm"), idx("forearm"));
        let mut sliced = g.part_of_vertex.clone();
        for (j, b) in g.blend.iter().enumerate() {
            if b.parts.contains(&upper) && b.parts.contains(&forearm) && b.weight > 0.02 && b.weight < 0.98 {
                sliced[j] = 3;
            }
        }
        assert!(sliced.iter().filter(|&&l| l == 3).count() >= 20);
        let data = Data::from_population(pop);
        let params = Params::default();
        let start = dissolve_start_flesh(pop, &data, &sliced, &params);
        assert_eq!(start.iter().max(), Some(&2), "the slice went to its sides");
        // (a wide band's middle is about as near one side's motion as the other's)
        let (before, after) =
            (adjusted_rand_index(&sliced, &g.part_of_vertex), adjusted_rand_index(&start, &g.part_of_vertex));
        assert!(after > 0.9 && after > before, "adjusted Rand against the truth {before} -> {after}");
        // the three true parts are no blend of each other: all stay
        let kept = dissolve_start_flesh(pop, &data, &g.part_of_vertex, &params);
        assert_eq!(adjusted_rand_index(&kept, &g.part_of_vertex), 1.0);
    }

    #[test]
    fn the_start_over_segments_a_generated_creature_inside_its_parts() {
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let (cut, start) = tree_start(pop, &Data::from_population(pop), &Params::default()).unwrap();
        let count = |l: &[u32]| l.iter().map(|&x| x as usize + 1).max().unwrap_or(0);
        let truth = count(&g.part_of_vertex);
        assert!(
            count(&start) >= truth && count(&cut) >= count(&start),
            "cut {}, start {}, truth {truth}",
            count(&cut),
            count(&start)
        );
        // every start part lies inside one true part (the joints are where the tree stops)
        let mut inside = 0;
        for k in 0..count(&start) as u32 {
            let mut per_part = vec![0usize; truth];
            for (j, _) in start.iter().enumerate().filter(|(_, &l)| l == k) {
                per_part[g.part_of_vertex[j] as usize] += 1;
            }
            inside += per_part.iter().max().copied().unwrap_or(0);
        }
        let purity = inside as f64 / pop.n_vertices() as f64;
        assert!(purity > 0.97, "purity {purity}");
    }

    #[test]
    fn parts_the_rule_leaves_alone_go_on_from_the_loose_run() {
        // a generated quadruped: the part rule's first round keeps the first run's parts as they are
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
        let mut pipe = Pipeline::new(&g.population, &Params::default()).unwrap();
        let mut runs: Vec<Vec<f64>> = vec![Vec::new()];
        while !pipe.is_done() {
            let p = pipe.step().unwrap();
            runs.last_mut().unwrap().push(p.log_likelihood);
            if p.run_finished && !pipe.is_done() {
                runs.push(Vec::new());
            }
        }
        let names: Vec<&str> = pipe.stats.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["tree", "final", "final"], "the first round removed nothing");
        // the second run starts where the first stopped (its components), so AECM's monotonicity carries over
        // from one run to the next; a start again from labels begins below it
        let (first, second) = (&runs[0], &runs[1]);
        let last = *first.last().unwrap();
        assert!(
            second[0] >= last - 1e-9 * last.abs(),
            "second run starts at {} after the first ended at {last}",
            second[0]
        );
        assert!(second.len() < first.len(), "{} iterations after {}", second.len(), first.len());
        let result = pipe.result();
        assert_eq!(result.model.n_parts(), 18);
    }

    #[test]
    fn a_refit_after_a_merge_goes_on_from_the_parts_that_stayed() {
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 10, ..Spec::default() }).unwrap();
        let mut pipe = Pipeline::new(&g.population, &Params::default()).unwrap();
        let done = pipe.run(&mut |_| true).unwrap();
        let last = pipe.last_run.clone().expect("the last run's model is kept");
        // the cheapest merge of the fitted parts' tree (the merge the part rule's rule 2 would make next)
        let tree = done.merge_tree.as_ref().expect("the tree pipeline keeps its tree");
        let merged = tree.labels_at(done.model.n_parts() - 1);
        let mut cold = Pipeline::new(&g.population, &Params::default()).unwrap();
        let state = cold.refit("distinct", &merged).unwrap();
        let State::Final(mut cold) = state else { panic!("a refit is a final-stage run") };
        let State::Final(mut warm) = pipe.refit_warm("distinct", &merged).unwrap() else {
            panic!("a refit is a final-stage run")
        };
        // every part that is one of the last run's (all but at most the union) starts from that run's component
        let before = crate::mfa::data::to_frame(warm.data(), &last.parts);
        let same = super::super::labels::same_parts(&merged, &last.labels);
        assert!(same.iter().filter(|s| s.is_some()).count() + 1 >= same.len(), "{same:?}");
        for (c, s) in warm.components().iter().zip(&same) {
            if let Some(b) = s {
                assert_eq!(c.rotations, before[*b as usize].rotations);
                assert_eq!(c.translations, before[*b as usize].translations);
            }
        }
        // and it ends where the refit from labels ends
        while !warm.is_finished() {
            warm.step();
        }
        while !cold.is_finished() {
            cold.step();
        }
        let (w, c) = (warm.model(), cold.model());
        assert_eq!(w.n_parts(), c.n_parts());
        assert!(adjusted_rand_index(&w.labels, &c.labels) > 0.99);
    }

    #[test]
    fn a_refine_from_the_merge_trees_partition_keeps_that_partition() {
        // the page's "Refine N parts": the fitted parts' tree cut at N, then the fit from those labels; on all
        // vertices and on a coarse mesh (each coarse vertex takes its seed's part)
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
        for coarse_vertices in [0, 1000] {
            let base = Params { coarse_vertices, ..Params::default() };
            let auto = fit(&g.population, &base, &mut |_| true).unwrap();
            let n = auto.model.n_parts() - 4;
            let start = auto.merge_tree.as_ref().expect("the tree rule's tree").labels_at(n);
            let params = Params { start_labels: Some(start.clone()), ..base.clone() };
            let refined = fit(&g.population, &params, &mut |_| true).unwrap();
            assert_eq!(refined.model.n_parts(), n, "coarse {coarse_vertices}");
            // every part is one of the partition shown: more than half of each in the other
            let (a, b) = (&refined.model.labels, &start);
            let mut overlap = std::collections::HashMap::new();
            let (mut size_a, mut size_b) = (vec![0usize; n], vec![0usize; n]);
            for (&x, &y) in a.iter().zip(b) {
                *overlap.entry((x, y)).or_insert(0usize) += 1;
                size_a[x as usize] += 1;
                size_b[y as usize] += 1;
            }
            let same =
                overlap.iter().filter(|(&(x, y), &k)| 2 * k > size_a[x as usize] && 2 * k > size_b[y as usize]).count();
            assert_eq!(same, n, "coarse {coarse_vertices}: {same} of the {n} parts shown came out of the refit");
            let ari = adjusted_rand_index(a, b);
            assert!(ari > 0.9, "coarse {coarse_vertices}: the refit moved away from the partition shown ({ari:.3})");
        }
        // what is not a start is refused, naming the field
        let short = Params { start_labels: Some(vec![0; 10]), ..Params::default() };
        let e = Pipeline::new(&g.population, &short).err().expect("refused").to_string();
        assert!(e.contains("startLabels has 10 labels for a population of"), "{e}");
        let distinct = Params {
            part_rule: PartRule::Distinct,
            start_labels: Some(vec![0; g.population.n_vertices()]),
            ..Params::default()
        };
        let e = Pipeline::new(&g.population, &distinct).err().expect("refused").to_string();
        assert!(e.contains("startLabels needs the merge tree's part rule"), "{e}");
    }

    #[test]
    fn an_exact_count_is_made_on_the_coarse_mesh() {
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
        let params = Params { coarse_vertices: 1000, target_parts: Some(12), ..Params::default() };
        let result = fit(&g.population, &params, &mut |_| true).unwrap();
        assert_eq!(result.model.n_parts(), 12);
        let names: Vec<&str> = result.stats.iter().map(|s| s.name.as_str()).collect();
        let (parts, all) = (names.iter().position(|&n| n == "parts"), names.iter().position(|&n| n == "all vertices"));
        assert!(parts.is_some() && parts < all, "the count on the coarse mesh, then all vertices: {names:?}");
        // a count the coarse mesh cannot hold (4 vertices a part) is made on all vertices
        let many = Params { coarse_vertices: 1000, target_parts: Some(300), ..Params::default() };
        assert!(!Pipeline::new(&g.population, &many).unwrap().on_coarse_mesh());
    }

    #[test]
    fn fewer_poses_get_a_larger_coarse_mesh() {
        // 10 poses of 24 000 vertices: a coarse mesh of 16 000 would be more than half of them, so all vertices
        let g = generate(&Spec { preset: Preset::Arm, vertices: 24000, poses: 10, ..Spec::default() }).unwrap();
        assert!(!Pipeline::new(&g.population, &Params::default()).unwrap().on_coarse_mesh());
        assert_eq!(coarse_target(8000, 10), 16000);
        assert_eq!(coarse_target(8000, 11), 14545);
        assert_eq!((coarse_target(8000, 20), coarse_target(8000, 200)), (8000, 8000));
        // 24 000 vertices in 20 poses: the default 8 000
        let g = generate(&Spec { preset: Preset::Arm, vertices: 24000, poses: 20, ..Spec::default() }).unwrap();
        let pipe = Pipeline::new(&g.population, &Params::default()).unwrap();
        assert!(pipe.on_coarse_mesh());
        assert_eq!(pipe.current_vertices().map(|v| v.len()), Some(8000));
    }

    #[test]
    fn a_population_is_judged_on_all_its_vertices_not_the_coarse_mesh() {
        // only 30 vertices that are no seed of the coarse mesh move: the population moves
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
        let mut pop = g.population.clone();
        let seeds = super::super::coarse_mesh::CoarseMesh::build(&pop, 1000).seeds;
        let mut shapes = vec![pop.shape(0).to_vec(); pop.n_shapes()];
        let movers: Vec<usize> = (0..pop.n_vertices()).filter(|j| !seeds.contains(j)).take(30).collect();
        for (i, s) in shapes.iter_mut().enumerate() {
            for &j in &movers {
                s[j][2] += 0.01 * i as f64;
            }
        }
        pop.set_shapes(&shapes);
        let params = Params { coarse_vertices: 1000, ..Params::default() };
        let pipe = Pipeline::new(&pop, &params).expect("the population moves");
        assert!(pipe.on_coarse_mesh());
    }

    #[test]
    fn parts_decided_on_a_coarse_mesh_are_the_parts_of_all_vertices() {
        // 3 000 vertices, decided on a coarse mesh of 1 000 (at least COARSE_FACTOR times as many; 20 poses:
        // with fewer the coarse mesh is larger)
        let g = generate(&Spec { preset: Preset::Quadruped, vertices: 3000, poses: 20, ..Spec::default() }).unwrap();
        let pop = &g.population;
        let nv = pop.n_vertices();
        let params = Params { coarse_vertices: 1000, ..Params::default() };
        let mut pipe = Pipeline::new(pop, &params).unwrap();
        assert!(pipe.on_coarse_mesh());
        assert_eq!(pipe.population().n_vertices(), nv);
        assert_eq!(pipe.current_vertices().map(|v| v.len()), Some(1000), "the first run is on the coarse mesh");
        assert_eq!(pipe.current_labels().len(), nv);
        // a fit stopped while deciding gives a model of every vertex
        pipe.step().unwrap();
        let early = pipe.result();
        assert_eq!((early.model.labels.len(), early.model.latent.len()), (nv, nv));
        // every run, on the coarse mesh and on all vertices, is an AECM run: its log-likelihood never falls
        // (but where a component is dropped)
        let mut last: Option<(f64, usize)> = None;
        while !pipe.is_done() {
            let p = pipe.step().unwrap();
            if let Some((ll, parts)) = last.filter(|&(_, parts)| parts == p.parts) {
                assert!(
                    p.log_likelihood >= ll - 1e-9 * ll.abs(),
                    "{:?}: {} after {ll} ({parts} parts)",
                    p.stage,
                    p.log_likelihood
                );
            }
            last = (!p.run_finished).then_some((p.log_likelihood, p.parts));
        }
        let result = pipe.result();
        assert!(!pipe.on_coarse_mesh());
        let names: Vec<&str> = result.stats.iter().map(|s| s.name.as_str()).collect();
        assert_eq!((names[0], *names.last().unwrap()), ("tree", "all vertices"), "{names:?}");
        // everything per vertex is per vertex of the population
        assert_eq!(result.model.n_vertices, nv);
        let tree = result.merge_tree.as_ref().expect("the merge tree is kept");
        assert_eq!(tree.leaves.len(), nv);
        assert_eq!((result.coarse_labels.len(), result.refined_labels.len()), (nv, nv));
        // the parts: the creature's, as the decisions on all vertices find them
        let all = fit(pop, &Params { coarse_vertices: 0, ..Params::default() }, &mut |_| true).unwrap();
        assert_eq!(result.model.n_parts(), all.model.n_parts());
        let truth = adjusted_rand_index(&result.model.labels, &g.part_of_vertex);
        let same = adjusted_rand_index(&result.model.labels, &all.model.labels);
        assert!(
            truth > 0.95 && same > 0.95,
            "adjusted Rand against the truth {truth}, against the fit on all vertices {same}"
        );
        // and the fit of all vertices is converged at the fit's tolerance, as good as the one decided there
        assert!(result.model.converged);
        let (rmse, rmse_all) = (result.model.rmse(pop), all.model.rmse(pop));
        assert!(rmse < 1.05 * rmse_all, "RMSE {rmse} against {rmse_all}");
    }
}
