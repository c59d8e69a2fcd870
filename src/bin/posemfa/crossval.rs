//! `posemfa crossval DIR_OR_FILES... [--bones N] [--json F]`: how well the rig generalises to poses it has not seen.

use crate::shared::{FitArgs, RigArgs};
use clap::ValueHint;
use posemfa::articulate::pose::{crossval, median_ratio};
use posemfa::export::gltf::Weights;

/// Leave one pose out: for every pose, fit and build the rig (fitted weights unless --weights says otherwise) on
/// all the other poses, solve the left-out pose onto it with the weights and bind pose fixed (as `posemfa pose`),
/// and print both E_RMS and their ratio; the median ratio at the end
#[derive(clap::Args)]
#[command(next_help_heading = "Crossval options")]
pub struct Args {
    /// Also write the folds as JSON ({poses: [{name, in_sample_e_rms, held_out_e_rms, ...}], median_ratio})
    #[arg(long, value_name = "F.json", value_hint = ValueHint::FilePath)]
    json: Option<String>,
    #[command(flatten)]
    rig: RigArgs,
    #[command(flatten)]
    fit: FitArgs,
}

pub fn run(a: Args) -> Result<(), String> {
    let start = a.fit.start()?;
    let (params, pop, _truth) = a.fit.load()?;
    let mut g = a.rig.options(&pop)?;
    if !a.rig.weights_given() {
        g.weights = Weights::Fitted;
    }
    let opts = g.rig_options();
    let folds = crossval(&pop, &params, &start, &opts, &mut |i, n| {
        eprintln!("fold {}/{n}: leaving out {}", i + 1, pop.names[i])
    })
    .map_err(|e| e.to_string())?;
    for f in &folds {
        out!(
            "{}: in sample {:.4}, held out {:.4}, ratio {:.3} ({} bones, fit {:.0} ms, solve {:.1} ms)",
            f.name,
            f.in_sample_e_rms,
            f.held_out_e_rms,
            f.held_out_e_rms / f.in_sample_e_rms,
            f.bones,
            f.fit_ms,
            f.solve_ms
        );
    }
    let median = median_ratio(&folds);
    out!("median held-out / in-sample E_RMS ratio: {median:.3} over {} poses", folds.len());
    if let Some(path) = &a.json {
        let json = serde_json::json!({"poses": folds, "median_ratio": median, "weights": format!("{:?}", g.weights).to_lowercase(), "influences": g.influences});
        std::fs::write(path, json.to_string()).map_err(|e| format!("cannot write {path}: {e}"))?;
    }
    Ok(())
}
