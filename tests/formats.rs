//! Mesh files as people have them (issue 12): fixtures written by other tools, read through the same
//! readers natively and in wasm.

#[macro_use]
mod common;

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
        let ascii: Vec<(String, Vec<u8>)> = pop.names.iter().zip(&pop.shapes).map(|(n, s)| {
            (n.replace(".obj", ".ply"), write_ply(s, &pop.faces, PlyFormat::Ascii, "ascii"))
        }).collect();
        let back = Population::from_files(ascii).unwrap();
        assert_eq!(back.shapes, pop.shapes);
        assert_eq!(back.faces, pop.faces);
        assert_eq!(back.source, "4 PLY files");
        let mixed: Vec<(String, Vec<u8>)> = pop.names.iter().zip(&pop.shapes).enumerate().map(|(i, (n, s))| {
            if i % 2 == 0 {
                (n.replace(".obj", ".ply"), write_ply(s, &pop.faces, PlyFormat::Binary, ""))
            } else {
                (n.clone(), obj_bytes(s, &pop.faces))
            }
        }).collect();
        let back = Population::from_files(mixed).unwrap();
        assert_eq!(back.source, "2 OBJ and 2 PLY files");
        assert_eq!(back.n_shapes(), 4);
        let worst = back.shapes.iter().zip(&pop.shapes).flat_map(|(a, b)| a.iter().zip(b))
            .map(|(p, q)| (0..3).map(|d| (p[d] - q[d]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst}");
    }

    /// A point cache over one base mesh: frames are the poses; a vertex-count mismatch names both files.
    fn point_caches_over_a_base_mesh() {
        let pop = small();
        let base = ("rest.obj".to_string(), obj_bytes(&pop.shapes[0], &pop.faces));
        for (name, bytes) in [("walk.pc2", write_pc2(&pop.shapes)), ("walk.mdd", write_mdd(&pop.shapes, 24.0))] {
            let back = Population::from_files(vec![(name.into(), bytes.clone()), base.clone()]).unwrap();
            assert_eq!(back.n_shapes(), 4);
            assert_eq!(back.faces, pop.faces);
            assert!(back.source.starts_with(&format!("4 frames of the point cache {name}")), "{}", back.source);
            assert!(back.source.ends_with("faces from rest.obj"), "{}", back.source);
            let e = Population::from_files(vec![(name.into(), bytes.clone())]).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("base mesh"), "{e}");
            let other = ("rest.ply".to_string(), write_ply(&pop.shapes[0][..500], &[[0, 1, 2]], PlyFormat::Ascii, ""));
            let e = Population::from_files(vec![(name.into(), bytes), other]).unwrap_err().to_string();
            let n = pop.n_vertices();
            assert!(e.contains(&format!("{n} vertices per frame")) && e.contains("rest.ply has 500"), "{e}");
        }
    }
}

/// horse-poses as binary PLY and as a .pc2 cache (float32 both) fits like the OBJ folder at the same seed:
/// same part count, adjusted Rand index >= 0.99. Skipped when the data are absent.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn horse_as_ply_and_pc2_fits_like_the_obj_folder() {
    use posemfa::metrics::adjusted_rand_index;
    use posemfa::model::{hierarchy::fit, Params};
    let dir = std::env::var("POSEMFA_HORSE_POSES")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/horse-poses").to_string());
    if !std::path::Path::new(&dir).is_dir() {
        println!("horse-poses not found at {dir}, skipping");
        return;
    }
    let obj = Population::from_paths(&[&dir]).unwrap();
    let original: Vec<Vec<[f64; 3]>> = obj.shapes.iter().map(|s| s.iter().map(|&p| obj.normalization.to_original(p)).collect()).collect();
    let ply: Vec<(String, Vec<u8>)> = obj.names.iter().zip(&original).map(|(n, s)| {
        (n.replace(".obj", ".ply"), write_ply(s, &obj.faces, PlyFormat::Binary, "horse-poses"))
    }).collect();
    let ply = Population::from_files(ply).unwrap();
    let pc2 = Population::from_files(vec![
        ("horse.pc2".into(), write_pc2(&original)),
        ("reference.obj".into(), std::fs::read(format!("{dir}/reference.obj")).unwrap()),
    ]).unwrap();
    assert_eq!(ply.n_shapes(), 11);
    assert_eq!(pc2.n_shapes(), 11);
    let params = Params::default();
    let reference = fit(&obj, &params, &mut |_| true).unwrap();
    let parts = reference.model.parts.len();
    for (what, pop) in [("binary PLY", &ply), ("pc2", &pc2)] {
        let r = fit(pop, &params, &mut |_| true).unwrap();
        let ari = adjusted_rand_index(&reference.model.labels, &r.model.labels);
        println!("{what}: {} parts (OBJ {parts}), ARI {ari:.4}", r.model.parts.len());
        assert_eq!(r.model.parts.len(), parts, "{what}");
        assert!(ari >= 0.99, "{what}: ARI {ari}");
    }
}
