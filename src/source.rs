//! Positions in source text, for error messages that name file, line and column.

use std::fmt;

/// Where in a text something is: 1-based line and column (columns count characters).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Position {
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
}

impl Position {
    /// Position of byte `offset` in `text` (clamped to its end).
    pub fn of(text: &str, offset: usize) -> Self {
        let offset = offset.min(text.len());
        let before = &text[..text.floor_char_boundary(offset)];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Self { line, column }
    }
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// An error located in a named source: `file:line:column: message`, or, for a source built
/// in code (no text to point into), `origin: key: message` with the key path of the value.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{origin}{}{}: {message}",
    position.map(|p| format!(":{p}")).unwrap_or_default(),
    key.as_ref().map(|k| format!(": {k}")).unwrap_or_default()
)]
pub struct SourceError {
    /// The file (or "command line", or a built-in name).
    pub origin: String,
    /// The position, where one exists.
    pub position: Option<Position>,
    /// The key path of the offending value (`view.zoom`, `layer[1].density`), where the
    /// source has no text to give a position in.
    pub key: Option<String>,
    /// What was wrong and what was expected.
    pub message: String,
}

impl SourceError {
    /// An error at byte `span.start` of `text`.
    pub fn at(origin: &str, text: &str, span: Option<std::ops::Range<usize>>, message: impl Into<String>) -> Self {
        Self {
            origin: origin.to_string(),
            position: span.map(|s| Position::of(text, s.start)),
            key: None,
            message: message.into(),
        }
    }

    /// An error in the value at key path `key` of a source that has no text.
    pub fn at_key(origin: &str, key: Option<&str>, message: impl Into<String>) -> Self {
        Self { origin: origin.to_string(), position: None, key: key.map(str::to_string), message: message.into() }
    }

    /// Converts a TOML parse or deserialisation error.
    pub fn from_toml(origin: &str, text: &str, err: &toml::de::Error) -> Self {
        let message = err.message().trim().to_string();
        Self::at(origin, text, err.span(), message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column() {
        let t = "ab\ncdé\nf";
        assert_eq!(Position::of(t, 0), Position { line: 1, column: 1 });
        assert_eq!(Position::of(t, 4), Position { line: 2, column: 2 });
        assert_eq!(Position::of(t, 7), Position { line: 2, column: 4 });
        assert_eq!(Position::of(t, 8), Position { line: 3, column: 1 });
    }
}
