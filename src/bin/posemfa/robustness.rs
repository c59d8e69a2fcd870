//! `posemfa robustness DIR_OR_FILES...`: does the answer depend on the start? Fits at several seeds and on four
//! nuisance variants of the same population, and prints the part counts, the pairwise adjusted Rand index and
//! the times (`posemfa::parts::robustness`).

use crate::shared::FitArgs;
use clap::ValueHint;
use posemfa::parts::robustness::{agreement, run_variants, Variant};

/// Fit at seeds 0..N and on four nuisance variants (poses reversed, first or middle pose dropped, all poses moved
/// and scaled); print part counts, pairwise adjusted Rand index (median, min) and times
#[derive(clap::Args)]
pub struct Args {
    /// Seeds 0..N-1 (the nuisance variants use seed 0)
    #[arg(long, value_name = "N", default_value_t = 5)]
    seeds: u64,
    /// Per-vertex labels to score every run against (a JSON array of integers, one per vertex; e.g. each
    /// vertex's dominant joint of a skinned character)
    #[arg(long, value_name = "FILE", value_hint = ValueHint::FilePath)]
    truth: Option<String>,
    /// Write the runs and the agreement as JSON
    #[arg(long, value_name = "OUT", value_hint = ValueHint::FilePath)]
    json: Option<String>,
    /// (last: its options under their own headings)
    #[command(flatten)]
    pub fit: FitArgs,
}

pub fn run(o: Args) -> Result<(), String> {
    let (params, pop, generated) = o.fit.load()?;
    let truth: Option<Vec<u32>> = match &o.truth {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {path}: {e}"))?;
            let labels: Vec<u32> = serde_json::from_str(&text)
                .map_err(|e| format!("{path}: {e}; give a JSON array of non-negative integers, one per vertex"))?;
            if labels.len() != pop.n_vertices() {
                return Err(format!("{path}: {} labels for {} vertices; give one per vertex", labels.len(), pop.n_vertices()));
            }
            Some(labels)
        }
        None => generated.map(|g| g.part_of_vertex.clone()),
    };
    out!("{} shapes x {} vertices; {} seeds and 4 nuisance variants", pop.n_shapes(), pop.n_vertices(), o.seeds);
    let score = |labels: &[u32]| truth.as_ref().map(|t| posemfa::metrics::adjusted_rand_index(labels, t));
    let runs = run_variants(&pop, &params, &Variant::standard(o.seeds), |r| {
        let t = score(&r.labels).map_or(String::new(), |a| format!("  ARI vs truth {a:.3}"));
        out!("  {:<15} {:>3} parts  RMSE {:.5}  {:>6.2} s{t}", r.variant, r.parts, r.rmse, r.seconds);
    })
    .map_err(|e| e.to_string())?;
    let a = agreement(&runs);
    out!(
        "parts {}-{} (spread {}) | pairwise adjusted Rand median {:.3}, min {:.3}",
        a.fewest_parts,
        a.most_parts,
        a.most_parts - a.fewest_parts,
        a.median_ari,
        a.min_ari
    );
    if let Some(path) = &o.json {
        let runs_json: Vec<serde_json::Value> = runs
            .iter()
            .map(|r| {
                let mut v = serde_json::to_value(r).unwrap_or_default();
                if let Some(a) = score(&r.labels) {
                    v["truthAri"] = serde_json::json!(a);
                }
                v
            })
            .collect();
        let doc = serde_json::json!({ "runs": runs_json, "agreement": a });
        std::fs::write(path, doc.to_string()).map_err(|e| format!("cannot write {path}: {e}"))?;
        out!("wrote {path}");
    }
    Ok(())
}
