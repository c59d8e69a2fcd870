//! Writing results out: the fit as JSON (`json`), a mesh as OBJ whose floats read back exactly (`obj`) or PLY (`ply`),
//! the mesh a viewer shows in the population's original units (`shown`), the articulated model as binary glTF
//! 2.0 with skeleton, skin and animations (`gltf`), a population as a .glb with one morph target per pose
//! (`morph_glb`), the rig's reconstruction error as exported (`rig_report`).

pub mod gltf;
pub mod json;
pub mod morph_glb;
pub mod obj;
pub mod ply;
pub mod pose_glb;
pub mod rig_report;
pub mod shown;
