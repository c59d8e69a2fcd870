//! bytes -> posemfa::model_file::ModelFile::from_bytes (a .posemfa model file).
//!
//! Must never panic, hang or allocate beyond the memory budget (lowered to 256 MiB here); an error names the
//! file. What it reads must be usable by everything that takes a model: its labels within its parts, its
//! merge tree's cuts of every count, its poses rebuilt, its figures measured, and saved again it must read back
//! as the same model (`posemfa::fuzzing::check_model_file`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa_fuzz::limit_memory;

fuzz_target!(|data: &[u8]| {
    limit_memory();
    posemfa::fuzzing::check_model_file(data);
});
