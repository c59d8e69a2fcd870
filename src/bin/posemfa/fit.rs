//! `posemfa fit DIR_OR_FILES...`: fit the model and print a summary.

use crate::shared::{ground_truth_json, median, run_fit, write_json, FitArgs, RunArgs};

/// Fit the model (Algorithm 1) and print a summary
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub run: RunArgs,
    #[command(flatten)]
    pub fit: FitArgs,
}

pub fn run(o: Args) -> Result<(), String> {
    let t_load = posemfa::clock::now_ms();
    let (params, pop, truth) = o.fit.load()?;
    let load_ms = posemfa::clock::now_ms() - t_load;
    let mut totals = Vec::new();
    let mut result = None;
    for _ in 0..o.run.repeat() {
        let t0 = posemfa::clock::now_ms();
        result = Some(run_fit(&params, &pop, o.run.quiet)?);
        totals.push(posemfa::clock::now_ms() - t0);
    }
    let result = result.ok_or("no fit ran")?;
    let m = &result.model;
    let s = &result.stages;
    out!(
        "{} shapes x {} vertices | parts: coarse {} -> refined {} -> final {} | final AECM {} iterations ({}) | RMSE {:.5} (unit box; E_RMS {:.3}) | {:.0} ms (load {:.0} ms)",
        pop.n_shapes(),
        pop.n_vertices(),
        s.coarse_parts,
        s.refined_parts,
        s.final_parts,
        m.iterations,
        if m.converged { "converged" } else { "NOT converged: iteration cap reached" },
        m.rmse(&pop),
        posemfa::export::rig_report::fit_e_rms(&pop, m),
        median(&mut totals),
        load_ms
    );
    let d = posemfa::parts::diagnosis::diagnose_fit(&pop, &result);
    out!(
        "  {}: {}",
        if d.undecided {
            "no verdict"
        } else if d.articulated {
            "articulated"
        } else {
            "NOT articulated"
        },
        d.reason
    );
    if let Some(g) = &truth {
        out!("  ground truth: {}", ground_truth_json(g, m));
    } else {
        out!("  poses: {}", pop.source);
    }
    if let [.., last] = result.part_curve.as_slice() {
        out!(
            "  part rule: {} merges from {} parts; the next pair scored {:.2} (kept apart from {}: --distinct-ratio)",
            result.part_curve.len() - 1,
            result.part_curve[0].parts,
            last.score,
            params.distinct_ratio
        );
    }
    for st in &result.stats {
        out!("  {:<7} {:>8.1} ms  {:>5} iterations in {:>3} AECM runs", st.name, st.ms, st.iterations, st.aecm_runs);
    }
    if let Some(path) = &o.run.json {
        write_json(path, &pop, &result)?;
        out!("wrote {path}");
    }
    Ok(())
}
