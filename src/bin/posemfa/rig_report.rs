//! `posemfa rig-report DIR_OR_FILES... [--glb FILE.glb] [--truth CHARACTER.glb]`: how well a rig's .glb
//! reproduces the poses, and where its joints are against an artist's skeleton.

use crate::shared::{BandArgs, FitArgs, RigArgs};
use clap::ValueHint;

/// Fit, build and write the rig, then play its .glb's "training poses" clip by linear blend skinning and print
/// E_RMS (Kavan et al. 2010), max error, per-pose errors and time per stage as JSON
#[derive(clap::Args)]
#[command(next_help_heading = "Rig-report options")]
pub struct Args {
    /// Measure this .glb (written by export-gltf from the same files) instead of fitting one
    #[arg(long, value_name = "FILE.glb", value_hint = ValueHint::FilePath)]
    glb: Option<String>,
    /// A rigged, animated character whose clip the poses are (the same file): also compare the rig's skeleton
    /// with the artist's (joint distances both ways, root placement, parents, parts against the skeleton)
    #[arg(long, value_name = "CHARACTER.glb", value_hint = ValueHint::FilePath, conflicts_with = "glb")]
    truth: Option<String>,
    /// Also write the .glb that was measured
    #[arg(long, value_name = "rig.glb", value_hint = ValueHint::FilePath)]
    out: Option<String>,
    #[command(flatten)]
    rig: RigArgs,
    #[command(flatten)]
    band: BandArgs,
    #[command(flatten)]
    fit: FitArgs,
}

pub fn run(a: Args) -> Result<(), String> {
    use posemfa::export::gltf::play_glb;
    use posemfa::export::rig_report::rig_error;
    let ms = |t: std::time::Instant| t.elapsed().as_secs_f64() * 1e3;
    let t_all = std::time::Instant::now();
    let mut timings = serde_json::Map::new();
    let t = std::time::Instant::now();
    // the poses, and with --model the fit too (without it the fit is made below, unless --glb gives the rig)
    let (params, pop, mut saved, saved_rig, start) = match &a.fit.input.model {
        Some(_) => {
            let f = a.fit.fitted_with_data("rig-report")?;
            (f.params, f.pop, Some(f.result), f.saved_rig, posemfa::mfa::FitStart::default())
        }
        None => {
            let start = a.fit.start()?;
            let (params, pop, _truth) = a.fit.load()?;
            (params, pop, None, None, start)
        }
    };
    timings.insert("read".into(), ms(t).into());
    let mut info = serde_json::Map::new();
    let glb = match &a.glb {
        Some(file) => {
            let glb = std::fs::read(file).map_err(|e| format!("cannot read {file}: {e}"))?;
            info.insert("glb".into(), file.clone().into());
            glb
        }
        None => {
            let result = match saved.take() {
                Some(result) => result,
                None => {
                    let t = std::time::Instant::now();
                    let result = crate::shared::run_fit(&params, &start, &pop, true)?;
                    timings.insert("fit".into(), ms(t).into());
                    result
                }
            };
            let t = std::time::Instant::now();
            let art = a.band.articulate(&result, &pop)?;
            timings.insert("articulate".into(), ms(t).into());
            let g = a.rig.options(&pop)?;
            let t = std::time::Instant::now();
            let (rig, source) = posemfa::model_file::kept_or_built(saved_rig.as_ref(), &art, &pop, &g.rig_options())
                .map_err(|e| e.to_string())?;
            info.insert("rig_source".into(), source.word().into());
            timings.insert("rig".into(), ms(t).into());
            let t = std::time::Instant::now();
            let glb = posemfa::export::gltf::write_glb(&art, &rig, &g).map_err(|e| e.to_string())?;
            timings.insert("write".into(), ms(t).into());
            info.insert("options".into(), serde_json::to_value(g).unwrap_or_default());
            info.insert("parts".into(), result.model.n_parts().into());
            info.insert(
                "islands".into(),
                posemfa::parts::islands::island_count(&result.model.labels, pop.graph_faces()).into(),
            );
            info.insert("solver_trace".into(), rig.trace.clone().into());
            if let Some(file) = &a.truth {
                let t = std::time::Instant::now();
                let m = skeleton_against(file, &a.fit.input, &pop, &art, &rig, g.bind_pose)?;
                info.insert("skeleton".into(), serde_json::to_value(m).map_err(|e| e.to_string())?);
                timings.insert("skeleton".into(), ms(t).into());
            }
            glb
        }
    };
    if let Some(out) = &a.out {
        std::fs::write(out, &glb).map_err(|e| format!("cannot write {out}: {e}"))?;
    }
    let t = std::time::Instant::now();
    let play = play_glb(&glb).map_err(|e| e.to_string())?;
    let bind = a.rig.bind(&pop)?;
    let err = rig_error(&pop, &play, bind).map_err(|e| e.to_string())?;
    timings.insert("evaluate".into(), ms(t).into());
    timings.insert("total".into(), ms(t_all).into());
    let mut json = serde_json::to_value(&err).map_err(|e| e.to_string())?;
    if let Some(m) = json.as_object_mut() {
        m.insert("bones".into(), play.joint_parent.len().into());
        m.insert("rest".into(), pop.names[bind].clone().into());
        m.insert("bytes".into(), glb.len().into());
        m.insert("timings_ms".into(), timings.into());
        m.extend(info);
    }
    out!("{json}");
    Ok(())
}

/// The rig's skeleton against the artist's of `file` ([`posemfa::articulate::skeleton_match`]).
fn skeleton_against(
    file: &str,
    input: &crate::shared::InputArgs,
    pop: &posemfa::mesh::Population,
    art: &posemfa::articulate::Articulation,
    rig: &posemfa::articulate::rig::Rig,
    bind: usize,
) -> Result<posemfa::articulate::skeleton_match::SkeletonMatch, String> {
    use posemfa::articulate::skeleton_match::{against_rig, read_artist};
    let bytes = std::fs::read(file).map_err(|e| format!("cannot read --truth {file}: {e}"))?;
    let artist = read_artist(file, &bytes, &[], &input.gltf(), pop).map_err(|e| e.to_string())?;
    against_rig(&artist, art, rig, bind).map_err(|e| e.to_string())
}
