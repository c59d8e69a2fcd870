//! bytes -> the rig input of `posemfa pose` (posemfa::export::pose_glb::read_rig, through the checked glTF reader)
//! and of `posemfa rig-report --glb` (posemfa::export::gltf::play_glb_clip).
//!
//! Must never panic, hang or allocate beyond the memory budget (lowered to 256 MiB here). An error names the
//! file. A rig that is read has its faces on its vertices and finite bind positions; written again with a
//! one-frame clip of its rest pose ([`GlbRig::with_clip`]), the .glb it gives is read and played back by the
//! same reader: one frame of its vertices.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::export::gltf::play_glb_clip;
use posemfa::export::pose_glb::read_rig;
use posemfa_fuzz::limit_memory;

fuzz_target!(|data: &[u8]| {
    limit_memory();
    match read_rig("fuzz.glb", data) {
        Err(e) => {
            let s = e.to_string();
            assert!(s.contains("fuzz.glb"), "an error that does not name the file: {s}");
        }
        Ok(rig) => {
            let nv = rig.rig.n_vertices();
            assert!(rig.faces.iter().flatten().all(|&v| (v as usize) < nv), "a face past the {nv} vertices");
            assert!(rig.rig.rest.iter().flatten().all(|x| x.is_finite()), "a bind position that is not finite");
            if let Ok(out) = rig.with_clip("frames", &[rig.rest_bones()]) {
                let again = read_rig("again.glb", &out).expect("a rig written by with_clip is read again");
                assert_eq!(again.rig.n_vertices(), nv);
                let play = play_glb_clip(&out, "frames").expect("the clip with_clip wrote plays");
                assert_eq!(play.frames.len(), 1);
                assert_eq!(play.frames[0].len(), nv);
            }
        }
    }
    // rig-report --glb: a user's .glb played (any outcome but a panic)
    let _ = play_glb_clip(data, "training poses");
});
