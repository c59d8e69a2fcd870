//! Inputs that crashed a fuzz target (scripts/fuzz.sh, fuzz/README.md), kept as plain tests: each is decoded
//! exactly as its target decodes it (`posemfa::fuzzing`, which the targets use) and must now give the
//! answer written beside it. Native and wasm.
//!
//! Where they came from: the targets were first run against the code as it was before the hardening against
//! bad input (commit 96d236b), each fix applied in turn, until a run found nothing more; the inputs below are
//! libFuzzer's crash files of those runs.

#[macro_use]
mod common;

use posemfa::fuzzing::{decode_shapes, params_from, ShapesInput};
use posemfa::mesh::Population;
use posemfa::parts::hierarchy::fit;
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
    /// a `Population` of unit-box shapes (the meshes' check looked at faces only against the other shapes' faces), so
    /// anything indexing vertices by face (part graph, export) would have panicked later.
    fn shapes_face_out_of_range_is_refused() {
        let data = b"\xd5\x21\x01\x0c\x81\x0c\x21\x04\xe9\xe9\xe9\x7f\xe9\xe9\xe9\x7f\xe9\xe9\x81\x0c\x81\x7a\x3f\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x86\xc0\x0c\x81\x0c\x81\x00\x00\x0c\x81\x0c\x81\x00\x00\x86\xc0\x0c\x81\x00\x00\x00\x00\x0c\x81";
        let ShapesInput { names, faces, shapes, .. } = decode_shapes(data).expect("long enough");
        assert_eq!(shapes[0].len(), 4);
        assert_eq!(faces[1], [1, 12, 129]);
        let e = Population::new(posemfa::mesh::Sources::UnitShapes { names, faces, shapes }).unwrap_err();
        assert!(matches!(e, Error::Population { ref file, .. } if file == "s0"), "{e:?}");
        let m = e.to_string();
        assert!(m.contains("triangle 2 is [2, 13, 130]") && m.contains("4 vertices"), "{m}");
    }

    /// ply_parse target: a text PLY whose file ends on `end_header` (no newline, no data) while the header
    /// says 4 vertices. The refusal named line 11 of a 10-line file and "1 bytes of data": it names the
    /// `end_header` line and the 0 bytes that follow.
    fn ply_header_ending_the_file_is_refused_at_a_line_it_has() {
        let data = b"ply\nformat ascii 1.0\ncomment tiny_tet\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header";
        let e = posemfa::mesh::ply::parse_ply("fuzz.ply", data).unwrap_err();
        assert!(matches!(e, Error::Mesh { line: 10, .. }), "{e:?}");
        assert!(e.to_string().contains("only 0 bytes of data follow, room for at most 0"), "{e}");
        // with the newline the data's line is the next one, which the file has
        let e = posemfa::mesh::ply::parse_ply("fuzz.ply", &[&data[..], b"\n"].concat()).unwrap_err();
        assert!(matches!(e, Error::Mesh { line: 11, .. }), "{e:?}");
    }

    /// shapes target: two shapes of 11 vertices that differ by less than the f32 rounding of the unit box
    /// (1e-6, after centring) are refused by the fit as the same shapes, as `check_motion` documents; the
    /// target's own test of that used 1e-9 and called the refusal a bug (its tolerance is now the fit's).
    fn shapes_equal_to_the_unit_box_rounding_are_the_same_shapes() {
        let data = b"\x21\x02\x00\x00\x00\x00\x00\x00\x00\x2c\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\xf0\x3f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\xf0\x3f\x00\xfc\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x98\x32\xea\x0b\x00\x00\x00\x00\x00\xf0\x3f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x08\x00\x00\x00\xf0\x3f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\xf0\x3f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\xf0\x3f";
        let ShapesInput { cfg, names, faces, shapes } = decode_shapes(data).expect("long enough");
        assert_eq!(shapes.len(), 2);
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names, faces, shapes }).unwrap();
        let e = fit(&pop, &params_from(cfg), &mut |_| true).unwrap_err();
        assert!(matches!(&e, Error::Data(m) if m.contains("all 2 shapes are the same")), "{e:?}");
    }

    /// shapes target, before the fix: 7 vertices in 2 shapes, 3 parts with the refinement. A coarse part of 2
    /// vertices was refitted alone in the refinement and the fit failed with "2 vertices; at least 3 are
    /// needed" (the whole-population minimum applied to a part).
    fn shapes_two_vertex_part_in_the_refinement_fits() {
        let data = b"\x21\x01\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\x81\x0c\x81\x0c\x81\xf4\x7e\x0c\xf4\x7e";
        let ShapesInput { cfg, names, faces, shapes } = decode_shapes(data).expect("long enough");
        assert_eq!((shapes.len(), shapes[0].len()), (2, 7));
        let params = params_from(cfg);
        assert!(params.refine && params.algorithm1.parts == 3);
        let pop = Population::new(posemfa::mesh::Sources::UnitShapes { names, faces, shapes }).unwrap();
        assert_fits(&pop, cfg);
    }
}

