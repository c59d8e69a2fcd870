//! The fit as JSON (the CLI's `--json`, the page's export). Unit-box coordinates throughout; the
//! `normalization` maps them back: unit = (original - offset) * scale.

use crate::mesh::{Normalization, Population};
use crate::parts::diagnosis::Diagnosis;
use crate::parts::distinct::CurvePoint;
use crate::parts::hierarchy::{FitResult, StageParts, StageStats};
use serde::Serialize;

#[derive(Serialize)]
pub struct PartJson {
    /// R_k^i per shape, row-major 3x3.
    pub rotations: Vec<[f64; 9]>,
    /// b_k^i per shape.
    pub translations: Vec<[f64; 3]>,
    pub lambda: [f64; 3],
    pub variances: Vec<f64>,
    pub weight: f64,
}

#[derive(Serialize)]
pub struct FitJson {
    pub shapes: Vec<String>,
    /// Where the shapes came from ("11 OBJ files", "49 frames of animation 'Gallop' ... in horse.glb; ...").
    pub source: String,
    pub n_vertices: usize,
    pub normalization: Normalization,
    pub labels: Vec<u32>,
    pub parts: Vec<PartJson>,
    /// v_j^ref (eq 21): shape i vertex j ≈ R^i_{l_j} latent_j + b^i_{l_j} (unit box).
    pub latent: Vec<[f64; 3]>,
    pub stages: StageParts,
    pub coarse_labels: Vec<u32>,
    pub refined_labels: Vec<u32>,
    /// Log-likelihood after every iteration of the final AECM run.
    pub log_likelihood: Vec<f64>,
    pub iterations: usize,
    pub converged: bool,
    pub complete: bool,
    pub rmse: f64,
    /// The fit's error in the rig's measure ([`crate::export::rig_report::fit_e_rms`]: E_RMS, thousandths of
    /// the bind pose's diagonal), to set beside a rig's.
    pub e_rms: f64,
    /// Extra connected pieces of the labels (Σ over parts of pieces - 1; 0: every part is one piece).
    pub islands: usize,
    pub timings_ms: std::collections::BTreeMap<String, f64>,
    pub stage_stats: Vec<StageStats>,
    /// Whether the population looks articulated, and why ([`crate::parts::diagnosis`]); null for a fit stopped
    /// early (cancelled in the page): the verdict needs a finished fit.
    pub diagnosis: Option<Diagnosis>,
    /// The part rule's merge decisions, most parts first: why the fit stopped at its part count
    /// ([`crate::parts::distinct::CurvePoint`]; empty with the paper's threshold rule).
    pub part_curve: Vec<CurvePoint>,
    /// Every round of the part rule, in order: [{parts, dissolved, after}] (the parts it judged, how many it
    /// dissolved as flesh, how many its merges left; `part_curve` is the last round's merges).
    pub part_rounds: Vec<crate::parts::hierarchy::PartRound>,
    /// The default part rule: the start's parts once its flesh was dissolved, before the first AECM (the start's
    /// cut is the first of `stages`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_parts: Option<usize>,
    /// The default part rule's merge tree of the fitted parts (`leaves`: the part of every vertex in the first
    /// final AECM; `merges` [{a, b, parts, rise, score, variance}] in order, merge m making node leaves + m) and
    /// the count the rule read off it (`tree_count`); absent with Algorithm 1's rules.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub merge_tree: Option<crate::parts::merge_tree::MergeTree>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tree_count: Option<usize>,
}

impl FitJson {
    pub fn new(pop: &Population, result: &FitResult) -> FitJson {
        let m = &result.model;
        let mut timings_ms = std::collections::BTreeMap::new();
        let mut total = 0.0;
        for s in &result.stats {
            timings_ms.insert(s.name.clone(), s.ms);
            total += s.ms;
        }
        timings_ms.insert("total".into(), total);
        FitJson {
            shapes: pop.names.clone(),
            source: pop.source.clone(),
            n_vertices: m.n_vertices,
            normalization: pop.normalization,
            labels: m.labels.clone(),
            parts: m
                .parts
                .iter()
                .map(|c| PartJson {
                    rotations: c.rotations.iter().map(crate::geometry::row_major).collect(),
                    translations: c.translations.clone(),
                    lambda: c.lambda,
                    variances: c.variances.clone(),
                    weight: c.weight,
                })
                .collect(),
            latent: m.latent.clone(),
            stages: result.stages,
            coarse_labels: result.coarse_labels.clone(),
            refined_labels: result.refined_labels.clone(),
            log_likelihood: m.log_likelihood.clone(),
            iterations: m.iterations,
            converged: m.converged,
            complete: result.complete,
            rmse: m.rmse(pop),
            e_rms: crate::export::rig_report::fit_e_rms(pop, m),
            islands: crate::parts::islands::island_count(&m.labels, pop.graph_faces()),
            timings_ms,
            stage_stats: result.stats.clone(),
            diagnosis: crate::parts::diagnosis::diagnose_finished(pop, result),
            part_curve: result.part_curve.clone(),
            part_rounds: result.part_rounds.clone(),
            start_parts: result.start_parts(),
            merge_tree: result.merge_tree().cloned(),
            tree_count: result.tree_count(),
        }
    }
}

/// The fit as a JSON string.
pub fn fit_to_json(pop: &Population, result: &FitResult) -> String {
    // Serialising plain numbers and strings cannot fail; NaN/inf become null.
    serde_json::to_string(&FitJson::new(pop, result)).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
}
