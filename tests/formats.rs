//! Mesh files as people have them: fixtures written by other tools, read through the same
//! readers natively and in wasm.

#[macro_use]
mod common;

use common::blender::{blender_source, fit_summary, max_diff, y_up};

use posemfa::mesh::obj::parse_obj;

dual_test! {
    /// 3ds Max writes its OBJ names in the system code page: Latin-1 `mtllib`, `g`, `o`, `usemtl` and
    /// comments must load, and the geometry must be the file's.
    fn latin1_names_from_3ds_max_load() {
        let bytes = include_bytes!("fixtures/latin1-3dsmax.obj");
        assert!(String::from_utf8(bytes.to_vec()).is_err(), "the fixture must not be UTF-8");
        let mesh = parse_obj("latin1-3dsmax.obj", bytes).expect("a Latin-1 material name loads");
        assert_eq!(mesh.positions.len(), 8);
        assert_eq!(mesh.faces.len(), 12);
        assert_eq!(mesh.positions[7], [1.0, 2.0, -1.0]);
        assert_eq!(mesh.faces[0], [0, 2, 3]);
    }
}

use posemfa::export::ply::{write_ply, PlyFormat};
use posemfa::mesh::cache::{write_mdd, write_pc2};
use posemfa::mesh::Population;
use posemfa::synth::{generate, Preset, Spec};

fn small() -> Population {
    generate(&Spec { preset: Preset::Arm, vertices: 600, poses: 4, ..Spec::default() }).unwrap().population
}

fn obj_bytes(p: &[[f64; 3]], f: &[[u32; 3]]) -> Vec<u8> {
    posemfa::export::obj::write_obj(p, f, "test").into_bytes()
}

