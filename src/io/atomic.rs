//! Writing files whole or not at all, and only where a file belongs.
//!
//! Everything ntori writes (models, drawings, exports) goes through [`write_atomically`],
//! [`write_atomically_with`] or [`write_new_with`]: the bytes go to a temporary file in the target's
//! directory, which is renamed over the target only once everything is written and flushed. A
//! failure part-way (a full disk, a writer's error) leaves no partial file behind and an existing
//! file untouched.
//!
//! The target is what the path names after following symbolic links, so a link keeps pointing at
//! the (new) file. Only regular files are replaced: a directory, FIFO, device node or socket is
//! refused, since renaming over it would destroy it (`-o /dev/null` as root would replace the
//! device). [`check_output`] says all this up front, and also refuses an output that is one of the
//! command's inputs, so a command can refuse before its long work rather than after.
//!
//! Temporary files are named `.ntori-<pid>-<random>.tmp`. A writer killed before its rename leaves
//! one behind; the next write into the same directory removes those whose process is gone and that
//! are older than [`STALE_AFTER`].

use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Why a file could not be written. Every message names the file (the target, never a temporary
/// file) and says the cause once.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("cannot write {}: cannot create a file in {}: {source}", .path.display(), .dir.display())]
    CreateTemporary {
        path: PathBuf,
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write {}: the directory {} does not exist", .path.display(), .dir.display())]
    NoDirectory { path: PathBuf, dir: PathBuf },
    #[error("cannot write {}: {source}", .path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "cannot write {}: it is a {kind}, not a regular file (ntori writes only regular files)",
        .path.display()
    )]
    NotRegular { path: PathBuf, kind: &'static str },
    #[error(
        "cannot write {}: it is the input {}, which writing would destroy; choose another output",
        .path.display(),
        .input.display()
    )]
    IsInput { path: PathBuf, input: PathBuf },
    #[error("cannot write {}: it exists; pass --force to replace it, or -o to write elsewhere", .path.display())]
    Exists { path: PathBuf },
    #[error("cannot write {}: {reason}", .path.display())]
    Link { path: PathBuf, reason: String },
}

/// Temporary files of writers that are gone are removed once they are this old (a live writer's
/// file is never touched, whatever its age).
pub const STALE_AFTER: Duration = Duration::from_secs(10 * 60);

/// The most symbolic links followed from one output path (as Linux's ELOOP).
const MAX_LINKS: usize = 40;

/// A writer that can also seek: what [`write_atomically_with`] hands out (a buffered temporary
/// file), so formats that go back to fill in lengths (ZIP) can be written through it too.
pub trait WriteSeek: Write + Seek {}

impl<T: Write + Seek + ?Sized> WriteSeek for T {}

/// Writes `bytes` to `path` atomically (see the module documentation).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_atomically_with(path, |w| w.write_all(bytes))
}

/// Streams a file to `path` atomically: `write` gets a buffered writer into a temporary file beside
/// the target (seekable), which replaces the target only if `write` and the final flush succeed.
pub fn write_atomically_with<F>(path: &Path, write: F) -> Result<(), FileError>
where
    F: FnOnce(&mut dyn WriteSeek) -> std::io::Result<()>,
{
    write_file(path, true, write)
}

/// Like [`write_atomically_with`], but never replaces a file: if one appeared at the target while
/// ntori worked, the new file is dropped and [`FileError::Exists`] returned (the check and the
/// rename are one step, so no file created in between is lost).
pub fn write_new_with<F>(path: &Path, write: F) -> Result<(), FileError>
where
    F: FnOnce(&mut dyn WriteSeek) -> std::io::Result<()>,
{
    write_file(path, false, write)
}

/// Checks an output path before the work that produces it: the file it names (links followed) is
/// regular or absent, is none of `inputs`, and its directory exists and takes new files. Returns the
/// target (the path with its links followed).
pub fn check_output(path: &Path, inputs: &[&Path]) -> Result<PathBuf, FileError> {
    let target = resolve_target(path)?;
    for input in inputs {
        if same_file(&target, input) {
            return Err(FileError::IsInput {
                path: path.to_owned(),
                input: input.to_path_buf(),
            });
        }
    }
    let dir = directory_of(path, &target)?;
    // The only sure test of "can I create a file here" is creating one.
    tempfile::Builder::new()
        .prefix(&temp_prefix())
        .suffix(".tmp")
        .tempfile_in(&dir)
        .map_err(|source| FileError::CreateTemporary {
            path: path.to_owned(),
            dir,
            source: plain(source),
        })?;
    Ok(target)
}

