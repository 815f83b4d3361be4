//! [`IoError`]: a file's failure, with the path it concerns and, where a system call or a
//! codec failed, that failure itself ([`Cause`]), so that a caller can tell a full disk
//! from a missing folder ([`IoError::kind`]) and not only read about it.
//!
//! The message quotes the cause as well, so that an error shown on its own (`{}`) says
//! everything; a reader that walks the chain of sources finds the cause again as the next
//! link, as its own type.

use std::path::Path;

/// An I/O failure with the path it concerns. Its [`source`](std::error::Error::source) is
/// the failure beneath itself (an [`std::io::Error`], the EXR or PNG codec's error), not
/// the [`Cause`] that holds it, so that a reader of the chain can downcast to it.
#[derive(Debug)]
pub struct IoError {
    /// The file.
    pub path: String,
    /// What went wrong (quoting the cause, when there is one).
    pub message: String,
    /// The failure beneath, when a system call or a codec failed; none for a fault found
    /// in the file's content or in what was requested. Boxed: an error travels in every
    /// `Result` of the I/O layer, and the causes are large.
    pub cause: Option<Box<Cause>>,
}

impl std::fmt::Display for IoError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path, self.message)
    }
}

impl std::error::Error for IoError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.cause.as_deref().map(Cause::error)
    }
}

/// The failure beneath an [`IoError`].
#[derive(Debug, thiserror::Error)]
pub enum Cause {
    /// The operating system's.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The EXR codec's.
    #[error(transparent)]
    Exr(#[from] ::exr::error::Error),
    /// The image codec's (trap bitmaps).
    #[error(transparent)]
    Image(#[from] image::ImageError),
    /// The PNG encoder's.
    #[error(transparent)]
    PngEncoding(#[from] png::EncodingError),
    /// The PNG decoder's.
    #[error(transparent)]
    PngDecoding(#[from] png::DecodingError),
    /// A file in another program's scene format that does not convert (it names its line
    /// and column).
    #[error(transparent)]
    Scene(#[from] crate::source::SourceError),
}

impl Cause {
    /// The failure itself.
    pub fn error(&self) -> &(dyn std::error::Error + 'static) {
        match self {
            Cause::Io(e) => e,
            Cause::Exr(e) => e,
            Cause::Image(e) => e,
            Cause::PngEncoding(e) => e,
            Cause::PngDecoding(e) => e,
            Cause::Scene(e) => e,
        }
    }

    /// The operating system's error beneath, if that is what failed (also when it came up
    /// through a codec).
    pub fn io(&self) -> Option<&std::io::Error> {
        match self {
            Cause::Io(e) => Some(e),
            Cause::Exr(::exr::error::Error::Io(e)) => Some(e),
            Cause::Image(image::ImageError::IoError(e)) => Some(e),
            Cause::PngEncoding(png::EncodingError::IoError(e)) => Some(e),
            Cause::PngDecoding(png::DecodingError::IoError(e)) => Some(e),
            _ => None,
        }
    }
}

impl IoError {
    /// A fault with no failure beneath: the file's content, or what was requested of it.
    pub(crate) fn new(path: &Path, message: impl Into<String>) -> Self {
        Self { path: path.display().to_string(), message: message.into(), cause: None }
    }

    /// A failure of the system or a codec, told in its own words.
    pub(crate) fn caused(path: &Path, cause: impl Into<Cause>) -> Self {
        let cause = cause.into();
        Self { path: path.display().to_string(), message: cause.to_string(), cause: Some(Box::new(cause)) }
    }

    /// A failure of the system or a codec while doing `doing` ("cannot write").
    pub(crate) fn context(path: &Path, doing: &str, cause: impl Into<Cause>) -> Self {
        let cause = cause.into();
        Self { path: path.display().to_string(), message: format!("{doing}: {cause}"), cause: Some(Box::new(cause)) }
    }

    /// The kind of the operating system's error beneath (a full disk, a missing folder, no
    /// permission), or None when the system did not fail (a damaged file, a codec's
    /// refusal).
    pub fn kind(&self) -> Option<std::io::ErrorKind> {
        self.cause.as_deref().and_then(Cause::io).map(std::io::Error::kind)
    }
}

#[cfg(test)]
mod tests {
    use std::error::Error as _;

    use super::*;

    /// A file in a missing folder: the error names the file and the folder, and the
    /// system's kind of failure is there to match on, as itself in the chain.
    #[test]
    fn a_missing_folder_is_found_under_the_message() {
        let dest = std::env::temp_dir().join("deepfield-no-such-folder").join("out.png");
        let e = crate::io::write_png_rgb8(&dest, 1, 1, &[0, 0, 0], "").expect_err("written into no folder");
        assert!(e.to_string().starts_with(&dest.display().to_string()), "{e}");
        assert!(e.to_string().contains("does not exist"), "{e}");
        assert_eq!(e.kind(), Some(std::io::ErrorKind::NotFound));
        let source = e.source().and_then(|s| s.downcast_ref::<std::io::Error>()).expect("the system's error");
        assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
    }

    /// A fault in the file's content has no system failure beneath.
    #[test]
    fn a_damaged_file_has_no_kind() {
        let e = IoError::new(Path::new("x.exr"), "damaged");
        assert_eq!(e.to_string(), "x.exr: damaged");
        assert!(e.kind().is_none() && e.source().is_none());
    }
}
