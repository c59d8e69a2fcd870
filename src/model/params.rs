//! Fit parameters, validated once before fitting. Each field's default is in its doc comment.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// How cycle 2 updates Λ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum LambdaRule {
    /// The exact conditional maximiser given R and Φ (METHOD_NOTES item 1). Default: a proper CM step, the
    /// log-likelihood never decreases.
    #[default]
    Exact,
    /// The paper's literal eq 18 (square roots of averaged per-shape covariance eigenvalues). Not a maximisation
    /// step: the log-likelihood can drop and AECM can cycle. Kept for teaching.
    PaperEq18,
}

/// How Algorithm 1 decides how many parts there are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PartRule {
    /// Scale-free ([`super::distinct`]): the refinement splits freely; then flesh between parts (a part moving
    /// as a fixed blend of two neighbours) is dissolved, and adjacent parts whose motions are not distinct are
    /// merged. Uses `distinct_ratio` and `blend_ratio`, both dimensionless. Default.
    #[default]
    Distinct,
    /// The paper's: stop splitting when a part's mean variance falls below `refine_threshold` (absolute, unit-box
    /// units²), and merge neighbours below `merge_ratio * refine_threshold`. Depends on the shape's size.
    Threshold,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, rename_all = "camelCase", deny_unknown_fields)]
pub struct Params {
    /// Number of coarse parts m of the first AECM (Algorithm 1's input). Default 11.
    pub parts: usize,
    /// Seed of the one random stream used for every restart. Default 0.
    pub seed: u64,
    /// Convergence tolerance on |ΔL| / n_v (nats per vertex) between AECM iterations. Default 1e-3.
    pub tol: f64,
    /// Iteration cap of each AECM run; reaching it is reported as not converged. Default 300.
    pub max_iter: usize,
    /// Lower bound of every per-shape variance s_k^i, unit-box units² (METHOD_NOTES item 6). Default 1e-7.
    pub variance_floor: f64,
    /// Λ update of cycle 2. Default [`LambdaRule::Exact`].
    pub lambda_rule: LambdaRule,
    /// End cycle 2 with the parameter-expanded step ([`super::cm::px_fold`], METHOD_NOTES item 12): same
    /// optimum, fewer iterations. Default true.
    pub px_em: bool,
    /// Accelerate every AECM run by SQUAREM ([`super::squarem`]) with a monotonicity safeguard: the same
    /// fixed points, fewer iterations; the log-likelihood still never decreases. Default true.
    pub accelerate: bool,
    /// k-means++ restarts (the best by k-means cost is kept). Default 4.
    pub restarts: usize,
    /// Run Algorithm 1's refinement and final stage; false stops after the coarse AECM. Default true.
    pub refine: bool,
    /// Multi-resolution ([`super::multires`]): with at least 3 times this many vertices
    /// ([`super::hierarchy::SUBSET_FACTOR`]), the coarse and refinement stages run on about this many
    /// well-spread vertices and only the final AECM on all of them; 0 runs every stage on all vertices (the full
    /// hierarchy). Only with `refine`. Default 2000.
    pub subset_vertices: usize,
    /// How the part count is decided. Default [`PartRule::Distinct`].
    pub part_rule: PartRule,
    /// [`PartRule::Distinct`]: two adjacent parts stay apart only if moving both by one rigid motion raises the
    /// squared error of the smaller one, per vertex, to at least this many times a typical part's variance; and
    /// a refinement split is kept only if it lowers the variance this many times. Default 4.
    pub distinct_ratio: f64,
    /// [`PartRule::Distinct`]: a part whose motion is a fixed in-between of two neighbours' motions to within
    /// this fraction of their relative rotation is flesh, not a part ([`super::distinct::blend_ratio`]).
    /// Default 0.1.
    pub blend_ratio: f64,
    /// [`PartRule::Threshold`], Algorithm 1 step 5: stop splitting a part when its mean variance err falls below
    /// this. Default 1e-5.
    pub refine_threshold: f64,
    /// [`PartRule::Threshold`]: after the refinement, adjacent parts that one rigid component explains with a
    /// mean variance below `merge_ratio * refine_threshold` are merged (0 turns the merge off). Default 0.25.
    pub merge_ratio: f64,
    /// Most sub-parts tried per coarse part in the refinement. Default 6.
    pub max_subparts: usize,
    /// A sub-part must lower err by at least this fraction to be kept (makes "stops decreasing" robust).
    /// Default 0.1.
    pub refine_min_gain: f64,
    /// Components whose responsibility mass falls below this many vertices are dropped. Default 4.
    pub min_part_vertices: usize,
    /// Iteration cap of each small AECM run inside the refinement. Default 60.
    pub refine_max_iter: usize,
    /// Convergence tolerance of the coarse AECM and of the small AECM runs of the refinement (they only
    /// decide the labels that start the next stage; the final stage uses `tol`). Default 1e-2.
    pub refine_tol: f64,
    /// Exact part count: after Algorithm 1, parts are split or merged until there are exactly this many, then
    /// the final AECM runs again ([`super::part_count`]). None (default) keeps Algorithm 1's own count.
    pub target_parts: Option<usize>,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            parts: 11,
            seed: 0,
            tol: 1e-3,
            max_iter: 300,
            variance_floor: 1e-7,
            lambda_rule: LambdaRule::Exact,
            px_em: true,
            accelerate: true,
            restarts: 4,
            refine: true,
            subset_vertices: 2000,
            part_rule: PartRule::Distinct,
            distinct_ratio: 4.0,
            blend_ratio: 0.1,
            refine_threshold: 1e-5,
            merge_ratio: 0.25,
            max_subparts: 6,
            refine_min_gain: 0.1,
            min_part_vertices: 4,
            refine_max_iter: 60,
            refine_tol: 1e-2,
            target_parts: None,
        }
    }
}

