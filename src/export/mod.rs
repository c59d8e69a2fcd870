//! Writing results out: the fit as JSON (`json`), a mesh as OBJ with round-trip floats (`obj`), the
//! articulated model as binary glTF 2.0 with skeleton, skin and animations (`gltf`).

pub mod gltf;
pub mod json;
pub mod obj;
pub mod ply;
pub mod rig_report;
