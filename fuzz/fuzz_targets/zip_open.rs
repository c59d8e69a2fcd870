//! bytes -> posemfa::mesh::zip_archive::open (a .zip of pose files), with an unpack budget of 1 MiB.
//!
//! Must never panic, hang or unpack past the budget; an error names the archive; every file it gives is named
//! inside the archive, in natural order, and together they are at most the budget.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    posemfa::fuzzing::check_zip_open(data);
});
