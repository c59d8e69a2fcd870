//! `posemfa subdivide DIR_OR_FILES... --out DIR [--levels N]`: a finer registered population for measuring.

use crate::shared::InputArgs;
use clap::ValueHint;

/// Split every triangle in four at its edge midpoints, the same in every pose (the population stays registered),
/// and write one OBJ file per pose, in the input's units and with its names (high-resolution test data:
/// horse-gallop once gives about 34 k vertices x 49 poses)
#[derive(clap::Args)]
#[command(next_help_heading = "Subdivide options")]
pub struct Args {
    /// Folder to write the OBJ files to (created if missing; files of the same names are overwritten)
    #[arg(long, value_name = "DIR", value_hint = ValueHint::DirPath)]
    out: String,
    /// How many times to subdivide (each multiplies the triangles by 4)
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=4))]
    levels: u8,
    /// (last: its options under their own heading)
    #[command(flatten)]
    input: InputArgs,
}

pub fn run(a: Args) -> Result<(), String> {
    a.input.no_model("subdivide")?;
    let (pop, _truth) = a.input.load()?;
    let budget = posemfa::memory::budget_bytes().map_err(|e| e.to_string())?;
    let (faces, shapes) =
        posemfa::mesh::subdivide::subdivide(&pop, a.levels as usize, budget).map_err(|e| e.to_string())?;
    let out_dir = std::path::Path::new(&a.out);
    std::fs::create_dir_all(out_dir).map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let mut taken = std::collections::HashSet::new();
    for (i, (name, shape)) in pop.names.iter().zip(&shapes).enumerate() {
        let mut file = format!("{}.obj", file_stem(name));
        if !taken.insert(file.clone()) {
            file = format!("{}-{}.obj", file_stem(name), i + 1);
            taken.insert(file.clone());
        }
        let header = format!("{name} subdivided {} time(s) at edge midpoints by posemfa subdivide", a.levels);
        let text = posemfa::export::obj::write_obj(shape, &faces, &header);
        let path = out_dir.join(&file);
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

/// A pose's file name (without `.obj`) from its name in the population: "0001.obj" -> "0001", "walk.glb frame 3"
/// (a pose of a file that holds many) -> "walk.glb-frame-3"; anything but letters, digits, '.', '_' and '-'
/// becomes '-', so the name is one file in the output folder.
fn file_stem(name: &str) -> String {
    let base = std::path::Path::new(name);
    let whole = match (base.file_stem(), base.extension()) {
        (Some(stem), Some(ext)) if ext.to_string_lossy().chars().all(|c| c.is_ascii_alphanumeric()) => {
            stem.to_string_lossy().into_owned()
        }
        _ => base.file_name().map_or_else(|| name.to_string(), |n| n.to_string_lossy().into_owned()),
    };
    whole.chars().map(|c| if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') { c } else { '-' }).collect()
}

#[cfg(test)]
mod tests {
    use super::file_stem;

    #[test]
    fn every_pose_gets_a_file_name_of_its_own() {
        assert_eq!(file_stem("0001.obj"), "0001");
        assert_eq!(file_stem("walk.glb frame 3"), "walk.glb-frame-3");
        assert_eq!(file_stem("horse.fbx frame 12 (take 'Run')"), "horse.fbx-frame-12--take--Run--");
        assert_eq!(file_stem("poses.pc2 frame 2"), "poses.pc2-frame-2");
    }
}