/// `posemfa::mesh::usd::read` of `bytes` as `name`, as an error message.
fn usd_error(name: &str, bytes: &[u8]) -> String {
    posemfa::mesh::usd::read(name, bytes, &Default::default()).map(|g| g.source).unwrap_err().to_string()
}

/// usd-core's .usdc of the arm point cache with the little-endian `u64` at `at` set to `value`.
fn usdc_with(at: usize, value: u64) -> Vec<u8> {
    let mut b = include_bytes!("fixtures/usd/arm-pointcache.usdc").to_vec();
    b[at..at + 8].copy_from_slice(&value.to_le_bytes());
    b
}

dual_test! {
    /// usd_read target (byte 0: the options, then a .usdc): usd-core's arm point cache with one byte of the
    /// SPECS section mutated, so that the compressed size of its second integer array reads 18 PB. openusd
    /// 0.6.0 allocated that much (`read_compressed`) and the process aborted; now the file is refused first
    /// (src/mesh/usdc_check.rs).
    fn usd_huge_compressed_size_is_refused() {
        let data = include_bytes!("fuzz_regressions/usd_read-openusd-huge-alloc.usdc");
        let (cfg, file) = data.split_first().expect("not empty");
        assert_eq!(*cfg, 0x20);
        assert_eq!(
            usd_error("fuzz.usdc", file),
            "file fuzz.usdc: cannot read the USD crate file (usdc): SPECS claims 18014398509482002 compressed bytes of \
             integers at byte 3647, but only 39 bytes follow; the file is cut or damaged: export it again"
        );
    }

    /// usd_read target (byte 0: the options, then a .usda): 654 bytes of a mangled stage whose property metadata
    /// nests arrays about 40 deep. openusd formats an array of arrays as the escaped text of its elements, which
    /// doubles per level: the read ran for minutes and took gigabytes (the fuzzer's 20 s timeout). Now the text is
    /// refused before openusd parses it (src/mesh/usd.rs, `USDA_MAX_ARRAY_NESTING`).
    fn usda_arrays_nested_past_the_limit_are_refused_at_once() {
        let data = include_bytes!("fuzz_regressions/usd_read-nested-metadata-arrays.usda");
        let (_, file) = data.split_first().expect("not empty");
        let e = usd_error("fuzz.usda", file);
        assert!(
            e.starts_with("file fuzz.usda: cannot read the USDA text: line ")
                && e.contains("its arrays nest deeper than 16 levels"),
            "{e}"
        );
    }

    /// Hand-mutated copies of usd-core's .usdc (tests/fixtures/usd/arm-pointcache.usdc: TOC at byte 26014,
    /// TOKENS at 25216, SPECS at 25936): each refused by the check with what is wrong, none reaching openusd.
    fn usdc_with_damaged_structure_is_refused() {
        let usdc = include_bytes!("fixtures/usd/arm-pointcache.usdc");
        let tail = "; the file is cut or damaged: export it again";
        let cases: Vec<(&str, Vec<u8>, String)> = vec![
            (
                "cut-toc.usdc",
                usdc[..26014 + 8 + 40].to_vec(),
                format!("the table of contents claims 6 sections at byte 26022 (32 bytes each), but only 40 bytes follow{tail}"),
            ),
            (
                "toc-out.usdc",
                usdc_with(16, 26214),
                format!("the table of contents is at byte 26214, outside the file of 26214 bytes{tail}"),
            ),
            (
                "section-out.usdc",
                usdc_with(26014 + 8 + 5 * 32 + 24, 1000),
                format!("section 5 (SPECS) spans bytes 25936 to 26936, past the end of the file (26214 bytes){tail}"),
            ),
            (
                "tokens.usdc",
                usdc_with(25216, 1 << 40),
                format!("TOKENS claims 1099511627776 tokens but holds only 336 bytes of them{tail}"),
            ),
            (
                "compressed.usdc",
                usdc_with(25232, 1 << 50),
                format!("TOKENS claims 1125899906842624 compressed bytes of tokens at byte 25232, but only 293 bytes follow{tail}"),
            ),
            (
                "expanded.usdc",
                usdc_with(25224, 1 << 40),
                format!("TOKENS claims 1099511627776 bytes of tokens at byte 25232, more than its 293 compressed bytes can hold{tail}"),
            ),
            (
                "old.usdc",
                {
                    let mut b = usdc.to_vec();
                    b[9] = 3;
                    b
                },
                "it is crate version 0.3.0, older than 0.4.0; the reader (openusd 0.6.0) reads crate versions 0.4.0 to \
                 0.12.x: save the stage again with a current USD (e.g. usdcat in.usdc -o out.usdc)"
                    .to_string(),
            ),
        ];
        for (name, bytes, message) in cases {
            assert_eq!(usd_error(name, &bytes), format!("file {name}: cannot read the USD crate file (usdc): {message}"));
        }
    }
}

