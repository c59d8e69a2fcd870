//! Fit parameters, validated once before fitting. Each field's default is in its doc comment; the fields
//! only one part rule reads are in that rule's own type (`rules`), the JSON's flat form is `wire`, and the
//! state a fit adds to them (the variance floor's scale) is `run`.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

mod rules;
mod run;
mod wire;

pub use rules::{Algorithm1Params, DistinctParams, ThresholdParams, TreeParams};
pub use run::{InFit, RunParams};
pub use wire::{FitStart, FlatParams};

/// How cycle 2 updates Λ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum LambdaRule {
    /// The exact conditional maximiser given R and Φ (docs/method.md#item-1). Default: a proper CM step, the
    /// log-likelihood never decreases.
    #[default]
    Exact,
    /// The paper's literal eq 18 (square roots of averaged per-shape covariance eigenvalues). Not a maximisation
    /// step: the log-likelihood can drop and AECM can cycle. Kept for teaching.
    PaperEq18,
}

/// How the parts are found and how many there are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PartRule {
    /// A function of the population, not of a random start ([`crate::parts::merge_tree`]): small patches merged
    /// greedily by the part rule's score into one merge tree; AECM from its partition; then the scale-free rule
    /// (flesh dissolved, parts without a distinct motion merged, read off a tree of the fitted parts). Default.
    #[default]
    Tree,
    /// Algorithm 1 (coarse k-means++ start, refinement) with the scale-free rule ([`crate::parts::distinct`]): the
    /// refinement splits freely; then flesh between parts (a part moving as a fixed blend of two neighbours) is
    /// dissolved, and adjacent parts whose motions are not distinct are merged. Uses `distinct_ratio` and
    /// `blend_ratio`, both dimensionless. Depends on the seed.
    Distinct,
    /// The paper's: stop splitting when a part's mean variance falls below `refine_threshold` (absolute, unit-box
    /// units²), and merge neighbours below `merge_ratio * refine_threshold`. Depends on the shape's size.
    Threshold,
}

/// The fit parameters, validated once before fitting ([`Params::validate`]). Those every rule reads are fields
/// here; those only one rule reads are in that rule's own type ([`TreeParams`], [`DistinctParams`],
/// [`Algorithm1Params`] with its [`ThresholdParams`]). Each default is in the doc comment of its field. The JSON
/// is flat ([`FlatParams`]): `{"parts": 11, "coarseVertices": 8000, ...}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "FlatParams", into = "FlatParams")]
pub struct Params {
    /// Seed of the one random stream used for every restart. Default 0.
    pub seed: u64,
    /// Convergence tolerance on |ΔL| / n_v (nats per vertex) between AECM iterations. Default 1e-3.
    pub tol: f64,
    /// Iteration cap of each AECM run; reaching it is reported as not converged. Default 300.
    pub max_iter: usize,
    /// Lower bound of every per-shape variance s_k^i (docs/method.md#item-6), in unit-box units² for a population
    /// whose mean squared radius in the unit box is [`REFERENCE_SQUARED_RADIUS`] (an animal's, about); the fit
    /// scales it by the population's own ([`RunParams::floor`]), so that it follows the shape, not its bounding
    /// box: a turn of every pose changes the box, not the shape. Default 1e-7.
    pub variance_floor: f64,
    /// Λ update of cycle 2. Default [`LambdaRule::Exact`].
    pub lambda_rule: LambdaRule,
    /// End cycle 2 with the parameter-expanded step ([`super::cm::px_fold`], docs/method.md#item-12): same
    /// optimum, fewer iterations. Default true.
    pub px_em: bool,
    /// Accelerate every AECM run by SQUAREM ([`super::squarem`]) with a monotonicity safeguard: the same
    /// fixed points, fewer iterations; the log-likelihood still never decreases. Default true.
    pub accelerate: bool,
    /// k-means++ restarts (the best by k-means cost is kept). Default 4.
    pub restarts: usize,
    /// Components whose responsibility mass falls below this many vertices are dropped, and no part may have
    /// fewer vertices. Default 4.
    pub min_part_vertices: usize,
    /// Exact part count: after the part rule, parts are split or merged until there are exactly this many, then
    /// the final AECM runs again ([`crate::parts::part_count`]). None (default) keeps the part rule's own count.
    pub target_parts: Option<usize>,
    /// How the parts are found and counted. Default [`PartRule::Tree`].
    pub part_rule: PartRule,
    /// Decide the parts. False is a choice of its own, for every part rule: Algorithm 1's coarse AECM alone
    /// (`algorithm1.parts` parts from k-means++), no refinement and no part rule; the merge tree has no stage
    /// without its rule, so `part_rule` is then not read ([`crate::parts::hierarchy::rule_of`]; the result says
    /// which rule ran). The CLI's `--no-refine`, the page's "refine" box. Default true.
    pub refine: bool,
    /// Convergence tolerance of the runs that only decide labels another run starts from: Algorithm 1's coarse
    /// AECM and the small runs of its refinement, and the merge tree's first run and its runs on a coarse mesh
    /// (when looser than `tol`). The last run uses `tol`. Default 1e-2.
    pub refine_tol: f64,
    /// The merge tree's ([`PartRule::Tree`]).
    pub tree: TreeParams,
    /// The scale-free rule's ratios ([`PartRule::Tree`] and [`PartRule::Distinct`]).
    pub distinct: DistinctParams,
    /// Algorithm 1's ([`PartRule::Distinct`], [`PartRule::Threshold`], `refine` off), with the threshold rule's.
    pub algorithm1: Algorithm1Params,
}

