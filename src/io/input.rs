//! Reading an input file whole, with a size cap: what model files and mesh files share. Each caller
//! turns an [`InputProblem`] into its own error, which names the file and its kind of file.

use std::fs::Metadata;
use std::io::Read as _;
use std::path::Path;

/// What can be wrong with an input file before its contents are looked at.
#[derive(Debug)]
pub enum InputProblem {
    Missing,
    Unreadable(std::io::Error),
    /// Not a regular file: a directory, a FIFO…, named as the atomic writer names such files.
    NotRegular(&'static str),
    /// More bytes than the cap (at least this many: a growing file is read one byte past it).
    TooLarge(u64),
}

impl From<std::io::Error> for InputProblem {
    fn from(e: std::io::Error) -> InputProblem {
        match e.kind() {
            std::io::ErrorKind::NotFound => InputProblem::Missing,
            _ => InputProblem::Unreadable(e),
        }
    }
}

/// The metadata of `path` if it is a regular file of at most `max` bytes. Looked at before the file
/// is opened: opening a FIFO blocks until someone writes to it.
pub fn regular_file(path: &Path, max: u64) -> Result<Metadata, InputProblem> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(InputProblem::NotRegular(crate::io::atomic::kind_of(
            &meta.file_type(),
        )));
    }
    if meta.len() > max {
        return Err(InputProblem::TooLarge(meta.len()));
    }
    Ok(meta)
}

/// The bytes of the file `meta` (from [`regular_file`]) describes, at most `max` of them: the file
/// may have grown since, so one byte past the cap is read to know.
pub fn read_capped(path: &Path, meta: &Metadata, max: u64) -> Result<Vec<u8>, InputProblem> {
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::with_capacity(meta.len().min(max) as usize);
    file.take(max + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(InputProblem::TooLarge(bytes.len() as u64));
    }
    Ok(bytes)
}
