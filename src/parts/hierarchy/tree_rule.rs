//! The merge tree's part rule ([`PartRule::Tree`], the default): the start is the patches' merge tree cut
//! generously ([`tree_start`]: no random draw), its flesh dissolved before the first AECM; after each final AECM
//! the rule reads the count off a merge tree of the fitted parts ([`Pipeline::decide_on_tree`]). The driver
//! ([`super::Pipeline`]) runs the AECM and the rounds; this says where the runs start, which run comes next
//! ([`Pipeline::tree_next`]) and which count the tree gives.
//!
//! What decides the count, in one list (each value is documented where it is defined, with why it is that):
//!
//! | what | value | where |
//! |---|---|---|
//! | a joint must explain this many typical variances (rule 2, the tree's cut) | 4 | `DistinctParams::distinct_ratio` |
//! | a part moving as a fixed blend of two neighbours within this fraction is flesh (rule 1) | 0.1 | `DistinctParams::blend_ratio` |
//! | a part needs this many vertices | 4 | `Params::min_part_vertices` |
//! | the start: the patches' tree cut at this many merge yardsticks | 28 | [`TREE_START_RATIO`] |
//! | the start with an exact count asked for: cut at this many typical variances | 64 | [`TREE_COUNT_START_RATIO`] |
//! | fewer patches than this: the start is every patch, uncut | 64 | [`TREE_CUT_LEAVES`] |
//! | the patches' least typical variance | 1e-14 | `PATCH_VARIANCE_FLOOR` |
//! | patches: at most / vertices per patch below that | 400 / 6 | [`crate::parts::patches::MAX_PATCHES`], [`crate::parts::patches::PATCH_VERTICES`] |
//! | poses the tree's rigid fits read | 16 | [`crate::parts::merge_tree::TREE_POSES`] |
//! | the start's yardstick averages merges above this many nodes | 100 | [`crate::parts::merge_tree::PART_NODES`] |
//! | the fitted parts' yardstick: the middle of the variances between these quantiles | 0.3 / 0.7 | [`crate::parts::merge_tree::MIDDLE_BAND`] |
//! | reference poses of the flesh test | 24 | [`crate::parts::distinct::BLEND_REFERENCES`] |
//! | an island this fraction of its part's largest piece becomes a part | 0.25 | [`crate::parts::islands::SPLIT_FRACTION`] |
//! | rounds of the part rule / of the exact count | 3 / 3 | `rounds::DECIDE_ROUNDS`, `rounds::COUNT_ROUNDS` |
//! | decided on a coarse mesh: from this many times its size / with fewer poses it grows | 2 / 20 | [`COARSE_FACTOR`], [`COARSE_POSES`] |
//! | the coarse mesh's vertices | 8 000 | `TreeParams::coarse_vertices` |

use super::rounds::Tail;
use super::{lay_out, FinalRun, Fine, Pipeline, State};
use crate::error::{Error, Result};
use crate::mesh::Population;
use crate::mfa::aecm::{Fit, StageStats};
use crate::mfa::data::Data;
use crate::mfa::params::{Params, PartRule, RunParams};
use crate::mfa::result::Model;
use crate::parts::labels::compact;

/// [`PartRule::Tree`] decides on a coarse mesh ([`crate::parts::coarse_mesh`]) only on populations with at least
/// this many times its size ([`coarse_target`]; 16 000 vertices at the default 8 000 and 20 poses or more):
/// below that the decisions on all vertices cost little more (which populations decide on every vertex:
/// docs/decisions.md, "Figures behind src/parts").
pub const COARSE_FACTOR: usize = 2;

/// With fewer poses than this, the coarse mesh has more vertices ([`coarse_target`]).
pub const COARSE_POSES: usize = 20;

/// The coarse mesh's size for `coarse_vertices` ([`crate::mfa::TreeParams::coarse_vertices`]) and `n_shapes` poses: at
/// least `coarse_vertices x COARSE_POSES` vertex-poses, i.e. `coarse_vertices` from 20 poses on and more below (16 000
/// at 10 poses by default). The decisions read the poses' motion at the coarse vertices, and a population of few poses
/// gives them less to read per vertex; the runs' cost goes with the vertex-poses, so it stays bounded. A fixed 8 000
/// vertices on 10-11 poses made the decisions move more than on all vertices over the standard runs of `posemfa
/// robustness` (the counts: docs/decisions.md, "Figures behind src/parts").
pub fn coarse_target(coarse_vertices: usize, n_shapes: usize) -> usize {
    if n_shapes >= COARSE_POSES {
        coarse_vertices
    } else {
        coarse_vertices * COARSE_POSES / n_shapes.max(1)
    }
}

