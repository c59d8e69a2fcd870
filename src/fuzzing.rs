//! How the fuzz targets (`fuzz/`, `scripts/fuzz.sh`) read their bytes. Kept in the library so that the
//! targets and the crash inputs kept as plain tests (`tests/fuzz_regressions.rs`) decode an input the same way.

use crate::geometry::Vec3;
use crate::mfa::{Algorithm1Params, Params};

/// Small, fast fit parameters chosen by a target's config byte (byte 0 of every input that fits).
pub fn params_from(cfg: u8) -> Params {
    Params {
        seed: cfg as u64,
        max_iter: 4,
        restarts: 1,
        refine: cfg & 1 == 1,
        min_part_vertices: 1 + (cfg as usize >> 1) % 3,
        algorithm1: Algorithm1Params {
            parts: 1 + (cfg as usize >> 4) % 5,
            max_subparts: 2,
            refine_max_iter: 3,
            ..Algorithm1Params::default()
        },
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
        2 => coords
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
            .collect(),
        _ => coords.iter().map(|&b| b as i8 as f64 / 16.0).collect(),
    };
    let n_vertices = values.len() / (3 * n_shapes);
    let shapes = (0..n_shapes)
        .map(|i| (0..n_vertices).map(|j| [0, 1, 2].map(|d| values[(i * n_vertices + j) * 3 + d])).collect())
        .collect();
    Some(ShapesInput { cfg: *cfg, names: (0..n_shapes).map(|i| format!("s{i}")).collect(), faces, shapes })
}

// ------------------------------------------------------------------------------------- FBX seeds and tests

use crate::mesh::fbx_tree::{Node, Prop};

/// An FBX node without an offset (for [`crate::mesh::fbx_tree::write`]).
pub fn fbx_node(name: &str, props: Vec<Prop>, children: Vec<Node>) -> Node {
    Node { name: name.into(), props, children, offset: 0 }
}

fn s(x: &str) -> Prop {
    Prop::Str(x.into())
}

fn p70(entries: Vec<(&str, Vec<Prop>)>) -> Node {
    let ps = entries
        .into_iter()
        .map(|(n, v)| {
            let mut props = vec![s(n), s(""), s(""), s("")];
            props.extend(v);
            fbx_node("P", props, vec![])
        })
        .collect();
    fbx_node("Properties70", vec![], ps)
}

