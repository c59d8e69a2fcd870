//! Writes the seed corpora of the fuzz targets into fuzz/corpus/<target>/ (run by scripts/fuzz.sh before
//! fuzzing; the folder is not committed):
//!
//! - obj_parse: the OBJ files of small generated populations (every posemfa::synth preset at its coarsest
//!   mesh), hand-written files covering each statement form, and every file of an extra folder given as the
//!   second argument (the project uses shared/objcorpus, real-world and broken OBJ files).
//! - population: several small populations (hinged boxes, a rigidly moving tetrahedron, identical shapes, a
//!   generated snake) as OBJ files joined by NUL bytes, behind a few config bytes.
//! - shapes: the same small geometries as numbers in each of the target's formats.
//!
//! Usage: cargo run --example gen_corpus -- CORPUS_DIR [EXTRA_OBJ_DIR]

use posemfa::export::obj::write_obj;
use posemfa::geometry::rotation::axis_angle;
use posemfa::geometry::{add, mat_vec, sub, Vec3};
use posemfa::synth::{generate, obj_files, Preset, Spec};
use std::path::Path;

fn write(dir: &Path, name: &str, bytes: &[u8]) {
    std::fs::write(dir.join(name), bytes).unwrap_or_else(|e| panic!("cannot write {}: {e}", dir.join(name).display()));
}

/// A box of 8 vertices and 12 triangles, corners `lo` and `hi`.
fn cuboid(lo: Vec3, hi: Vec3, base: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = (0..8)
        .map(|c| [if c & 1 == 0 { lo[0] } else { hi[0] }, if c & 2 == 0 { lo[1] } else { hi[1] }, if c & 4 == 0 { lo[2] } else { hi[2] }])
        .collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let f = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).map(|t: [u32; 3]| t.map(|v| v + base)).collect();
    (p, f)
}

/// `links` boxes end to end along x, the i-th turned about z by `angles[i]` at its left end (forward
/// kinematics), in `angles.len()` poses.
fn chain(links: usize, poses: &[Vec<f64>]) -> (Vec<Vec<Vec3>>, Vec<[u32; 3]>) {
    let mut rest = Vec::new();
    let mut faces = Vec::new();
    for l in 0..links {
        let x = l as f64;
        let (p, f) = cuboid([x + 0.05, -0.2, -0.1], [x + 0.95, 0.2, 0.1 + 0.05 * l as f64], 8 * l as u32);
        rest.extend(p);
        faces.extend(f);
    }
    let shapes = poses
        .iter()
        .map(|angles| {
            let mut out = Vec::new();
            let mut rot = posemfa::geometry::IDENTITY;
            let mut origin = [0.0; 3];
            for l in 0..links {
                let joint_rest = [l as f64, 0.0, 0.0];
                rot = posemfa::geometry::mat_mul(&rot, &axis_angle([0.0, 0.3, 1.0], angles[l]));
                for p in &rest[8 * l..8 * l + 8] {
                    out.push(add(origin, mat_vec(&rot, sub(*p, joint_rest))));
                }
                origin = add(origin, mat_vec(&rot, [1.0, 0.0, 0.0]));
            }
            out
        })
        .collect();
    (shapes, faces)
}

/// OBJ text; coordinates far from 1 in exponent notation (posemfa's writer spells every digit out).
fn obj_text(positions: &[Vec3], faces: &[[u32; 3]], header: &str) -> String {
    let extreme = positions.iter().flatten().any(|c| *c != 0.0 && !(1e-6..1e6).contains(&c.abs()));
    if !extreme {
        return write_obj(positions, faces, header);
    }
    let mut out = format!("# {header}\n");
    for p in positions {
        out.push_str(&format!("v {:e} {:e} {:e}\n", p[0], p[1], p[2]));
    }
    for f in faces {
        out.push_str(&format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1));
    }
    out
}