/// [`PartRule::Tree`]'s start when the part rule chooses the count: the patches' tree is cut where a merge first
/// costs the smaller side, per vertex, this many times what merging two pieces of one part typically costs
/// ([`MergeTree::merge_yardstick`]). A generous over-segmentation: the part rule decides after the first AECM.
/// The merges' yardstick, not the patches' typical variance (the median of a few hundred tiny fits,
/// [`TREE_COUNT_START_RATIO`]): with a pose dropped it moves the start far less (the counts, and the other
/// ratios tried: docs/decisions.md, "Figures behind src/parts").
pub const TREE_START_RATIO: f64 = 28.0;

/// [`PartRule::Tree`]'s start with an exact part count (`target_parts`): the cut where a merge first costs 64
/// times the patches' typical variance ([`MergeTree::typical`]), and no flesh dissolved before the first AECM.
/// The count's steadiness does not matter there, and this start rigs better than the part rule's at the bone
/// counts asked for (the rigs' errors: docs/decisions.md, "Figures behind src/parts").
pub const TREE_COUNT_START_RATIO: f64 = 64.0;

/// A patch tree with fewer leaves than this (a mesh of under about 384 vertices) starts from every patch, uncut. There
/// a patch of about 6 vertices spans much of a part, so most patches straddle a joint and their typical variance is not
/// a rigid patch's, and a cut at [`TREE_START_RATIO`] can keep so few patches that the fit loses most of the parts;
/// from every patch it finds them (the character it was measured on: docs/decisions.md, "Figures behind src/parts").
/// The AECM from at most 63 parts on so few vertices is cheap.
pub const TREE_CUT_LEAVES: usize = 64;

/// The least typical variance of the patches (unit-box units²; the data are in the unit box), against 0 on
/// exactly rigid data.
const PATCH_VARIANCE_FLOOR: f64 = 1e-14;

impl Pipeline {
    /// [`PartRule::Tree`]: the patches' merge tree gives the start ([`super::merge_tree`]: no random draw), cut
    /// where a merge first costs the smaller side [`TREE_START_RATIO`] times the tree's typical merge within a
    /// part; the start's flesh goes ([`dissolve_start_flesh`]) and the final AECM runs from what is left. With
    /// an exact part count, the cut at [`TREE_COUNT_START_RATIO`] instead, flesh and all.
    pub(super) fn from_tree(pop: &Population, params: &RunParams, start: Option<&[u32]>, t0: f64) -> Result<Pipeline> {
        // (an exact count the coarse mesh cannot hold is made on all vertices)
        let target = coarse_target(params.tree.coarse_vertices, pop.n_shapes());
        let on_coarse = params.tree.coarse_vertices > 0
            && pop.n_vertices() >= COARSE_FACTOR * target
            && params
                .target_parts
                .is_none_or(|n| crate::parts::part_count::check_target(n, target, params.min_part_vertices).is_ok());
        // (the last run's data first: see [`Fine::full`]); the data are judged on every vertex (a motion of a few
        // vertices no seed holds is still motion)
        let full = on_coarse.then(|| lay_out(Data::from_population(pop)));
        if let Some((data, _)) = &full {
            crate::mfa::aecm::check_population(data, 1, 1)?;
        }
        let coarse = on_coarse.then(|| crate::parts::coarse_mesh::CoarseMesh::build(pop, target));
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
        let (cut, labels) = match start {
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
            start_labels: start.map(<[u32]>::to_vec),
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
            final_runs: Vec::new(),
            fine: coarse.zip(full).map(|(mesh, full)| Box::new(Fine { pop: pop.clone(), mesh, full })),
            last_run: None,
        };
        p.close_stage(None);
        p.begin_final(FinalRun::First);
        // the first run only feeds the part rule's decisions: at the refinement's loose tolerance (from a
        // generous over-segmentation a converged run takes several times the iterations: docs/decisions.md)
        let loose = params.at_loose_tolerance();
        let (data, layout) = lay_out(data);
        p.state = State::Final(Fit::from_labels_laid_out(data, layout, &labels, &loose)?);
        Ok(p)
    }

