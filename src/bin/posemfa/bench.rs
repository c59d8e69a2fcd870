//! `posemfa bench DIR_OR_FILES...`: fit and print per-stage figures as JSON.

use crate::shared::{ground_truth_json, median, run_fit, write_json, FitArgs, RunArgs};

/// Fit and print per-stage figures as JSON (time, iterations, E-step GFLOP/s, kernel limits, peak memory)
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: RunArgs,
    #[command(flatten)]
    fit: FitArgs,
}

pub fn run(o: Args) -> Result<(), String> {
    let t_load = posemfa::clock::now_ms();
    let start = o.fit.start()?;
    let (params, pop, truth) = o.fit.load()?;
    let load_ms = posemfa::clock::now_ms() - t_load;
    // the kernels right after each fit, so that each fraction compares two measurements of one moment
    let data = posemfa::mfa::data::Data::from_population(&pop);
    let mut totals = Vec::new();
    let mut limits = Vec::new();
    let mut result = None;
    for _ in 0..o.run.repeat() {
        let t0 = posemfa::clock::now_ms();
        let r = run_fit(&params, &start, &pop, o.run.quiet)?;
        totals.push(posemfa::clock::now_ms() - t0);
        limits.push(posemfa::mfa::limit::limit_report(&data, &r.model.parts, &r.stats, 200.0));
        result = Some(r);
    }
    let (Some(result), Some(limit)) = (result, limits.last()) else { return Err("no fit ran".into()) };
    let m = &result.model;
    let mut fractions: Vec<f64> = limits.iter().map(|l| l.fraction).collect();
    let vertex_major = posemfa::mfa::estep::kernel_rate_vertex_major(&data, &m.parts, 200.0);
    let stages: Vec<_> = result
        .stats
        .iter()
        .zip(&limit.stage_fractions)
        .map(|(s, fraction)| {
            serde_json::json!({
                "stage": s.name, "ms": s.ms, "iterations": s.iterations, "aecm_runs": s.aecm_runs,
                "estep_ms": s.estep_ms, "estep_gflop": s.estep_flops / 1e9, "estep_gflop_f32": s.estep_flops_f32 / 1e9,
                "estep_gflops_per_s": if s.estep_ms > 0.0 { s.estep_flops / s.estep_ms / 1e6 } else { 0.0 },
                "estep_fraction_of_limit": fraction,
            })
        })
        .collect();
    let fit_ms = median(&mut totals.clone());
    let out = serde_json::json!({
        "runtime": "native",
        "inputs": o.fit.input.inputs, "shapes": pop.n_shapes(), "vertices": pop.n_vertices(),
        "load_ms": load_ms, "fit_ms_median": fit_ms, "fit_ms_all": totals,
        "parts": m.n_parts(), "rmse": m.rmse(&pop), "iterations": result.stats.iter().map(|s| s.iterations).sum::<usize>(),
        "stages": stages,
        "kernel_limit_f64": limit.f64, "kernel_limit_f32": limit.f32,
        "estep_fraction_of_limit": median(&mut fractions), "estep_fraction_of_limit_all": fractions,
        "kernel_vertex_major_f64": vertex_major,
        "peak_memory_bytes": peak_rss_bytes(),
        "ground_truth": truth.as_ref().map(|g| ground_truth_json(g, m)),
    });
    out!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
    if let Some(path) = &o.run.json {
        write_json(path, &pop, &result)?;
    }
    Ok(())
}

/// Peak resident set of this process (Linux: VmHWM in /proc/self/status), or null elsewhere.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
