//! Writing results out: the fit as JSON (`json`), a mesh as OBJ with round-trip floats (`obj`), the
//! articulated model as binary glTF 2.0 with skeleton, skin and animations (`gltf`), a population as a .glb
//! with one morph target per pose (`morph_glb`).

pub mod gltf;
pub mod json;
pub mod morph_glb;
pub mod obj;
pub mod ply;
pub mod rig_report;
