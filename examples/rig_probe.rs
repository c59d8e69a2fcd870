//! The rig stage alone: `cargo run --release --example rig_probe -- DIR [--bones 10,20,30] [--builds R] [--out F]`.
//! Fits DIR once per bone count (`target_parts`, fitted weights, 4 influences, bind pose as the CLI's), then times
//! R builds of the rig (`articulate::rig::build`) and R runs of the part count (`parts::part_count::labels_with_count`
//! on the labels the part rule decided) and prints JSON: per count the wall-clock and CPU milliseconds of each
//! (CPU: this thread's, from Linux's /proc/thread-self/schedstat; 0 elsewhere). With `--out F` it also writes every result in full precision (the count's labels, the rig's trace, weights, bind
//! positions, bones and f64 E_RMS / max error over the training poses), to compare two builds of the code.
use posemfa::articulate::rig::{build, RigOptions, RigWeights};
use posemfa::articulate::Articulation;
use posemfa::mesh::Population;
use posemfa::mfa::Params;
use posemfa::parts::hierarchy::Pipeline;
use std::time::Instant;

/// CPU milliseconds this thread has run (Linux: /proc/thread-self/schedstat, nanoseconds), else 0.
fn cpu_ms() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns / 1e6)
}

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let mut dir = None;
    let mut bones = vec![10usize, 20, 30];
    let mut builds = 3usize;
    let mut out = None;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--bones" => {
                bones = args
                    .next()
                    .ok_or("--bones N,..")?
                    .split(',')
                    .map(|s| s.parse().map_err(|e| format!("{e}")))
                    .collect::<Result<_, _>>()?
            }
            "--builds" => builds = args.next().ok_or("--builds R")?.parse().map_err(|e| format!("{e}"))?,
            "--out" => out = Some(args.next().ok_or("--out F")?),
            _ => dir = Some(a),
        }
    }
    let dir = dir.ok_or("usage: rig_probe DIR [--bones 10,20,30] [--builds R] [--out F]")?;
    let mut files = Vec::new();
    let mut entries: Vec<_> =
        std::fs::read_dir(&dir).map_err(|e| e.to_string())?.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for e in entries.iter().filter(|e| e.extension().is_some_and(|x| x == "obj")) {
        files.push((
            e.file_name().unwrap_or_default().to_string_lossy().into_owned(),
            std::fs::read(e).map_err(|e| e.to_string())?,
        ));
    }
    let t = Instant::now();
    let pop = Population::new(posemfa::mesh::Sources::Files(files)).map_err(|e| e.to_string())?;
    let read_ms = t.elapsed().as_secs_f64() * 1e3;
    let bind = posemfa::export::rig_report::default_bind_pose(&pop);
    let mut report = Vec::new();
    let mut full = Vec::new();
    for &n in &bones {
        let params = Params { target_parts: Some(n), ..Default::default() };
        let mut pipe = Pipeline::new(&pop, &params).map_err(|e| e.to_string())?;
        let result = pipe.run(&mut |_| true).map_err(|e| e.to_string())?;
        let mut count_ms = Vec::new();
        let mut count_cpu_ms = Vec::new();
        let mut counted = None;
        if let Some(decided) = &result.decided_labels {
            for _ in 0..builds {
                let t = Instant::now();
                let c = cpu_ms();
                let (labels, _) = posemfa::parts::part_count::labels_with_count(&pop, decided, n, &params)
                    .map_err(|e| e.to_string())?;
                count_ms.push(t.elapsed().as_secs_f64() * 1e3);
                count_cpu_ms.push(cpu_ms() - c);
                counted = Some(labels);
            }
        }
        let art = Articulation::new(&result.model, &pop).map_err(|e| e.to_string())?;
        let opts = RigOptions { weights: RigWeights::Fitted, bind_pose: bind, ..Default::default() };
        let mut rig_ms = Vec::new();
        let mut rig_cpu_ms = Vec::new();
        let mut rig = None;
        for _ in 0..builds {
            let t = Instant::now();
            let c = cpu_ms();
            rig = Some(build(&art, &opts).map_err(|e| e.to_string())?);
            rig_ms.push(t.elapsed().as_secs_f64() * 1e3);
            rig_cpu_ms.push(cpu_ms() - c);
        }
        let rig = rig.expect("builds >= 1");
        let (mut sq, mut worst) = (0.0f64, 0.0f64);
        for i in 0..pop.n_shapes() {
            for (x, y) in rig.pose(i).iter().zip(pop.shape(i).to_vec().iter()) {
                let d = (0..3).map(|c| (x[c] - y[c]).powi(2)).sum::<f64>();
                sq += d;
                worst = worst.max(d.sqrt());
            }
        }
        let e_rms = (sq / (3.0 * (pop.n_vertices() * pop.n_shapes()) as f64)).sqrt();
        report.push(serde_json::json!({"bones": n, "count_ms": count_ms, "count_cpu_ms": count_cpu_ms, "rig_ms": rig_ms, "rig_cpu_ms": rig_cpu_ms, "alternations": rig.trace.len() - 1, "e_rms_unit": e_rms}));
        if out.is_some() {
            full.push(serde_json::json!({
                "bones": n,
                "model_labels": result.model.labels,
                "counted": counted,
                "trace": rig.trace,
                "e_rms_unit": e_rms,
                "max_error_unit": worst,
                "weights": rig.weights.influences,
                "rest": rig.rest,
                "bones_motions": rig.bones.iter().map(|p| p.iter().map(|m| (m.rotation.as_slice().to_vec(), m.translation)).collect::<Vec<_>>()).collect::<Vec<_>>(),
            }));
        }
    }
    println!("{}", serde_json::json!({"read_ms": read_ms, "counts": report}));
    if let Some(f) = out {
        std::fs::write(&f, serde_json::to_string(&full).map_err(|e| e.to_string())?).map_err(|e| e.to_string())?;
    }
    Ok(())
}
