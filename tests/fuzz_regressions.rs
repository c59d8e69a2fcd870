//! Inputs that crashed a fuzz target (scripts/fuzz.sh, fuzz/README.md), kept as plain tests: each is decoded
//! exactly as its target decodes it (the layouts are copied from fuzz/fuzz_targets/*.rs) and must now give the
//! answer written beside it. Native and wasm.
//!
//! Where they came from: the targets were first run against the code as it was before the hardening of
//! issue 6 (commit 96d236b), each fix applied in turn, until a run found nothing more; the inputs below are
//! libFuzzer's crash files of those runs.

#[macro_use]
mod common;

use posemfa::mesh::Population;
use posemfa::model::hierarchy::fit;
use posemfa::model::Params;
use posemfa::Error;


/// fuzz/src/lib.rs `params_from`: the fit settings chosen by a target's config byte.
fn params_from(cfg: u8) -> Params {
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

/// fuzz/fuzz_targets/shapes.rs: (config byte, names, faces, shapes).
#[allow(clippy::type_complexity)]
fn decode_shapes(data: &[u8]) -> (u8, Vec<String>, Vec<[u32; 3]>, Vec<Vec<[f64; 3]>>) {
    let [cfg, layout, rest @ ..] = data else { panic!("too short") };
    let format = layout & 3;
    let n_shapes = 2 + ((layout >> 2) & 7) as usize;
    let n_faces = ((layout >> 5) & 7) as usize;
    let (face_bytes, coords) = rest.split_at((3 * n_faces).min(rest.len()));
    let mut faces = vec![[0u32, 1, 2]];
    faces.extend(face_bytes.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]));
    let values: Vec<f64> = match format {
        1 => coords.chunks_exact(2).map(|c| i16::from_le_bytes([c[0], c[1]]) as f64 / 256.0).collect(),
        2 => coords.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect(),
        _ => coords.iter().map(|&b| b as i8 as f64 / 16.0).collect(),
    };
    let n_vertices = values.len() / (3 * n_shapes);
    let shapes = (0..n_shapes)
        .map(|i| (0..n_vertices).map(|j| [0, 1, 2].map(|d| values[(i * n_vertices + j) * 3 + d])).collect())
        .collect();
    (*cfg, (0..n_shapes).map(|i| format!("s{i}")).collect(), faces, shapes)
}

/// The fit of the targets must give a model with every number finite and every rotation proper.
fn assert_fits(pop: &Population, cfg: u8) {
    let result = fit(pop, &params_from(cfg), &mut |_| true).unwrap_or_else(|e| panic!("the fit refused: {e}"));
    let m = &result.model;
    assert!(result.complete);
    assert!(m.log_likelihood.iter().all(|l| l.is_finite()), "{:?}", m.log_likelihood);
    assert!(m.latent.iter().flatten().all(|v| v.is_finite()));
    for c in &m.parts {
        assert!(c.lambda.iter().chain(&c.variances).all(|v| v.is_finite() && *v > 0.0));
        assert!(c.translations.iter().flatten().all(|v| v.is_finite()));
        assert!(c.rotations.iter().all(|r| (posemfa::geometry::det(r) - 1.0).abs() < 1e-9));
    }
}

dual_test! {
    /// shapes target, before the fix: a face naming vertex 130 of a 4-vertex mesh was accepted by
    /// `Population::from_unit_shapes` (from_meshes checked faces only against the other shapes' faces), so
    /// anything indexing vertices by face (part graph, export) would have panicked later.
    fn shapes_face_out_of_range_is_refused() {
        let data = b"\xd5\x21\x01\x0c\x81\x0c\x21\x04\xe9\xe9\xe9\x7f\xe9\xe9\xe9\x7f\xe9\xe9\x81\x0c\x81\x7a\x3f\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x86\xc0\x0c\x81\x0c\x81\x00\x00\x0c\x81\x0c\x81\x00\x00\x86\xc0\x0c\x81\x00\x00\x00\x00\x0c\x81";
        let (_, names, faces, shapes) = decode_shapes(data);
        assert_eq!(shapes[0].len(), 4);
        assert_eq!(faces[1], [1, 12, 129]);
        let e = Population::from_unit_shapes(names, faces, shapes).unwrap_err();
        assert!(matches!(e, Error::Population { ref file, .. } if file == "s0"), "{e:?}");
        let m = e.to_string();
        assert!(m.contains("triangle 2 is [2, 13, 130]") && m.contains("4 vertices"), "{m}");
    }

    /// shapes target, before the fix: 7 vertices in 2 shapes, 3 parts with the refinement. A coarse part of 2
    /// vertices was refitted alone in the refinement and the fit failed with "2 vertices; at least 3 are
    /// needed" (the whole-population minimum applied to a part).
    fn shapes_two_vertex_part_in_the_refinement_fits() {
        let data = b"\x21\x01\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\xf4\x7e";
        let (cfg, names, faces, shapes) = decode_shapes(data);
        assert_eq!((shapes.len(), shapes[0].len()), (2, 7));
        let params = params_from(cfg);
        assert!(params.refine && params.parts == 3);
        let pop = Population::from_unit_shapes(names, faces, shapes).unwrap();
        assert_fits(&pop, cfg);
    }
}
