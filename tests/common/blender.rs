//! What the tests of Blender-written fixtures (tests/fixtures/blender/: FBX, glTF, PLY) compare against.

use posemfa::mesh::Population;
use posemfa::synth::{generate, Preset, Spec};

/// The population the Blender fixtures were made from (scripts/fixtures/make-blender-fixtures.sh).
pub fn blender_source() -> posemfa::synth::Generated {
    generate(&Spec { preset: Preset::Quadruped, vertices: 1200, poses: 6, seed: 5, ..Spec::default() }).unwrap()
}

/// Blender is Z-up; its FBX and glTF exporters write Y-up: (x, y, z) -> (x, z, -y).
pub fn y_up(p: [f64; 3]) -> [f64; 3] {
    [p[0], p[2], -p[1]]
}

/// The largest coordinate difference between two point lists.
pub fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (0..3).map(|d| (p[d] - q[d]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max)
}

/// Parts, RMSE and labels of the default fit.
pub fn fit_summary(pop: &Population) -> (usize, f64, Vec<u32>) {
    let r = posemfa::parts::hierarchy::fit(pop, &posemfa::mfa::Params::default(), &mut |_| true).unwrap();
    let rmse = r.model.rmse(pop);
    (r.model.parts.len(), rmse, r.model.labels)
}

/// Asserts that a file's fit (parts, RMSE in the OBJ's units, labels) is the OBJ folder's: the same part count,
/// RMSE within 1 % and adjusted Rand at least 0.99; prints both.
pub fn assert_same_fit_as_obj(name: &str, file: (usize, f64, &[u32]), obj: (usize, f64, &[u32])) {
    let ((parts, rmse, labels), (parts_obj, rmse_obj, labels_obj)) = (file, obj);
    let ari = posemfa::metrics::adjusted_rand_index(labels, labels_obj);
    eprintln!(
        "{name}: {parts} parts, RMSE {rmse:.3e}, ARI {ari:.4}; OBJ folder: {parts_obj} parts, RMSE {rmse_obj:.3e}"
    );
    assert_eq!(parts, parts_obj, "{name}");
    assert!((rmse - rmse_obj).abs() <= 0.01 * rmse_obj, "{name}: RMSE {rmse}, OBJ {rmse_obj}");
    assert!(ari >= 0.99, "{name}: ARI {ari}");
}
