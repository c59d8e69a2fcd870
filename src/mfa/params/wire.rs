//! The fit parameters as JSON: one flat object with camelCase keys, as the page, wasm, Python and the model file
//! have always written them (docs/formats.md). [`super::Params`] groups them by the rule that reads them; this
//! is the one place that maps the flat keys to those groups (serde's `flatten` cannot be used: it does not work
//! with `deny_unknown_fields`, and a misspelt key must stay an error).

use super::{Algorithm1Params, DistinctParams, LambdaRule, Params, PartRule, ThresholdParams, TreeParams};
use serde::{Deserialize, Serialize};

/// Where a fit starts when it is not from its rule's own start: a partition, one label per vertex. Not a
/// parameter of the method (it is data, of one population): a fit takes it beside [`Params`]
/// ([`crate::parts::hierarchy::Pipeline::starting`]). With the merge tree's part rule its parts are the start of
/// the final AECM in place of the patches' cut, and the count is exactly its number of parts (`target_parts`,
/// when unset). The page's "Refine N parts" fits the merge tree's partition it shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FitStart {
    /// None: the part rule's own start.
    pub labels: Option<Vec<u32>>,
}

/// A fit request as JSON: every field of [`Params`], flat, and the start's labels (`startLabels`). The page's
/// fit form and the wasm `Fitter` take this object (a `startLabels` in it is the start, [`FitStart`]); a
/// [`Params`] read from JSON refuses `startLabels`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, rename_all = "camelCase", deny_unknown_fields)]
pub struct FlatParams {
    parts: usize,
    seed: u64,
    tol: f64,
    max_iter: usize,
    variance_floor: f64,
    lambda_rule: LambdaRule,
    px_em: bool,
    accelerate: bool,
    restarts: usize,
    refine: bool,
    subset_vertices: usize,
    coarse_vertices: usize,
    part_rule: PartRule,
    distinct_ratio: f64,
    blend_ratio: f64,
    refine_threshold: f64,
    merge_ratio: f64,
    max_subparts: usize,
    refine_min_gain: f64,
    min_part_vertices: usize,
    refine_max_iter: usize,
    refine_tol: f64,
    target_parts: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    start_labels: Option<Vec<u32>>,
}

impl Default for FlatParams {
    fn default() -> Self {
        FlatParams::new(&Params::default(), &FitStart::default())
    }
}

impl FlatParams {
    /// The flat object of `params` and `start`.
    pub fn new(params: &Params, start: &FitStart) -> FlatParams {
        let p = params;
        let (a, d, t) = (&p.algorithm1, &p.distinct, &p.algorithm1.threshold);
        FlatParams {
            parts: a.parts,
            seed: p.seed,
            tol: p.tol,
            max_iter: p.max_iter,
            variance_floor: p.variance_floor,
            lambda_rule: p.lambda_rule,
            px_em: p.px_em,
            accelerate: p.accelerate,
            restarts: p.restarts,
            refine: p.refine,
            subset_vertices: a.subset_vertices,
            coarse_vertices: p.tree.coarse_vertices,
            part_rule: p.part_rule,
            distinct_ratio: d.distinct_ratio,
            blend_ratio: d.blend_ratio,
            refine_threshold: t.refine_threshold,
            merge_ratio: t.merge_ratio,
            max_subparts: a.max_subparts,
            refine_min_gain: a.refine_min_gain,
            min_part_vertices: p.min_part_vertices,
            refine_max_iter: a.refine_max_iter,
            refine_tol: p.refine_tol,
            target_parts: p.target_parts,
            start_labels: start.labels.clone(),
        }
    }

    /// The parameters and the start this object names.
    pub fn split(self) -> (Params, FitStart) {
        let f = self;
        let params = Params {
            seed: f.seed,
            tol: f.tol,
            max_iter: f.max_iter,
            variance_floor: f.variance_floor,
            lambda_rule: f.lambda_rule,
            px_em: f.px_em,
            accelerate: f.accelerate,
            restarts: f.restarts,
            min_part_vertices: f.min_part_vertices,
            target_parts: f.target_parts,
            part_rule: f.part_rule,
            refine: f.refine,
            refine_tol: f.refine_tol,
            tree: TreeParams { coarse_vertices: f.coarse_vertices },
            distinct: DistinctParams { distinct_ratio: f.distinct_ratio, blend_ratio: f.blend_ratio },
            algorithm1: Algorithm1Params {
                parts: f.parts,
                max_subparts: f.max_subparts,
                refine_min_gain: f.refine_min_gain,
                refine_max_iter: f.refine_max_iter,
                subset_vertices: f.subset_vertices,
                threshold: ThresholdParams { refine_threshold: f.refine_threshold, merge_ratio: f.merge_ratio },
            },
        };
        (params, FitStart { labels: f.start_labels })
    }
}

impl TryFrom<FlatParams> for Params {
    type Error = String;

    fn try_from(f: FlatParams) -> Result<Params, String> {
        match f.split() {
            (params, FitStart { labels: None }) => Ok(params),
            (_, FitStart { labels: Some(_) }) => {
                Err("startLabels is where a fit starts, not one of its parameters: give it with the fit request".into())
            }
        }
    }
}

impl From<Params> for FlatParams {
    fn from(p: Params) -> FlatParams {
        FlatParams::new(&p, &FitStart::default())
    }
}