/// [`check_output`], and unless `force` the output does not exist yet: what a command checks before
/// its work, so that it replaces a file only when asked to (`--force`). Returns the target.
pub fn check_new_output(path: &Path, inputs: &[&Path], force: bool) -> Result<PathBuf, FileError> {
    let target = check_output(path, inputs)?;
    if !force && std::fs::symlink_metadata(&target).is_ok() {
        return Err(FileError::Exists {
            path: path.to_owned(),
        });
    }
    Ok(target)
}

/// Writes `bytes` to `path` atomically, replacing a file there only if `force` (otherwise
/// [`write_new_with`]: a file that appeared while ntori worked is kept).
pub fn write_output(path: &Path, bytes: &[u8], force: bool) -> Result<(), FileError> {
    if force {
        write_atomically(path, bytes)
    } else {
        write_new_with(path, |w| w.write_all(bytes))
    }
}

/// The file `path` names once its symbolic links are followed (the path itself where it is no
/// link; a link's target whether or not it exists). Refuses what is not a regular file.
pub fn resolve_target(path: &Path) -> Result<PathBuf, FileError> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        let meta = match std::fs::symlink_metadata(&current) {
            Ok(meta) => meta,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(current),
            Err(source) => {
                return Err(FileError::Write {
                    path: path.to_owned(),
                    source: plain(source),
                });
            }
        };
        if meta.file_type().is_symlink() {
            let link = std::fs::read_link(&current).map_err(|source| FileError::Write {
                path: path.to_owned(),
                source: plain(source),
            })?;
            current = match current.parent() {
                Some(parent) if link.is_relative() => parent.join(link),
                _ => link,
            };
            continue;
        }
        if meta.is_file() {
            return Ok(current);
        }
        return Err(FileError::NotRegular {
            path: path.to_owned(),
            kind: kind_of(&meta.file_type()),
        });
    }
    Err(FileError::Link {
        path: path.to_owned(),
        reason: format!("more than {MAX_LINKS} symbolic links (a loop?)"),
    })
}

fn write_file<F>(path: &Path, replace: bool, write: F) -> Result<(), FileError>
where
    F: FnOnce(&mut dyn WriteSeek) -> std::io::Result<()>,
{
    let target = resolve_target(path)?;
    let dir = directory_of(path, &target)?;
    remove_stale_temporaries(&dir);
    let mut builder = tempfile::Builder::new();
    let prefix = temp_prefix();
    builder.prefix(&prefix).suffix(".tmp");
    // A temporary file is private (0600) by default; the file it becomes should get the permissions
    // an ordinary new file gets (0666 less the umask), or keep those of the file it replaces.
    #[cfg(unix)]
    let permissions = match std::fs::metadata(&target) {
        Ok(m) if m.is_file() => m.permissions(),
        _ => std::os::unix::fs::PermissionsExt::from_mode(0o666),
    };
    #[cfg(unix)]
    builder.permissions(permissions);
    let mut tmp = builder
        .tempfile_in(&dir)
        .map_err(|source| FileError::CreateTemporary {
            path: path.to_owned(),
            dir: dir.clone(),
            source: plain(source),
        })?;
    let failed = |source: std::io::Error| FileError::Write {
        path: path.to_owned(),
        source: plain(source),
    };
    {
        let mut out = BufWriter::with_capacity(1 << 20, tmp.as_file_mut());
        write(&mut out).map_err(failed)?;
        out.flush().map_err(failed)?;
    }
    tmp.as_file().sync_all().map_err(failed)?;
    // Dropping `tmp` on any error above deletes the temporary file.
    if replace {
        tmp.persist(&target).map_err(|e| failed(e.error))?;
    } else {
        tmp.persist_noclobber(&target).map_err(|e| {
            if e.error.kind() == std::io::ErrorKind::AlreadyExists {
                FileError::Exists {
                    path: path.to_owned(),
                }
            } else {
                failed(e.error)
            }
        })?;
    }
    Ok(())
}

