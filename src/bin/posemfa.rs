//! posemfa command line: `inspect`, `fit`, `bench` (and more as they land). Run `posemfa help`.

use posemfa::export::json::{fit_to_json, FitJson};
use posemfa::mesh::Population;
use posemfa::model::hierarchy::{Pipeline, Progress, Stage};
use posemfa::model::{LambdaRule, Params};
use std::io::Write;
use std::process::ExitCode;

/// println! that never panics (a closed pipe, e.g. `| head`, just ends the output).
macro_rules! out {
    ($($t:tt)*) => {{
        let _ = writeln!(std::io::stdout().lock(), $($t)*);
    }};
}

const USAGE: &str = "posemfa: learn rigid parts and their motion from registered triangle meshes

USAGE:
  posemfa inspect FILE.obj                  print vertices and triangles as JSON (exit 1 on error)
  posemfa fit DIR_OR_FILES... [options]      fit the model (Algorithm 1) and print a summary
  posemfa bench DIR_OR_FILES... [options]    fit and print per-stage figures as JSON
  posemfa generate PRESET [--vertices N] [--poses P] [--seed S] [--band B] [--noise X] --out DIR
                                             write a generated population (quadruped, arm, snake, blob) as OBJ
  Instead of DIR_OR_FILES, fit and bench accept synth:PRESET[:VERTICES[:POSES[:SEED[:BAND[:MAX_ANGLE]]]]], a generated
  population whose ground truth (adjusted Rand index, rotation error) is then reported too.

FIT OPTIONS:
  --parts M          coarse parts (default 11)
  --seed S           random seed (default 0)
  --tol T            convergence tolerance on |dL|/n_v (default 1e-3)
  --max-iter N       iteration cap per AECM run (default 300)
  --floor F          variance floor, unit-box units^2 (default 1e-7)
  --literal-eq18     use the paper's literal eq 18 for Lambda (breaks monotonicity; for teaching)
  --no-px            no parameter-expanded step at the end of cycle 2 (PX-EM, on by default; same optimum)
  --refine-threshold E   Algorithm 1: stop splitting a part below this mean variance (default 1e-5)
  --max-subparts N   Algorithm 1: most sub-parts per coarse part (default 6)
  --refine-tol T     tolerance of the coarse and refinement AECM runs (default 1e-2)
  --no-refine        stop after the coarse AECM
  --json OUT         write the result as JSON
  --quiet            no per-stage progress on stderr
";

struct Opts {
    inputs: Vec<String>,
    params: Params,
    json: Option<String>,
    quiet: bool,
    repeat: usize,
}

fn parse_opts(args: &[String]) -> Result<Opts, String> {
    let mut o = Opts { inputs: Vec::new(), params: Params::default(), json: None, quiet: false, repeat: 1 };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = |name: &str| it.next().cloned().ok_or_else(|| format!("{name} needs a value"));
        fn num<T: std::str::FromStr>(name: &str, v: String) -> Result<T, String> {
            v.parse().map_err(|_| format!("{name}: '{v}' is not a valid number"))
        }
        match a.as_str() {
            "--parts" => o.params.parts = num("--parts", val("--parts")?)?,
            "--seed" => o.params.seed = num("--seed", val("--seed")?)?,
            "--tol" => o.params.tol = num("--tol", val("--tol")?)?,
            "--max-iter" => o.params.max_iter = num("--max-iter", val("--max-iter")?)?,
            "--floor" => o.params.variance_floor = num("--floor", val("--floor")?)?,
            "--repeat" => o.repeat = num("--repeat", val("--repeat")?)?,
            "--refine-threshold" => o.params.refine_threshold = num("--refine-threshold", val("--refine-threshold")?)?,
            "--refine-tol" => o.params.refine_tol = num("--refine-tol", val("--refine-tol")?)?,
            "--max-subparts" => o.params.max_subparts = num("--max-subparts", val("--max-subparts")?)?,
            "--literal-eq18" => o.params.lambda_rule = LambdaRule::PaperEq18,
            "--no-px" => o.params.px_em = false,
            "--no-refine" => o.params.refine = false,
            "--json" => o.json = Some(val("--json")?),
            "--quiet" => o.quiet = true,
            s if s.starts_with("--") => return Err(format!("unknown option {s}\n\n{USAGE}")),
            s => o.inputs.push(s.to_string()),
        }
    }
    if o.inputs.is_empty() {
        return Err(format!("no input: give a folder of OBJ files or the files\n\n{USAGE}"));
    }
    o.params.validate().map_err(|e| e.to_string())?;
    Ok(o)
}