/// The mean squared radius (unit-box units²) at which `variance_floor` is the floor itself: about the horses'
/// (0.091, 0.093), the generated creatures' 0.084-0.148, the lion's 0.057.
pub const REFERENCE_SQUARED_RADIUS: f64 = 0.09;

impl Default for Params {
    fn default() -> Self {
        Params {
            seed: 0,
            tol: 1e-3,
            max_iter: 300,
            variance_floor: 1e-7,
            lambda_rule: LambdaRule::Exact,
            px_em: true,
            accelerate: true,
            restarts: 4,
            min_part_vertices: 4,
            target_parts: None,
            part_rule: PartRule::Tree,
            refine: true,
            refine_tol: 1e-2,
            tree: TreeParams::default(),
            distinct: DistinctParams::default(),
            algorithm1: Algorithm1Params::default(),
        }
    }
}

impl Params {
    /// These parameters for a population of mean squared radius `mean_squared_radius` (unit box): a fit's
    /// parameters, with the variance floor scaled for it ([`RunParams`]).
    pub fn for_radius(&self, mean_squared_radius: f64) -> RunParams {
        RunParams::new(self, mean_squared_radius)
    }
}

/// What each field of the page's fit form (and the same CLI flags) allows, in words: the one text the page, the
/// CLI and [`Params::validate`] give.
pub const ALLOWED_PARTS: &str = "a whole number from 1 to 512 (try 11)";
pub const ALLOWED_SEED: &str = "a whole number from 0 to 2^64 - 1 (try 0)";
pub const ALLOWED_TOL: &str = "a positive number (try 1e-3)";
pub const ALLOWED_VARIANCE_FLOOR: &str = "a number in (0, 1) unit-box units² (try 1e-7)";
pub const ALLOWED_TARGET_PARTS: &str = "a positive whole number, or auto (the part rule's own count)";

