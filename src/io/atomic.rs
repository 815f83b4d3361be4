//! Write-to-temporary-then-rename.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use super::IoError;

/// A file that appears at its destination only when [`AtomicFile::commit_written`] is called; if
/// dropped before that, its temporary file is removed.
#[derive(Debug)]
pub struct AtomicFile {
    dest: PathBuf,
    temp: PathBuf,
    committed: bool,
}

impl AtomicFile {
    /// Creates the temporary file beside `dest` (same folder, so the rename is atomic).
    pub fn create(dest: &Path) -> Result<(Self, BufWriter<File>), IoError> {
        let dir = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        // Said before the system is asked, which would name neither the folder nor the fix.
        if !dir.is_dir() {
            let missing =
                std::io::Error::new(std::io::ErrorKind::NotFound, format!("folder {} does not exist", dir.display()));
            return Err(IoError::context(dest, "cannot write", missing));
        }
        if dest.is_dir() {
            let folder = std::io::Error::new(std::io::ErrorKind::IsADirectory, "it is a folder; give a file name");
            return Err(IoError::context(dest, "cannot write", folder));
        }
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let serial = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let name = dest.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "output".into());
        let temp = dir.join(format!(".{name}.{}-{serial}.partial", std::process::id()));
        let file = File::create(&temp).map_err(|e| IoError::context(dest, "cannot write", e))?;
        Ok((Self { dest: dest.to_path_buf(), temp, committed: false }, BufWriter::with_capacity(1 << 20, file)))
    }

    /// Renames the already flushed and synced file into place.
    pub fn commit_written(mut self) -> Result<(), IoError> {
        std::fs::rename(&self.temp, &self.dest).map_err(|e| IoError::caused(&self.dest, e))?;
        self.committed = true;
        Ok(())
    }

    /// The destination path.
    pub fn dest(&self) -> &Path {
        &self.dest
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// A buffered file handed to an encoder that consumes its writer (png, exr): when the
/// encoder drops it, it flushes and syncs the file and reports a failure through the
/// shared slot returned by [`Tail::new`].
pub(crate) struct Tail {
    inner: Option<BufWriter<File>>,
    error: TailError,
}

/// Where a [`Tail`] reports the failure of its final flush.
pub(crate) type TailError = Arc<Mutex<Option<std::io::Error>>>;

impl Tail {
    pub(crate) fn new(inner: BufWriter<File>) -> (Self, TailError) {
        let error = Arc::new(Mutex::new(None));
        (Self { inner: Some(inner), error: error.clone() }, error)
    }
}

/// Takes the failure a [`Tail`] reported, if any.
pub(crate) fn take_tail_error(slot: &TailError) -> Option<std::io::Error> {
    slot.lock().ok().and_then(|mut e| e.take())
}

impl Write for Tail {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.inner.as_mut().map_or(Ok(0), |w| w.write(buf))
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.as_mut().map_or(Ok(()), |w| w.flush())
    }
}

impl Seek for Tail {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.inner.as_mut().map_or(Ok(0), |w| w.seek(pos))
    }
}

impl Drop for Tail {
    fn drop(&mut self) {
        if let Some(w) = self.inner.take() {
            let result = w.into_inner().map_err(std::io::IntoInnerError::into_error).and_then(|f| f.sync_all());
            if let (Err(e), Ok(mut slot)) = (result, self.error.lock()) {
                *slot = Some(e);
            }
        }
    }
}
