//! How the fuzz targets (`fuzz/`, `scripts/fuzz.sh`) read their bytes. Kept in the library so that the
//! targets and the crash inputs kept as plain tests (`tests/fuzz_regressions.rs`) decode an input the same way.

use crate::geometry::Vec3;
use crate::model::Params;

/// Small, fast fit parameters chosen by a target's config byte (byte 0 of every input that fits).
pub fn params_from(cfg: u8) -> Params {
    Params {
        parts: 1 + (cfg as usize >> 4) % 5,
        seed: cfg as u64,
        max_iter: 4,
        restarts: 1,
        refine: cfg & 1 == 1,
        max_subparts: 2,
        refine_max_iter: 3,
        min_part_vertices: 1 + (cfg as usize >> 1) % 3,
        ..Params::default()
    }
}

/// An input of the `shapes` target, decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapesInput {
    pub cfg: u8,
    /// "s0", "s1", ...
    pub names: Vec<String>,
    /// [0, 1, 2] first, then the input's faces (indices may be out of range).
    pub faces: Vec<[u32; 3]>,
    pub shapes: Vec<Vec<Vec3>>,
}

/// The `shapes` target's layout: byte 0 configures the fit ([`params_from`]); byte 1: bits 0-1 the number
/// format (0/3: i8 on a grid of 1/16, 1: i16 / 256, 2: raw f64 bits, so NaN and infinities too), bits 2-4 the
/// number of shapes - 2, bits 5-7 the number of extra faces; then the extra faces (3 bytes each); the rest is
/// read as coordinates, shape after shape (a partial vertex at the end is dropped). None below 2 bytes.
pub fn decode_shapes(data: &[u8]) -> Option<ShapesInput> {
    let [cfg, layout, rest @ ..] = data else { return None };
    let format = layout & 3;
    let n_shapes = 2 + ((layout >> 2) & 7) as usize;
    let n_faces = ((layout >> 5) & 7) as usize;
    let (face_bytes, coords) = rest.split_at((3 * n_faces).min(rest.len()));
    let mut faces = vec![[0u32, 1, 2]];
    faces.extend(face_bytes.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]));
    let values: Vec<f64> = match format {
        1 => coords.chunks_exact(2).map(|c| i16::from_le_bytes([c[0], c[1]]) as f64 / 256.0).collect(),
        2 => coords.chunks_exact(8).map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])).collect(),
        _ => coords.iter().map(|&b| b as i8 as f64 / 16.0).collect(),
    };
    let n_vertices = values.len() / (3 * n_shapes);
    let shapes = (0..n_shapes)
        .map(|i| (0..n_vertices).map(|j| [0, 1, 2].map(|d| values[(i * n_vertices + j) * 3 + d])).collect())
        .collect();
    Some(ShapesInput { cfg: *cfg, names: (0..n_shapes).map(|i| format!("s{i}")).collect(), faces, shapes })
}
