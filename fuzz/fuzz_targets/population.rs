//! bytes -> several OBJ files -> Population::read of them (and Population::new, which must agree) ->
//! a bounded fit on small populations.
//!
//! Input layout: byte 0 configures the names and the fit parameters ([`posemfa_fuzz::params_from`]); the
//! rest is split at NUL bytes into at most 8 files (NUL never occurs in a valid OBJ file, so the split
//! loses nothing that would load).
#![no_main]

use libfuzzer_sys::fuzz_target;
use posemfa::mesh::Population;
use posemfa::Error;
use posemfa_fuzz::{bounded_fit, check_population};

/// Names that exercise the natural sort: numbers of different widths, case, shared prefixes.
const NAMES: [&str; 8] =
    ["pose10.obj", "pose2.obj", "Pose1.obj", "pose02.obj", "a.obj", "A.obj", "pose1.obj", "b9.obj"];

fuzz_target!(|data: &[u8]| {
    let Some((&cfg, rest)) = data.split_first() else { return };
    let files: Vec<(String, Vec<u8>)> = rest
        .split(|&b| b == 0)
        .take(8)
        .enumerate()
        .map(|(i, bytes)| (NAMES[(i + cfg as usize) % NAMES.len()].to_string(), bytes.to_vec()))
        .collect();
    let all = Population::read(posemfa::mesh::Sources::Files(files.clone()), &Default::default());
    let first = Population::new(posemfa::mesh::Sources::Files(files.clone()));
    match (&all, &first) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a, b, "Population::new and Population::read disagree");
            check_population(a);
            bounded_fit(a, cfg);
        }
        (Err(errors), Err(e)) => {
            assert!(!errors.is_empty());
            for err in errors {
                match err {
                    Error::Obj { file, message, .. }
                    | Error::Mesh { file, message, .. }
                    | Error::Population { file, message } => {
                        assert!(files.iter().any(|(n, _)| n == file) || file == "(none)", "unknown file {file}");
                        assert!(!message.is_empty());
                    }
                    Error::Data(m) => assert!(m.contains("memory"), "unexpected Data error: {m}"),
                    other => panic!("unexpected kind of error: {other:?}"),
                }
            }
            // new stops at the first failure, which read reports too.
            assert!(errors.contains(e), "{e:?} not among {errors:?}");
        }
        _ => panic!("Population::new and Population::read disagree: {all:?} vs {first:?}"),
    }
});
