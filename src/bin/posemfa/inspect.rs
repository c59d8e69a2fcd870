//! `posemfa inspect FILE.obj`: one OBJ file's vertices and triangles as JSON.

use clap::ValueHint;

/// Print an OBJ file's vertices and triangles as JSON (exit 1 on error)
#[derive(clap::Args)]
pub struct Args {
    /// The OBJ file
    #[arg(value_name = "FILE.obj", value_hint = ValueHint::FilePath)]
    file: String,
}

pub fn run(a: Args) -> Result<(), String> {
    let file = a.file;
    let bytes = std::fs::read(&file).map_err(|e| format!("cannot read {file}: {e}"))?;
    let name = std::path::Path::new(&file).file_name().map_or(file.clone(), |n| n.to_string_lossy().into_owned());
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
