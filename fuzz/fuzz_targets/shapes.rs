//! bytes -> coordinates -> Population::from_unit_shapes -> a bounded fit. Reaches the model with geometry
//! the OBJ text rarely gives: coincident and collinear vertices on a coarse grid, huge and tiny scales,
//! subnormals, NaN and infinities (raw f64 bits), faces out of range.
//!
//! Input layout: byte 0 configures the fit ([`posemfa_fuzz::params_from`]); byte 1: bits 0-1 the number
//! format (0/3: i8 on a grid of 1/16, 1: i16 / 256, 2: raw f64 bits), bits 2-4 the number of shapes - 2
//! (2..=9, so some exceed the fit's cap), bits 5-7 the number of extra faces; then the extra faces (3 bytes
//! each, indices may be out of range); the rest is read as coordinates, shape after shape.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::mesh::Population;
use posemfa::Error;
use posemfa_fuzz::{bounded_fit, check_population};

fuzz_target!(|data: &[u8]| {
    let [cfg, layout, rest @ ..] = data else { return };
    let format = layout & 3;
    let n_shapes = 2 + ((layout >> 2) & 7) as usize;
    let n_faces = ((layout >> 5) & 7) as usize;
    let (face_bytes, coords) = rest.split_at((3 * n_faces).min(rest.len()));
    let mut faces = vec![[0u32, 1, 2]];
    faces.extend(face_bytes.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]));
    let values: Vec<f64> = match format {
        1 => coords.chunks_exact(2).map(|c| i16::from_le_bytes([c[0], c[1]]) as f64 / 256.0).collect(),
        2 => coords.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect(),
        _ => coords.iter().map(|&b| b as i8 as f64 / 16.0).collect(),
    };
    let n_vertices = values.len() / (3 * n_shapes);
    let shapes: Vec<Vec<[f64; 3]>> = (0..n_shapes)
        .map(|i| {
            (0..n_vertices)
                .map(|j| {
                    let at = (i * n_vertices + j) * 3;
                    [values[at], values[at + 1], values[at + 2]]
                })
                .collect()
        })
        .collect();
    let names: Vec<String> = (0..n_shapes).map(|i| format!("s{i}")).collect();
    let faces_ok = faces.iter().flatten().all(|&v| (v as usize) < n_vertices);
    let finite = values[..n_vertices * n_shapes * 3].iter().all(|v| v.is_finite());
    match Population::from_unit_shapes(names, faces, shapes) {
        Ok(pop) => {
            assert!(faces_ok, "a face out of range was accepted");
            assert!(finite, "a non-finite coordinate was accepted");
            check_population(&pop);
            bounded_fit(&pop, *cfg);
        }
        Err(Error::Population { file, message }) => {
            assert!(file.starts_with('s') || file == "(none)", "{file}");
            assert!(!message.is_empty());
        }
        Err(e) => panic!("unexpected kind of error: {e:?}"),
    }
});
