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
    /// Also fit with every pose dropped in turn (one run per pose), and report the part counts of those runs
    /// apart: how much the answer hangs on any one pose
    #[arg(long)]
    drop_each: bool,
    /// Write the runs and the agreement as JSON
    #[arg(long, value_name = "OUT", value_hint = ValueHint::FilePath)]
    json: Option<String>,
    /// (last: its options under their own headings)
    #[command(flatten)]
    pub fit: FitArgs,
}

pub fn run(o: Args) -> Result<(), String> {
    let start = o.fit.start()?;
    let (params, pop, generated) = o.fit.load()?;
    let truth: Option<Vec<u32>> = match &o.truth {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {path}: {e}"))?;
            let labels: Vec<u32> = serde_json::from_str(&text)
                .map_err(|e| format!("{path}: {e}; give a JSON array of non-negative integers, one per vertex"))?;
            if labels.len() != pop.n_vertices() {
                return Err(format!(
                    "{path}: {} labels for {} vertices; give one per vertex",
                    labels.len(),
                    pop.n_vertices()
                ));
            }
            Some(labels)
        }
        None => generated.map(|g| g.part_of_vertex.clone()),
    };
    out!("{} shapes x {} vertices; {} seeds and 4 nuisance variants", pop.n_shapes(), pop.n_vertices(), o.seeds);
    let score = |labels: &[u32]| truth.as_ref().map(|t| posemfa::metrics::adjusted_rand_index(labels, t));
    let show = |r: &posemfa::parts::robustness::Run| {
        let t = score(&r.labels).map_or(String::new(), |a| format!("  ARI vs truth {a:.3}"));
        out!("  {:<15} {:>3} parts  RMSE {:.5}  {:>6.2} s{t}", r.variant, r.parts, r.rmse, r.seconds);
    };
    let runs = run_variants(&pop, &params, &start, &Variant::standard(o.seeds), show).map_err(|e| e.to_string())?;
    let a = agreement(&runs);
    let line = |a: &posemfa::parts::robustness::Agreement| {
        format!(
            "parts {}-{} (spread {}) | pairwise adjusted Rand median {:.3}, min {:.3}",
            a.fewest_parts,
            a.most_parts,
            a.most_parts - a.fewest_parts,
            a.median_ari,
            a.min_ari
        )
    };
    out!("{}", line(&a));
    let each = if o.drop_each {
        let each_variants = Variant::leave_each_out(pop.n_shapes());
        if each_variants.is_empty() {
            out!("each pose dropped: not run ({} poses: dropping one would leave too few)", pop.n_shapes());
            None
        } else {
            out!("each pose dropped in turn ({} runs, seed 0):", each_variants.len());
            let runs = run_variants(&pop, &params, &start, &each_variants, show).map_err(|e| e.to_string())?;
            let e = agreement(&runs);
            out!("each pose dropped: {}", line(&e));
            Some((runs, e))
        }
    } else {
        None
    };
    if let Some(path) = &o.json {
        let to_json = |runs: &[posemfa::parts::robustness::Run]| -> Vec<serde_json::Value> {
            runs.iter()
                .map(|r| {
                    let mut v = serde_json::to_value(r).unwrap_or_default();
                    if let Some(a) = score(&r.labels) {
                        v["truthAri"] = serde_json::json!(a);
                    }
                    v
                })
                .collect()
        };
        let runs_json = to_json(&runs);
        let mut doc = serde_json::json!({ "runs": runs_json, "agreement": a });
        if let Some((runs, e)) = &each {
            doc["eachDropped"] = serde_json::json!({ "runs": to_json(runs), "agreement": e });
        }
        std::fs::write(path, doc.to_string()).map_err(|e| format!("cannot write {path}: {e}"))?;
        out!("wrote {path}");
    }
    Ok(())
}
