//! What a fit reports: which run the pipeline is in ([`Stage`]: the [`Rule`] and its [`FinalRun`]),
//! [`Progress`], the stages' part counts, the part rule's rounds, and everything the fit produced ([`FitResult`]).

use crate::mfa::aecm::StageStats;
use crate::mfa::result::Model;
use serde::Serialize;

/// The rule that decides the parts of a fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "camelCase")]
pub enum Rule {
    /// The merge tree (the default, [`PartRule::Tree`](crate::mfa::params::PartRule::Tree) with `refine` on):
    /// the start is the patches' merge tree cut, the count read off the tree of the fitted parts.
    MergeTree,
    /// The paper's Algorithm 1 (the other part rules, `refine` off, and a step-by-step lesson): a coarse AECM
    /// from k-means++, each coarse part refined, then the final AECM.
    Algorithm1,
}

/// Which of the final stage's AECM runs: why it runs and what it starts from. Each also names its
/// [`StageStats`] entry ([`FinalRun::stats_name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "camelCase")]
pub enum FinalRun {
    /// The first run on every part, from the rule's start (the merge tree's cut, at the refinement's loose
    /// tolerance; Algorithm 1's refined labels).
    First,
    /// The parts the part rule left as they were after the first run, fitted on at the fit's own tolerance.
    Settle,
    /// A refit of the parts left after a round of the part rule removed some.
    Round,
    /// A refit with the part count asked for (`target_parts`).
    Count,
    /// The parts decided on a coarse mesh, fitted on all vertices (the fit's last run).
    AllVertices,
}

impl FinalRun {
    /// The name of the run's [`StageStats`] entry (the JSON's `stage_stats[].name`): "final" for the first run
    /// and its settling, "distinct" after a round of the part rule, "parts" with the count asked for, "all
    /// vertices" for the last run after a coarse mesh.
    pub fn stats_name(self) -> &'static str {
        match self {
            FinalRun::First | FinalRun::Settle => "final",
            FinalRun::Round => "distinct",
            FinalRun::Count => "parts",
            FinalRun::AllVertices => "all vertices",
        }
    }
}

/// Which run of the fit an AECM iteration belongs to (serialised with `kind`, as the progress's `stage`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "camelCase", rename_all_fields = "camelCase")]
pub enum Stage {
    /// Algorithm 1's coarse AECM from k-means++.
    Coarse,
    /// Algorithm 1's refinement: coarse part `part` (0-based) of `of`, trying `sub_parts` components.
    Refine {
        part: usize,
        of: usize,
        sub_parts: usize,
    },
    /// A run of the final stage: which `rule` asked for it, which `run`, its `number` among the fit's runs of
    /// that kind (1 for the first; a [`FinalRun::Round`]'s is the part rule's round), and the coarse mesh's
    /// vertex count while the parts are decided on one (None on all vertices).
    Final {
        rule: Rule,
        run: FinalRun,
        number: usize,
        coarse_vertices: Option<usize>,
    },
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

/// Everything a fit produced: the model, the labels and counts of its stages, each run's statistics, and
/// what its rule decided.
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
    pub part_curve: Vec<crate::parts::distinct::CurvePoint>,
    /// Every round of the part rule, in order (`part_curve` is the last one's merges; empty without the rule).
    pub part_rounds: Vec<PartRound>,
    /// With `target_parts` and [`PartRule::Distinct`]: the labels the part rule decided, before the count was made
    /// exact (what auto would have kept), for the diagnosis ([`crate::parts::diagnosis::diagnose_fit`]).
    pub decided_labels: Option<Vec<u32>>,
    /// The part count is the user's own, with no rule behind it (`refine` off: Algorithm 1's coarse stage alone,
    /// m = `parts`; or a partition given to start from, [`crate::mfa::FitStart`]), so too few parts cannot be
    /// told from a shape that is no articulated one ([`crate::parts::diagnosis::diagnose_fit`]).
    pub count_unjudged: bool,
    /// The exact part count asked for (`target_parts`), if one was.
    pub parts_asked: Option<usize>,
    /// The partition the fit started from ([`crate::mfa::FitStart`]), if one was given.
    pub start_labels: Option<Vec<u32>>,
    /// What the rule that decided the parts reports of itself (the fields above both rules fill).
    pub rule: RuleReport,
}

/// What each rule reports of itself in a [`FitResult`].
#[derive(Debug, Clone, PartialEq)]
pub enum RuleReport {
    /// The merge tree's rule ([`Rule::MergeTree`]).
    MergeTree {
        /// The start's parts once its flesh was dissolved, before the first AECM (None when none was; the cut's
        /// own count is `stages.coarse_parts`).
        start_parts: Option<usize>,
        /// The merge tree of the fitted parts the rule read its count from (its leaves are the parts of the
        /// first final AECM, its merges go down to one part): a partition for every count. None when the fit
        /// was stopped before that run finished.
        merge_tree: Option<crate::parts::merge_tree::MergeTree>,
        /// The count the rule read off `merge_tree`.
        tree_count: Option<usize>,
    },
    /// Algorithm 1 ([`Rule::Algorithm1`]).
    Algorithm1 {
        /// The refinement ran (`refine` on): the refined stage is its own, not the coarse one again.
        refined: bool,
    },
}

impl FitResult {
    /// The partitions of the merge tree (the merge tree's rule; none with Algorithm 1).
    pub fn tree_cuts(&self) -> Option<crate::parts::merge_tree::TreeCuts> {
        let tree = self.merge_tree()?.clone();
        Some(crate::parts::merge_tree::TreeCuts::new(tree, self.tree_count(), &self.model.labels))
    }

    /// The parts came from the merge tree ([`Rule::MergeTree`]), not from Algorithm 1 (the other part rules,
    /// `refine` off, and a step-by-step lesson): what the page names the stages after.
    pub fn from_merge_tree(&self) -> bool {
        matches!(self.rule, RuleReport::MergeTree { .. })
    }

    /// The refinement ran: always with the merge tree, with Algorithm 1 when `refine` was on.
    pub fn refined(&self) -> bool {
        match self.rule {
            RuleReport::MergeTree { .. } => true,
            RuleReport::Algorithm1 { refined } => refined,
        }
    }

    /// The merge tree's start once its flesh was dissolved ([`RuleReport::MergeTree`]'s `start_parts`).
    pub fn start_parts(&self) -> Option<usize> {
        match self.rule {
            RuleReport::MergeTree { start_parts, .. } => start_parts,
            RuleReport::Algorithm1 { .. } => None,
        }
    }

    /// The merge tree of the fitted parts ([`RuleReport::MergeTree`]'s `merge_tree`).
    pub fn merge_tree(&self) -> Option<&crate::parts::merge_tree::MergeTree> {
        match &self.rule {
            RuleReport::MergeTree { merge_tree, .. } => merge_tree.as_ref(),
            RuleReport::Algorithm1 { .. } => None,
        }
    }

    /// [`FitResult::merge_tree`], to change (a page hands its leaves over without a copy).
    pub fn merge_tree_mut(&mut self) -> Option<&mut crate::parts::merge_tree::MergeTree> {
        match &mut self.rule {
            RuleReport::MergeTree { merge_tree, .. } => merge_tree.as_mut(),
            RuleReport::Algorithm1 { .. } => None,
        }
    }

    /// The count the merge tree's rule read off its tree ([`RuleReport::MergeTree`]'s `tree_count`).
    pub fn tree_count(&self) -> Option<usize> {
        match self.rule {
            RuleReport::MergeTree { tree_count, .. } => tree_count,
            RuleReport::Algorithm1 { .. } => None,
        }
    }
}