/// The directory the target goes into, which must exist.
fn directory_of(path: &Path, target: &Path) -> Result<PathBuf, FileError> {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(FileError::NoDirectory {
            path: path.to_owned(),
            dir,
        });
    }
    Ok(dir)
}

/// Is `target` the same file as `input` (same device and inode, links followed)?
fn same_file(target: &Path, input: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        match (std::fs::metadata(target), std::fs::metadata(input)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (target.canonicalize(), input.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

/// What a file that is not regular is, in words.
pub(crate) fn kind_of(file_type: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if file_type.is_fifo() {
            return "FIFO (named pipe)";
        }
        if file_type.is_char_device() || file_type.is_block_device() {
            return "device";
        }
        if file_type.is_socket() {
            return "socket";
        }
    }
    if file_type.is_dir() {
        "directory"
    } else {
        "special file"
    }
}

/// `.ntori-<pid>-`: the writer's process id, so that a later writer can tell a dead writer's file.
fn temp_prefix() -> String {
    format!(".ntori-{}-", std::process::id())
}

/// An I/O error without the path tempfile adds to its messages ("… at path \"/dir/.ntori-….tmp\""):
/// a temporary file's name means nothing to the user, and the error names the target instead.
fn plain(e: std::io::Error) -> std::io::Error {
    if let Some(code) = e.raw_os_error() {
        return std::io::Error::from_raw_os_error(code);
    }
    if let Some(inner) = e.get_ref() {
        let text = inner.to_string();
        if let Some(cut) = text.find(" at path ") {
            return std::io::Error::new(e.kind(), text[..cut].to_owned());
        }
    }
    e
}

/// Removes `.ntori-<pid>-*.tmp` files in `dir` whose process is gone and that are older than
/// [`STALE_AFTER`]. Best effort: any error leaves the file (it is litter, not data). Returns how
/// many were removed.
pub fn remove_stale_temporaries(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_owner) else {
            continue;
        };
        if process_alive(pid) {
            continue;
        }
        let old = entry
            .metadata()
            .ok()
            .filter(|m| m.is_file())
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age >= STALE_AFTER);
        if old && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// The writer's pid in a temporary file's name `.ntori-<pid>-<random>.tmp`.
fn temp_owner(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(".ntori-")?.strip_suffix(".tmp")?;
    let (pid, random) = rest.split_once('-')?;
    if random.is_empty() {
        return None;
    }
    pid.parse().ok()
}

/// Is a process with this id running? Where that cannot be known (no /proc), it counts as running,
/// so nothing is removed that might still be written.
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc = Path::new("/proc");
    if cfg!(target_os = "linux") && proc.join("self").exists() {
        proc.join(pid.to_string()).exists()
    } else {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_drops_tempfiles_path() {
        // tempfile's PathError: an io::Error whose custom payload prints "{err} at path {path:?}".
        #[derive(Debug)]
        struct PathError;
        impl std::fmt::Display for PathError {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("No space left on device (os error 28) at path \"/d/.ntori-1-x.tmp\"")
            }
        }
        impl std::error::Error for PathError {}
        let wrapped = std::io::Error::new(std::io::ErrorKind::StorageFull, PathError);
        let text = plain(wrapped).to_string();
        assert_eq!(text, "No space left on device (os error 28)");
        let os = std::io::Error::from_raw_os_error(28);
        assert_eq!(
            plain(os).to_string(),
            "No space left on device (os error 28)"
        );
    }

    #[test]
    fn temp_owner_reads_the_pid() {
        assert_eq!(temp_owner(".ntori-1234-AbCdEf.tmp"), Some(1234));
        assert_eq!(temp_owner(".ntori-AbCdEf.tmp"), None);
        assert_eq!(temp_owner(".ntori-1234-.tmp"), None);
        assert_eq!(temp_owner("model.json"), None);
    }
}