dual_test! {
    /// A population as PLY files (ASCII: bit for bit; binary float32: to float precision), mixed with OBJ.
    fn ply_files_give_the_obj_population() {
        let pop = small();
        let ascii: Vec<(String, Vec<u8>)> = pop.names.iter().zip(&pop.unit_shapes()).map(|(n, s)| {
            (n.replace(".obj", ".ply"), write_ply(s, &pop.faces, PlyFormat::Ascii, "ascii"))
        }).collect();
        let back = Population::new(posemfa::mesh::Sources::Files(ascii)).unwrap();
        assert_eq!(back.unit_shapes(), pop.unit_shapes());
        assert_eq!(back.faces, pop.faces);
        assert_eq!(back.source, "4 PLY files");
        let mixed: Vec<(String, Vec<u8>)> = pop.names.iter().zip(&pop.unit_shapes()).enumerate().map(|(i, (n, s))| {
            if i % 2 == 0 {
                (n.replace(".obj", ".ply"), write_ply(s, &pop.faces, PlyFormat::Binary, ""))
            } else {
                (n.clone(), obj_bytes(s, &pop.faces))
            }
        }).collect();
        let back = Population::new(posemfa::mesh::Sources::Files(mixed)).unwrap();
        assert_eq!(back.source, "2 OBJ and 2 PLY files");
        assert_eq!(back.n_shapes(), 4);
        let worst = back.unit_shapes().iter().zip(&pop.unit_shapes()).flat_map(|(a, b)| a.iter().zip(b))
            .map(|(p, q)| (0..3).map(|d| (p[d] - q[d]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst}");
    }

    /// A population written as one .glb with a morph target per pose (`posemfa generate --format glb`)
    /// reads back through the animation (one key per pose) to float32 precision, in the original units.
    fn morph_target_glb_gives_the_population() {
        let pop = small();
        let glb = posemfa::export::morph_glb::write_morph_glb("arm", &pop.names, &pop.unit_shapes(), &pop.faces).unwrap();
        let back = Population::new(posemfa::mesh::Sources::Files(vec![("arm.glb".into(), glb)])).unwrap();
        assert!(back.source.starts_with("4 frames of animation 'Poses' (sampled at its keyframes, 24 fps) of mesh 'arm' in arm.glb"), "{}", back.source);
        assert_eq!((back.n_shapes(), back.n_vertices()), (4, pop.n_vertices()));
        assert_eq!(back.faces, pop.faces);
        let worst = back.unit_shapes().iter().zip(&pop.unit_shapes()).flat_map(|(a, b)| a.iter().zip(b))
            .map(|(p, q)| {
                let p = back.normalization.to_original(*p);
                let q = pop.normalization.to_original(*q);
                (0..3).map(|d| (p[d] - q[d]).abs()).fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst}");
    }

    /// A point cache over one base mesh: frames are the poses; a vertex-count mismatch names both files.
    fn point_caches_over_a_base_mesh() {
        let pop = small();
        let base = ("rest.obj".to_string(), obj_bytes(&pop.unit_shapes()[0], &pop.faces));
        for (name, bytes) in [("walk.pc2", write_pc2(&pop.unit_shapes())), ("walk.mdd", write_mdd(&pop.unit_shapes(), 24.0))] {
            let back = Population::new(posemfa::mesh::Sources::Files(vec![(name.into(), bytes.clone()), base.clone()])).unwrap();
            assert_eq!(back.n_shapes(), 4);
            assert_eq!(back.faces, pop.faces);
            assert!(back.source.starts_with(&format!("4 frames of the point cache {name}")), "{}", back.source);
            assert!(back.source.ends_with("faces from rest.obj"), "{}", back.source);
            let e = Population::new(posemfa::mesh::Sources::Files(vec![(name.into(), bytes.clone())])).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("base mesh"), "{e}");
            let other = ("rest.ply".to_string(), write_ply(&pop.unit_shapes()[0][..500], &[[0, 1, 2]], PlyFormat::Ascii, ""));
            let e = Population::new(posemfa::mesh::Sources::Files(vec![(name.into(), bytes), other])).unwrap_err().to_string();
            let n = pop.n_vertices();
            assert!(e.contains(&format!("{n} vertices per frame")) && e.contains("rest.ply has 500"), "{e}");
        }
    }
}

/// horse-poses as ASCII PLY (the OBJ files' own numbers), binary PLY and a .pc2 cache (float32 both) fits like
/// the OBJ folder at the same seed: same part count, adjusted Rand index >= 0.99. At seed 0, or at each seed of
/// `POSEMFA_SEEDS` (e.g. `0,1,2,3,4`; scripts/check-horse-formats.sh --seeds sets it), one line per seed and
/// format. Counted as skipped when the data are absent (fails under CI=true).
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn horse_as_ply_and_pc2_fits_like_the_obj_folder() {
    use posemfa::metrics::adjusted_rand_index;
    use posemfa::{mfa::Params, parts::hierarchy::fit};
    let Some(dir) = common::shared_dir("data/horse-poses", "horse_as_ply_and_pc2_fits_like_the_obj_folder") else {
        return;
    };
    let obj = Population::new(posemfa::mesh::Sources::paths(&[&dir])).unwrap();
    let original: Vec<Vec<[f64; 3]>> =
        obj.unit_shapes().iter().map(|s| s.iter().map(|&p| obj.normalization.to_original(p)).collect()).collect();
    let ply: Vec<(String, Vec<u8>)> = obj
        .names
        .iter()
        .zip(&original)
        .map(|(n, s)| (n.replace(".obj", ".ply"), write_ply(s, &obj.faces, PlyFormat::Binary, "horse-poses")))
        .collect();
    let ply = Population::new(posemfa::mesh::Sources::Files(ply)).unwrap();
    // ASCII PLY of each OBJ file's own coordinates (printed in full: they read back bit for bit)
    let ascii: Vec<(String, Vec<u8>)> = obj
        .names
        .iter()
        .map(|n| {
            let m = parse_obj(n, &std::fs::read(dir.join(n)).unwrap()).unwrap();
            (n.replace(".obj", ".ply"), write_ply(&m.positions, &m.faces, PlyFormat::Ascii, "horse-poses"))
        })
        .collect();
    let ascii = Population::new(posemfa::mesh::Sources::Files(ascii)).unwrap();
    assert_eq!(ascii.source, "11 PLY files");
    assert_eq!(
        (&ascii.unit_shapes(), &ascii.faces),
        (&obj.unit_shapes(), &obj.faces),
        "ASCII PLY gives the OBJ population exactly"
    );
    let pc2 = Population::new(posemfa::mesh::Sources::Files(vec![
        ("horse.pc2".into(), write_pc2(&original)),
        ("reference.obj".into(), std::fs::read(dir.join("reference.obj")).unwrap()),
    ]))
    .unwrap();
    assert_eq!(ply.n_shapes(), 11);
    assert_eq!(pc2.n_shapes(), 11);
    let seeds: Vec<u64> = match std::env::var("POSEMFA_SEEDS") {
        Ok(v) => v
            .split(',')
            .map(|s| s.trim().parse().unwrap_or_else(|_| panic!("POSEMFA_SEEDS: '{s}' is not a seed (0,1,2)")))
            .collect(),
        Err(_) => vec![0],
    };
    let mut failed = Vec::new();
    for seed in seeds {
        let params = Params { seed, ..Params::default() };
        let reference = fit(&obj, &params, &mut |_| true).unwrap();
        let parts = reference.model.parts.len();
        for (what, pop) in [("ASCII PLY", &ascii), ("binary PLY", &ply), ("pc2", &pc2)] {
            let r = fit(pop, &params, &mut |_| true).unwrap();
            let ari = adjusted_rand_index(&reference.model.labels, &r.model.labels);
            let pass = r.model.parts.len() == parts && ari >= 0.99;
            println!(
                "{} seed {seed}: horse-poses as {what}: {} parts (OBJ folder {parts}), ARI {ari:.4} (same count, >= 0.99), RMSE {:.5} (OBJ {:.5})",
                if pass { "ok  " } else { "FAIL" },
                r.model.parts.len(),
                r.model.rmse(pop),
                reference.model.rmse(&obj),
            );
            if !pass {
                failed.push(format!("seed {seed} {what}"));
            }
        }
    }
    assert!(failed.is_empty(), "fits unlike the OBJ folder's: {failed:?}");
}

dual_test! {
    /// Blender's PLY exporter (ASCII and binary) renumbers vertices by first use, so the check maps every
    /// PLY vertex to the generator's vertex at the same position: all 1198 found, and the same triangles.
    fn blender_ply_ascii_and_binary_load_as_the_generated_pose() {
        let g = blender_source();
        let pose = &g.population.unit_shapes()[0];
        for (name, bytes, tol) in [
            ("pose01-ascii.ply", &include_bytes!("fixtures/blender/pose01-ascii.ply")[..], 1e-6),
            ("pose01-binary.ply", &include_bytes!("fixtures/blender/pose01-binary.ply")[..], 1e-7),
        ] {
            let m = posemfa::mesh::ply::parse_ply(name, bytes).unwrap();
            assert_eq!((m.positions.len(), m.faces.len()), (pose.len(), g.population.faces.len()), "{name}");
            let to_obj: Vec<u32> = m.positions.iter().map(|p| {
                let (j, d) = pose.iter().enumerate().map(|(j, q)| (j, (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max)))
                    .min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
                assert!(d <= tol, "{name}: a vertex is {d} from the nearest generated one");
                j as u32
            }).collect();
            let canon = |t: [u32; 3]| { let r = t.iter().position(|&v| v == *t.iter().min().unwrap()).unwrap(); [t[r], t[(r + 1) % 3], t[(r + 2) % 3]] };
            let mut ours: Vec<[u32; 3]> = m.faces.iter().map(|f| canon(f.map(|v| to_obj[v as usize]))).collect();
            let mut want: Vec<[u32; 3]> = g.population.faces.iter().map(|&f| canon(f)).collect();
            ours.sort();
            want.sort();
            assert_eq!(ours, want, "{name}");
        }
    }

    /// Blender's glTF of the poses as shape keys, animated one key per frame: the animation gives the six
    /// poses (to float precision, Y-up), and the fit matches the OBJ population's.
    fn blender_shape_key_glb_fits_like_the_obj_population() {
        let g = blender_source();
        let bytes = include_bytes!("fixtures/blender/quadruped-shapekeys.glb").to_vec();
        let pop = Population::new(posemfa::mesh::Sources::Files(vec![("quadruped-shapekeys.glb".into(), bytes)])).unwrap();
        assert!(pop.source.starts_with("6 frames of animation"), "{}", pop.source);
        assert!(pop.source.contains("24 fps"), "{}", pop.source);
        assert_eq!((pop.n_shapes(), pop.n_vertices()), (6, 1198));
        assert_eq!(pop.faces.len(), g.population.faces.len());
        for (i, shape) in pop.unit_shapes().iter().enumerate() {
            let ours: Vec<[f64; 3]> = shape.iter().map(|&p| pop.normalization.to_original(p)).collect();
            let want: Vec<[f64; 3]> = g.population.unit_shapes()[i].iter().map(|&p| y_up(p)).collect();
            assert!(max_diff(&ours, &want) < 1e-6, "pose {i}: {}", max_diff(&ours, &want));
        }
        let (parts_obj, rmse_obj, labels_obj) = fit_summary(&g.population);
        let (parts, rmse, labels) = fit_summary(&pop);
        assert!(parts.abs_diff(parts_obj) <= 3, "{parts} parts, OBJ {parts_obj}");
        assert!((rmse - rmse_obj).abs() <= 0.1 * rmse_obj, "RMSE {rmse}, OBJ {rmse_obj}");
        assert!(posemfa::metrics::adjusted_rand_index(&labels, &labels_obj) > 0.9);
    }

    /// A skinned glTF that Blender exported with every vertex split per face corner welds back to the
    /// generator's 1198 vertices and fits.
    fn blender_skinned_glb_with_seams_welds_back_and_fits() {
        let bytes = include_bytes!("fixtures/blender/quadruped-skinned-seams.glb");
        let gl = posemfa::mesh::gltf::read("quadruped-skinned-seams.glb", bytes, &[], &Default::default()).unwrap();
        assert!(gl.vertices_in_file > 3 * 1198, "{} vertices in the file", gl.vertices_in_file);
        assert_eq!(gl.vertices_welded, 1198);
        assert!(gl.source.contains(&format!("{} vertices welded to 1198", gl.vertices_in_file)), "{}", gl.source);
        let pop = Population::new(posemfa::mesh::Sources::Files(vec![("quadruped-skinned-seams.glb".into(), bytes.to_vec())])).unwrap();
        assert_eq!(pop.n_vertices(), 1198);
        let (parts, rmse, _) = fit_summary(&pop);
        assert!((5..=30).contains(&parts) && rmse < 0.01, "{parts} parts, RMSE {rmse}");
    }
}
