//! bytes -> coordinates -> a Population of unit-box shapes -> a bounded fit. Reaches the model with geometry
//! the OBJ text rarely gives: coincident and collinear vertices on a coarse grid, huge and tiny scales,
//! subnormals, NaN and infinities (raw f64 bits), faces out of range.
//!
//! Input layout ([`posemfa::fuzzing::decode_shapes`]): byte 0 configures the fit; byte 1: bits 0-1 the number
//! format (0/3: i8 on a grid of 1/16, 1: i16 / 256, 2: raw f64 bits), bits 2-4 the number of shapes - 2
//! (2..=9, so some exceed the fit's cap), bits 5-7 the number of extra faces; then the extra faces (3 bytes
//! each, indices may be out of range); the rest is read as coordinates, shape after shape.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::fuzzing::{decode_shapes, ShapesInput};
use posemfa::mesh::Population;
use posemfa::Error;
use posemfa_fuzz::{bounded_fit, check_population};

fuzz_target!(|data: &[u8]| {
    let Some(ShapesInput { cfg, names, faces, shapes }) = decode_shapes(data) else { return };
    let n_vertices = shapes[0].len();
    let faces_ok = faces.iter().flatten().all(|&v| (v as usize) < n_vertices);
    let finite = shapes.iter().flatten().flatten().all(|v| v.is_finite());
    match Population::new(posemfa::mesh::Sources::UnitShapes { names, faces, shapes }) {
        Ok(pop) => {
            assert!(faces_ok, "a face out of range was accepted");
            assert!(finite, "a non-finite coordinate was accepted");
            check_population(&pop);
            bounded_fit(&pop, cfg);
        }
        Err(Error::Population { file, message }) => {
            assert!(file.starts_with('s') || file == "(none)", "{file}");
            assert!(!message.is_empty());
        }
        Err(e) => panic!("unexpected kind of error: {e:?}"),
    }
});
