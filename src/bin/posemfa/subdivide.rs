//! `posemfa subdivide DIR_OR_FILES... --out DIR [--levels N]`: a finer registered population for measuring.

use crate::shared::{inputs_help, load_inputs};
use clap::ValueHint;

/// Split every triangle in four at its edge midpoints, the same in every pose (the population stays registered),
/// and write one OBJ file per pose, in the input's units and with its names (issue 27's high-resolution data:
/// horse-gallop once gives about 34 k vertices x 49 poses)
#[derive(clap::Args)]
#[command(next_help_heading = "Subdivide options")]
pub struct Args {
    #[arg(value_name = "DIR_OR_FILES", required = true, value_hint = ValueHint::AnyPath, help = format!("A {}", inputs_help()),
          help_heading = "Arguments")]
    inputs: Vec<String>,
    /// Folder to write the OBJ files to (created if missing; files of the same names are overwritten)
    #[arg(long, value_name = "DIR", value_hint = ValueHint::DirPath)]
    out: String,
    /// How many times to subdivide (each multiplies the triangles by 4)
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=4))]
    levels: u8,
}

pub fn run(a: Args) -> Result<(), String> {
    let (pop, _truth) = load_inputs(&a.inputs, &Default::default())?;
    let (faces, shapes) = posemfa::mesh::subdivide::subdivide(&pop, a.levels as usize).map_err(|e| e.to_string())?;
    let out_dir = std::path::Path::new(&a.out);
    std::fs::create_dir_all(out_dir).map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    for (name, shape) in pop.names.iter().zip(&shapes) {
        let stem = std::path::Path::new(name).file_stem().map_or(name.clone(), |s| s.to_string_lossy().into_owned());
        let header = format!("{name} subdivided {} time(s) at edge midpoints by posemfa subdivide", a.levels);
        let text = posemfa::export::obj::write_obj(shape, &faces, &header);
        let path = out_dir.join(format!("{stem}.obj"));
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    out!(
        "wrote {} poses of {} vertices and {} triangles (from {} and {}) to {}",
        shapes.len(),
        shapes.first().map_or(0, Vec::len),
        faces.len(),
        pop.n_vertices(),
        pop.faces.len(),
        out_dir.display()
    );
    Ok(())
}