impl Params {
    /// Checks every field; the message names the field, the value, and the valid range.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Params(m));
        if self.parts == 0 || self.parts > 512 {
            return bad(format!("parts = {} must be between 1 and 512", self.parts));
        }
        if !(self.tol > 0.0 && self.tol.is_finite()) {
            return bad(format!("tol = {} must be a positive number (try 1e-3)", self.tol));
        }
        if self.max_iter == 0 || self.max_iter > 100_000 {
            return bad(format!("max_iter = {} must be between 1 and 100000", self.max_iter));
        }
        if !(self.variance_floor > 0.0 && self.variance_floor < 1.0) {
            return bad(format!("variance_floor = {} must be in (0, 1) unit-box units² (try 1e-7)", self.variance_floor));
        }
        if self.restarts == 0 || self.restarts > 100 {
            return bad(format!("restarts = {} must be between 1 and 100", self.restarts));
        }
        if !(self.refine_threshold >= 0.0 && self.refine_threshold.is_finite()) {
            return bad(format!("refine_threshold = {} must be >= 0", self.refine_threshold));
        }
        if !(self.distinct_ratio > 0.0 && self.distinct_ratio.is_finite()) {
            return bad(format!("distinct_ratio = {} must be a positive number (try 4)", self.distinct_ratio));
        }
        if !(0.0..1.0).contains(&self.blend_ratio) {
            return bad(format!("blend_ratio = {} must be in [0, 1) (try 0.1; 0 keeps every part)", self.blend_ratio));
        }
        if !(0.0..=1.0).contains(&self.merge_ratio) {
            return bad(format!("merge_ratio = {} must be in [0, 1]", self.merge_ratio));
        }
        if self.max_subparts == 0 || self.max_subparts > 64 {
            return bad(format!("max_subparts = {} must be between 1 and 64", self.max_subparts));
        }
        if !(0.0..1.0).contains(&self.refine_min_gain) {
            return bad(format!("refine_min_gain = {} must be in [0, 1)", self.refine_min_gain));
        }
        if self.min_part_vertices == 0 {
            return bad("min_part_vertices must be at least 1".into());
        }
        if !(self.refine_tol > 0.0 && self.refine_tol.is_finite()) {
            return bad(format!("refine_tol = {} must be a positive number (try 1e-2)", self.refine_tol));
        }
        if self.subset_vertices > 0 && self.subset_vertices < 64 {
            return bad(format!(
                "subset_vertices = {} must be 0 (every stage on all vertices) or at least 64 (try 2000)",
                self.subset_vertices
            ));
        }
        if self.target_parts == Some(0) {
            return bad("target_parts = 0 must be at least 1 (or none: Algorithm 1's own count)".into());
        }
        if self.refine_max_iter == 0 {
            return bad("refine_max_iter must be at least 1".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_each_bad_value_is_named() {
        Params::default().validate().unwrap();
        let cases: Vec<(Params, &str)> = vec![
            (Params { parts: 0, ..Default::default() }, "parts"),
            (Params { tol: -1.0, ..Default::default() }, "tol"),
            (Params { tol: f64::NAN, ..Default::default() }, "tol"),
            (Params { variance_floor: 0.0, ..Default::default() }, "variance_floor"),
            (Params { restarts: 0, ..Default::default() }, "restarts"),
            (Params { max_iter: 0, ..Default::default() }, "max_iter"),
            (Params { target_parts: Some(0), ..Default::default() }, "target_parts"),
        ];
        for (p, field) in cases {
            match p.validate() {
                Err(Error::Params(m)) => assert!(m.starts_with(field), "{m}"),
                other => panic!("{field}: {other:?}"),
            }
        }
    }
}
