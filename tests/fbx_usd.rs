//! FBX and USD files as characters leave Maya, 3ds Max, Blender, MotionBuilder and USD pipelines:
//! fixtures written by Blender (FBX) and Pixar's usd-core (USD) from generated populations, read through the
//! same readers natively and in wasm; hostile files refused with their exact messages.

#[macro_use]
mod common;

use common::blender::{blender_source, fit_summary, max_diff, y_up};

use posemfa::mesh::Population;
use posemfa::synth::{generate, Preset, Spec};

dual_test! {
    /// Blender's FBX of the poses as shape keys, animated one key per frame (DeformPercent curves): six
    /// frames at 24 fps, the generated poses to float32 precision (Y up, metres), the same fit.
    fn blender_shape_key_fbx_gives_the_obj_population() {
        let g = blender_source();
        let bytes = include_bytes!("fixtures/blender/quadruped-shapekeys.fbx").to_vec();
        let pop = Population::new(posemfa::mesh::Sources::Files(vec![("quadruped-shapekeys.fbx".into(), bytes)])).unwrap();
        assert!(pop.source.starts_with("6 frames of posed in quadruped-shapekeys.fbx (animation 'Scene', 24 fps"), "{}", pop.source);
        assert!(pop.source.contains("5 blend shapes"), "{}", pop.source);
        assert_eq!((pop.n_shapes(), pop.n_vertices()), (6, 1198));
        assert_eq!(pop.faces, g.population.faces);
        for (i, shape) in pop.unit_shapes().iter().enumerate() {
            let ours: Vec<[f64; 3]> = shape.iter().map(|&p| pop.normalization.to_original(p)).collect();
            let want: Vec<[f64; 3]> = g.population.unit_shapes()[i].iter().map(|&p| y_up(p)).collect();
            assert!(max_diff(&ours, &want) < 1e-6, "pose {i}: {}", max_diff(&ours, &want));
        }
        let (parts_obj, rmse_obj, labels_obj) = fit_summary(&g.population);
        let (parts, rmse, labels) = fit_summary(&pop);
        assert_eq!(parts, parts_obj);
        assert!((rmse - rmse_obj).abs() <= 0.01 * rmse_obj, "RMSE {rmse}, OBJ {rmse_obj}");
        assert!(posemfa::metrics::adjusted_rand_index(&labels, &labels_obj) >= 0.99);
    }

    /// Blender's FBX of posemfa's rig (armature, Skin / Clusters, baked bone curves): the character's 1198
    /// vertices, every frame of the take, and a fit within 1.5x the RMSE of the same rig read as glTF.
    fn blender_skinned_fbx_gives_the_character() {
        let bytes = include_bytes!("fixtures/blender/quadruped-skinned.fbx");
        let f = posemfa::mesh::fbx::read("quadruped-skinned.fbx", bytes, &Default::default()).unwrap();
        assert_eq!(f.vertices_welded, 1198, "{}", f.source);
        assert!(f.source.contains("skinned by"), "{}", f.source);
        let pop = Population::new(posemfa::mesh::Sources::Files(vec![("quadruped-skinned.fbx".into(), bytes.to_vec())])).unwrap();
        let glb = include_bytes!("fixtures/blender/quadruped-skinned-seams.glb");
        let gl = Population::new(posemfa::mesh::Sources::Files(vec![("quadruped-skinned-seams.glb".into(), glb.to_vec())])).unwrap();
        assert!(pop.source.starts_with("121 frames of mesh in quadruped-skinned.fbx (animation 'Scene', 24 fps, 0.000 s to 5.000 s; skinned by 18 bones)"), "{}", pop.source);
        let (parts, rmse, _) = fit_summary(&pop);
        let (parts_gl, rmse_gl, _) = fit_summary(&gl);
        eprintln!("skinned FBX: {parts} parts, RMSE {rmse}; glTF: {parts_gl} parts, RMSE {rmse_gl}");
        assert!(rmse <= 1.5 * rmse_gl, "RMSE {rmse}, glTF {rmse_gl}");
    }
}

// ------------------------------------------------------------------------------------- hostile FBX files

use posemfa::mesh::fbx_tree::{Node, Prop};

use posemfa::fuzzing::tiny_fbx_with as tiny_fbx;

fn node(name: &str, props: Vec<Prop>, children: Vec<Node>) -> Node {
    Node { name: name.into(), props, children, offset: 0 }
}

