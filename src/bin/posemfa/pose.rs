//! `posemfa pose RIG.glb FRAMES... --out OUT.glb`: new frames of the same mesh onto a rig this project wrote.

use clap::ValueHint;
use posemfa::articulate::pose::{e_rms, solve_frames, sse};
use posemfa::export::pose_glb::read_rig;

/// Solve every bone's motion per frame with the rig's weights and bind pose fixed (the rig's own bone step),
/// write the rig with a clip "frames" (keyframe k at k s), play it back from the file and print E_RMS per frame
/// and overall (diagonal: the rig's bind positions)
#[derive(clap::Args)]
#[command(next_help_heading = "Pose options")]
pub struct Args {
    /// A rig .glb written by posemfa (export-gltf, rig-report --out, the page)
    #[arg(value_name = "RIG.glb", value_hint = ValueHint::FilePath, help_heading = "Arguments")]
    rig: String,
    /// Frames of the rig's mesh: a folder of mesh files or the files themselves (any format posemfa reads;
    /// natural order of the names)
    #[arg(value_name = "FRAMES", required = true, value_hint = ValueHint::AnyPath, help_heading = "Arguments")]
    frames: Vec<String>,
    /// The .glb to write (the rig with the clip "frames")
    #[arg(long, value_name = "OUT.glb", required = true, value_hint = ValueHint::FilePath)]
    out: String,
    /// Also write the figures as JSON
    #[arg(long, value_name = "F.json", value_hint = ValueHint::FilePath)]
    json: Option<String>,
}

/// The frames read: every frame's name and positions, in natural order of the names, and the first frame's
/// triangles (the mesh the rig must be).
type Frames = (Vec<(String, Vec<[f64; 3]>)>, Vec<[u32; 3]>);

/// Reads the frame files (folders expanded) in natural order of their names.
pub fn read_frames(paths: &[String]) -> Result<Frames, String> {
    use posemfa::mesh::load::FileKind;
    let mut files: Vec<std::path::PathBuf> = Vec::new();
    for p in paths {
        let p = std::path::Path::new(p);
        if p.is_dir() {
            let rd = std::fs::read_dir(p).map_err(|e| format!("cannot read directory {}: {e}", p.display()))?;
            for entry in rd {
                let path = entry.map_err(|e| format!("cannot read directory {}: {e}", p.display()))?.path();
                let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
                if path.is_file() && FileKind::is_known_extension(&name) {
                    files.push(path);
                }
            }
        } else {
            files.push(p.to_path_buf());
        }
    }
    if files.is_empty() {
        return Err("no frame files found in the given paths: pass a folder of mesh files or the files".into());
    }
    let mut named = Vec::with_capacity(files.len());
    for f in files {
        let bytes = std::fs::read(&f).map_err(|e| format!("cannot read {}: {e}", f.display()))?;
        named.push((f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(), bytes));
    }
    named.sort_by(|a, b| posemfa::mesh::population::natural_cmp(&a.0, &b.0));
    let loaded = posemfa::mesh::load::load(named)
        .map_err(|errors| errors.iter().map(|e| e.to_string()).collect::<Vec<_>>().join("\n"))?;
    let faces = loaded.poses.first().map(|(_, m)| m.faces.clone()).unwrap_or_default();
    Ok((loaded.poses.into_iter().map(|(n, m)| (n, m.positions)).collect(), faces))
}

pub fn run(a: Args) -> Result<(), String> {
    let t_all = std::time::Instant::now();
    let ms = |t: std::time::Instant| t.elapsed().as_secs_f64() * 1e3;
    let bytes = std::fs::read(&a.rig).map_err(|e| format!("cannot read {}: {e}", a.rig))?;
    let rig = read_rig(&a.rig, &bytes).map_err(|e| e.to_string())?;
    let t = std::time::Instant::now();
    let (frames, faces) = read_frames(&a.frames)?;
    let read_ms = ms(t);
    // the rig on the frames' vertices: its own, or its points when the file splits vertices along seams
    let (first_name, first) = &frames[0];
    let on = rig.on_frames(&a.rig, first_name, first.len(), &faces).map_err(|e| e.to_string())?;
    let nv = on.rig.n_vertices();
    if on.file_vertex.is_some() {
        out!(
            "the rig's {} vertices are the frames' {nv} points, some written more than once (split along seams or per \
             face, as exporters do for flat shading): posed and measured at the points",
            rig.rig.n_vertices()
        );
    }
    posemfa::articulate::pose::check_frame_sizes(frames.iter().map(|(n, f)| (n.as_str(), f.len())), nv, Some(&a.rig))
        .map_err(|e| e.to_string())?;
    let points: Vec<Vec<[f64; 3]>> = frames.iter().map(|(_, f)| f.clone()).collect();
    let t = std::time::Instant::now();
    let solved = solve_frames(&on.rig, &points).map_err(|e| e.to_string())?;
    let solve_ms = ms(t);
    let glb = rig.with_clip("frames", &solved.bones).map_err(|e| e.to_string())?;
    std::fs::write(&a.out, &glb).map_err(|e| format!("cannot write {}: {e}", a.out))?;
    // measured on the file as written: its clip played by linear blend skinning from the stored numbers
    let play = posemfa::export::gltf::play_glb_clip(&glb, "frames").map_err(|e| e.to_string())?;
    let d = on.rig.diagonal();
    let mut total = 0.0;
    let mut per_frame = Vec::new();
    for ((name, f), shown) in frames.iter().zip(&play.frames) {
        let e = sse(&on.at_frames(shown), f);
        total += e;
        let x = e_rms(e, nv, d);
        out!("{name}: E_RMS {x:.4}");
        per_frame.push(serde_json::json!({"name": name, "e_rms": x}));
    }
    let overall = e_rms(total, nv * frames.len(), d);
    let steps: Vec<usize> = solved.steps.clone();
    out!(
        "overall E_RMS {overall:.4} over {} frames ({} bones, {nv} vertices, diagonal {d:.6}); solve {:.2} ms per frame; wrote {} ({} bytes)",
        frames.len(),
        rig.rig.order.len(),
        solve_ms / frames.len() as f64,
        a.out,
        glb.len()
    );
    if let Some(path) = &a.json {
        let json = serde_json::json!({
            "rig": a.rig, "out": a.out, "bones": rig.rig.order.len(), "vertices": nv, "diagonal": d,
            "e_rms": overall, "frames": per_frame, "steps": steps,
            "timings_ms": {"read_frames": read_ms, "solve": solve_ms, "solve_per_frame": solve_ms / frames.len() as f64, "total": ms(t_all)},
        });
        std::fs::write(path, json.to_string()).map_err(|e| format!("cannot write {path}: {e}"))?;
    }
    Ok(())
}
