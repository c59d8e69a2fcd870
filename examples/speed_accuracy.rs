//! The fast path (multi-resolution + SQUAREM, the defaults) against the full path (every stage on all vertices,
//! no acceleration: `subsetVertices 0`, `accelerate false`), seed by seed:
//!
//!   cargo run --release --example speed_accuracy -- [INPUT...] [--seeds N]
//!
//! INPUT: a folder of registered OBJ files, `example:ID` (a built-in example with its own parameters) or
//! `synth:PRESET:VERTICES:POSES` (generated, default parameters). Default: ../shared/data/horse-poses,
//! ../shared/data/horse-gallop and every built-in example that does not fail on purpose; seeds 0..N (default 5).
//! Prints one line per input, seed and path (parts, RMSE, final AECM iterations, time, and for generated
//! populations adjusted Rand index and median / largest rotation error in degrees), then per input the largest
//! part-count difference and RMSE ratio over the seeds.

use posemfa::mesh::Population;
use posemfa::mfa::Params;
use posemfa::parts::hierarchy::fit;
use posemfa::synth::{self, Generated};

struct Input {
    label: String,
    pop: Population,
    truth: Option<Generated>,
    params: Params,
}

fn load(arg: &str) -> Result<Input, String> {
    if let Some(id) = arg.strip_prefix("example:") {
        let ex = synth::presets::example(id).ok_or_else(|| format!("no built-in example '{id}'"))?;
        let g = synth::generate(&ex.spec).map_err(|e| e.to_string())?;
        return Ok(Input { label: arg.into(), pop: g.population.clone(), truth: Some(g), params: ex.params });
    }
    if let Some(rest) = arg.strip_prefix("synth:") {
        let f: Vec<&str> = rest.split(':').collect();
        let preset =
            serde_json::from_value(serde_json::json!(f[0])).map_err(|_| format!("unknown preset in '{arg}'"))?;
        let mut spec = synth::Spec { preset, ..Default::default() };
        if let Some(v) = f.get(1) {
            spec.vertices = v.parse().map_err(|_| format!("bad vertex count in '{arg}'"))?;
        }
        if let Some(v) = f.get(2) {
            spec.poses = v.parse().map_err(|_| format!("bad pose count in '{arg}'"))?;
        }
        let g = synth::generate(&spec).map_err(|e| e.to_string())?;
        return Ok(Input { label: arg.into(), pop: g.population.clone(), truth: Some(g), params: Params::default() });
    }
    let pop = Population::new(posemfa::mesh::Sources::paths(&[arg])).map_err(|e| e.to_string())?;
    Ok(Input { label: arg.into(), pop, truth: None, params: Params::default() })
}

struct Row {
    parts: usize,
    rmse: f64,
    ari: Option<f64>,
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut seeds = 5u64;
    if let Some(i) = args.iter().position(|a| a == "--seeds") {
        seeds = args.get(i + 1).and_then(|v| v.parse().ok()).unwrap_or(5);
        args.drain(i..(i + 2).min(args.len()));
    }
    if args.is_empty() {
        let shared = std::env::var("POSEMFA_SHARED").unwrap_or_else(|_| "../shared".into());
        args.push(format!("{shared}/data/horse-poses"));
        args.push(format!("{shared}/data/horse-gallop"));
        for ex in synth::presets::examples() {
            if !ex.fails_on_purpose {
                args.push(format!("example:{}", ex.id));
            }
        }
    }
    for arg in &args {
        let input = match load(arg) {
            Ok(i) => i,
            Err(e) => {
                eprintln!("{arg}: {e} (skipped)");
                continue;
            }
        };
        println!("{} ({} shapes x {} vertices)", input.label, input.pop.n_shapes(), input.pop.n_vertices());
        let mut worst_parts = 0i64;
        let mut worst_rmse = 0.0f64;
        let mut worst_ari = f64::NEG_INFINITY;
        for seed in 0..seeds {
            let mut rows = Vec::new();
            for (name, subset, accelerate) in
                [("full", 0, false), ("fast", input.params.algorithm1.subset_vertices, true)]
            {
                let mut params = Params { seed, accelerate, ..input.params.clone() };
                params.algorithm1.subset_vertices = subset;
                let t0 = std::time::Instant::now();
                let r = match fit(&input.pop, &params, &mut |_| true) {
                    Ok(r) => r,
                    Err(e) => {
                        println!("  seed {seed} {name}: {e}");
                        continue;
                    }
                };
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                let m = &r.model;
                let rmse = m.rmse(&input.pop);
                let mut line = format!(
                    "  seed {seed} {name}: parts {:>3}  RMSE {rmse:.5}  final AECM {:>3} iterations  {ms:>7.0} ms",
                    m.n_parts(),
                    m.iterations
                );
                let mut ari = None;
                if let Some(g) = &input.truth {
                    let a = posemfa::metrics::adjusted_rand_index(&m.labels, &g.part_of_vertex);
                    let fitted: Vec<Vec<posemfa::geometry::Mat3>> =
                        m.parts.iter().map(|p| p.rotations.clone()).collect();
                    let errs =
                        posemfa::metrics::rotation_errors_deg(&fitted, &m.labels, &g.rotations, &g.part_of_vertex)
                            .unwrap_or_default();
                    let max = errs.iter().cloned().fold(0.0, f64::max);
                    line += &format!(
                        "  ARI {a:.3}  rotation error median {:.2} max {max:.2} deg",
                        posemfa::metrics::median(&errs)
                    );
                    ari = Some(a);
                }
                println!("{line}");
                rows.push(Row { parts: m.n_parts(), rmse, ari });
            }
            if let [full, fast] = &rows[..] {
                worst_parts = worst_parts.max((fast.parts as i64 - full.parts as i64).abs());
                worst_rmse = worst_rmse.max(fast.rmse / full.rmse);
                if let (Some(a), Some(b)) = (fast.ari, full.ari) {
                    worst_ari = worst_ari.max(b - a);
                }
            }
        }
        let ari = if worst_ari.is_finite() {
            format!(", ARI at most {worst_ari:.3} below the full path's")
        } else {
            String::new()
        };
        println!("  => fast vs full over the seeds: part counts differ by at most {worst_parts}, RMSE ratio at most {worst_rmse:.3}{ari}");
    }
}
