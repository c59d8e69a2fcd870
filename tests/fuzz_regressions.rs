//! Inputs that crashed a fuzz target (scripts/fuzz.sh, fuzz/README.md), kept as plain tests: each is decoded
//! exactly as its target decodes it (`posemfa::fuzzing`, which the targets use) and must now give the
//! answer written beside it. Native and wasm.
//!
//! Where they came from: the targets were first run against the code as it was before the hardening of
//! issue 6 (commit 96d236b), each fix applied in turn, until a run found nothing more; the inputs below are
//! libFuzzer's crash files of those runs.

#[macro_use]
mod common;

use posemfa::mesh::Population;
use posemfa::parts::hierarchy::fit;
use posemfa::fuzzing::{decode_shapes, params_from, ShapesInput};
use posemfa::Error;

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
    /// gltf_read target (byte 0: the options, then a .glb): posemfa's rigged export with one animation
    /// channel's path mutated to "tranSlation". The `gltf` crate leaves channel targets unvalidated and
    /// panicked in `Channel::target().property()`; now the file is refused, naming the channel.
    fn gltf_invalid_channel_path_is_refused() {
        let data = include_bytes!("fuzz_regressions/gltf-channel-path-tranSlation.bin");
        let (cfg, file) = data.split_first().expect("not empty");
        assert_eq!(*cfg, 0);
        let e = posemfa::mesh::gltf::read("fuzz.glb", file, &[], &Default::default()).unwrap_err().to_string();
        assert!(e.contains("file fuzz.glb") && e.contains("channel 0 of animation 0 has an invalid target"), "{e}");
    }

    /// gltf_read target (byte 0: the options, then a .glb): the morph-target .glb of the generated snake with
    /// its "accessors" key mutated away, so POSITION names accessor 0 of none. The `gltf` crate's own
    /// validation indexed the accessors with it unchecked and panicked; now the file is refused first.
    fn gltf_position_accessor_out_of_range_is_refused() {
        let data = include_bytes!("fuzz_regressions/gltf-position-accessor-missing.bin");
        let (_, file) = data.split_first().expect("not empty");
        let e = posemfa::mesh::gltf::read("fuzz.glb", file, &[], &Default::default()).unwrap_err().to_string();
        assert!(e.contains("file fuzz.glb") && e.contains("names accessor 0, but the file has 0"), "{e}");
    }

    /// shapes target, before the fix: a face naming vertex 130 of a 4-vertex mesh was accepted by
    /// `Population::from_unit_shapes` (from_meshes checked faces only against the other shapes' faces), so
    /// anything indexing vertices by face (part graph, export) would have panicked later.
    fn shapes_face_out_of_range_is_refused() {
        let data = b"\xd5\x21\x01\x0c\x81\x0c\x21\x04\xe9\xe9\xe9\x7f\xe9\xe9\xe9\x7f\xe9\xe9\x81\x0c\x81\x7a\x3f\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x86\xc0\x0c\x81\x0c\x81\x00\x00\x0c\x81\x0c\x81\x00\x00\x86\xc0\x0c\x81\x00\x00\x00\x00\x0c\x81";
        let ShapesInput { names, faces, shapes, .. } = decode_shapes(data).expect("long enough");
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
        let ShapesInput { cfg, names, faces, shapes } = decode_shapes(data).expect("long enough");
        assert_eq!((shapes.len(), shapes[0].len()), (2, 7));
        let params = params_from(cfg);
        assert!(params.refine && params.parts == 3);
        let pop = Population::from_unit_shapes(names, faces, shapes).unwrap();
        assert_fits(&pop, cfg);
    }
}
