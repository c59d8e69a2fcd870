//! `posemfa inspect DIR_OR_FILES`: what `fit` would read from the inputs (any format it reads, a folder, a
//! `.zip`), without fitting: where the poses came from, how many, the vertices and triangles, what was welded.

use crate::shared::InputArgs;

/// Read the inputs as `fit` reads them and say what they hold: where the poses came from, the poses, vertices,
/// triangles and what the reader welded (exit 1 with the reader's error when they do not read)
#[derive(clap::Args)]
#[command(next_help_heading = "Inspect options")]
pub struct Args {
    /// Print JSON (the same fields) instead of text
    #[arg(long)]
    json: bool,
    /// With --json: also the first pose's vertices (in the file's units, as the readers give them) and the
    /// triangles
    #[arg(long, requires = "json")]
    geometry: bool,
    /// (last: its options under their own heading)
    #[command(flatten)]
    input: InputArgs,
}

/// What a glTF, FBX or USD reader says it welded: "7176 vertices welded to 1198 (seams split by the exporter)"
/// in the source line (written by `mesh::gltf` and `mesh::fbx`'s weld, which the USD reader shares): the
/// count in the file, the count kept and why.
fn welded(source: &str) -> Option<(usize, usize, String)> {
    let at = source.find(" vertices welded to ")?;
    let n_file = source[..at].rsplit(|c: char| !c.is_ascii_digit()).next()?.parse().ok()?;
    let rest = &source[at + " vertices welded to ".len()..];
    let digits = rest.find(|c: char| !c.is_ascii_digit()).unwrap_or(rest.len());
    let n_kept = rest[..digits].parse().ok()?;
    let why = rest[digits..].trim_start();
    let why = why.strip_prefix('(').and_then(|w| w.split_once(')')).map_or("", |(w, _)| w).to_string();
    Some((n_file, n_kept, why))
}

/// What inspect prints, from a population or from one pose file.
struct Summary {
    source: String,
    names: Vec<String>,
    faces: Vec<[u32; 3]>,
    /// The first pose's vertices, in the units read.
    first: Vec<[f64; 3]>,
}

/// The inputs as `fit` reads them; one OBJ or PLY file alone (which `fit` refuses: it needs two poses) as the
/// same reader reads it.
fn read(input: &InputArgs) -> Result<Summary, String> {
    let population_error = match input.load() {
        Ok((pop, _truth)) => {
            let first = pop.shape(0).iter().map(|p| pop.normalization.to_original(p)).collect();
            return Ok(Summary {
                source: pop.source.clone(),
                names: pop.names.clone(),
                faces: pop.faces.to_vec(),
                first,
            });
        }
        Err(e) => e,
    };
    let [one] = &input.inputs[..] else { return Err(population_error) };
    let path = std::path::Path::new(one);
    let name = path.file_name().map_or(one.clone(), |n| n.to_string_lossy().into_owned());
    let kind = posemfa::mesh::load::FileKind::of(&name);
    if !path.is_file() || !matches!(kind, posemfa::mesh::load::FileKind::Obj | posemfa::mesh::load::FileKind::Ply) {
        return Err(population_error);
    }
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {one}: {e}"))?;
    let mesh = posemfa::mesh::load::read_mesh(&name, &bytes).map_err(|e| e.to_string())?;
    let what = if kind == posemfa::mesh::load::FileKind::Obj { "OBJ" } else { "PLY" };
    Ok(Summary {
        source: format!("1 {what} file (one pose: fit needs at least 2 poses of the same mesh)"),
        names: vec![name],
        faces: mesh.faces,
        first: mesh.positions,
    })
}

pub fn run(a: Args) -> Result<(), String> {
    a.input.no_model("inspect")?;
    let s = read(&a.input)?;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &s.first {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let weld = welded(&s.source);
    if a.json {
        let mut out = serde_json::json!({
            "source": s.source,
            "n_poses": s.names.len(),
            "poses": s.names,
            "n_vertices": s.first.len(),
            "n_triangles": s.faces.len(),
            "welded": weld.as_ref().map(|(n_file, n_kept, why)| serde_json::json!({
                "vertices_in_file": n_file, "vertices": n_kept, "why": why,
            })),
            "first_pose_bounds": { "min": lo, "max": hi },
        });
        if a.geometry {
            out["vertices"] = serde_json::json!(s.first);
            out["triangles"] = serde_json::json!(s.faces);
        }
        out!("{out}");
        return Ok(());
    }
    let n = s.names.len();
    let names =
        if n <= 4 { s.names.join(", ") } else { format!("{}, {}, ..., {}", s.names[0], s.names[1], s.names[n - 1]) };
    let weld_text = match &weld {
        Some((n_file, n_kept, why)) => format!("{n_file} vertices in the file welded to {n_kept} ({why})"),
        None => "none".to_string(),
    };
    let size: Vec<String> = (0..3).map(|d| format!("{:.4}", hi[d] - lo[d])).collect();
    out!("source:     {}", s.source);
    out!("poses:      {n}: {names}");
    out!("vertices:   {}", s.first.len());
    out!("triangles:  {}", s.faces.len());
    out!("welded:     {weld_text}");
    out!("first pose: {} (x, y, z extent, in the units read)", size.join(" x "));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::welded;

    #[test]
    fn the_weld_is_read_off_the_source_line() {
        let s =
            "6 frames of mesh in a.glb (animation 'Walk'); 7176 vertices welded to 1198 (seams split by the exporter)";
        assert_eq!(welded(s), Some((7176, 1198, "seams split by the exporter".into())));
        assert_eq!(welded("5 frames of Body in q.usdc (time-sampled points); upAxis Y; 408 vertices"), None);
    }
}
