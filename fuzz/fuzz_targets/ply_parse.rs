//! bytes -> posemfa::mesh::ply::parse_ply (ASCII, binary little and big endian). Must never panic or
//! allocate from an unchecked count; a loaded mesh has vertices, finite coordinates and faces in range, and
//! no more vertices than the file has bytes; an error names the file and a line of the file (0: the whole
//! file or binary data, where the message gives the byte offset).
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::mesh::ply::parse_ply;
use posemfa::error::Format;
use posemfa::Error;
use posemfa_fuzz::check_mesh;

fuzz_target!(|data: &[u8]| {
    let lines = data.iter().filter(|&&b| b == b'\n' || b == b'\r').count() + 1;
    match parse_ply("fuzz.ply", data) {
        Ok(mesh) => {
            check_mesh(&mesh);
            // Every vertex takes at least one byte (a 1-byte property, or a character and a separator).
            assert!(mesh.positions.len() <= data.len(), "{} vertices from {} bytes", mesh.positions.len(), data.len());
        }
        Err(Error::Mesh { format: Format::Ply, file, line, message }) => {
            assert_eq!(file, "fuzz.ply");
            assert!(!message.is_empty());
            assert!(line <= lines, "error on line {line} of a {lines}-line file: {message}");
        }
        Err(e) => panic!("parse_ply returned an error that is not a PLY reader's: {e:?}"),
    }
});