/// Small populations (shapes, faces) for the population and shapes targets.
fn geometries() -> Vec<(&'static str, Vec<Vec<Vec3>>, Vec<[u32; 3]>)> {
    let mut out = Vec::new();
    let (s, f) = chain(2, &[vec![0.0, 0.0], vec![0.2, 0.9], vec![-0.3, -0.7]]);
    out.push(("hinge2", s, f));
    let (s, f) = chain(3, &[vec![0.0, 0.0, 0.0], vec![0.5, 0.4, -0.6], vec![0.1, -0.8, 0.9], vec![1.0, 0.2, 0.3]]);
    out.push(("chain3", s, f));
    let tet = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let tet_faces = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let rigid = (0..3).map(|i| tet.iter().map(|&p| add(mat_vec(&axis_angle([1.0, 1.0, 0.0], 0.7 * i as f64), p), [0.1 * i as f64, 0.0, 0.0])).collect()).collect();
    out.push(("rigid_tet", rigid, tet_faces.clone()));
    out.push(("identical_tet", vec![tet.clone(), tet.clone()], tet_faces.clone()));
    // the same rigid motion at extreme scales (the unit-box normalisation must cope or refuse by name)
    for (name, scale) in [("tiny_tet", 1e-300), ("huge_tet", 1e300)] {
        let shapes = out[2].1.iter().map(|s: &Vec<Vec3>| s.iter().map(|p| p.map(|c| c * scale)).collect()).collect();
        out.push((name, shapes, tet_faces.clone()));
    }
    let line: Vec<Vec3> = (0..5).map(|j| [j as f64, 0.0, 0.0]).collect();
    let bent: Vec<Vec3> = (0..5).map(|j| if j < 3 { [j as f64, 0.0, 0.0] } else { [2.0, (j - 2) as f64, 0.0] }).collect();
    out.push(("collinear", vec![line, bent], vec![[0, 1, 2], [2, 3, 4]]));
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let root = Path::new(args.get(1).map(String::as_str).unwrap_or("fuzz/corpus"));
    let extra = args.get(2).map(Path::new);
    let dirs = ["obj_parse", "population", "shapes"].map(|t| {
        let d = root.join(t);
        std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("cannot create {}: {e}", d.display()));
        d
    });
    let [obj_dir, pop_dir, shapes_dir] = &dirs;

    // --- obj_parse
    let mut n_obj = 0;
    let mut snake = Vec::new();
    for preset in [Preset::Arm, Preset::Snake, Preset::Blob, Preset::Quadruped] {
        let spec = Spec { preset, vertices: 100, poses: 2, seed: 1, noise: 0.001, ..Spec::default() };
        let generated = generate(&spec).expect("generate a small population");
        let files = obj_files(&generated);
        if preset == Preset::Snake {
            snake = files.clone();
        }
        write(obj_dir, &format!("synth-{}.obj", preset.name()), files[0].1.as_bytes());
        n_obj += 1;
    }
    let snippets: [&[u8]; 10] = [
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        b"o a\nv 0 0 0\nv 1 0 0\nv 9 9 9\nv 0 1 0\nf 4 2 1\ng b\nv 5 5 5\no c\nv 2 0 0\nv 2 1 0\nf 1 6 7\n",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -1 -2 1\nvt 0 0\nvn 0 0 1\nf -4/-1/-1 2 3\n",
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 1 0\nv -1 0 0\nf 1 2 3 4\nf 1 2 3 4 5 6\n",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\nf 1/1 2/2 3/1\nf 1//1 2//1 3//1\nf 1/1/1 2/2/1 3/1/1\nl 1 2 3\np 1 2 3\ns off\nusemtl x\n",
        b"v 1 2 3 0.5 0.25 1\nv 4 5 6 2.0\nv .5 -.7e+2 2.e01 \nv +1 1E2 -0\nf 1 2 3\n",
        b"# c\r\nv 0 0 0\r\nv 1 0 0 # inline\r\nv\t0  1\t0\r\n\r\nf 1 2 3 # tri\r\n",
        b"v -1 \\\n 0 1\nv 1 0 \\  \n1\nv 0 \\\n\\\n1 0\nf 1 \\\n2 3\n#   / \\\n# x\n",
        b"\xEF\xBB\xBFv 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\x1A",
        b"v 1e-310 0 0\nv 0 2.5e-320 0\nv 0 0 1e308\nfo 1 2 3\n",
    ];
    for (i, s) in snippets.iter().enumerate() {
        write(obj_dir, &format!("snippet-{i}.obj"), s);
        n_obj += 1;
    }
    if let Some(extra) = extra {
        match std::fs::read_dir(extra) {
            Ok(entries) => {
                for entry in entries.flatten() {
                    let path = entry.path();
                    if path.is_file() && path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")) {
                        if let Ok(bytes) = std::fs::read(&path) {
                            write(obj_dir, &format!("extra-{}", entry.file_name().to_string_lossy()), &bytes);
                            n_obj += 1;
                        }
                    }
                }
            }
            Err(e) => eprintln!("gen_corpus: no extra OBJ files from {} ({e})", extra.display()),
        }
    }

    // --- population and shapes
    let (mut n_pop, mut n_shapes) = (0, 0);
    for (name, shapes, faces) in geometries() {
        let files: Vec<String> = shapes.iter().map(|s| obj_text(s, &faces, name)).collect();
        let joined = files.join("\0");
        for cfg in [0x00u8, 0x11, 0x23, 0x31, 0x40] {
            let mut bytes = vec![cfg];
            bytes.extend_from_slice(joined.as_bytes());
            write(pop_dir, &format!("{name}-{cfg:02x}"), &bytes);
            n_pop += 1;
        }
        // shapes target: 3 formats; the shape count goes into bits 2-4 of the layout byte
        let ns = shapes.len().clamp(2, 9);
        let all: Vec<f64> = shapes.iter().take(ns).flatten().flatten().copied().collect();
        let lo = all.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = all.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let unit = |v: f64| (v - lo) / (hi - lo).max(1e-12);
        for format in 0u8..3 {
            let layout = format | (((ns - 2) as u8) << 2);
            let mut bytes = vec![0x21, layout];
            for &v in &all {
                match format {
                    0 => bytes.push(((unit(v) * 255.0).round() as i32 - 128) as i8 as u8),
                    1 => bytes.extend_from_slice(&(((unit(v) - 0.5) * 65000.0).round() as i16).to_le_bytes()),
                    _ => bytes.extend_from_slice(&v.to_le_bytes()),
                }
            }
            write(shapes_dir, &format!("{name}-f{format}"), &bytes);
            n_shapes += 1;
        }
    }
    let mut bytes = vec![0x01];
    bytes.extend_from_slice(snake.iter().map(|(_, text)| text.as_str()).collect::<Vec<_>>().join("\0").as_bytes());
    write(pop_dir, "synth-snake", &bytes);
    n_pop += 1;
    println!("gen_corpus: {n_obj} obj_parse, {n_pop} population, {n_shapes} shapes seeds in {}", root.display());
    format_seeds(root);
}