/// A quad (two triangles) with one blend shape channel animated 0 -> 100 % over 3 frames at 24 fps, Y up,
/// metres (UnitScaleFactor 100). `edit` changes the Geometry's children before writing.
pub fn tiny_fbx_with(edit: impl FnOnce(&mut Vec<Node>), compress: bool) -> Vec<u8> {
    let ktime = 46_186_158_000i64 / 24;
    let mut geometry = vec![
        fbx_node("Vertices", vec![Prop::F64s(vec![0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.])], vec![]),
        fbx_node("PolygonVertexIndex", vec![Prop::I32s(vec![0, 1, 2, -4])], vec![]),
    ];
    edit(&mut geometry);
    let nodes = vec![
        fbx_node(
            "GlobalSettings",
            vec![],
            vec![p70(vec![
                ("UpAxis", vec![Prop::Int(1)]),
                ("UnitScaleFactor", vec![Prop::Float(100.0)]),
                ("TimeMode", vec![Prop::Int(11)]),
            ])],
        ),
        fbx_node(
            "Objects",
            vec![],
            vec![
                fbx_node("Geometry", vec![Prop::Int(10), s("quad\0\u{1}Geometry"), s("Mesh")], geometry),
                fbx_node("Model", vec![Prop::Int(20), s("Quad\0\u{1}Model"), s("Mesh")], vec![]),
                fbx_node("Deformer", vec![Prop::Int(30), s("quad\0\u{1}Deformer"), s("BlendShape")], vec![]),
                fbx_node(
                    "Deformer",
                    vec![Prop::Int(31), s("lift\0\u{1}SubDeformer"), s("BlendShapeChannel")],
                    vec![fbx_node("DeformPercent", vec![Prop::Float(0.0)], vec![])],
                ),
                fbx_node(
                    "Geometry",
                    vec![Prop::Int(32), s("lift\0\u{1}Geometry"), s("Shape")],
                    vec![
                        fbx_node("Indexes", vec![Prop::I32s(vec![2, 3])], vec![]),
                        fbx_node("Vertices", vec![Prop::F64s(vec![0., 0., 1., 0., 0., 2.])], vec![]),
                    ],
                ),
                fbx_node(
                    "AnimationStack",
                    vec![Prop::Int(40), s("Take 1\0\u{1}AnimStack"), s("")],
                    vec![p70(vec![("LocalStop", vec![Prop::Int(2 * ktime)])])],
                ),
                fbx_node("AnimationLayer", vec![Prop::Int(41), s("Layer\0\u{1}AnimLayer"), s("")], vec![]),
                fbx_node(
                    "AnimationCurveNode",
                    vec![Prop::Int(42), s("DeformPercent\0\u{1}AnimCurveNode"), s("")],
                    vec![],
                ),
                fbx_node(
                    "AnimationCurve",
                    vec![Prop::Int(43), s("\0\u{1}AnimCurve"), s("")],
                    vec![
                        fbx_node("KeyTime", vec![Prop::I64s(vec![0, 2 * ktime])], vec![]),
                        fbx_node("KeyValueFloat", vec![Prop::F32s(vec![0.0, 100.0])], vec![]),
                    ],
                ),
            ],
        ),
        fbx_node(
            "Connections",
            vec![],
            [
                ("OO", 20, 0, None),
                ("OO", 10, 20, None),
                ("OO", 30, 10, None),
                ("OO", 31, 30, None),
                ("OO", 32, 31, None),
                ("OO", 41, 40, None),
                ("OO", 42, 41, None),
                ("OP", 42, 31, Some("DeformPercent")),
                ("OP", 43, 42, Some("d|DeformPercent")),
            ]
            .into_iter()
            .map(|(k, c, p, prop): (&str, i64, i64, Option<&str>)| {
                let mut props = vec![s(k), Prop::Int(c), Prop::Int(p)];
                props.extend(prop.map(s));
                fbx_node("C", props, vec![])
            })
            .collect(),
        ),
    ];
    crate::mesh::fbx_tree::write(&nodes, compress)
}

/// [`tiny_fbx_with`] unchanged: a seed of the fbx_read fuzz target.
pub fn tiny_fbx(compress: bool) -> Vec<u8> {
    tiny_fbx_with(|_| {}, compress)
}

/// The pose-file readers' options picked by a target's config byte (byte 0 of the input): bits 0-1 the pose
/// source (auto, animation, morph targets, auto), bits 2-4 `frames` (0: the file's own, else 1-7 evenly
/// spread), bit 5 asks for object `0`, bit 6 for animation `0`. The fbx_read, gltf_read and usd_read targets.
pub fn read_options_from(cfg: u8) -> crate::mesh::gltf::Options {
    use crate::mesh::gltf::{Options, PoseSource};
    Options {
        source: [PoseSource::Auto, PoseSource::Animation, PoseSource::MorphTargets, PoseSource::Auto]
            [(cfg & 3) as usize],
        frames: match (cfg >> 2) & 7 {
            0 => None,
            f => Some(f as usize),
        },
        mesh: (cfg & 32 != 0).then(|| "0".to_string()),
        animation: (cfg & 64 != 0).then(|| "0".to_string()),
    }
}

