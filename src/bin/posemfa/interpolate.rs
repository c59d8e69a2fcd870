//! `posemfa interpolate DIR_OR_FILES... --from I --to J --t T --out pose.obj`: one interpolated pose as OBJ.

use crate::shared::{articulate_fit, choice, pose_index, pose_number, BandArgs, FitArgs};
use clap::ValueHint;
use posemfa::articulate::{Blend, Options, RootRule, Skin};

const SKINS: &[(&str, Skin)] = &[("rigid", Skin::Rigid), ("smooth", Skin::Smooth)];
const BLENDS: &[(&str, Blend)] = &[("dq", Blend::DualQuaternion), ("lbs", Blend::Linear)];

/// Fit, then write one interpolated pose as OBJ in the original units with the population's faces
#[derive(clap::Args)]
#[command(next_help_heading = "Interpolate options")]
pub struct Args {
    /// First pose
    #[arg(long, value_name = "I", value_parser = pose_number)]
    from: usize,
    /// Second pose
    #[arg(long, value_name = "J", value_parser = pose_number)]
    to: usize,
    /// Where between them: 0 = I, 1 = J
    #[arg(long = "t", value_name = "T")]
    t: f64,
    /// OBJ file to write
    #[arg(long, value_name = "pose.obj", value_hint = ValueHint::FilePath)]
    out: String,
    /// Rigid (default: every vertex on its part) or smooth (weights across part boundaries)
    #[arg(long, value_name = "rigid|smooth", value_parser = choice(SKINS))]
    skin: Option<Skin>,
    /// Smooth skin blending: dq (dual quaternion, default) or lbs (linear blend)
    #[arg(long, value_name = "dq|lbs", value_parser = choice(BLENDS))]
    blend: Option<Blend>,
    /// Leave out eq 24's residual (ends = rigid reconstructions)
    #[arg(long)]
    pub no_residual: bool,
    /// The paper's root (smallest rotation) instead of the anchor (largest part)
    #[arg(long)]
    pub paper_root: bool,
    /// Algorithm 2 as printed: paper root, BFS tree, no joint-offset blending (ends not exact)
    #[arg(long)]
    pub paper: bool,
    /// Plain linear vertex interpolation of the two poses (the baseline)
    #[arg(long)]
    linear: bool,
    #[command(flatten)]
    band: BandArgs,
    #[command(flatten)]
    pub fit: FitArgs,
}

pub fn run(a: Args) -> Result<(), String> {
    let (t, out) = (a.t, a.out.as_str());
    // --paper first: the other choices refine it, whatever their order on the command line
    let mut opts = if a.paper { Options::paper() } else { Options::default() };
    if a.paper_root {
        opts.root = RootRule::Paper;
    }
    if a.no_residual {
        opts.residual = false;
    }
    opts.skin = a.skin.unwrap_or_default();
    opts.blend = a.blend.unwrap_or_default();
    let (pop, art) = articulate_fit("interpolate", &a.fit, &a.band)?;
    let i = pose_index("--from", a.from, pop.n_shapes())?;
    let j = pose_index("--to", a.to, pop.n_shapes())?;
    let (pos, how) = if a.linear {
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
    std::fs::write(out, text).map_err(|e| format!("cannot write {out}: {e}"))?;
    out!("wrote {out}");
    Ok(())
}
