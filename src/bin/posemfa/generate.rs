//! `posemfa generate PRESET --out DIR`: write a generated population.

use crate::shared::{preset, preset_names};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::ValueHint;
use posemfa::synth::{Preset, Spec};

/// What `--format` writes.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Format {
    /// One OBJ file per pose
    Obj,
    /// One binary PLY file (float32) per pose
    Ply,
    /// One ASCII PLY file per pose
    PlyAscii,
    /// One point cache (poses.pc2) and its base mesh (rest.obj)
    Pc2,
    /// One .glb: a morph target per pose, animated one per frame
    Glb,
}

fn preset_parser() -> impl TypedValueParser<Value = Preset> {
    PossibleValuesParser::new(preset_names()).try_map(|name| preset(&name))
}

/// Write a generated population (quadruped, arm, snake, blob, spider, giraffe, hand) as mesh files
#[derive(clap::Args)]
#[command(next_help_heading = "Generate options")]
pub struct Args {
    /// The creature
    #[arg(value_name = "PRESET", help_heading = "Arguments", default_value = Spec::default().preset.name(), value_parser = preset_parser())]
    preset: Preset,
    /// Folder to write the files to
    #[arg(long, value_name = "DIR", value_hint = ValueHint::DirPath)]
    out: String,
    /// File format
    #[arg(long, value_name = "F", value_enum, default_value_t = Format::Obj)]
    format: Format,
    /// Vertex count
    #[arg(long, value_name = "N", default_value_t = Spec::default().vertices)]
    vertices: usize,
    /// Pose count
    #[arg(long, value_name = "P", default_value_t = Spec::default().poses)]
    poses: usize,
    /// Random seed
    #[arg(long, value_name = "S", default_value_t = Spec::default().seed)]
    seed: u64,
    /// Half-width of the flesh band around each joint
    #[arg(long, value_name = "B", default_value_t = Spec::default().joint_band)]
    band: f64,
    /// Vertex noise, standard deviation
    #[arg(long, value_name = "X", default_value_t = Spec::default().noise)]
    noise: f64,
    /// Largest joint angle, degrees
    #[arg(long, value_name = "DEG", default_value_t = Spec::default().max_angle_deg)]
    max_angle: f64,
}

pub fn run(a: Args) -> Result<(), String> {
    let spec = Spec {
        preset: a.preset,
        vertices: a.vertices,
        poses: a.poses,
        seed: a.seed,
        joint_band: a.band,
        noise: a.noise,
        max_angle_deg: a.max_angle,
        ..Spec::default()
    };
    let out_dir = a.out;
    let g = posemfa::synth::generate(&spec).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&out_dir).map_err(|e| format!("cannot create {out_dir}: {e}"))?;
    let pop = &g.population;
    let files: Vec<(String, Vec<u8>)> = match a.format {
        Format::Obj => posemfa::synth::obj_files(&g).into_iter().map(|(n, t)| (n, t.into_bytes())).collect(),
        Format::Pc2 => {
            let shapes = pop.unit_shapes();
            let rest = posemfa::export::obj::write_obj(&shapes[0], &pop.faces, "faces for poses.pc2 (pose 1)");
            vec![("rest.obj".into(), rest.into_bytes()), ("poses.pc2".into(), posemfa::mesh::cache::write_pc2(&shapes))]
        }
        Format::Glb => {
            let name = spec.preset.name();
            let glb = posemfa::export::morph_glb::write_morph_glb(name, &pop.names, &pop.unit_shapes(), &pop.faces)
                .map_err(|e| e.to_string())?;
            vec![(format!("{name}.glb"), glb)]
        }
        Format::Ply | Format::PlyAscii => {
            use posemfa::export::ply::PlyFormat;
            let fmt = if a.format == Format::Ply { PlyFormat::Binary } else { PlyFormat::Ascii };
            pop.names
                .iter()
                .zip(pop.shapes())
                .map(|(n, s)| {
                    let comment = format!("posemfa synthetic population: preset {}, {n}", spec.preset.name());
                    (n.replace(".obj", ".ply"), posemfa::export::ply::write_ply(&s.to_vec(), &pop.faces, fmt, &comment))
                })
                .collect()
        }
    };
    for (name, bytes) in files {
        let path = std::path::Path::new(&out_dir).join(&name);
        std::fs::write(&path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
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