/// Invariants of a mesh that a reader returned: vertices, finite coordinates, faces in range. Panics otherwise.
pub fn check_mesh(mesh: &crate::mesh::Mesh) {
    assert!(!mesh.positions.is_empty(), "a mesh without vertices loaded");
    assert!(mesh.positions.iter().flatten().all(|c| c.is_finite()), "non-finite coordinate loaded");
    let n = mesh.positions.len();
    assert!(mesh.faces.iter().flatten().all(|&i| (i as usize) < n), "face index out of range for {n} vertices");
}

/// What a pose-file reader (FBX, glTF, USD) must give for file `name` read with `options`: at least one pose,
/// every pose with the welded vertex count (at most the file's) and the first pose's faces, each mesh whole
/// ([`check_mesh`]), the asked number of animation frames, a source naming the file; or an error naming the
/// file. Panics otherwise (a crash for the fuzz targets). Returns whether the file loaded.
pub fn check_pose_read(
    name: &str,
    options: &crate::mesh::gltf::Options,
    read: crate::Result<crate::mesh::gltf::Gltf>,
) -> bool {
    use crate::mesh::gltf::PoseSource;
    match read {
        Ok(g) => {
            assert!(!g.poses.is_empty(), "no poses");
            assert!(g.vertices_welded >= 1 && g.vertices_welded <= g.vertices_in_file);
            assert!(g.source.contains(name), "{}", g.source);
            let faces = &g.poses[0].1.faces;
            assert!(!faces.is_empty());
            for (_, mesh) in &g.poses {
                check_mesh(mesh);
                assert_eq!(mesh.positions.len(), g.vertices_welded);
                assert_eq!(&mesh.faces, faces);
            }
            if let Some(f) = options.frames.filter(|_| options.source == PoseSource::Animation) {
                assert_eq!(g.poses.len(), f, "{}", g.source);
            }
            true
        }
        Err(crate::Error::Obj { file, message, .. } | crate::Error::Mesh { file, message, .. }) => {
            assert_eq!(file, name);
            assert!(!message.is_empty());
            false
        }
        Err(e) => panic!("the reader of {name} returned an error that is not a file's (Obj / Mesh): {e:?}"),
    }
}

// ------------------------------------------------------------------------------------- model files

/// The `model_file` target's check of one input: reading `data` as a model file never panics; an error names the
/// file; a model read is usable (labels within its parts, every cut of its merge tree, every pose rebuilt, its
/// figures measured on its population) and, saved again, reads back as the same model.
pub fn check_model_file(data: &[u8]) {
    use crate::model_file::{ModelFile, Summary};
    let name = "fuzz.posemfa";
    let saved = match ModelFile::from_bytes(name, data) {
        Ok(m) => m,
        Err(e) => {
            assert!(e.to_string().contains(name), "an error that does not name the file: {e}");
            return;
        }
    };
    let r = &saved.result;
    let m = &r.model;
    let pop = &saved.population;
    assert_eq!((m.n_vertices, m.n_shapes), (pop.n_vertices(), pop.n_shapes()));
    assert!(m.labels.iter().all(|&l| (l as usize) < m.n_parts()));
    if let Some(cuts) = r.tree_cuts() {
        let (most, fewest) = cuts.counts();
        for count in fewest..=most.min(fewest + 64) {
            assert_eq!(cuts.labels(count).len(), m.n_vertices);
        }
    }
    for i in 0..m.n_shapes {
        assert_eq!(m.reconstruct(i).len(), m.n_vertices);
    }
    let _ = Summary::measure(pop, r);
    let again = ModelFile::from_bytes(name, &saved.to_bytes(true)).expect("a model saved again reads back");
    assert_eq!(again.result.model, saved.result.model);
    assert_eq!(again.population, saved.population);
}