/// A number as a message shows it: as Rust writes it between 1e-4 and 1e6, in exponent form outside (1e30, not
/// thirty-one digits).
fn shown(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A field of the fit form that cannot be used: its name (camelCase, as in [`Params`]'s JSON and the page's
/// form) and why, with what is allowed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FieldProblem {
    pub field: &'static str,
    pub message: String,
}

impl Params {
    /// Sets one field from text as typed in the page's form or on the command line: `parts`, `seed`, `tol`,
    /// `varianceFloor` or `targetParts` (empty or "auto": none). The value is checked against what the field
    /// allows; the error says what was typed and what is allowed.
    pub fn set_field(&mut self, field: &str, text: &str) -> std::result::Result<(), String> {
        let t = text.trim();
        let whole = |allowed: &str| -> std::result::Result<u64, String> {
            if t.is_empty() {
                return Err(format!("is empty: it must be {allowed}"));
            }
            if t.strip_prefix('-').is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit())) {
                return Err(format!("'{t}' is negative: it must be {allowed}"));
            }
            if let Ok(n) = t.parse::<u64>() {
                return Ok(n);
            }
            // a whole number written another way (1e9, 12.0): its value, which the range check then judges
            match t.parse::<f64>() {
                Ok(x) if x.is_finite() && x >= 0.0 && x.fract() == 0.0 && x < u64::MAX as f64 => Ok(x as u64),
                Ok(x) if x.is_finite() && x.fract() == 0.0 => Err(format!("'{t}' is too large: it must be {allowed}")),
                _ => Err(format!("'{t}' is not a whole number: it must be {allowed}")),
            }
        };
        let number = |allowed: &str| -> std::result::Result<f64, String> {
            if t.is_empty() {
                return Err(format!("is empty: it must be {allowed}"));
            }
            match t.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                // (Rust reads 1e400 as infinity)
                Ok(x) if x.is_infinite() && !t.to_ascii_lowercase().contains("inf") => Err(format!(
                    "'{t}' is too {}: it must be {allowed}",
                    if x > 0.0 { "large" } else { "far below zero" }
                )),
                _ => Err(format!("'{t}' is not a number: it must be {allowed}")),
            }
        };
        match field {
            "parts" => self.algorithm1.parts = whole(ALLOWED_PARTS)?.min(usize::MAX as u64) as usize,
            "seed" => self.seed = whole(ALLOWED_SEED)?,
            "tol" => self.tol = number(ALLOWED_TOL)?,
            "varianceFloor" => self.variance_floor = number(ALLOWED_VARIANCE_FLOOR)?,
            "targetParts" => {
                self.target_parts = if t.is_empty() || t.eq_ignore_ascii_case("auto") {
                    None
                } else {
                    Some(whole(ALLOWED_TARGET_PARTS)?.min(usize::MAX as u64) as usize)
                }
            }
            other => return Err(format!("no field {other} (parts, seed, tol, varianceFloor, targetParts)")),
        }
        Ok(())
    }

    /// These parameters with the form's fields (name, text) set over them, every field checked: the
    /// parameters, or one problem per field that cannot be used (each field's text first, then its range).
    pub fn with_fields(&self, fields: &[(&str, &str)]) -> std::result::Result<Params, Vec<FieldProblem>> {
        self.with_fields_for(fields, None)
    }

    /// [`Params::with_fields`] for a population of `n_vertices` vertices (when known): a part count the
    /// population cannot hold ([`Params::target_problem`]) is refused too, naming the limit.
    pub fn with_fields_for(
        &self,
        fields: &[(&str, &str)],
        n_vertices: Option<usize>,
    ) -> std::result::Result<Params, Vec<FieldProblem>> {
        let mut p = self.clone();
        let mut problems = Vec::new();
        for &(name, text) in fields {
            if let Err(m) = p.set_field(name, text) {
                let field = FIELDS.iter().find(|f| f.0 == name).map_or("unknown", |f| f.0);
                problems.push(FieldProblem { field, message: m });
            }
        }
        let limit = n_vertices.and_then(|n| p.target_problem(n)).map(|m| ("targetParts", m));
        for (field, message) in p.problems().into_iter().chain(limit) {
            if !problems.iter().any(|q| q.field == field) {
                // "= 0 must be ..." after the field's name in validate(); here the value leads
                problems.push(FieldProblem { field, message: message.trim_start_matches("= ").to_string() });
            }
        }
        if problems.is_empty() {
            Ok(p)
        } else {
            Err(problems)
        }
    }

    /// Checks every field; the message names the field, the value, and the valid range.
    pub fn validate(&self) -> Result<()> {
        match self.problems().into_iter().next() {
            Some((field, m)) => {
                let snake = FIELDS.iter().find(|f| f.0 == field).map_or(field, |f| f.1);
                Err(Error::Params(format!("{snake} {m}")))
            }
            None => Ok(()),
        }
    }

    /// These parameters for Algorithm 1's refinement runs (a sub-part's AECM, and the cuts the exact part count
    /// makes the same way): the refinement's tolerance and cap, no SQUAREM (they stop loose and only hand labels
    /// on).
    pub fn for_refinement(&self) -> Params {
        Params { max_iter: self.algorithm1.refine_max_iter, tol: self.refine_tol, accelerate: false, ..self.clone() }
    }

    /// These parameters for a final-stage run that only decides (the merge tree's first run, every run on a
    /// coarse mesh): the refinement's looser tolerance, when it is looser; SQUAREM and the cap as they are.
    pub fn at_loose_tolerance(&self) -> Params {
        Params { tol: self.refine_tol.max(self.tol), ..self.clone() }
    }

    /// The most parts a population of `n_vertices` vertices can have: every part needs at least
    /// `min_part_vertices` vertices ([`crate::parts::part_count::check_target`] refuses more).
    pub fn most_parts(&self, n_vertices: usize) -> usize {
        n_vertices / self.min_part_vertices.max(1)
    }

    /// `target_parts` against a population of `n_vertices` vertices: "= N is more than ..." naming the limit, or
    /// None when the count fits (or is auto).
    pub fn target_problem(&self, n_vertices: usize) -> Option<String> {
        let n = self.target_parts?;
        let most = self.most_parts(n_vertices);
        (n > most).then(|| {
            format!(
                "= {n} is more than this population allows: it has {n_vertices} vertices and every part needs at \
                 least {}, so it must be at most {most} (or auto)",
                self.min_part_vertices.max(1)
            )
        })
    }

    /// Every field that is out of its range: (camelCase name, "= value must be ...").
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut out: Vec<(&'static str, String)> = Vec::new();
        let mut bad = |f: &'static str, m: String| out.push((f, m));
        self.algorithm1.problems(&mut bad);
        if !(self.tol > 0.0 && self.tol.is_finite()) {
            bad("tol", format!("= {} must be {ALLOWED_TOL}", shown(self.tol)));
        }
        if self.max_iter == 0 || self.max_iter > 100_000 {
            bad("maxIter", format!("= {} must be between 1 and 100000", self.max_iter));
        }
        if !(self.variance_floor > 0.0 && self.variance_floor < 1.0) {
            bad("varianceFloor", format!("= {} must be {ALLOWED_VARIANCE_FLOOR}", shown(self.variance_floor)));
        }
        if self.restarts == 0 || self.restarts > 100 {
            bad("restarts", format!("= {} must be between 1 and 100", self.restarts));
        }
        self.distinct.problems(&mut bad);
        if self.min_part_vertices == 0 {
            bad("minPartVertices", "= 0 must be at least 1".into());
        }
        if !(self.refine_tol > 0.0 && self.refine_tol.is_finite()) {
            bad("refineTol", format!("= {} must be a positive number (try 1e-2)", self.refine_tol));
        }
        self.tree.problems(&mut bad);
        if self.target_parts == Some(0) {
            bad("targetParts", format!("= 0 must be {ALLOWED_TARGET_PARTS}"));
        }
        out
    }
}

