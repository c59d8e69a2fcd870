//! Blender's glTF and FBX at a real size, written by Blender's own exporters: a generated quadruped of 30 930
//! vertices and 61 856 triangles in 8 poses, as shape keys animated one key per frame
//! (`scripts/fixtures/make-blender-real-size.sh`, headless Debian Blender; never ../shared/data). Each must read
//! to the OBJ folder of the same poses (Blender's Y up: (x, y, z) -> (x, z, -y)), and fit to the same parts:
//! the same count, adjusted Rand >= 0.99, RMSE within 1 %. Reading times (median of 3) are printed against the
//! OBJ folder's (docs/formats.md).
//!
//! The files are about 10 MB together, so they are written into a temporary folder when the test runs, not
//! committed. Without `blender` on the PATH the test prints `SKIPPED(needs blender): NAME` and returns, which
//! scripts/test.sh counts as skipped.
#![cfg(not(target_arch = "wasm32"))]

#[macro_use]
#[allow(unused_macros)]
mod common;

use common::blender::{assert_same_fit_as_obj, fit_summary, max_diff, y_up};
use posemfa::mesh::Population;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Reads `path` three times: the population and the median time in ms.
fn read_timed(path: &Path) -> (Population, f64) {
    let mut times = Vec::new();
    let mut pop = None;
    for _ in 0..3 {
        let t = std::time::Instant::now();
        let p = Population::new(posemfa::mesh::Sources::paths(&[path.to_path_buf()]))
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        times.push(t.elapsed().as_secs_f64() * 1e3);
        pop = Some(p);
    }
    times.sort_by(f64::total_cmp);
    (pop.unwrap(), times[1])
}

#[test]
fn blender_gltf_and_fbx_of_30k_vertices_give_the_obj_population() {
    use std::io::Write;
    let test = "blender_gltf_and_fbx_of_30k_vertices_give_the_obj_population";
    if Command::new("blender").arg("--version").output().map_or(true, |o| !o.status.success()) {
        let _ = writeln!(
            std::io::stderr().lock(),
            "SKIPPED(needs blender): {test} (no `blender` on the PATH: apt-get install -y blender python3-numpy)"
        );
        return;
    }
    let dir: PathBuf = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("blender-real-size-{}", std::process::id()));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/fixtures/make-blender-real-size.sh");
    let t = std::time::Instant::now();
    let made = Command::new("bash")
        .arg(&script)
        .arg(&dir)
        .env("POSEMFA", env!("CARGO_BIN_EXE_posemfa"))
        .output()
        .expect("bash runs");
    assert!(made.status.success(), "{}: {}", script.display(), String::from_utf8_lossy(&made.stderr));
    eprintln!("{test}: files written in {:.1} s", t.elapsed().as_secs_f64());

    let (obj, obj_ms) = read_timed(&dir.join("obj"));
    eprintln!("OBJ folder (8 files): read in {obj_ms:.0} ms (median of 3)");
    assert_eq!((obj.n_shapes(), obj.n_vertices(), obj.faces.len()), (8, 30_930, 61_856));
    let obj_shapes: Vec<Vec<[f64; 3]>> =
        obj.shapes().map(|s| s.iter().map(|p| y_up(obj.normalization.to_original(p))).collect()).collect();
    let (parts_obj, rmse_obj, labels_obj) = fit_summary(&obj);
    let rmse_obj = obj.normalization.length_to_original(rmse_obj);

    for (name, source) in [
        (
            "quadruped-shapekeys.glb",
            "8 frames of animation 'KeyAction' (sampled at its keyframes, 24 fps) of mesh 'posed'",
        ),
        ("quadruped-shapekeys.fbx", "8 frames of posed in quadruped-shapekeys.fbx (animation 'Scene', 24 fps"),
    ] {
        let path = dir.join(name);
        let bytes = std::fs::metadata(&path).unwrap().len();
        let (pop, ms) = read_timed(&path);
        eprintln!("{name} ({bytes} bytes): read in {ms:.0} ms (median of 3), {:.2} x the OBJ folder's", ms / obj_ms);
        assert!(pop.source.starts_with(source), "{name}: {}", pop.source);
        assert_eq!((pop.n_shapes(), pop.n_vertices()), (8, 30_930), "{name}");
        assert_eq!(pop.faces, obj.faces, "{name}: the same triangles, in the same order");
        for (k, shape) in pop.shapes().enumerate() {
            let ours: Vec<[f64; 3]> = shape.iter().map(|p| pop.normalization.to_original(p)).collect();
            // (f32 in the files: about 1e-7 of the 0.9-wide box)
            let d = max_diff(&ours, &obj_shapes[k]);
            assert!(d < 1e-6, "{name} pose {k}: {d}");
        }
        let (parts, rmse, labels) = fit_summary(&pop);
        let rmse = pop.normalization.length_to_original(rmse);
        assert_same_fit_as_obj(name, (parts, rmse, &labels), (parts_obj, rmse_obj, &labels_obj));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