fn fbx_error(name: &str, bytes: &[u8]) -> String {
    posemfa::mesh::fbx::read(name, bytes, &Default::default()).map(|g| g.source).unwrap_err().to_string()
}

dual_test! {
    /// The tiny scene reads (plain and zlib arrays): three frames, the shape at 0, 50 and 100 %.
    fn a_tiny_blend_shape_scene_reads() {
        for compress in [false, true] {
            let f = posemfa::mesh::fbx::read("tiny.fbx", &tiny_fbx(|_| {}, compress), &Default::default()).unwrap();
            assert_eq!(f.source, "3 frames of Quad in tiny.fbx (animation 'Take 1', 24 fps, 0.000 s to 0.083 s; 1 blend shapes); Y up, metres (UnitScaleFactor 100); 4 vertices");
            assert_eq!(f.poses.len(), 3);
            assert_eq!(f.poses[0].1.faces, vec![[0, 1, 2], [0, 2, 3]]);
            assert_eq!(f.poses[1].1.positions[2], [1.0, 1.0, 0.5]);
            assert_eq!(f.poses[2].1.positions[3], [0.0, 1.0, 2.0]);
        }
    }

    fn fbx_wrong_magic_and_ascii_are_refused() {
        assert_eq!(
            fbx_error("a.fbx", b"PK\x03\x04 not an fbx"),
            "file a.fbx: is not a binary FBX file (it does not start with \"Kaydara FBX Binary\"); the file is damaged or has the wrong extension: export it again as binary FBX 7.x"
        );
        assert_eq!(
            fbx_error("b.fbx", b"; FBX 7.4.0 project file\n; ----\nFBXHeaderExtension:  {\n}\n"),
            "file b.fbx: is an ASCII FBX file; posemfa reads binary FBX 7.x: export it again as binary FBX (Blender always writes binary; in Maya, 3ds Max and MotionBuilder choose File Format: Binary in the FBX export options)"
        );
        let mut old = tiny_fbx(|_| {}, false);
        old[23..27].copy_from_slice(&6100u32.to_le_bytes());
        assert_eq!(fbx_error("c.fbx", &old), "file c.fbx: is FBX version 6.1 (6100); posemfa reads binary FBX 7.x (7.0 to 7.7): export it again as FBX 2011 or newer");
    }

    fn fbx_truncated_is_refused() {
        let bytes = tiny_fbx(|_| {}, false);
        assert_eq!(
            fbx_error("cut.fbx", &bytes[..20]),
            "file cut.fbx: is not a binary FBX file (it does not start with \"Kaydara FBX Binary\"); the file is damaged or has the wrong extension: export it again as binary FBX 7.x"
        );
        assert_eq!(fbx_error("cut.fbx", &bytes[..25]), "file cut.fbx: the FBX header is cut (25 of 27 bytes); the file is cut: export it again");
        assert_eq!(
            fbx_error("cut.fbx", &bytes[..bytes.len() / 2]),
            format!("file cut.fbx: node 'Objects' at byte 263 says it ends at byte 1462, past the end of the file (byte {}); the file is cut or damaged: export it again", bytes.len() / 2)
        );
        let mut lying = bytes.clone();
        lying[263..267].copy_from_slice(&270u32.to_le_bytes());
        assert_eq!(
            fbx_error("lying.fbx", &lying),
            "file lying.fbx: node 'Objects' at byte 263 says it ends at byte 270, before its own properties end (byte 283); the file is damaged: export it again"
        );
    }

    fn fbx_arrays_that_lie_about_their_size_are_refused() {
        // A zlib array that inflates past the count it declares: 12 doubles of data, 2 declared.
        let mut bytes = tiny_fbx(|_| {}, true);
        let at = find_array(&bytes, b"Vertices", b'd');
        bytes[at + 1..at + 5].copy_from_slice(&2u32.to_le_bytes());
        let msg = fbx_error("inflate.fbx", &bytes);
        assert_eq!(msg, format!("file inflate.fbx: property 0 of node 'Vertices' at byte {at} inflates past the 16 bytes it declares; the file is damaged: export it again"));
        // A zlib array that claims more than its bytes can inflate to.
        bytes[at + 1..at + 5].copy_from_slice(&50_000_000u32.to_le_bytes());
        let msg = fbx_error("inflate.fbx", &bytes);
        assert!(msg.starts_with(&format!("file inflate.fbx: property 0 of node 'Vertices' at byte {at} declares 50000000 elements (400000000 bytes) from ")), "{msg}");
        assert!(msg.ends_with(" compressed bytes, more than zlib can hold; the file is damaged: export it again"), "{msg}");
        // A plain array whose count asks for 32 GB.
        let mut bytes = tiny_fbx(|_| {}, false);
        let at = find_array(&bytes, b"Vertices", b'd');
        bytes[at + 1..at + 5].copy_from_slice(&u32::MAX.to_le_bytes());
        let msg = fbx_error("huge.fbx", &bytes);
        assert!(msg.starts_with(&format!("file huge.fbx: property 0 of node 'Vertices' at byte {at} asks for 4294967295 elements (34359738360 bytes), more than the memory budget left for this file (")), "{msg}");
        // A plain array whose stored length runs past its node.
        let mut bytes = tiny_fbx(|_| {}, false);
        let at = find_array(&bytes, b"Vertices", b'd');
        bytes[at + 9..at + 13].copy_from_slice(&1_000_000u32.to_le_bytes());
        assert_eq!(
            fbx_error("past.fbx", &bytes),
            format!("file past.fbx: property 0 of node 'Vertices' (1000000 bytes of array data) at byte {at} runs past the end of the file ({} bytes); the file is cut or damaged: export it again", bytes.len())
        );
    }

    fn fbx_indices_past_the_mesh_are_refused() {
        let bytes = tiny_fbx(|g| g[1] = node("PolygonVertexIndex", vec![Prop::I32s(vec![0, 1, 99, -4])], vec![]), false);
        assert_eq!(
            fbx_error("index.fbx", &bytes),
            "file index.fbx: Geometry 'quad' (id 10) of model 'Quad': PolygonVertexIndex[2] names control point 99, but there are 4; the file is damaged: export it again"
        );
        let bytes = tiny_fbx(|g| g[0] = node("Vertices", vec![Prop::F64s(vec![0.0; 10])], vec![]), false);
        assert_eq!(
            fbx_error("odd.fbx", &bytes),
            "file odd.fbx: Geometry 'quad' (id 10) of model 'Quad': Vertices holds 10 numbers, not a multiple of 3; the file is damaged: export it again"
        );
    }

    fn fbx_object_choice_names_the_meshes() {
        let bytes = tiny_fbx(|_| {}, false);
        let options = posemfa::mesh::gltf::Options { mesh: Some("Body".into()), ..Default::default() };
        let e = posemfa::mesh::fbx::read("tiny.fbx", &bytes, &options).unwrap_err().to_string();
        assert_eq!(e, "file tiny.fbx: no mesh is called or numbered `Body`; the file has Quad");
        let options = posemfa::mesh::gltf::Options { mesh: Some("Quad".into()), ..Default::default() };
        assert!(posemfa::mesh::fbx::read("tiny.fbx", &bytes, &options).is_ok());
    }
}

