//! posemfa: learn the rigid parts of an articulated shape, and how they move, from a population of registered
//! triangle meshes (X. Wang, "Learning pose variations within shape population by constrained mixtures of
//! factor analyzers"), with the corrections listed in the README.
//!
//! Data flow: OBJ bytes -> [`mesh::obj`] -> [`mesh::Mesh`] -> [`mesh::population::Population`] ->
//! [`model`] (init, AECM, hierarchy) -> [`model::Model`] -> [`articulate`] (part graph, joints,
//! interpolation, skinning) -> [`export`] (JSON, OBJ, glTF).

pub mod clock;
pub mod error;
pub mod geometry;
pub mod mesh;
pub mod metrics;
pub mod model;
pub mod articulate;
pub mod export;
pub mod fuzzing;
pub mod synth;

#[cfg(target_arch = "wasm32")]
pub mod wasm;

pub use error::{Error, Result};
