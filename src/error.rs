//! One error type for the whole crate. Every message says what is wrong, where, and what to try.

use std::fmt;

/// Everything that can go wrong in posemfa. Messages are meant to be shown to a person as they are.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A mesh file could not be read. `line` is 1-based; 0 when the problem is the whole file.
    Obj { file: String, line: usize, message: String },
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
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Obj { file, line, message } if *line > 0 => write!(f, "file {file}, line {line}: {message}"),
            Error::Obj { file, message, .. } => write!(f, "file {file}: {message}"),
            Error::Population { file, message } => write!(f, "file {file}: {message}"),
            Error::Params(m) => write!(f, "invalid parameter: {m}"),
            Error::Data(m) => write!(f, "cannot fit this population: {m}"),
            Error::Request(m) => write!(f, "invalid request: {m}"),
            Error::Io(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;