/// The offset of the first array property of type `code` of the node `name` (its type code byte).
fn find_array(bytes: &[u8], name: &[u8], code: u8) -> usize {
    let mut pat = vec![name.len() as u8];
    pat.extend_from_slice(name);
    let at = bytes.windows(pat.len()).position(|w| w == &pat[..]).expect("node present") + pat.len();
    assert_eq!(bytes[at], code);
    at
}

// ------------------------------------------------------------------------------------------------ USD

/// The population the USD fixtures were made from (scripts/fixtures/make-usd-fixtures.sh).
fn usd_source() -> posemfa::synth::Generated {
    generate(&Spec { preset: Preset::Arm, vertices: 400, poses: 5, seed: 3, ..Spec::default() }).unwrap()
}

/// Where pose `k` (0-based) of the fixture's points lands: /World/Character's translate (0.5 k, 0, 0),
/// rotateXYZ (0, 0, 30), scale 2, then /World/Character/Body's translate (0, 1, 0); then the stage's Z up
/// turned to Y up ((x, y, z) -> (x, z, -y)) and centimetres to metres.
fn usd_expected(k: usize, p: [f64; 3]) -> [f64; 3] {
    let (s, c) = 30f64.to_radians().sin_cos();
    let (x, y, z) = (p[0], p[1] + 1.0, p[2]);
    let (x, y, z) = (2.0 * x, 2.0 * y, 2.0 * z);
    let (x, y) = (c * x - s * y, s * x + c * y);
    let x = x + 0.5 * k as f64;
    [0.01 * x, 0.01 * z, -0.01 * y]
}