fn stage_name(s: &Stage) -> String {
    match s {
        Stage::Coarse => "coarse".into(),
        Stage::Refine { part, of, sub_parts } => format!("refining part {} of {of} ({sub_parts} sub-parts)", part + 1),
        Stage::Final => "final".into(),
        Stage::Done => "done".into(),
    }
}

fn cmd_inspect(args: &[String]) -> Result<(), String> {
    let [file] = args else { return Err(format!("inspect takes one file\n\n{USAGE}")) };
    let bytes = std::fs::read(file).map_err(|e| format!("cannot read {file}: {e}"))?;
    let name = std::path::Path::new(file).file_name().map_or(file.clone(), |n| n.to_string_lossy().into_owned());
    let mesh = posemfa::mesh::obj::parse_obj(&name, &bytes).map_err(|e| e.to_string())?;
    let out = serde_json::json!({
        "file": name,
        "n_vertices": mesh.positions.len(),
        "n_triangles": mesh.faces.len(),
        "vertices": mesh.positions,
        "triangles": mesh.faces,
    });
    out!("{out}");
    Ok(())
}

fn run_fit(o: &Opts, pop: &Population) -> Result<posemfa::model::hierarchy::FitResult, String> {
    let mut pipe = Pipeline::new(pop, &o.params).map_err(|e| e.to_string())?;
    let quiet = o.quiet;
    let mut last_stage = String::new();
    let mut observer = |p: &Progress| {
        let name = stage_name(&p.stage);
        let top = name.split(' ').next().unwrap_or("").to_string();
        if !quiet && top != last_stage {
            eprintln!("stage: {name}");
            last_stage = top;
        }
        true
    };
    pipe.run(&mut observer).map_err(|e| e.to_string())
}

