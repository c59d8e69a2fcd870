//! bytes -> posemfa::mesh::fbx::read (a .fbx file) with the options picked by byte 0
//! (`posemfa::fuzzing::read_options_from`).
//!
//! Must never panic, hang or allocate beyond the memory budget (lowered to 256 MiB here); what it reads must
//! pass `posemfa::fuzzing::check_pose_read` (poses with the welded vertex count and the same faces, finite
//! coordinates, a source naming the file; an error names the file).
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::fuzzing::{check_pose_read, read_options_from};
use posemfa_fuzz::limit_memory;

fuzz_target!(|data: &[u8]| {
    limit_memory();
    let Some((&cfg, file)) = data.split_first() else { return };
    let options = read_options_from(cfg);
    let name = "fuzz.fbx";
    let read = posemfa::mesh::fbx::read(name, file, &options);
    check_pose_read(name, &options, read);
});
