//! bytes -> posemfa::mesh::obj::parse_obj. Must never panic; a loaded mesh has vertices, finite
//! coordinates and faces whose indices are in range; an error names the file and a real line.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::mesh::obj::parse_obj;
use posemfa::Error;

fuzz_target!(|data: &[u8]| {
    match parse_obj("fuzz.obj", data) {
        Ok(mesh) => {
            assert!(!mesh.positions.is_empty(), "a mesh without vertices loaded");
            assert!(mesh.positions.iter().flatten().all(|c| c.is_finite()), "non-finite coordinate loaded");
            let n = mesh.positions.len();
            assert!(mesh.faces.iter().flatten().all(|&i| (i as usize) < n), "face index out of range");
            // Every `v` line gives one vertex: never more vertices than lines.
            let lines = data.iter().filter(|&&b| b == b'\n' || b == b'\r').count() + 1;
            assert!(n <= lines, "{n} vertices from {lines} lines");
        }
        Err(Error::Obj { file, line, message }) => {
            assert_eq!(file, "fuzz.obj");
            assert!(!message.is_empty());
            // line 0 = the whole file; otherwise a line that exists (a line end counts as one more line).
            let lines = data.iter().filter(|&&b| b == b'\n' || b == b'\r').count() + 1;
            assert!(line <= lines, "error on line {line} of a {lines}-line file: {message}");
        }
        Err(e) => panic!("parse_obj returned a non-Obj error: {e:?}"),
    }
});
