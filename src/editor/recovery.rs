//! Autosave and crash recovery. While a document has unsaved changes, the editor writes it every so
//! often to `recovery-<pid>.json` in a recovery directory (`$XDG_STATE_HOME/ntori`, or
//! `~/.local/state/ntori`); a clean exit, or saving, removes the file. A recovery file whose process
//! is gone is what a crash left, and the next editor offers it.
//!
//! "Gone" is decided carefully, since a wrong "still running" hides the work for good: a process
//! that exited but was not reaped (a zombie) is gone, and so is one whose id now belongs to another
//! process. The file records its writer's boot and start time ([`ProcessStamp`]); a process with
//! the same id but another start, or a file from an earlier boot, is not its writer.

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
    /// Which run of process `pid` wrote it (absent in files of older versions, and off Linux).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub process: Option<ProcessStamp>,
}

/// What tells one run of a process from another with the same id: the boot it ran in and when it
/// started (in clock ticks since that boot, as `/proc/<pid>/stat` gives it).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ProcessStamp {
    pub boot: String,
    pub start_ticks: u64,
}

impl ProcessStamp {
    /// This process's stamp.
    pub fn current() -> Option<ProcessStamp> {
        ProcessStamp::of(std::process::id())
    }

    /// The stamp of process `pid`, where `/proc` can tell it (Linux).
    pub fn of(pid: u32) -> Option<ProcessStamp> {
        Some(ProcessStamp {
            boot: boot_id()?,
            start_ticks: proc_stat(pid)?.start_ticks,
        })
    }
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
            process: ProcessStamp::current(),
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
            })
            .filter_map(|path| {
                let text = std::fs::read_to_string(&path).ok()?;
                let file: RecoveryFile = serde_json::from_str(&text).ok()?;
                (file.format == RECOVERY_FORMAT && !written_by_a_live_process(&file))
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

/// Is the process that wrote `file` still running? (Elsewhere than Linux only this process
/// counts as running: a file a crash left there is offered rather than hidden.)
fn written_by_a_live_process(file: &RecoveryFile) -> bool {
    let own = std::process::id();
    if !cfg!(target_os = "linux") {
        return file.pid == own;
    }
    let Some(stat) = proc_stat(file.pid) else {
        return false;
    };
    // Z: exited, not yet reaped by its parent; X: dead.
    if matches!(stat.state, 'Z' | 'X' | 'x') {
        return false;
    }
    match &file.process {
        Some(stamp) => {
            boot_id().as_deref() == Some(stamp.boot.as_str())
                && stat.start_ticks == stamp.start_ticks
        }
        // An older file without a stamp: a running process with its id is taken for its writer.
        None => true,
    }
}

/// The fields of `/proc/<pid>/stat` that tell whether and since when a process runs.
struct ProcStat {
    state: char,
    start_ticks: u64,
}

fn proc_stat(pid: u32) -> Option<ProcStat> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may itself hold spaces and ')': the other
    // fields start after the last ')'. Then field 3 is the state and field 22 the start time.
    let rest = &text[text.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    Some(ProcStat {
        state: fields.first()?.chars().next()?,
        start_ticks: fields.get(19)?.parse().ok()?,
    })
}

/// This boot's id (it changes on every reboot, when process ids start over).
fn boot_id() -> Option<String> {
    let id = std::fs::read_to_string("/proc/sys/kernel/random/boot_id").ok()?;
    Some(id.trim().to_owned())
}
