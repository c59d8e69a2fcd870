//! Triangle meshes and populations of registered meshes.

pub mod cache;
pub mod fbx;
pub mod fbx_tree;
pub mod gltf;
pub mod load;
pub mod obj;
pub mod ply;
pub mod usd;
pub mod usdc_check;
pub mod population;
pub mod subdivide;
pub mod zip_archive;

pub use population::{Normalization, Population, ReadOptions, Saved, Sources};

/// A triangle mesh: positions in file order (`v` order) and triangles as 0-based vertex indices.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    pub positions: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
}
