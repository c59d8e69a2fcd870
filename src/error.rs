//! One error type for the whole crate. Every message says what is wrong, where, and what to try.

use serde::Serialize;
use std::fmt;

/// Everything that can go wrong in posemfa. Messages are meant to be shown to a person as they are.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// An OBJ file could not be read. `line` is 1-based; 0 when the problem is the whole file.
    Obj { file: String, line: usize, message: String },
    /// A mesh file of another format (PLY, glTF, FBX, USD, point cache) could not be read: its reader's
    /// message, naming the line (1-based; 0 when it has none) or the field / accessor / node at fault.
    Mesh { format: Format, file: String, line: usize, message: String },
    /// The files do not form a population (different vertex counts, faces, too few shapes...).
    Population { file: String, message: String },
    /// A parameter is out of its valid range.
    Params(String),
    /// The data cannot be fitted (degenerate, too large, ...).
    Data(String),
    /// A request on a fitted model is invalid (pose index out of range, ...).
    Request(String),
    /// Reading or writing a file failed.
    Io(String),
    /// A model file ([`crate::model_file`]) cannot be read, or does not belong to the population given with it.
    ModelFile { file: String, message: String },
}

/// The format of a mesh file a reader refused ([`Error::Mesh`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    Ply,
    Gltf,
    Fbx,
    Usd,
    /// `.pc2` / `.mdd` point caches.
    PointCache,
}

impl Format {
    /// The [`Problem::kind`] of its errors: "ply", "gltf", "fbx", "usd", "pointcache".
    pub fn kind(self) -> &'static str {
        match self {
            Format::Ply => "ply",
            Format::Gltf => "gltf",
            Format::Fbx => "fbx",
            Format::Usd => "usd",
            Format::PointCache => "pointcache",
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Obj { file, line, message } if *line > 0 => write!(f, "file {file}, line {line}: {message}"),
            Error::Obj { file, message, .. } => write!(f, "file {file}: {message}"),
            Error::Mesh { file, line, message, .. } if *line > 0 => write!(f, "file {file}, line {line}: {message}"),
            Error::Mesh { file, message, .. } => write!(f, "file {file}: {message}"),
            Error::Population { file, message } => write!(f, "file {file}: {message}"),
            Error::Params(m) => write!(f, "invalid parameter: {m}"),
            Error::Data(m) => write!(f, "cannot fit this population: {m}"),
            Error::Request(m) => write!(f, "invalid request: {m}"),
            Error::Io(m) => write!(f, "{m}"),
            Error::ModelFile { file, message } => write!(f, "model file {file}: {message}"),
        }
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;

/// One problem as plain data, for the wasm boundary and JSON: `kind` names the variant ("obj", "population",
/// "params", "data", "request", "io", "model") or, for a mesh file of another format, its format ("ply",
/// "gltf", "fbx", "usd", "pointcache"); `file` and `line` (1-based) when the problem has them; `message`
/// without the file and line (the whole text is the error's Display).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Problem {
    pub kind: &'static str,
    pub file: Option<String>,
    pub line: Option<usize>,
    pub message: String,
}

impl Error {
    /// The error as a [`Problem`].
    pub fn problem(&self) -> Problem {
        let (kind, file, line, message) = match self {
            Error::Obj { file, line, message } => {
                ("obj", Some(file.clone()), (*line > 0).then_some(*line), message.clone())
            }
            Error::Mesh { format, file, line, message } => {
                (format.kind(), Some(file.clone()), (*line > 0).then_some(*line), message.clone())
            }
            Error::Population { file, message } => ("population", Some(file.clone()), None, message.clone()),
            Error::Params(_) => ("params", None, None, self.to_string()),
            Error::Data(_) => ("data", None, None, self.to_string()),
            Error::Request(_) => ("request", None, None, self.to_string()),
            Error::Io(_) => ("io", None, None, self.to_string()),
            Error::ModelFile { file, message } => ("model", Some(file.clone()), None, message.clone()),
        };
        Problem { kind, file, line, message }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn problems_keep_file_line_and_message_apart() {
        let e = Error::Obj { file: "a.obj".into(), line: 12, message: "face index 9 out of range".into() };
        assert_eq!(e.to_string(), "file a.obj, line 12: face index 9 out of range");
        assert_eq!(
            e.problem(),
            Problem {
                kind: "obj",
                file: Some("a.obj".into()),
                line: Some(12),
                message: "face index 9 out of range".into()
            }
        );
        let whole = Error::Obj { file: "b.obj".into(), line: 0, message: "empty file".into() };
        assert_eq!(whole.problem().line, None);
        let p = Error::Params("parts must be at least 1".into()).problem();
        assert_eq!((p.kind, p.file, p.line), ("params", None, None));
        assert_eq!(p.message, "invalid parameter: parts must be at least 1");
        let json = serde_json::to_string(
            &Error::Population { file: "c.obj".into(), message: "8 vertices, not 9".into() }.problem(),
        )
        .unwrap();
        assert_eq!(json, r#"{"kind":"population","file":"c.obj","line":null,"message":"8 vertices, not 9"}"#);
    }

    #[test]
    fn mesh_errors_carry_their_format_as_kind() {
        let e = Error::Mesh { format: Format::Ply, file: "a.ply".into(), line: 3, message: "bad count".into() };
        assert_eq!(e.to_string(), "file a.ply, line 3: bad count");
        let p = e.problem();
        assert_eq!((p.kind, p.file.as_deref(), p.line), ("ply", Some("a.ply"), Some(3)));
        for (format, kind) in
            [(Format::Gltf, "gltf"), (Format::Fbx, "fbx"), (Format::Usd, "usd"), (Format::PointCache, "pointcache")]
        {
            let e = Error::Mesh { format, file: "f".into(), line: 0, message: "cut".into() };
            assert_eq!(e.to_string(), "file f: cut");
            assert_eq!((e.problem().kind, e.problem().line), (kind, None));
        }
    }
}
