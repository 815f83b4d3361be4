//! Kalles Fraktaler's `Key: value` text: the lines of a `.kfr` location and of a `.kfp`
//! palette, which are the same format (a palette file is a location file read without its
//! location).
//!
//! KF writes one `Key: value` pair per line (`CFraktalSFT::ToText` in KF's
//! `fraktal_sft/Parameter.cpp`), with CRLF line ends, case-sensitive keys, no sections and
//! no comments. [`KfText::parse`] splits such text into [`Entry`]s that keep the byte
//! offsets of key and value, so that a reader's own errors (a bad number, a key it
//! refuses) can name the line and column; see [`crate::source::SourceError::at`].
//!
//! Accepted: CRLF or LF line ends, a leading byte-order mark, blank lines, and spaces
//! around keys and values. Refused, with the offending line's position: a non-blank line
//! without `:`, a line with nothing before its `:`, and a second line for a key the reader
//! names as allowed once (KF would silently take the first). Other keys may repeat; each
//! reader decides which keys it reads and ignores the rest.

use crate::source::Position;

/// One `Key: value` line, both sides trimmed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry<'a> {
    /// The key.
    pub key: &'a str,
    /// The value (empty when nothing follows the colon).
    pub value: &'a str,
    /// Byte offset of the key in the text.
    pub key_at: usize,
    /// Byte offset of the `:` in the text.
    pub colon_at: usize,
    /// Byte offset of the value in the text (the end of the line when the value is empty).
    pub value_at: usize,
}

/// A line that is not `Key: value`, or a key given twice. `at` is the byte offset of the
/// line's first non-blank character.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum KfTextError {
    /// A non-blank line without `:`.
    #[error("expected a Kalles Fraktaler location line `Key: value` (like `Re: -0.75`), found `{found}` with no `:`")]
    NoColon {
        /// Byte offset of the line's text.
        at: usize,
        /// The line's first 40 characters.
        found: String,
    },
    /// A line starting with `:`.
    #[error("expected a key before `:` (a line `Key: value`, like `Re: -0.75`)")]
    NoKey {
        /// Byte offset of the line's text.
        at: usize,
    },
    /// A second line for a key allowed once.
    #[error("`{key}` is given twice (first on line {first_line}); expected it once")]
    Twice {
        /// Byte offset of the second line's key.
        at: usize,
        /// The key.
        key: String,
        /// 1-based line of the first.
        first_line: usize,
    },
}

impl KfTextError {
    /// Byte offset in the text the error points at.
    pub fn at(&self) -> usize {
        match *self {
            KfTextError::NoColon { at, .. } | KfTextError::NoKey { at } | KfTextError::Twice { at, .. } => at,
        }
    }
}

/// The `Key: value` lines of a text, in order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KfText<'a> {
    entries: Vec<Entry<'a>>,
}

impl<'a> KfText<'a> {
    /// Splits `text` into its entries; each key in `once` may appear at most once.
    pub fn parse(text: &'a str, once: &[&str]) -> Result<Self, KfTextError> {
        let mut entries: Vec<Entry<'a>> = Vec::new();
        let mut start = 0;
        for raw in text.split_inclusive('\n') {
            let line_start = start;
            start += raw.len();
            let mut line = raw.trim_end_matches(['\n', '\r']);
            let mut base = line_start;
            if line_start == 0
                && let Some(rest) = line.strip_prefix('\u{feff}')
            {
                base += line.len() - rest.len();
                line = rest;
            }
            if line.trim().is_empty() {
                continue;
            }
            let key_at = base + (line.len() - line.trim_start().len());
            let Some(colon) = line.find(':') else {
                let found = line.trim().chars().take(40).collect();
                return Err(KfTextError::NoColon { at: key_at, found });
            };
            let key = line[..colon].trim();
            if key.is_empty() {
                return Err(KfTextError::NoKey { at: key_at });
            }
            let after = &line[colon + 1..];
            let value = after.trim();
            let value_at = base + colon + 1 + (after.len() - after.trim_start().len());
            if once.contains(&key)
                && let Some(first) = entries.iter().find(|e| e.key == key)
            {
                let first_line = Position::of(text, first.key_at).line;
                return Err(KfTextError::Twice { at: key_at, key: key.to_string(), first_line });
            }
            entries.push(Entry { key, value, key_at, colon_at: base + colon, value_at });
        }
        Ok(Self { entries })
    }

    /// The first entry of `key`.
    pub fn get(&self, key: &str) -> Option<&Entry<'a>> {
        self.entries.iter().find(|e| e.key == key)
    }

    /// Every entry, in the text's order.
    pub fn entries(&self) -> &[Entry<'a>] {
        &self.entries
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_of_keys_and_values() {
        let text = "\u{feff}Re: -0.75\r\n\r\n  Zoom :  2 \r\nColors: \nIm:0";
        let kf = KfText::parse(text, &[]).unwrap();
        let keys: Vec<_> = kf.entries().iter().map(|e| (e.key, e.value)).collect();
        assert_eq!(keys, [("Re", "-0.75"), ("Zoom", "2"), ("Colors", ""), ("Im", "0")]);
        let zoom = kf.get("Zoom").unwrap();
        assert_eq!((&text[zoom.key_at..zoom.key_at + 4], &text[zoom.colon_at..=zoom.colon_at]), ("Zoom", ":"));
        assert_eq!(&text[zoom.value_at..zoom.value_at + 1], "2");
        let re = kf.get("Re").unwrap();
        assert_eq!((Position::of(text, re.key_at).column, Position::of(text, re.value_at).column), (2, 6));
        let colors = kf.get("Colors").unwrap();
        assert_eq!(&text[colors.value_at..=colors.value_at], "\n", "an empty value sits at the line's end");
    }

    #[test]
    fn malformed_lines_and_keys_given_twice() {
        let e = KfText::parse("Re: 0\n  not a line\n", &[]).unwrap_err();
        assert_eq!(e, KfTextError::NoColon { at: 8, found: "not a line".into() });
        assert!(e.to_string().contains("Key: value"), "{e}");
        assert_eq!(KfText::parse("Re: 0\n: 5\n", &[]).unwrap_err(), KfTextError::NoKey { at: 6 });
        let e = KfText::parse("Re: 0\nIm: 0\nRe: 1\n", &["Re"]).unwrap_err();
        assert_eq!(e, KfTextError::Twice { at: 12, key: "Re".into(), first_line: 1 });
        assert_eq!(e.at(), 12);
        let kf = KfText::parse("Foo: 1\nFoo: 2\n", &["Re"]).unwrap();
        assert_eq!(kf.get("Foo").unwrap().value, "1", "keys not named once may repeat; the first counts");
    }
}
