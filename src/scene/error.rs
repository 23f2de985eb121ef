//! The scene module's error type.
//!
//! Every error a user can cause names where it came from (`file:line:column` when the
//! place is known), what is wrong, and a hint of what to do, so that a typo in a scene
//! file or a `--set` override is fixed from the message alone.

use std::fmt;
use std::path::PathBuf;

/// A place in a file: the file, and the 1-based line and column where known.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub column: Option<usize>,
}

impl Location {
    /// A location naming the file only.
    pub fn file(file: impl Into<PathBuf>) -> Self {
        Location { file: file.into(), line: None, column: None }
    }

    /// The location of a byte offset in `text`, the contents of `file`.
    pub fn at_offset(file: impl Into<PathBuf>, text: &str, offset: usize) -> Self {
        let (line, column) = line_col(text, offset);
        Location { file: file.into(), line: Some(line), column: Some(column) }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(column) = self.column {
                write!(f, ":{column}")?;
            }
        }
        Ok(())
    }
}

/// The 1-based line and column (in characters, as editors count) of a byte offset.
/// An offset past the end, or inside a multi-byte character, is clamped rather than
/// trusted, since spans come from another crate.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// What kind of mistake an [`SceneError::Invalid`] reports; lets callers and tests tell
/// errors apart without matching on message text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file is not valid TOML.
    Syntax,
    /// Valid TOML whose keys or value types do not fit the scene format (unknown key,
    /// missing key, a string where a number belongs).
    Schema,
    /// A value of the right type that is out of range (negative radius, ior <= 0,
    /// non-finite number, zero image width, unknown technique name).
    Value,
    /// A name that refers to nothing (unknown material).
    Reference,
    /// A referenced file (mesh, image) is missing or unreadable.
    MissingFile,
    /// A mesh file is malformed (bad index, non-finite position).
    Mesh,
    /// An image file could not be decoded.
    Image,
}

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file itself could not be read.
    #[error("{}: cannot read scene file: {source}\n  hint: check the path; the benchmark scenes live in assets/scenes/", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// A `--set` override that is malformed or names a path that does not exist.
    #[error("--set {set}: {message}\n  hint: {hint}")]
    Override { set: String, message: String, hint: String },

    /// Anything wrong with the scene's contents or the files it references. `set`
    /// names the override that put the offending value there, if one did.
    #[error("{at}: {}{message}\n  hint: {hint}", set.as_ref().map(|s| format!("--set {s}: ")).unwrap_or_default())]
    Invalid { kind: ErrorKind, at: Location, set: Option<String>, message: String, hint: String },
}

impl SceneError {
    /// The kind of an [`SceneError::Invalid`]; `None` for the other variants.
    pub fn kind(&self) -> Option<ErrorKind> {
        match self {
            SceneError::Invalid { kind, .. } => Some(*kind),
            _ => None,
        }
    }

    /// The location an error points at, where it has one.
    pub fn location(&self) -> Option<&Location> {
        match self {
            SceneError::Invalid { at, .. } => Some(at),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_from_one() {
        let t = "ab\ncdé\nf";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 3), (2, 1));
        assert_eq!(line_col(t, 5), (2, 3));
        // Inside 'é' (2 bytes): clamped back to its start.
        assert_eq!(line_col(t, 6), (2, 3));
        assert_eq!(line_col(t, 8), (3, 1));
        assert_eq!(line_col(t, 1000), (3, 2));
    }
}
