//! The one error type of the loaders: a message tied to a file and, when known, a position.

use std::fmt;
use std::path::{Path, PathBuf};

/// A 1-based line and column in a text file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextPos {
    pub line: u32,
    pub col: u32,
}

impl fmt::Display for TextPos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.col)
    }
}

/// Why a scene or mesh could not be loaded. Displays as `FILE:LINE:COL: message`
/// (`FILE:LINE: message` or `FILE: message` when the position is not known).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}: {message}", location(.file, .line, .col))]
pub struct LoadError {
    /// The file the problem is in (the scene XML, or a mesh file it references).
    pub file: PathBuf,
    pub line: Option<u32>,
    pub col: Option<u32>,
    pub message: String,
}

fn location(file: &Path, line: &Option<u32>, col: &Option<u32>) -> String {
    match (line, col) {
        (Some(l), Some(c)) => format!("{}:{l}:{c}", file.display()),
        (Some(l), None) => format!("{}:{l}", file.display()),
        _ => file.display().to_string(),
    }
}

impl LoadError {
    /// An error at a known line and column of `file`.
    pub fn at(file: &Path, pos: TextPos, message: impl Into<String>) -> Self {
        Self {
            file: file.to_path_buf(),
            line: Some(pos.line),
            col: Some(pos.col),
            message: message.into(),
        }
    }

    /// An error at a known line (no column) of `file`.
    pub fn at_line(file: &Path, line: u32, message: impl Into<String>) -> Self {
        Self {
            file: file.to_path_buf(),
            line: Some(line),
            col: None,
            message: message.into(),
        }
    }

    /// An error about `file` as a whole.
    pub fn in_file(file: &Path, message: impl Into<String>) -> Self {
        Self {
            file: file.to_path_buf(),
            line: None,
            col: None,
            message: message.into(),
        }
    }
}