/// (camelCase, snake_case) names of the fields [`Params::problems`] and [`Params::set_field`] know.
const FIELDS: &[(&str, &str)] = &[
    ("parts", "parts"),
    ("seed", "seed"),
    ("tol", "tol"),
    ("maxIter", "max_iter"),
    ("varianceFloor", "variance_floor"),
    ("restarts", "restarts"),
    ("refineThreshold", "refine_threshold"),
    ("distinctRatio", "distinct_ratio"),
    ("blendRatio", "blend_ratio"),
    ("mergeRatio", "merge_ratio"),
    ("maxSubparts", "max_subparts"),
    ("refineMinGain", "refine_min_gain"),
    ("minPartVertices", "min_part_vertices"),
    ("refineTol", "refine_tol"),
    ("subsetVertices", "subset_vertices"),
    ("coarseVertices", "coarse_vertices"),
    ("targetParts", "target_parts"),
    ("refineMaxIter", "refine_max_iter"),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_each_bad_value_is_named() {
        Params::default().validate().unwrap();
        let cases: Vec<(Params, &str)> = vec![
            (Params { algorithm1: Algorithm1Params { parts: 0, ..Default::default() }, ..Default::default() }, "parts"),
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

    #[test]
    fn the_json_is_flat_with_the_same_keys_and_the_start_is_no_parameter() {
        let mut p = Params { seed: 7, refine: false, part_rule: PartRule::Distinct, ..Params::default() };
        p.algorithm1.parts = 9;
        p.tree.coarse_vertices = 600;
        p.distinct.blend_ratio = 0.2;
        p.algorithm1.threshold.merge_ratio = 0.5;
        let json = serde_json::to_value(&p).unwrap();
        let keys: Vec<&str> = json.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        assert_eq!(keys.len(), FIELDS.len() + 5, "{keys:?}");
        assert!(FIELDS.iter().all(|f| keys.contains(&f.0)), "{keys:?}");
        assert_eq!((json["parts"].as_u64(), json["coarseVertices"].as_u64()), (Some(9), Some(600)));
        assert_eq!((json["blendRatio"].as_f64(), json["mergeRatio"].as_f64()), (Some(0.2), Some(0.5)));
        assert!(json.get("startLabels").is_none());
        assert_eq!(serde_json::from_value::<Params>(json).unwrap(), p);
        // a missing key takes its default, an unknown one is refused
        assert_eq!(serde_json::from_str::<Params>("{}").unwrap(), Params::default());
        assert!(serde_json::from_str::<Params>(r#"{"part": 3}"#).is_err());
        // the start: in a fit request beside the parameters, refused by the parameters alone
        let request = r#"{"parts": 5, "startLabels": [0, 0, 1]}"#;
        let (q, start) = serde_json::from_str::<FlatParams>(request).unwrap().split();
        assert_eq!((q.algorithm1.parts, start.labels), (5, Some(vec![0, 0, 1])));
        let e = serde_json::from_str::<Params>(request).unwrap_err().to_string();
        assert!(e.contains("startLabels is where a fit starts"), "{e}");
        let back = serde_json::to_value(FlatParams::new(&q, &FitStart { labels: Some(vec![0, 0, 1]) })).unwrap();
        assert_eq!(back["startLabels"], serde_json::json!([0, 0, 1]));
    }

    #[test]
    fn form_fields_are_read_and_each_bad_one_is_named_with_what_is_allowed() {
        let base = Params { refine: false, ..Params::default() };
        let p = base
            .with_fields(&[
                ("parts", " 7 "),
                ("targetParts", "auto"),
                ("seed", "3"),
                ("tol", "1e-4"),
                ("varianceFloor", "1e-6"),
            ])
            .unwrap();
        assert_eq!(
            (p.algorithm1.parts, p.target_parts, p.seed, p.tol, p.variance_floor, p.refine),
            (7, None, 3, 1e-4, 1e-6, false)
        );
        assert_eq!(base.with_fields(&[("targetParts", "12")]).unwrap().target_parts, Some(12));
        let e = base
            .with_fields(&[("tol", "abc"), ("targetParts", "seven"), ("parts", "0"), ("varianceFloor", "")])
            .unwrap_err();
        let by = |f: &str| e.iter().find(|q| q.field == f).map(|q| q.message.clone()).unwrap_or_default();
        assert_eq!(e.len(), 4, "{e:?}");
        assert_eq!(by("tol"), format!("'abc' is not a number: it must be {ALLOWED_TOL}"));
        assert_eq!(by("targetParts"), format!("'seven' is not a whole number: it must be {ALLOWED_TARGET_PARTS}"));
        assert_eq!(by("parts"), format!("0 must be {ALLOWED_PARTS}"));
        assert!(by("varianceFloor").starts_with("is empty"), "{e:?}");
        for bad in ["-1", "1.5", "NaN", "inf"] {
            assert!(base.with_fields(&[("parts", bad)]).is_err(), "parts {bad}");
        }
        assert!(base.with_fields(&[("tol", "NaN")]).is_err() && base.with_fields(&[("tol", "-1e-3")]).is_err());
        assert!(base.with_fields(&[("varianceFloor", "2")]).unwrap_err()[0].message.contains("(0, 1)"));
        assert!(base.with_fields(&[("targetParts", "0")]).unwrap_err()[0].field == "targetParts");
        // a whole number in exponent form is read as its value, then judged by its range
        assert_eq!(base.with_fields(&[("parts", "1.2e1")]).unwrap().algorithm1.parts, 12);
        let big = base.with_fields(&[("parts", "1e9")]).unwrap_err();
        assert_eq!(big[0].message, format!("1000000000 is too large: it must be {ALLOWED_PARTS}"));
        assert_eq!(
            base.with_fields(&[("seed", "1e30")]).unwrap_err()[0].message,
            format!("'1e30' is too large: it must be {ALLOWED_SEED}")
        );
        assert_eq!(
            base.with_fields(&[("parts", "2.5")]).unwrap_err()[0].message,
            format!("'2.5' is not a whole number: it must be {ALLOWED_PARTS}")
        );
        // beyond f64 (read as infinity): too large, not "not a number"; a huge value in range checks shown short
        assert_eq!(
            base.with_fields(&[("tol", "1e400")]).unwrap_err()[0].message,
            format!("'1e400' is too large: it must be {ALLOWED_TOL}")
        );
        assert_eq!(
            base.with_fields(&[("tol", "inf")]).unwrap_err()[0].message,
            format!("'inf' is not a number: it must be {ALLOWED_TOL}")
        );
        assert_eq!(
            base.with_fields(&[("varianceFloor", "1e30")]).unwrap_err()[0].message,
            format!("1e30 must be {ALLOWED_VARIANCE_FLOOR}")
        );
        // a negative count is named as negative, with what is allowed
        let neg = base.with_fields(&[("targetParts", "-3")]).unwrap_err();
        assert_eq!(neg[0].message, format!("'-3' is negative: it must be {ALLOWED_TARGET_PARTS}"));
        assert!(neg[0].message.contains("must be a positive whole number"));
        // more parts than the population can hold: refused when its vertex count is known, naming the limit
        let big = base.with_fields_for(&[("targetParts", "500")], Some(1198)).unwrap_err();
        assert_eq!((big.len(), big[0].field), (1, "targetParts"));
        assert!(big[0].message.starts_with("500 is more than") && big[0].message.contains("at most 299"), "{big:?}");
        assert_eq!(base.with_fields_for(&[("targetParts", "299")], Some(1198)).unwrap().target_parts, Some(299));
        assert!(base.with_fields_for(&[("targetParts", "auto")], Some(3)).is_ok());
        // the CLI's words for the same value are the same (its flags call set_field)
        let mut q = Params::default();
        assert_eq!(q.set_field("tol", "abc").unwrap_err(), by("tol"));
        assert!(q.set_field("nope", "1").is_err());
    }
}