/// Every file of `dir` whose name ends with one of `exts` (case-insensitive), as (name, bytes).
fn files_in(dir: &Path, exts: &[&str]) -> Vec<(String, Vec<u8>)> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut out: Vec<(String, Vec<u8>)> = entries
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let lower = name.to_ascii_lowercase();
            (exts.iter().any(|x| lower.ends_with(x)) && e.path().is_file())
                .then(|| std::fs::read(e.path()).ok().map(|b| (name, b)))
                .flatten()
        })
        .collect();
    out.sort();
    out
}

/// Seeds of the ply_parse, point_cache and gltf_read targets: files written by posemfa's writers from the
/// small geometries and generated meshes, hand-written edge cases, and the small files written by Blender in
/// fuzz/seeds/ (scripts/fixtures/make-fuzz-seeds.sh).
fn format_seeds(root: &Path) {
    use posemfa::export::morph_glb::write_morph_glb;
    use posemfa::export::ply::{write_ply, PlyFormat};
    use posemfa::mesh::cache::{write_mdd, write_pc2};
    let dir = |t: &str| {
        let d = root.join(t);
        std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("cannot create {}: {e}", d.display()));
        d
    };
    let (ply_dir, cache_dir, gltf_dir) = (dir("ply_parse"), dir("point_cache"), dir("gltf_read"));
    let seeds = Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds");
    let (mut n_ply, mut n_cache, mut n_gltf) = (0, 0, 0);
    let mut populations: Vec<(String, Vec<String>, Vec<Vec<Vec3>>, Vec<[u32; 3]>)> = geometries()
        .into_iter()
        .map(|(name, shapes, faces)| {
            let names = (1..=shapes.len()).map(|k| format!("{name}-{k}")).collect();
            (name.to_string(), names, shapes, faces)
        })
        .collect();
    for preset in [Preset::Arm, Preset::Snake] {
        let spec = Spec { preset, vertices: 100, poses: 3, seed: 2, ..Spec::default() };
        let g = generate(&spec).expect("generate a small population").population;
        let shapes = g.shapes().map(|s| s.to_vec()).collect();
        populations.push((format!("synth-{}", preset.name()), g.names, shapes, g.faces.to_vec()));
    }
    for (name, names, shapes, faces) in &populations {
        // ply: ASCII and binary little endian from posemfa's writer; big endian by hand below
        write(&ply_dir, &format!("{name}-ascii.ply"), &write_ply(&shapes[0], faces, PlyFormat::Ascii, name));
        write(&ply_dir, &format!("{name}-binary.ply"), &write_ply(&shapes[0], faces, PlyFormat::Binary, name));
        n_ply += 2;
        // point caches: byte 0 even = pc2, odd = mdd
        let mut pc2 = vec![0u8];
        pc2.extend(write_pc2(shapes));
        let mut mdd = vec![1u8];
        mdd.extend(write_mdd(shapes, 24.0));
        write(&cache_dir, &format!("{name}.pc2"), &pc2);
        write(&cache_dir, &format!("{name}.mdd"), &mdd);
        n_cache += 2;
        // glb with one morph target per pose, under a few option bytes
        if let Ok(glb) = write_morph_glb(name, names, shapes, faces) {
            for cfg in [0x00u8, 0x02, 0x0d, 0x61] {
                let mut b = vec![cfg];
                b.extend_from_slice(&glb);
                write(&gltf_dir, &format!("{name}-morph-{cfg:02x}.glb"), &b);
                n_gltf += 1;
            }
        }
    }
    // 3-point caches, which load over the target's one-triangle base mesh
    let tri: Vec<Vec<Vec3>> = (0..3).map(|k| vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.1 * k as f64]]).collect();
    for (cfg, bytes) in [(0u8, write_pc2(&tri)), (1u8, write_mdd(&tri, 30.0))] {
        let mut b = vec![cfg];
        b.extend(bytes);
        write(&cache_dir, &format!("triangle-{cfg}"), &b);
        n_cache += 1;
    }
    let plies: [&[u8]; 6] = [
        b"ply\nformat ascii 1.0\ncomment \xe9t\xe9\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 255\n1 0 0 0\n0 1 0 7\n3 0 1 2\n",
        b"ply\r\nformat ascii 1.0\r\nelement face 2\r\nproperty uchar flags\r\nproperty list uint8 uint32 vertex_index\r\nelement vertex 4\r\nproperty double z\r\nproperty double y\r\nproperty double x\r\nelement edge 1\r\nproperty int a\r\nproperty int b\r\nend_header\r\n1 3 0 1 2\r\n0 4 0 1 2 3\r\n0 0 0\r\n1e-3 0 1\r\n-2.5E2 1 0\r\n0 1 1\r\n0 1\r\n",
        b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x3f\x80\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x3f\x80\x00\x00\x00\x00\x00\x00\x03\x00\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x02",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty short x\nproperty char y\nproperty ushort z\nproperty list ushort float normals\nelement face 1\nproperty list int ushort vertex_indices\nend_header\n\x00\x00\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x80\x3f\x00\x00\x01\x00\x00\x00\x00\x00\x03\x00\x00\x00\x00\x00\x01\x00\x02\x00",
        b"ply\nformat ascii 1.0\nobj_info generated\nelement vertex 4294967296\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
        b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 nan\n5 0 1 2 3 0\n",
    ];
    for (i, b) in plies.iter().enumerate() {
        write(&ply_dir, &format!("snippet-{i}.ply"), b);
        n_ply += 1;
    }
    // small .gltf documents with data-URI buffers: a quad with a skin and a weights animation
    let gltf_docs: [&str; 1] = [concat!(
        r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":92,"uri":"data:application/octet-stream;base64,"#,
        r#"AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAPwAAgD8AAAAAAAAAAAAAgD8AAAAAAAABAAIAAAACAAMAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAAAAAACAPwAAAAA="}],"#,
        r#""bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12},"#,
        r#"{"buffer":0,"byteOffset":60,"byteLength":8},{"buffer":0,"byteOffset":68,"byteLength":24}],"#,
        r#""accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},"#,
        r#"{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"},{"bufferView":2,"componentType":5126,"count":2,"type":"SCALAR"},"#,
        r#"{"bufferView":3,"componentType":5126,"count":6,"type":"SCALAR"}],"#,
        r#""meshes":[{"name":"quad","primitives":[{"attributes":{"POSITION":0},"indices":1,"targets":[{"POSITION":0}]}],"weights":[0]}],"#,
        r#""nodes":[{"name":"body","mesh":0,"children":[1]},{"name":"child","translation":[0,1,0]}],"scenes":[{"nodes":[0]}],"#,
        r#""animations":[{"name":"Go","samplers":[{"input":2,"output":3,"interpolation":"CUBICSPLINE"},{"input":2,"output":3,"interpolation":"LINEAR"}],"#,
        r#""channels":[{"sampler":0,"target":{"node":0,"path":"weights"}}]}]}"#
    )];
    for (i, d) in gltf_docs.iter().enumerate() {
        for cfg in [0u8, 0x09] {
            let mut b = vec![cfg];
            b.extend_from_slice(d.as_bytes());
            write(&gltf_dir, &format!("snippet-{i}-{cfg:02x}.gltf"), &b);
            n_gltf += 1;
        }
    }
    // small files written by Blender (fuzz/seeds/, made by scripts/fixtures/make-fuzz-seeds.sh)
    for (name, bytes) in files_in(&seeds, &[".ply"]) {
        write(&ply_dir, &format!("blender-{name}"), &bytes);
        n_ply += 1;
    }
    // pose_rig: the .glb files as they are (posemfa's rig, re-laid interleaved and sparse, Blender's)
    let rig_dir = dir("pose_rig");
    let rigs = files_in(&seeds, &[".glb"]);
    for (name, bytes) in &rigs {
        write(&rig_dir, name, bytes);
    }
    println!("gen_corpus: {} pose_rig seeds in {}", rigs.len(), root.display());
    for (name, bytes) in files_in(&seeds, &[".glb", ".gltf"]) {
        for cfg in [0u8, 0x02, 0x05] {
            let mut b = vec![cfg];
            b.extend_from_slice(&bytes);
            write(&gltf_dir, &format!("blender-{cfg:02x}-{name}"), &b);
            n_gltf += 1;
        }
    }
    // FBX: the hand-built blend shape scene (plain and zlib arrays) and Blender's small files; USD: usd-core's
    // small point caches (fuzz/seeds/, scripts/fixtures/make-fuzz-seeds.sh), each under a few option bytes
    let (fbx_dir, usd_dir) = (dir("fbx_read"), dir("usd_read"));
    let (mut n_fbx, mut n_usd) = (0, 0);
    let mut fbx_files = vec![
        ("tiny-plain.fbx".to_string(), posemfa::fuzzing::tiny_fbx(false)),
        ("tiny-zlib.fbx".to_string(), posemfa::fuzzing::tiny_fbx(true)),
    ];
    fbx_files.extend(files_in(&seeds, &[".fbx"]));
    for (name, bytes) in fbx_files {
        for cfg in [0u8, 0x02, 0x05, 0x20] {
            let mut b = vec![cfg];
            b.extend_from_slice(&bytes);
            write(&fbx_dir, &format!("{cfg:02x}-{name}"), &b);
            n_fbx += 1;
        }
    }
    for (name, bytes) in files_in(&seeds, &[".usda", ".usdc", ".usdz"]) {
        for cfg in [0u8, 0x05, 0x20] {
            let mut b = vec![cfg];
            b.extend_from_slice(&bytes);
            write(&usd_dir, &format!("{cfg:02x}-{name}"), &b);
            n_usd += 1;
        }
    }
    println!(
        "gen_corpus: {n_ply} ply_parse, {n_cache} point_cache, {n_gltf} gltf_read, {n_fbx} fbx_read, {n_usd} usd_read seeds in {}",
        root.display()
    );
    // model files: small fits saved with and without their poses
    let model_dir = dir("model_file");
    let seeds = posemfa::fuzzing::model_file_seeds();
    for (name, bytes) in &seeds {
        write(&model_dir, name, bytes);
    }
    println!("gen_corpus: {} model_file seeds in {}", seeds.len(), root.display());
    let zip_dir = dir("zip_open");
    let zips = posemfa::fuzzing::zip_seeds();
    for (name, bytes) in &zips {
        write(&zip_dir, name, bytes);
    }
    println!("gen_corpus: {} zip_open seeds in {}", zips.len(), root.display());
}
