//! bytes -> posemfa::mesh::fbx::read (a .fbx file) with the options picked by byte 0: bits 0-1 the pose source (auto,
//! animation, morph targets), bits 2-4 `frames` (0: the file's frames, else 1-7 evenly spaced), bit 5 asks for
//! object `0`, bit 6 for animation `0`.
//!
//! Must never panic, hang or allocate beyond the memory budget (lowered to 256 MiB here); a loaded file gives
//! at least one pose, every pose with the welded vertex count (at most the file's), the same faces in range,
//! finite coordinates, and a source naming the file; an error names the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::mesh::gltf::{Options, PoseSource};
use posemfa::Error;
use posemfa_fuzz::{check_mesh, limit_memory};

fuzz_target!(|data: &[u8]| {
    limit_memory();
    let Some((&cfg, file)) = data.split_first() else { return };
    let options = Options {
        source: [PoseSource::Auto, PoseSource::Animation, PoseSource::MorphTargets, PoseSource::Auto][(cfg & 3) as usize],
        frames: match (cfg >> 2) & 7 {
            0 => None,
            f => Some(f as usize),
        },
        mesh: (cfg & 32 != 0).then(|| "0".to_string()),
        animation: (cfg & 64 != 0).then(|| "0".to_string()),
    };
    let name = "fuzz.fbx";
    match posemfa::mesh::fbx::read(name, file, &options) {
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
        }
        Err(Error::Obj { file, message, .. }) => {
            assert_eq!(file, name);
            assert!(!message.is_empty());
        }
        Err(e) => panic!("the reader returned a non-Obj error: {e:?}"),
    }
});
