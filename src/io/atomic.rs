//! Writing files whole or not at all.
//!
//! Everything ntori writes (models, drawings, exports) goes through [`write_atomically`] or
//! [`write_atomically_with`]: the bytes go to a temporary file in the target's directory, which is
//! renamed over the target only once everything is written and flushed. A failure part-way (a full
//! disk, a writer's error) leaves no partial file behind and an existing file untouched.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why a file could not be written. Every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("cannot write {}: cannot create a file in {}: {source}", .path.display(), .dir.display())]
    CreateTemporary {
        path: PathBuf,
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write {}: {source}", .path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Writes `bytes` to `path` atomically (see the module documentation).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_atomically_with(path, |w| w.write_all(bytes))
}

/// Streams a file to `path` atomically: `write` gets a buffered writer into a temporary file beside
/// `path`, which replaces `path` only if `write` and the final flush succeed.
pub fn write_atomically_with<F>(path: &Path, write: F) -> Result<(), FileError>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".ntori-").suffix(".tmp");
    // A temporary file is private (0600) by default; the file it becomes should get the permissions
    // an ordinary new file gets (0666 less the umask), or keep those of the file it replaces.
    #[cfg(unix)]
    let permissions = match std::fs::metadata(path) {
        Ok(m) if m.is_file() => m.permissions(),
        _ => std::os::unix::fs::PermissionsExt::from_mode(0o666),
    };
    #[cfg(unix)]
    builder.permissions(permissions);
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|source| FileError::CreateTemporary {
            path: path.to_owned(),
            dir: dir.to_owned(),
            source,
        })?;
    let failed = |source| FileError::Write {
        path: path.to_owned(),
        source,
    };
    {
        let mut out = BufWriter::with_capacity(1 << 20, tmp.as_file_mut());
        write(&mut out).map_err(failed)?;
        out.flush().map_err(failed)?;
    }
    tmp.as_file().sync_all().map_err(failed)?;
    // Dropping `tmp` on any error above deletes the temporary file.
    tmp.persist(path).map_err(|e| failed(e.error))?;
    Ok(())
}
