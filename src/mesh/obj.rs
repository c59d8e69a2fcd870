//! OBJ import (being written: see issue 2).
use super::Mesh;
use crate::error::{Error, Result};

/// Parses one OBJ file. `name` is used in error messages.
pub fn parse_obj(name: &str, _bytes: &[u8]) -> Result<Mesh> {
    Err(Error::Obj { file: name.to_string(), line: 0, message: "OBJ import is not built yet".into() })
}
