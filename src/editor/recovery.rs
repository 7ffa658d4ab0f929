//! Autosave and crash recovery. While a document has unsaved changes, the editor writes it every so
//! often to `recovery-<pid>.json` in a recovery directory (`$XDG_STATE_HOME/ntori`, or
//! `~/.local/state/ntori`); a clean exit, or saving, removes the file. A recovery file whose process
//! is gone is what a crash left, and the next editor offers it.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use embedding::Model;
use serde::{Deserialize, Serialize};

use crate::io::atomic::{FileError, write_atomically};

/// The recovery file's format name.
pub const RECOVERY_FORMAT: &str = "ntori-recovery";

/// What a recovery file holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecoveryFile {
    pub format: String,
    /// The process that wrote it.
    pub pid: u32,
    /// When, in seconds since the Unix epoch.
    pub saved_at: u64,
    /// The document's own file, if it had one.
    pub original: Option<PathBuf>,
    pub model: Model,
}

/// A recovery file left by a process that is gone.
#[derive(Clone, Debug, PartialEq)]
pub struct Orphan {
    pub path: PathBuf,
    pub file: RecoveryFile,
}

/// This process's autosave.
#[derive(Debug)]
pub struct Recovery {
    dir: PathBuf,
    own: PathBuf,
    /// The document state last written, and when.
    written: Option<u64>,
    last: Option<Instant>,
    pub interval: Duration,
}

impl Recovery {
    pub fn new(dir: impl Into<PathBuf>) -> Recovery {
        let dir = dir.into();
        Recovery {
            own: dir.join(format!("recovery-{}.json", std::process::id())),
            dir,
            written: None,
            last: None,
            interval: Duration::from_secs(20),
        }
    }

    /// `$XDG_STATE_HOME/ntori`, or `~/.local/state/ntori`.
    pub fn default_dir() -> Option<PathBuf> {
        let state = std::env::var_os("XDG_STATE_HOME")
            .filter(|s| !s.is_empty())
            .map(PathBuf::from)
            .or_else(|| {
                std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local").join("state"))
            })?;
        Some(state.join("ntori"))
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }
    pub fn own_file(&self) -> &Path {
        &self.own
    }

    /// Writes the model if the document changed since the last autosave and the interval has
    /// passed (or `force`). `state` names the document's state (see `History::state`). Returns
    /// whether it wrote.
    pub fn autosave(
        &mut self,
        state: u64,
        model: impl FnOnce() -> Model,
        original: Option<&Path>,
        force: bool,
    ) -> Result<bool, FileError> {
        if self.written == Some(state) {
            return Ok(false);
        }
        if !force && self.last.is_some_and(|t| t.elapsed() < self.interval) {
            return Ok(false);
        }
        let file = RecoveryFile {
            format: RECOVERY_FORMAT.into(),
            pid: std::process::id(),
            saved_at: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
            original: original.map(Path::to_owned),
            model: model(),
        };
        std::fs::create_dir_all(&self.dir).map_err(|source| FileError::Write {
            path: self.own.clone(),
            source,
        })?;
        let text = serde_json::to_string(&file).map_err(|e| FileError::Write {
            path: self.own.clone(),
            source: std::io::Error::other(e),
        })?;
        write_atomically(&self.own, text.as_bytes())?;
        self.written = Some(state);
        self.last = Some(Instant::now());
        Ok(true)
    }

    /// Removes this process's recovery file (nothing left to recover).
    pub fn clear(&mut self) {
        let _ = std::fs::remove_file(&self.own);
        self.written = None;
    }

    /// Recovery files of processes that are gone, newest first.
    pub fn orphans(&self) -> Vec<Orphan> {
        let Ok(entries) = std::fs::read_dir(&self.dir) else {
            return Vec::new();
        };
        let mut found: Vec<Orphan> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("recovery-") && n.ends_with(".json"))
                    && *p != self.own
            })
            .filter_map(|path| {
                let text = std::fs::read_to_string(&path).ok()?;
                let file: RecoveryFile = serde_json::from_str(&text).ok()?;
                (file.format == RECOVERY_FORMAT && !alive(file.pid))
                    .then_some(Orphan { path, file })
            })
            .collect();
        found.sort_by_key(|o| std::cmp::Reverse(o.file.saved_at));
        found
    }

    /// Removes a recovery file once it was recovered or discarded.
    pub fn discard(orphan: &Orphan) {
        let _ = std::fs::remove_file(&orphan.path);
    }
}

/// Is a process with this id running? (Linux: /proc; elsewhere a file's owner counts as gone.)
fn alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        false
    }
}
