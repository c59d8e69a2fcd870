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

FIT OPTIONS:
  --parts M          coarse parts (default 11)
  --seed S           random seed (default 0)
  --tol T            convergence tolerance on |dL|/n_v (default 1e-3)
  --max-iter N       iteration cap per AECM run (default 300)
  --floor F          variance floor, unit-box units^2 (default 1e-7)
  --literal-eq18     use the paper's literal eq 18 for Lambda (breaks monotonicity; for teaching)
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
            "--literal-eq18" => o.params.lambda_rule = LambdaRule::PaperEq18,
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
    let pop = Population::from_paths(&o.inputs).map_err(|e| e.to_string())?;
    let load_ms = posemfa::clock::now_ms() - t_load;
    let mut result = None;
    let mut totals = Vec::new();
    for _ in 0..o.repeat.max(1) {
        let t0 = posemfa::clock::now_ms();
        let r = run_fit(&o, &pop)?;
        totals.push(posemfa::clock::now_ms() - t0);
        result = Some(r);
    }
    let result = result.expect("at least one run");
    let fit_ms = median(&mut totals.clone());
    let m = &result.model;
    if bench {
        let stages: Vec<_> = result
            .stats
            .iter()
            .map(|s| {
                serde_json::json!({
                    "stage": s.name, "ms": s.ms, "iterations": s.iterations, "aecm_runs": s.aecm_runs,
                    "estep_ms": s.estep_ms, "estep_gflop": s.estep_flops / 1e9,
                    "estep_gflops_per_s": if s.estep_ms > 0.0 { s.estep_flops / s.estep_ms / 1e6 } else { 0.0 },
                })
            })
            .collect();
        let out = serde_json::json!({
            "runtime": "native",
            "inputs": o.inputs, "shapes": pop.n_shapes(), "vertices": pop.n_vertices(),
            "load_ms": load_ms, "fit_ms_median": fit_ms, "fit_ms_all": totals,
            "parts": m.n_parts(), "rmse": m.rmse(&pop), "stages": stages,
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
        Some("fit") => cmd_fit(&args[1..], false),
        Some("bench") => cmd_fit(&args[1..], true),
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