dual_test! {
    /// usd-core's .usda, .usdc and .usdz of the same point cache give the generated poses with the
    /// transforms applied (to float32 rounding), and the same fit as the OBJ population.
    fn usd_point_caches_give_the_obj_population() {
        let g = usd_source();
        let (parts_obj, rmse_obj, labels_obj) = fit_summary(&g.population);
        for (name, bytes) in [
            ("arm-pointcache.usda", &include_bytes!("fixtures/usd/arm-pointcache.usda")[..]),
            ("arm-pointcache.usdc", &include_bytes!("fixtures/usd/arm-pointcache.usdc")[..]),
            ("arm-pointcache.usdz", &include_bytes!("fixtures/usd/arm-pointcache.usdz")[..]),
        ] {
            let pop = Population::new(posemfa::mesh::Sources::Files(vec![(name.into(), bytes.to_vec())])).unwrap();
            assert_eq!(
                pop.source,
                format!("5 frames of Body in {name} (time-sampled points of /World/Character/Body, one per time sample, times 1 to 5 at 24 per second); upAxis Z turned to Y up, metersPerUnit 0.01 turned to metres; 408 vertices")
            );
            assert_eq!((pop.n_shapes(), pop.n_vertices()), (5, 408));
            assert_eq!(pop.faces, g.population.faces);
            for (k, shape) in pop.unit_shapes().iter().enumerate() {
                let ours: Vec<[f64; 3]> = shape.iter().map(|&p| pop.normalization.to_original(p)).collect();
                let want: Vec<[f64; 3]> = g.population.unit_shapes()[k].iter().map(|&p| usd_expected(k, p)).collect();
                let d = max_diff(&ours, &want);
                assert!(d < 1e-8, "{name} pose {k}: {d}");
            }
            // RMSE in the OBJ's units: the file's are scaled by 2 (the parent) and 0.01 (centimetres to metres).
            let (parts, rmse, labels) = fit_summary(&pop);
            let rmse = pop.normalization.length_to_original(rmse) / 0.02;
            let rmse_obj = g.population.normalization.length_to_original(rmse_obj);
            assert_eq!(parts, parts_obj, "{name}");
            assert!((rmse - rmse_obj).abs() <= 0.01 * rmse_obj, "{name}: RMSE {rmse}, OBJ {rmse_obj}");
            assert!(posemfa::metrics::adjusted_rand_index(&labels, &labels_obj) >= 0.99, "{name}");
        }
    }
}

fn usd_error(name: &str, bytes: &[u8]) -> String {
    posemfa::mesh::usd::read(name, bytes, &Default::default()).map(|g| g.source).unwrap_err().to_string()
}

/// A usda stage with one quad mesh: `points` is the points attribute's text, `faces` the face attributes'.
fn usda(points: &str, faces: &str) -> Vec<u8> {
    format!("#usda 1.0\n(\n    upAxis = \"Y\"\n)\n\ndef Mesh \"Quad\"\n{{\n    {faces}\n    {points}\n}}\n")
        .into_bytes()
}

const QUAD_FACES: &str = "int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 3]";
const QUAD_POINTS: &str = "point3f[] points.timeSamples = {\n        1: [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)],\n        2: [(0, 0, 0), (1, 0, 0), (1, 1, 1), (0, 1, 1)],\n    }";

