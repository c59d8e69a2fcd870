//! posemfa: learn the rigid parts of an articulated shape, and how they move, from a population of registered
//! triangle meshes (X. Wang, "Learning pose variations within shape population by constrained mixtures of
//! factor analyzers"), with the corrections listed in the README.
//!
//! Data flow: mesh file bytes -> [`mesh`] readers -> [`mesh::Mesh`] -> [`mesh::population::Population`] ->
//! [`parts`] (which vertices form a part: a driver and two rules, the merge tree and Algorithm 1), each run fit
//! by [`mfa`] (the constrained mixture: E-step, CM steps, AECM) -> [`mfa::Model`] -> [`articulate`] (part
//! graph, joints, interpolation, skinning) -> [`export`] (JSON, OBJ, glTF).
//!
//! Two rooms: [`mfa`] is the model and its fit and never names [`parts`]; [`parts`] decides the partition and
//! calls into [`mfa`]. [`mesh`] and [`geometry`] name neither (`tests/module_rooms.rs` checks all three).

/// `fn NAME(ARGS) -> R { BODY }` whose body runs compiled for AVX2 when the CPU has it (x86_64; checked at run
/// time, cached by std), else as it is. For the few hot loops (the E-step's kernel, the CM steps' sums): AVX2
/// runs their 4-lane f64 arithmetic in one instruction where the x86_64 baseline (SSE2) needs two. No FMA is
/// enabled and Rust never contracts a * b + c, so every result is the same bit for bit on both paths.
macro_rules! avx2_fn {
    ($(#[$m:meta])* $vis:vis fn $name:ident($($a:ident: $t:ty),* $(,)?) $(-> $r:ty)? $body:block) => {
        $(#[$m])*
        $vis fn $name($($a: $t),*) $(-> $r)? {
            #[inline(always)]
            fn body($($a: $t),*) $(-> $r)? $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                fn wide($($a: $t),*) $(-> $r)? {
                    body($($a),*)
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: `wide` needs AVX2, and the CPU has it (checked just above)
                    return unsafe { wide($($a),*) };
                }
            }
            body($($a),*)
        }
    };
}

pub mod clock;
pub mod error;
pub mod geometry;
pub mod mesh;
pub mod metrics;
pub mod model_file;
pub mod memory;
pub mod mfa;
pub mod parts;
pub mod articulate;
pub mod export;
pub mod fuzzing;
pub mod synth;
pub mod trace;

#[cfg(target_arch = "wasm32")]
pub mod wasm;

/// The Python extension module (`pip install .`: pyproject.toml, python/posemfa/).
#[cfg(feature = "python")]
pub mod python;

pub use error::{Error, Result};