/// The usd_read fuzz target's body (fuzz/fuzz_targets/usd_read.rs) over random mutations of its .usdc seed
/// (fuzz/seeds/arm-pointcache.usdc): byte changes, `u64`s set to edge values (mostly in the TOC and the
/// structural sections, where the counts are), cuts. None may abort or panic; a file that loads gives poses
/// with the welded vertex count and the same faces. `POSEMFA_USD_MUTATIONS` sets how many (default 3000),
/// `POSEMFA_USD_MUTATION_SEED` the random seed (29).
/// Native only (an abort would take the whole wasm test run with it, and it is slow there).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn usd_read_survives_mutated_usdc() {
    use posemfa::fuzzing::{check_pose_read, read_options_from};
    use rand::{Rng, SeedableRng};
    let seed = include_bytes!("../fuzz/seeds/arm-pointcache.usdc");
    let n: usize = std::env::var("POSEMFA_USD_MUTATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(3000);
    let seed_no = std::env::var("POSEMFA_USD_MUTATION_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(29);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed_no);
    // where the TOC points: the structural sections follow the values
    let toc = u64::from_le_bytes(seed[16..24].try_into().unwrap()) as usize;
    let structure = 2896.min(toc);
    let edges = [
        0u64,
        1,
        2,
        3,
        4,
        7,
        8,
        255,
        256,
        4096,
        65535,
        1 << 31,
        1 << 32,
        1 << 40,
        1 << 62,
        u64::MAX,
        u64::MAX - 7,
        i64::MAX as u64,
    ];
    let (mut loaded, mut refused) = (0, 0);
    for _ in 0..n {
        let mut b = seed.to_vec();
        for _ in 0..rng.gen_range(1..=3) {
            let from = if rng.gen_bool(0.8) { structure.min(b.len() - 1) } else { 0 };
            match rng.gen_range(0..4) {
                0 => {
                    let at = rng.gen_range(from..b.len());
                    b[at] = rng.gen();
                }
                1 if b.len() >= 8 => {
                    let at = rng.gen_range(from.min(b.len() - 8)..=b.len() - 8);
                    let v = if rng.gen_bool(0.5) {
                        edges[rng.gen_range(0..edges.len())]
                    } else {
                        rng.gen::<u64>() >> rng.gen_range(0..64)
                    };
                    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
                }
                2 => {
                    let at = rng.gen_range(from..b.len());
                    b[at] ^= 1 << rng.gen_range(0..8);
                }
                _ => {
                    let at = rng.gen_range(from..b.len());
                    b.truncate(at.max(1));
                }
            }
        }
        let options = read_options_from(rng.gen());
        if check_pose_read("fuzz.usdc", &options, posemfa::mesh::usd::read("fuzz.usdc", &b, &options)) {
            loaded += 1;
        } else {
            refused += 1;
        }
    }
    eprintln!(
        "usd_read_survives_mutated_usdc: {n} mutations, {loaded} loaded, {refused} refused, none aborted or panicked"
    );
}

dual_test! {
    /// model_file target: a model file whose header names two poses alike (a mutated byte of "pose02.obj").
    /// The population's check of repeated names answered with the pose's name, not the model file's; now the
    /// model file is refused by its own name, and the fuzz target's whole check passes on it.
    fn model_file_with_a_repeated_pose_name_is_refused_by_its_name() {
        let data = include_bytes!("fuzz_regressions/model_file-repeated-pose-name.posemfa");
        let e = posemfa::model_file::ModelFile::from_bytes("fuzz.posemfa", data).unwrap_err().to_string();
        assert!(e.starts_with("model file fuzz.posemfa: two poses are named 'pose01.obj'"), "{e}");
        posemfa::fuzzing::check_model_file(data);
    }
}
