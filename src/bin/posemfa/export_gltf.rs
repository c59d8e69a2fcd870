//! `posemfa export-gltf DIR_OR_FILES... --out model.glb`: the fitted rig as binary glTF 2.0.

use crate::shared::{articulate_fit_rig, BandArgs, FitArgs, RigArgs};
use clap::ValueHint;
use posemfa::model_file::{kept_or_built, RigSource};

/// Fit, then write binary glTF 2.0: mesh bound in one pose, skeleton, skin (rigid, smooth or fitted weights),
/// clips "training poses" (one pose per second) and "interpolated" (rigid/smooth, free joints)
#[derive(clap::Args)]
#[command(next_help_heading = "Export-gltf options")]
pub struct Args {
    /// File to write
    #[arg(long, value_name = "model.glb", value_hint = ValueHint::FilePath)]
    out: String,
    /// Samples per second of the "interpolated" clip (default 10)
    #[arg(long, value_name = "N")]
    samples: Option<usize>,
    #[command(flatten)]
    rig: RigArgs,
    #[command(flatten)]
    band: BandArgs,
    #[command(flatten)]
    fit: FitArgs,
}

pub fn run(a: Args) -> Result<(), String> {
    let out = &a.out;
    let (pop, art, saved_rig) = articulate_fit_rig("export-gltf", &a.fit, &a.band)?;
    let mut g = a.rig.options(&pop)?;
    if let Some(s) = a.samples {
        g.samples_per_second = s;
    }
    // (a model file's own rig when it is this one: the same bytes as building it, without the weight solve)
    let (rig, source) = kept_or_built(saved_rig.as_ref(), &art, &pop, &g.rig_options()).map_err(|e| e.to_string())?;
    let glb = posemfa::export::gltf::write_glb(&art, &rig, &g).map_err(|e| e.to_string())?;
    std::fs::write(out, &glb).map_err(|e| format!("cannot write {out}: {e}"))?;
    out!(
        "wrote {out} ({} bytes, {} parts, {} poses{})",
        glb.len(),
        art.graph.used_parts().len(),
        pop.n_shapes(),
        if source == RigSource::ModelFile { ", the rig kept in the model file" } else { "" }
    );
    Ok(())
}
