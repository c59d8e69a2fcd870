//! `posemfa articulate-report DIR_OR_FILES... --from I --to J`: every interpolation method's errors as JSON.

use crate::shared::{articulate_fit, pose_index, pose_number, BandArgs, FitArgs};
use clap::ValueHint;

/// Fit, then print endpoint errors, volume and edge stretch at t for every interpolation method, as JSON
#[derive(clap::Args)]
#[command(next_help_heading = "Articulate-report options")]
pub struct Args {
    /// First pose
    #[arg(long, value_name = "I", value_parser = pose_number)]
    from: usize,
    /// Second pose
    #[arg(long, value_name = "J", value_parser = pose_number)]
    to: usize,
    /// Where between them
    #[arg(long = "t", value_name = "T", default_value_t = 0.5)]
    t: f64,
    /// Also write the rigid .glb and check its animation
    #[arg(long, value_name = "OUT.glb", value_hint = ValueHint::FilePath)]
    glb: Option<String>,
    /// With --glb: run scripts/validate-gltf.mjs (Khronos validator) on it
    #[arg(long)]
    validate: bool,
    #[command(flatten)]
    band: BandArgs,
    #[command(flatten)]
    fit: FitArgs,
}

pub fn run(a: Args) -> Result<(), String> {
    let t = a.t;
    let t0 = posemfa::clock::now_ms();
    let (pop, art) = articulate_fit("articulate-report", &a.fit, &a.band)?;
    let fit_ms = posemfa::clock::now_ms() - t0;
    let i = pose_index("--from", a.from, pop.n_shapes())?;
    let j = pose_index("--to", a.to, pop.n_shapes())?;
    let rep = posemfa::articulate::report::report(&art, i, j, t).map_err(|e| e.to_string())?;
    let mut out = serde_json::to_value(&rep).map_err(|e| e.to_string())?;
    out["inputs"] = serde_json::json!(a.fit.input.inputs);
    out["fit_ms"] = serde_json::json!(fit_ms);
    if let Some(path) = &a.glb {
        let g = posemfa::export::gltf::GltfOptions::default();
        let glb = posemfa::export::gltf::to_glb(&art, &g).map_err(|e| e.to_string())?;
        std::fs::write(path, &glb).map_err(|e| format!("cannot write {path}: {e}"))?;
        let check = posemfa::export::gltf::check_glb(&art, &glb).map_err(|e| e.to_string())?;
        let mut gl = serde_json::json!({ "path": path, "bytes": glb.len(), "check": check });
        if a.validate {
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
    out!("{}", serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?);
    Ok(())
}