/// Small model files for the `model_file` target's seed corpus: fits of generated populations, saved with and
/// without their poses.
pub fn model_file_seeds() -> Vec<(String, Vec<u8>)> {
    use crate::model_file::ModelFile;
    use crate::synth::{generate, Preset, Spec};
    let mut out = Vec::new();
    for (preset, vertices, poses) in [(Preset::Snake, 160, 3), (Preset::Arm, 200, 4)] {
        let spec = Spec { preset, vertices, poses, ..Default::default() };
        let Ok(g) = generate(&spec) else { continue };
        let params = Params { max_iter: 10, ..Params::default() };
        let Ok(result) = crate::parts::hierarchy::fit(&g.population, &params, &mut |_| true) else { continue };
        let saved = ModelFile::new(g.population, result, params);
        out.push((format!("{}-with-poses.posemfa", preset.name()), saved.to_bytes(true)));
        out.push((format!("{}-without-poses.posemfa", preset.name()), saved.to_bytes(false)));
    }
    out
}

// ------------------------------------------------------------------------------------- zip archives

/// The `zip_open` target's check of one input: opening `data` as a .zip never panics nor unpacks past its
/// budget (1 MiB here); an error names the archive; what it gives is named inside it and in natural order.
pub fn check_zip_open(data: &[u8]) {
    const BUDGET: u64 = 1 << 20;
    let name = "fuzz.zip";
    match crate::mesh::zip_archive::open(name, data, BUDGET) {
        Err(e) => assert!(e.to_string().contains(name), "an error that does not name the archive: {e}"),
        Ok(a) => {
            let total: u64 = a.files.iter().map(|(_, b)| b.len() as u64).sum();
            assert!(total <= BUDGET && total == a.unpacked, "{total} bytes unpacked, budget {BUDGET}");
            assert!(a.files.iter().all(|(n, _)| n.starts_with("fuzz.zip/")));
            assert!(a.files.windows(2).all(|w| crate::mesh::population::natural_cmp(&w[0].0, &w[1].0).is_le()));
        }
    }
}

/// Small archives for the `zip_open` target's seed corpus: pose files of a generated population, stored and
/// deflated, with a folder, a README and a resource fork beside them.
pub fn zip_seeds() -> Vec<(String, Vec<u8>)> {
    use std::io::Write;
    let Ok(g) = crate::synth::generate(&crate::synth::Spec {
        preset: crate::synth::Preset::Snake,
        vertices: 120,
        poses: 3,
        ..Default::default()
    }) else {
        return Vec::new();
    };
    let pop = g.population;
    let mut out = Vec::new();
    for (k, method) in [zip::CompressionMethod::Stored, zip::CompressionMethod::Deflated].into_iter().enumerate() {
        let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let opts = zip::write::SimpleFileOptions::default().compression_method(method);
        let mut ok = true;
        for i in 0..pop.n_shapes() {
            let text = crate::export::obj::write_obj(&pop.shape(i).to_vec(), &pop.faces, "seed");
            ok &= w.start_file(format!("poses/{}", pop.names[i]), opts).is_ok() && w.write_all(text.as_bytes()).is_ok();
        }
        ok &= w.start_file("README.txt", opts).is_ok() && w.write_all(b"poses of a snake").is_ok();
        ok &= w.start_file("__MACOSX/._pose01.obj", opts).is_ok() && w.write_all(b"fork").is_ok();
        if let (true, Ok(c)) = (ok, w.finish()) {
            out.push((format!("snake-{k}.zip"), c.into_inner()));
        }
    }
    out
}

#[cfg(test)]
mod zip_seed_tests {
    /// The zip target's seeds open (their three poses, the README and the fork skipped) and pass its check.
    #[test]
    fn the_zip_seeds_open_and_pass_the_target_check() {
        let seeds = super::zip_seeds();
        assert_eq!(seeds.len(), 2);
        for (name, bytes) in &seeds {
            let a = crate::mesh::zip_archive::open("fuzz.zip", bytes, 1 << 20).expect("a seed opens");
            assert_eq!(a.files.len(), 3, "{name}");
            assert_eq!(a.skipped.len(), 2, "{name}: {:?}", a.skipped);
            super::check_zip_open(bytes);
            super::check_zip_open(&bytes[..bytes.len() / 2]);
        }
    }
}
