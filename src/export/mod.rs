//! (being written)
pub mod gltf;
pub mod json;
pub mod obj;
pub mod ply;