fn cmd_fit(args: &[String], bench: bool) -> Result<(), String> {
    let o = parse_opts(args)?;
    let t_load = posemfa::clock::now_ms();
    let (pop, truth) = load_inputs(&o.inputs)?;
    let load_ms = posemfa::clock::now_ms() - t_load;
    let mut result = None;
    let mut totals = Vec::new();
    // bench: the kernels right after each fit, so that each fraction compares two measurements of one moment
    let data = if bench { Some(posemfa::model::data::Data::from_population(&pop)) } else { None };
    let mut limits = Vec::new();
    for _ in 0..o.repeat.max(1) {
        let t0 = posemfa::clock::now_ms();
        let r = run_fit(&o, &pop)?;
        totals.push(posemfa::clock::now_ms() - t0);
        if let Some(data) = &data {
            limits.push(posemfa::model::limit::limit_report(data, &r.model.parts, &r.stats, 200.0));
        }
        result = Some(r);
    }
    let result = result.expect("at least one run");
    let fit_ms = median(&mut totals.clone());
    let m = &result.model;
    if bench {
        let data = data.as_ref().expect("bench keeps the data");
        let mut fractions: Vec<f64> = limits.iter().map(|l| l.fraction).collect();
        let limit = limits.last().expect("at least one run");
        let vertex_major = posemfa::model::estep::kernel_rate_vertex_major(data, &m.parts, 200.0);
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
        let out = serde_json::json!({
            "runtime": "native",
            "inputs": o.inputs, "shapes": pop.n_shapes(), "vertices": pop.n_vertices(),
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
    } else {
        let s = &result.stages;
        out!(
            "{} shapes x {} vertices | parts: coarse {} -> refined {} -> final {} | final AECM {} iterations ({}) | RMSE {:.5} (unit box) | {:.0} ms (load {:.0} ms)",
            pop.n_shapes(),
            pop.n_vertices(),
            s.coarse_parts,
            s.refined_parts,
            s.final_parts,
            m.iterations,
            if m.converged { "converged" } else { "NOT converged: iteration cap reached" },
            m.rmse(&pop),
            fit_ms,
            load_ms
        );
        if let Some(g) = &truth {
            out!("  ground truth: {}", ground_truth_json(g, m));
        }
        for st in &result.stats {
            out!("  {:<7} {:>8.1} ms  {:>5} iterations in {:>3} AECM runs", st.name, st.ms, st.iterations, st.aecm_runs);
        }
    }
    if let Some(path) = &o.json {
        let _ = FitJson::new(&pop, &result);
        std::fs::write(path, fit_to_json(&pop, &result)).map_err(|e| format!("cannot write {path}: {e}"))?;
        if !bench {
            out!("wrote {path}");
        }
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

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let res = match args.first().map(String::as_str) {
        Some("inspect") => cmd_inspect(&args[1..]),
        Some("generate") => cmd_generate(&args[1..]),
        Some("fit") => cmd_fit(&args[1..], false),
        Some("bench") => cmd_fit(&args[1..], true),
        Some("interpolate") => cmd_interpolate(&args[1..]),
        Some("export-gltf") => cmd_export_gltf(&args[1..]),
        Some("articulate-report") => cmd_articulate_report(&args[1..]),
        Some("help") | Some("--help") | Some("-h") => {
            out!("{USAGE}");
            Ok(())
        }
        Some(other) => Err(format!("unknown command '{other}'\n\n{USAGE}")),
        None => Err(USAGE.to_string()),
    };
    match res {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

// ---------------------------------------------------------------- articulation (issue 4)

const ARTICULATE_USAGE: &str = "ARTICULATION (each fits DIR first; fit options as for `fit`; poses are 1-based, natural order):
  posemfa interpolate DIR --from I --to J --t T --out pose.obj [--skin rigid|smooth] [--blend dq|lbs]
                      [--no-residual] [--paper-root] [--paper] [--linear]
      one interpolated pose as OBJ in the original units with the population's faces.
      --skin       rigid (default: every vertex on its part) or smooth (weights across part boundaries)
      --blend      smooth skin blending: dq (dual quaternion, default) or lbs (linear blend)
      --no-residual  leave out eq 24's residual (ends = rigid reconstructions)
      --paper-root   the paper's root (smallest rotation) instead of the anchor (largest part)
      --paper        Algorithm 2 as printed: paper root, BFS tree, no joint-offset blending (ends not exact)
      --linear       plain linear vertex interpolation of the two poses (the baseline)
      --band B       smooth weights: blend half-width as a fraction of the smaller part's RMS radius (default 1)
  posemfa export-gltf DIR --out model.glb [--weights rigid|smooth] [--bind N] [--samples N]
      binary glTF 2.0: mesh bound in pose N's rigid reconstruction (default 1), skeleton, skin, clips
      \"training poses\" (one pose per second) and \"interpolated\" (N samples per second, default 10)
  posemfa articulate-report DIR --from I --to J [--t T] [--glb OUT.glb [--validate]]
      endpoint errors, volume and edge stretch at t (default 0.5) for every method, as JSON; with --glb
      also writes the rigid .glb and checks its animation; --validate runs scripts/validate-gltf.mjs on it
";

/// Splits `args` into the articulation flags in `flags` (name -> takes a value) and the rest (fit options
/// and inputs), which `parse_opts` reads.
fn split_articulate_args(
    args: &[String],
    flags: &[(&str, bool)],
) -> Result<(std::collections::BTreeMap<String, String>, Vec<String>), String> {
    let mut mine = std::collections::BTreeMap::new();
    let mut rest = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match flags.iter().find(|(n, _)| n == a) {
            Some((name, true)) => {
                let v = it.next().ok_or_else(|| format!("{name} needs a value"))?;
                mine.insert(name.to_string(), v.clone());
            }
            Some((name, false)) => {
                mine.insert(name.to_string(), String::new());
            }
            None => rest.push(a.clone()),
        }
    }
    Ok((mine, rest))
}

fn pose_arg(m: &std::collections::BTreeMap<String, String>, name: &str, n: usize) -> Result<usize, String> {
    let v = m.get(name).ok_or_else(|| format!("{name} is required\n\n{ARTICULATE_USAGE}"))?;
    let k: usize = v.parse().map_err(|_| format!("{name}: '{v}' is not a pose number"))?;
    if k == 0 || k > n {
        return Err(format!("{name} {k}: poses are numbered 1 to {n} (natural order of the file names)"));
    }
    Ok(k - 1)
}

fn articulate_fit(
    rest: &[String],
    m: &std::collections::BTreeMap<String, String>,
) -> Result<(Population, posemfa::articulate::Articulation), String> {
    let mut o = parse_opts(rest).map_err(|e| format!("{e}\n{ARTICULATE_USAGE}"))?;
    o.quiet = true;
    let band = match m.get("--band") {
        Some(v) => v.parse().map_err(|_| format!("--band: '{v}' is not a number"))?,
        None => posemfa::articulate::skin::DEFAULT_BAND,
    };
    let (pop, _truth) = load_inputs(&o.inputs)?;
    let result = run_fit(&o, &pop)?;
    let art = posemfa::articulate::Articulation::with_band(&result.model, &pop, band).map_err(|e| e.to_string())?;
    Ok((pop, art))
}

fn cmd_interpolate(args: &[String]) -> Result<(), String> {
    use posemfa::articulate::{Blend, Options, RootRule, Skin};
    let (m, rest) = split_articulate_args(
        args,
        &[
            ("--from", true),
            ("--to", true),
            ("--t", true),
            ("--out", true),
            ("--skin", true),
            ("--band", true),
            ("--blend", true),
            ("--no-residual", false),
            ("--paper-root", false),
            ("--paper", false),
            ("--linear", false),
        ],
    )?;
    let out = m.get("--out").ok_or_else(|| format!("--out is required\n\n{ARTICULATE_USAGE}"))?.clone();
    let t: f64 = m
        .get("--t")
        .ok_or_else(|| format!("--t is required\n\n{ARTICULATE_USAGE}"))?
        .parse()
        .map_err(|_| "--t: not a number".to_string())?;
    let mut opts = if m.contains_key("--paper") { Options::paper() } else { Options::default() };
    if m.contains_key("--paper-root") {
        opts.root = RootRule::Paper;
    }
    if m.contains_key("--no-residual") {
        opts.residual = false;
    }
    opts.skin = match m.get("--skin").map(String::as_str) {
        None | Some("rigid") => Skin::Rigid,
        Some("smooth") => Skin::Smooth,
        Some(o) => return Err(format!("--skin {o}: use rigid or smooth")),
    };
    opts.blend = match m.get("--blend").map(String::as_str) {
        None | Some("dq") => Blend::DualQuaternion,
        Some("lbs") => Blend::Linear,
        Some(o) => return Err(format!("--blend {o}: use dq or lbs")),
    };
    let (pop, art) = articulate_fit(&rest, &m)?;
    let i = pose_arg(&m, "--from", pop.n_shapes())?;
    let j = pose_arg(&m, "--to", pop.n_shapes())?;
    let (pos, how) = if m.contains_key("--linear") {
        (art.linear(i, j, t).map_err(|e| e.to_string())?, "linear vertex interpolation".to_string())
    } else {
        let p = art.interpolate(i, j, t, &opts).map_err(|e| e.to_string())?;
        (p, serde_json::to_string(&opts).unwrap_or_default())
    };
    let header = format!(
        "posemfa interpolate: pose {} -> {} ({} -> {}) at t = {t}\n{how}",
        i + 1,
        j + 1,
        pop.names[i],
        pop.names[j]
    );
    let text = posemfa::export::obj::write_obj(&art.to_original(&pos), &pop.faces, &header);
    std::fs::write(&out, text).map_err(|e| format!("cannot write {out}: {e}"))?;
    println!("wrote {out}");
    Ok(())
}

fn cmd_export_gltf(args: &[String]) -> Result<(), String> {
    use posemfa::export::gltf::{GltfOptions, Weights};
    let (m, rest) =
        split_articulate_args(args, &[("--out", true), ("--weights", true), ("--bind", true), ("--samples", true), ("--band", true)])?;
    let out = m.get("--out").ok_or_else(|| format!("--out is required\n\n{ARTICULATE_USAGE}"))?.clone();
    let mut g = GltfOptions::default();
    g.weights = match m.get("--weights").map(String::as_str) {
        None | Some("rigid") => Weights::Rigid,
        Some("smooth") => Weights::Smooth,
        Some(o) => return Err(format!("--weights {o}: use rigid or smooth")),
    };
    if let Some(s) = m.get("--samples") {
        g.samples_per_second = s.parse().map_err(|_| format!("--samples: '{s}' is not a number"))?;
    }
    let (pop, art) = articulate_fit(&rest, &m)?;
    if m.contains_key("--bind") {
        g.bind_pose = pose_arg(&m, "--bind", pop.n_shapes())?;
    }
    let glb = posemfa::export::gltf::to_glb(&art, &g).map_err(|e| e.to_string())?;
    std::fs::write(&out, &glb).map_err(|e| format!("cannot write {out}: {e}"))?;
    println!("wrote {out} ({} bytes, {} parts, {} poses)", glb.len(), art.graph.used_parts().len(), pop.n_shapes());
    Ok(())
}

fn cmd_articulate_report(args: &[String]) -> Result<(), String> {
    let (m, rest) = split_articulate_args(
        args,
        &[("--from", true), ("--to", true), ("--t", true), ("--glb", true), ("--validate", false), ("--band", true)],
    )?;
    let t: f64 = match m.get("--t") {
        Some(v) => v.parse().map_err(|_| format!("--t: '{v}' is not a number"))?,
        None => 0.5,
    };
    let t0 = posemfa::clock::now_ms();
    let (pop, art) = articulate_fit(&rest, &m)?;
    let fit_ms = posemfa::clock::now_ms() - t0;
    let i = pose_arg(&m, "--from", pop.n_shapes())?;
    let j = pose_arg(&m, "--to", pop.n_shapes())?;
    let rep = posemfa::articulate::report::report(&art, i, j, t).map_err(|e| e.to_string())?;
    let mut out = serde_json::to_value(&rep).map_err(|e| e.to_string())?;
    out["inputs"] = serde_json::json!(rest.iter().filter(|a| !a.starts_with("--")).collect::<Vec<_>>());
    out["fit_ms"] = serde_json::json!(fit_ms);
    if let Some(path) = m.get("--glb") {
        let g = posemfa::export::gltf::GltfOptions::default();
        let glb = posemfa::export::gltf::to_glb(&art, &g).map_err(|e| e.to_string())?;
        std::fs::write(path, &glb).map_err(|e| format!("cannot write {path}: {e}"))?;
        let check = posemfa::export::gltf::check_glb(&art, &glb).map_err(|e| e.to_string())?;
        let mut gl = serde_json::json!({ "path": path, "bytes": glb.len(), "check": check });
        if m.contains_key("--validate") {
            let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/validate-gltf.mjs");
            let res = std::process::Command::new("node")
                .arg(script)
                .arg(path)
                .output()
                .map_err(|e| format!("cannot run node {script}: {e}"))?;
            let text = String::from_utf8_lossy(&res.stdout).into_owned();
            gl["validator"] = serde_json::from_str(&text).unwrap_or(serde_json::json!({
                "error": format!("validator did not print JSON (exit {:?}): {} {}", res.status.code(), text, String::from_utf8_lossy(&res.stderr))
            }));
        }
        out["gltf"] = gl;
    }
    println!("{}", serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?);
    Ok(())
}

/// A folder / files, or `synth:PRESET[:VERTICES[:POSES[:SEED[:BAND[:MAX_ANGLE]]]]]` (a generated population with its truth).
fn load_inputs(inputs: &[String]) -> Result<(Population, Option<posemfa::synth::Generated>), String> {
    if let [one] = inputs {
        if let Some(rest) = one.strip_prefix("synth:") {
            let mut it = rest.split(':');
            let preset: posemfa::synth::Preset = serde_json::from_value(serde_json::json!(it.next().unwrap_or("")))
                .map_err(|_| format!("unknown preset in '{one}': use quadruped, arm, snake or blob"))?;
            let mut spec = posemfa::synth::Spec { preset, ..Default::default() };
            let num = |v: Option<&str>, what: &str| -> Result<Option<u64>, String> {
                v.map(|v| v.parse::<u64>().map_err(|_| format!("{what} '{v}' in '{one}' is not a number"))).transpose()
            };
            if let Some(v) = num(it.next(), "vertex count")? {
                spec.vertices = v as usize;
            }
            if let Some(v) = num(it.next(), "pose count")? {
                spec.poses = v as usize;
            }
            if let Some(v) = num(it.next(), "seed")? {
                spec.seed = v;
            }
            let float = |v: Option<&str>, what: &str| -> Result<Option<f64>, String> {
                v.map(|v| v.parse::<f64>().map_err(|_| format!("{what} '{v}' in '{one}' is not a number"))).transpose()
            };
            if let Some(v) = float(it.next(), "joint band")? {
                spec.joint_band = v;
            }
            if let Some(v) = float(it.next(), "max angle")? {
                spec.max_angle_deg = v;
            }
            let g = posemfa::synth::generate(&spec).map_err(|e| e.to_string())?;
            return Ok((g.population.clone(), Some(g)));
        }
    }
    Ok((Population::from_paths(inputs).map_err(|e| e.to_string())?, None))
}

/// Adjusted Rand index of the labels and rotation errors (degrees) against a generated population's truth.
fn ground_truth_json(g: &posemfa::synth::Generated, m: &posemfa::model::Model) -> serde_json::Value {
    let ari = posemfa::metrics::adjusted_rand_index(&m.labels, &g.part_of_vertex);
    let fitted: Vec<Vec<posemfa::geometry::Mat3>> = m.parts.iter().map(|p| p.rotations.clone()).collect();
    let errs = posemfa::metrics::rotation_errors_deg(&fitted, &m.labels, &g.rotations, &g.part_of_vertex)
        .unwrap_or_default();
    let max = errs.iter().cloned().fold(0.0, f64::max);
    serde_json::json!({
        "ari": ari, "true_parts": g.n_parts(),
        "rotation_error_deg_median": posemfa::metrics::median(&errs), "rotation_error_deg_max": max,
    })
}

fn cmd_generate(args: &[String]) -> Result<(), String> {
    let mut spec = posemfa::synth::Spec::default();
    let mut out_dir = None;
    let mut it = args.iter();
    let mut preset_set = false;
    while let Some(a) = it.next() {
        let mut val = |name: &str| it.next().cloned().ok_or_else(|| format!("{name} needs a value"));
        fn num<T: std::str::FromStr>(name: &str, v: String) -> Result<T, String> {
            v.parse().map_err(|_| format!("{name}: '{v}' is not a valid number"))
        }
        match a.as_str() {
            "--vertices" => spec.vertices = num("--vertices", val("--vertices")?)?,
            "--poses" => spec.poses = num("--poses", val("--poses")?)?,
            "--seed" => spec.seed = num("--seed", val("--seed")?)?,
            "--band" => spec.joint_band = num("--band", val("--band")?)?,
            "--noise" => spec.noise = num("--noise", val("--noise")?)?,
            "--max-angle" => spec.max_angle_deg = num("--max-angle", val("--max-angle")?)?,
            "--out" => out_dir = Some(val("--out")?),
            s if s.starts_with("--") => return Err(format!("unknown option {s}\n\n{USAGE}")),
            s if !preset_set => {
                spec.preset = serde_json::from_value(serde_json::json!(s))
                    .map_err(|_| format!("unknown preset '{s}': use quadruped, arm, snake or blob"))?;
                preset_set = true;
            }
            s => return Err(format!("unexpected argument '{s}'\n\n{USAGE}")),
        }
    }
    let out_dir = out_dir.ok_or_else(|| format!("generate needs --out DIR\n\n{USAGE}"))?;
    let g = posemfa::synth::generate(&spec).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&out_dir).map_err(|e| format!("cannot create {out_dir}: {e}"))?;
    for (name, text) in posemfa::synth::obj_files(&g) {
        let path = std::path::Path::new(&out_dir).join(&name);
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    out!(
        "wrote {} poses of the {} ({} vertices, {} parts) to {out_dir}",
        g.population.n_shapes(),
        spec.preset.name(),
        g.population.n_vertices(),
        g.n_parts()
    );
    Ok(())
}
