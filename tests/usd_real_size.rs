//! USD point caches at a real size, written by the real writer: Pixar's usd-core writes a generated
//! quadruped of 30 930 vertices and 61 856 triangles in 8 poses as .usda, .usdc and .usdz
//! (`scripts/fixtures/make-usd-real-size.sh`: time-sampled points under a transformed parent, Z up,
//! centimetres, two compressed float primvars; usd-core compresses `faceVertexCounts`, 61 856 threes, to a few
//! dozen bytes, which the usdc check used to refuse as damaged). Each must read to the OBJ folder of the same
//! poses with the transforms applied, and fit to the same parts: the same count, adjusted Rand >= 0.99, RMSE
//! within 1 %.
//!
//! The files are about 17 MB together, so they are written into a temporary folder when the test runs, not
//! committed (docs/testing.md). That needs a Python with usd-core: `POSEMFA_USD_PYTHON`, else
//! `.venv-fixtures/bin/python` (made by scripts/setup.sh), else `python3` if it imports `pxr`. Without one the
//! test prints `SKIPPED(needs usd-core): NAME` and returns, which scripts/test.sh counts as skipped; with
//! `CI=true` it fails instead.
#![cfg(not(target_arch = "wasm32"))]

#[macro_use]
#[allow(unused_macros)]
mod common;

use common::blender::{assert_same_fit_as_obj, fit_summary, max_diff};
use posemfa::mesh::Population;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A Python that imports usd-core's `pxr`, or None (after the SKIPPED line; a panic under CI=true).
fn usd_python(test: &str) -> Option<PathBuf> {
    use std::io::Write;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut tried = Vec::new();
    let candidates = std::env::var_os("POSEMFA_USD_PYTHON")
        .map(PathBuf::from)
        .into_iter()
        .chain([root.join(".venv-fixtures/bin/python"), PathBuf::from("python3")]);
    for python in candidates {
        let ok = Command::new(&python).args(["-c", "import pxr"]).output().is_ok_and(|o| o.status.success());
        if ok {
            return Some(python);
        }
        tried.push(python.display().to_string());
    }
    let why = format!(
        "no Python with usd-core (tried {}): run scripts/setup.sh, or set POSEMFA_USD_PYTHON",
        tried.join(", ")
    );
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{test}: {why}, and CI=true: the usd-core fixtures must be written in CI");
    }
    let _ = writeln!(std::io::stderr().lock(), "SKIPPED(needs usd-core): {test} ({why})");
    None
}

/// Where pose `k` (0-based) of the fixture's points lands (scripts/fixtures/usd_fixtures.py): /World/Character's
/// translate (0.5 k, 0, 0), rotateXYZ (0, 0, 30), scale 2, then /World/Character/Body's translate (0, 1, 0);
/// then the stage's Z up turned to Y up ((x, y, z) -> (x, z, -y)) and centimetres to metres.
fn usd_expected(k: usize, p: [f64; 3]) -> [f64; 3] {
    let (s, c) = 30f64.to_radians().sin_cos();
    let (x, y, z) = (2.0 * p[0], 2.0 * (p[1] + 1.0), 2.0 * p[2]);
    let (x, y) = (c * x - s * y, s * x + c * y);
    let x = x + 0.5 * k as f64;
    [0.01 * x, 0.01 * z, -0.01 * y]
}

#[test]
fn usd_core_point_caches_of_30k_vertices_give_the_obj_population() {
    let test = "usd_core_point_caches_of_30k_vertices_give_the_obj_population";
    let Some(python) = usd_python(test) else { return };
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("usd-real-size-{}", std::process::id()));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/fixtures/make-usd-real-size.sh");
    let t = std::time::Instant::now();
    let made = Command::new("bash")
        .arg(&script)
        .arg(&dir)
        .env("POSEMFA", env!("CARGO_BIN_EXE_posemfa"))
        .env("USD_PYTHON", &python)
        .output()
        .expect("bash runs");
    assert!(made.status.success(), "{}: {}", script.display(), String::from_utf8_lossy(&made.stderr));
    eprintln!("{test}: files written in {:.1} s", t.elapsed().as_secs_f64());

    let t = std::time::Instant::now();
    let obj = Population::new(posemfa::mesh::Sources::paths(&[dir.join("obj")])).unwrap();
    eprintln!("OBJ folder: read in {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
    assert_eq!(obj.source, "8 OBJ files");
    assert!(obj.n_vertices() >= 30_000, "{}", obj.n_vertices());
    assert_eq!((obj.n_shapes(), obj.n_vertices(), obj.faces.len()), (8, 30_930, 61_856));
    let obj_shapes: Vec<Vec<[f64; 3]>> =
        obj.shapes().map(|s| s.iter().map(|p| obj.normalization.to_original(p)).collect()).collect();
    let (parts_obj, rmse_obj, labels_obj) = fit_summary(&obj);
    let rmse_obj = obj.normalization.length_to_original(rmse_obj);

    for ext in ["usda", "usdc", "usdz"] {
        let name = format!("quadruped.{ext}");
        let bytes = std::fs::metadata(dir.join(&name)).unwrap().len();
        let t = std::time::Instant::now();
        let pop = Population::new(posemfa::mesh::Sources::paths(&[dir.join(&name)]))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        eprintln!("{name} ({bytes} bytes): read in {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(
            pop.source,
            format!(
                "8 frames of Body in {name} (time-sampled points of /World/Character/Body, one per time sample, \
                 times 1 to 8 at 24 per second); upAxis Z turned to Y up, metersPerUnit 0.01 turned to metres; \
                 30930 vertices"
            )
        );
        assert_eq!((pop.n_shapes(), pop.n_vertices()), (8, 30_930), "{name}");
        assert_eq!(pop.faces, obj.faces, "{name}");
        for (k, shape) in pop.shapes().enumerate() {
            let ours: Vec<[f64; 3]> = shape.iter().map(|p| pop.normalization.to_original(p)).collect();
            let want: Vec<[f64; 3]> = obj_shapes[k].iter().map(|&p| usd_expected(k, p)).collect();
            // (both stored as f32 in their unit boxes: about 1e-7 of the boxes, which are 1.4 and 0.04 wide)
            let d = max_diff(&ours, &want);
            assert!(d < 2e-8, "{name} pose {k}: {d}");
        }
        let (parts, rmse, labels) = fit_summary(&pop);
        // RMSE in the OBJ's units: the file's are scaled by 2 (the parent) and 0.01 (centimetres to metres)
        let rmse = pop.normalization.length_to_original(rmse) / 0.02;
        assert_same_fit_as_obj(&name, (parts, rmse, &labels), (parts_obj, rmse_obj, &labels_obj));
    }
    let _ = std::fs::remove_dir_all(&dir);
}
