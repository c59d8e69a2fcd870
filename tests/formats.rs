//! Mesh files as people have them (issue 12): fixtures written by other tools, read through the same
//! readers natively and in wasm.

#[macro_use]
mod common;

use posemfa::mesh::obj::parse_obj;

dual_test! {
    /// 3ds Max writes its OBJ names in the system code page: Latin-1 `mtllib`, `g`, `o`, `usemtl` and
    /// comments must load, and the geometry must be the file's.
    fn latin1_names_from_3ds_max_load() {
        let bytes = include_bytes!("fixtures/latin1-3dsmax.obj");
        assert!(std::str::from_utf8(bytes).is_err(), "the fixture must not be UTF-8");
        let mesh = parse_obj("latin1-3dsmax.obj", bytes).expect("a Latin-1 material name loads");
        assert_eq!(mesh.positions.len(), 8);
        assert_eq!(mesh.faces.len(), 12);
        assert_eq!(mesh.positions[7], [1.0, 2.0, -1.0]);
        assert_eq!(mesh.faces[0], [0, 2, 3]);
    }
}
