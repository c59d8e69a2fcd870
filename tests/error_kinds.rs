//! Errors name their format: a damaged file of each format read through `mesh::load` (what `fit`, `inspect`
//! and the page use) gives an error whose kind is its format ("obj", "ply", "gltf", "fbx", "usd",
//! "pointcache"; `Problem::kind`, which src/wasm.rs hands to JavaScript as `kind`), with the file's name and,
//! where the format has lines, the line.

#[macro_use]
mod common;

use posemfa::error::{Error, Format};
use posemfa::mesh::load::load;

fn refused(files: &[(&str, &[u8])], file: &str) -> Error {
    let given = files.iter().map(|(n, b)| (n.to_string(), b.to_vec())).collect();
    let errors = match load(given) {
        Ok(l) => panic!("{file}: read, {} poses", l.poses.len()),
        Err(e) => e,
    };
    errors
        .into_iter()
        .find(|e| e.problem().file.as_deref() == Some(file))
        .unwrap_or_else(|| panic!("no error names {file}"))
}

dual_test! {
    fn each_format_s_reader_gives_its_own_kind() {
        let obj = refused(&[("a.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 9\n"), ("b.obj", b"v 0 0 0\n")], "a.obj");
        assert_eq!((obj.problem().kind, obj.problem().line), ("obj", Some(3)), "{obj}");
        let ply = refused(
            &[("a.ply", b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\nzz\n")],
            "a.ply",
        );
        assert!(matches!(ply, Error::Mesh { format: Format::Ply, .. }), "{ply:?}");
        assert_eq!(ply.problem().kind, "ply");
        assert!(ply.problem().line.is_some() && ply.to_string().starts_with("file a.ply, line "), "{ply}");
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(1000u32.to_le_bytes());
        let gltf = refused(&[("a.glb", &glb)], "a.glb");
        assert_eq!(gltf.problem().kind, "gltf", "{gltf}");
        assert!(gltf.to_string().starts_with("file a.glb: "), "{gltf}");
        let gltf = refused(&[("a.gltf", br#"{"asset": {"version": "2.0"}, "meshes": 7}"#)], "a.gltf");
        assert_eq!(gltf.problem().kind, "gltf", "{gltf}");
        let mut fbx = b"Kaydara FBX Binary  \x00\x1a\x00".to_vec();
        fbx.extend(7400u32.to_le_bytes());
        fbx.extend([0xff; 40]);
        let fbx = refused(&[("a.fbx", &fbx)], "a.fbx");
        assert_eq!(fbx.problem().kind, "fbx", "{fbx}");
        let usd = refused(&[("a.usda", b"#usda 1.0\ndef Mesh \"m\" {\n  point3f[] points = [(0, 0\n")], "a.usda");
        assert_eq!(usd.problem().kind, "usd", "{usd}");
        let mut usdc = b"PXR-USDC".to_vec();
        usdc.extend([0u8; 80]);
        let usdc = refused(&[("a.usdc", &usdc)], "a.usdc");
        assert_eq!(usdc.problem().kind, "usd", "{usdc}");
        let mut pc2 = b"POINTCACHE2\0".to_vec();
        pc2.extend(1u32.to_le_bytes());
        pc2.extend(3u32.to_le_bytes());
        let cache =
            refused(&[("rest.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), ("a.pc2", &pc2)], "a.pc2");
        assert_eq!(cache.problem().kind, "pointcache", "{cache}");
        // JSON as the page gets it: the kind is the format
        let json = serde_json::to_value(gltf_problem()).unwrap();
        assert_eq!(json["kind"], "gltf");
    }
}

fn gltf_problem() -> posemfa::error::Problem {
    let mut glb = b"glTF".to_vec();
    glb.extend(3u32.to_le_bytes());
    glb.extend(12u32.to_le_bytes());
    refused(&[("v3.glb", &glb)], "v3.glb").problem()
}