    /// The merge tree's rule after a final-stage run ([`Pipeline::next_run`]): the vertices labelled by motion
    /// and the parts made connected; then, while a round is due, a round of the part rule (flesh dissolved,
    /// the count read off the tree of the fitted parts, [`Pipeline::decide_on_tree`]). A round that removed
    /// parts refits them (warm on a coarse mesh, [`Pipeline::refit_warm`]), or makes the count asked for; one
    /// that removed none lets the loose first run go on at the fit's tolerance ([`Pipeline::go_on`]) or, on a
    /// coarse mesh, fits the parts on all vertices ([`Pipeline::finish_on_all_vertices`]). A partition given to
    /// start from is the user's: the rule does not change it, but its tree of the fitted parts is made as on
    /// any fit (the page's slider, the JSON).
    pub(super) fn tree_next(&mut self, mut model: Model) -> Result<State> {
        self.tidy(&mut model, true);
        // whether the parts were fitted to the motion labels in this call (a model the rule leaves as it is
        // stays fitted)
        let mut fitted = false;
        if self.count_rounds == 0 && self.decide_rounds == 0 && self.start_labels.is_some() {
            self.decide_rounds += 1;
            self.fit_to_labels(&mut model);
            fitted = true;
            let (_, curve) = self.decide_on_tree(&model.labels);
            self.part_curve = curve;
        } else if self.round_due() {
            let (dissolved, before) = self.dissolve_round(&mut model);
            fitted = true;
            let (merged, curve) = self.decide_on_tree(&model.labels);
            let after = self.record_round(&merged, curve, before, dissolved);
            if dissolved > 0 || after < before {
                self.refined_labels = merged.clone();
                // more parts than decided: the tree's finer partition; fewer: merged from the decided parts
                // (the tree's own 10-part cut of horse-gallop rigged worse than the merges, docs/part-count.md)
                if let Some(next) = self.count_after_round(&merged, after, |p, n| p.tree_partition(n))? {
                    return Ok(next);
                }
                if self.fine.is_some() {
                    return self.refit_warm(FinalRun::Round, &merged);
                }
                return self.refit(FinalRun::Round, &merged);
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
        match self.exact_count(model, !fitted)? {
            Tail::Run(next) => Ok(next),
            Tail::Final(model) if self.fine.is_some() => self.finish_on_all_vertices(model),
            Tail::Final(model) => Ok(self.done(model)),
        }
    }

    /// [`PartRule::Tree`]'s rule 2: the merge tree of the fitted parts
    /// ([`crate::parts::merge_tree::MergeTree::from_leaves`], every merge down to one part), cut where a merge first
    /// scores `distinct_ratio`. The opening round's tree is the one kept in the result (its leaves are the parts of the
    /// first final AECM). Returns the labels at the count read off the tree and the curve of decisions (as
    /// [`crate::parts::distinct::merge_indistinct`]'s).
    pub(super) fn decide_on_tree(&mut self, labels: &[u32]) -> (Vec<u32>, Vec<crate::parts::distinct::CurvePoint>) {
        let leaves = compact(labels);
        let mut tree = crate::parts::merge_tree::MergeTree::from_leaves(&self.pop, leaves, self.params.floor());
        // the opening round's typical variance stays the yardstick: a refit's larger parts have larger variances,
        // and with its own yardstick every round would merge a few more (lion-poses: 43 -> 40 -> 36 -> 34)
        let yardstick = self.merge_tree.as_ref().map_or_else(|| tree.middle_typical(), |first| first.typical);
        tree.rescore(yardstick);
        let count = tree.decided_count(self.params.distinct.distinct_ratio);
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
    pub(super) fn tree_partition(&self, n: usize) -> Option<Vec<u32>> {
        let t = self.merge_tree.as_ref()?;
        let (most, fewest) = t.counts();
        (fewest..=most).contains(&n).then(|| t.labels_at(n))
    }
}

/// The number of parts of a start's labels ([`crate::mfa::FitStart`]), once they are found to be a start for `pop`: one
/// label per vertex, with the merge tree's part rule.
pub(super) fn check_start_labels(start: &[u32], pop: &Population, params: &Params) -> Result<usize> {
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
pub(super) fn tree_start(pop: &Population, data: &Data, params: &RunParams) -> Result<(Vec<u32>, Vec<u32>)> {
    // the patches' own yardstick, not the variance floor: on clean data the patches fit far below the floor,
    // and the floor as the yardstick merged the generated hand's fingertips before the AECM
    let t0 = crate::clock::now_ms();
    let mut tree = crate::parts::merge_tree::MergeTree::build(pop, PATCH_VARIANCE_FLOOR);
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

/// [`PartRule::Tree`]: the part rule's first rule ([`crate::parts::distinct::dissolve_flesh`]) on the start, before any
/// AECM: each start part's component in closed form ([`crate::mfa::init::components_from_labels`]), and a part
/// whose motion is a blend of two neighbours' goes to them. A start cut from the patches has slices of the
/// skinning bands between bones; left in, the first AECM makes each a band part of its own, how many depending on
/// small changes of the data (a frame dropped), and the decided count with them (docs/decisions.md). Dissolved on
/// the start, the AECM starts with fewer components and the rounds after it find next to no flesh. Compact
/// labels.
pub(super) fn dissolve_start_flesh(pop: &Population, data: &Data, labels: &[u32], params: &RunParams) -> Vec<u32> {
    let t0 = crate::clock::now_ms();
    let comps = crate::mfa::init::components_from_labels(data, labels, params.floor());
    let mut model = crate::mfa::aecm::model_of(data, &comps, compact(labels));
    let dissolved = crate::parts::distinct::dissolve_flesh(&mut model, pop, params.distinct.blend_ratio);
    if dissolved > 0 {
        crate::parts::islands::connect_parts(&mut model, pop, false, params.min_part_vertices);
    }
    if crate::trace::enabled() {
        crate::trace_line!(
            "start: {dissolved} parts dissolved as flesh before the first AECM ({:.1} ms)",
            crate::clock::now_ms() - t0
        );
    }
    compact(&model.labels)
}