dual_test! {
    fn a_tiny_usda_point_cache_reads() {
        let g = posemfa::mesh::usd::read("quad.usda", &usda(QUAD_POINTS, QUAD_FACES), &Default::default()).unwrap();
        assert_eq!(g.source, "2 frames of Quad in quad.usda (time-sampled points of /Quad, one per time sample, times 1 to 2 at 24 per second); upAxis Y, metersPerUnit not stated: lengths as in the file; 4 vertices");
        assert_eq!(g.poses[1].1.positions[3], [0.0, 1.0, 1.0]);
        assert_eq!(g.poses[0].1.faces, vec![[0, 1, 2], [0, 2, 3]]);
    }

    fn usd_wrong_magic_truncated_and_empty_packages_are_refused() {
        assert_eq!(
            usd_error("a.usd", b"glTF not usd"),
            "file a.usd: is not a USD file (it starts with neither \"#usda\", \"PXR-USDC\" nor a zip header); the file is damaged or has the wrong extension: export it again as .usda, .usdc or .usdz"
        );
        let usdc = include_bytes!("fixtures/usd/arm-pointcache.usdc");
        let msg = usd_error("cut.usdc", &usdc[..usdc.len() / 2]);
        assert!(msg.starts_with("file cut.usdc: cannot read the USD crate file (usdc): "), "{msg}");
        assert!(msg.ends_with("; the file is cut or damaged: export it again"), "{msg}");
        let msg = usd_error("cut.usdc", &usdc[..100]);
        assert!(msg.starts_with("file cut.usdc: cannot read the USD crate file (usdc): "), "{msg}");
        let usdz = include_bytes!("fixtures/usd/arm-pointcache.usdz");
        let msg = usd_error("cut.usdz", &usdz[..usdz.len() / 2]);
        assert!(msg.starts_with("file cut.usdz: cannot read the USD"), "{msg}");
        assert!(msg.ends_with("; the file is cut or damaged: export it again"), "{msg}");
        // a zip with no USD layer in it (tests/fixtures/usd/no-layer.usdz: one readme.txt)
        assert_eq!(
            usd_error("no-layer.usdz", include_bytes!("fixtures/usd/no-layer.usdz")),
            "file no-layer.usdz: the USDZ package holds no .usda, .usdc or .usd layer; package the stage again (usdzip)"
        );
    }

    fn usd_faces_and_points_that_do_not_fit_are_refused() {
        assert_eq!(
            usd_error("sum.usda", &usda(QUAD_POINTS, "int[] faceVertexCounts = [4, 3]\n    int[] faceVertexIndices = [0, 1, 2, 3]")),
            "file sum.usda: mesh /Quad: faceVertexCounts add up to 7 corners but faceVertexIndices has 4; the file is damaged: export it again"
        );
        assert_eq!(
            usd_error("index.usda", &usda(QUAD_POINTS, "int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 9]")),
            "file index.usda: mesh /Quad: faceVertexIndices[3] names point 9, but the mesh has 4; the file is damaged: export it again"
        );
        let changing = "point3f[] points.timeSamples = {\n        1: [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)],\n        2: [(0, 0, 0), (1, 0, 0), (1, 1, 1)],\n    }";
        assert_eq!(
            usd_error("count.usda", &usda(changing, QUAD_FACES)),
            "file count.usda: mesh /Quad: points at time 2 has 3 points but 4 at time 1; a point cache keeps its points: export it again"
        );
    }

    fn usd_meshes_without_a_point_cache_are_refused() {
        let still = "point3f[] points = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]";
        assert_eq!(
            usd_error("still.usda", &usda(still, QUAD_FACES)),
            "file still.usda: mesh /Quad has no time-sampled points; posemfa reads only point-cached meshes from USD (a UsdGeomMesh whose points are time-sampled, one pose per sample): bake the animation to points (e.g. Blender's USD export of the evaluated mesh), or export the character as FBX or glTF"
        );
        let skinned = format!("{still}\n    rel skel:skeleton = </Skel>");
        assert_eq!(
            usd_error("skinned.usda", &usda(&skinned, QUAD_FACES)),
            "file skinned.usda: mesh /Quad is a skinned UsdSkel mesh; posemfa reads only point-cached meshes from USD (a UsdGeomMesh whose points are time-sampled, one pose per sample): bake the animation to points (e.g. Blender's USD export of the evaluated mesh), or export the character as FBX or glTF"
        );
        assert_eq!(
            usd_error("none.usda", b"#usda 1.0\n\ndef Xform \"World\"\n{\n}\n"),
            "file none.usda: the stage holds no Mesh prim (UsdGeomMesh); export the character's mesh (with its points time-sampled)"
        );
        let options = posemfa::mesh::gltf::Options { mesh: Some("Body".into()), ..Default::default() };
        assert_eq!(
            posemfa::mesh::usd::read("quad.usda", &usda(QUAD_POINTS, QUAD_FACES), &options).unwrap_err().to_string(),
            "file quad.usda: no mesh is called or numbered `Body`; the stage has /Quad"
        );
    }
}
