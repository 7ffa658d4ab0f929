//! Model files: an [`embedding::Model`] as JSON, read with every check a user's file needs and
//! written atomically.
//!
//! [`load`] reads the header (`format`, `version`) before the rest, so a file from a newer ntori is
//! refused as such rather than as malformed, refuses control points beyond
//! [`embedding::model::MAX_COORDINATE`] (naming the first), then builds the [`Surface`] (which
//! checks the model against the layout its genus and settings define). Every error names the file.

use std::path::{Path, PathBuf};

use embedding::{EmbeddingError, Model, ModelHeader, Surface};

use crate::io::atomic::{FileError, write_atomically, write_new_with};
use crate::io::input::{self, InputProblem};

/// The largest model file read, in bytes. A model of genus 64 with 64×64 control grids (the
/// largest `ntori new` makes) is about 40 MB; a larger file is refused before it is read, so a
/// mistaken path (`/dev/zero`, a huge log) cannot exhaust the memory.
pub const MAX_MODEL_BYTES: u64 = 256 << 20;

/// The longest piece of a file quoted in an error message (a 10 MB string is not echoed whole).
const MAX_QUOTE: usize = 60;

/// Why a model file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    #[error("cannot read {}: no such file", .path.display())]
    Missing { path: PathBuf },
    #[error("cannot read {}: {source}", .path.display())]
    Unreadable {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot read {}: it is a {kind}, not a regular file", .path.display())]
    NotRegular { path: PathBuf, kind: &'static str },
    #[error(
        "cannot read {}: it has {size} bytes or more, and a model file may have at most {max}",
        .path.display()
    )]
    TooLarge { path: PathBuf, size: u64, max: u64 },
    #[error("{} is not a JSON file: {reason}", .path.display())]
    NotJson { path: PathBuf, reason: String },
    #[error("{} is not an ntori model: {reason}", .path.display())]
    NotAModel { path: PathBuf, reason: String },
    #[error(
        "{} was written by a newer ntori (model format version {version}; this build reads up to {supported})",
        .path.display()
    )]
    FutureVersion {
        path: PathBuf,
        version: u32,
        supported: u32,
    },
    #[error("{} is not a consistent ntori model: {source}", .path.display())]
    Inconsistent {
        path: PathBuf,
        source: EmbeddingError,
    },
    #[error("cannot write {}: {source}, so it could not be read back", .path.display())]
    Unloadable {
        path: PathBuf,
        source: EmbeddingError,
    },
    #[error("cannot write {}: {source}", .path.display())]
    Serialize {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error(transparent)]
    Write(#[from] FileError),
}

/// Reads and checks a model file: the surface it holds, validated once and for all.
///
/// Only regular files of at most [`MAX_MODEL_BYTES`] are read (a FIFO would block, a device never
/// end). The JSON is parsed straight into the model (no intermediate tree, so memory stays a small
/// multiple of the file); unknown fields, duplicate keys and version 0 are refused, and a wrong
/// value is reported with its place, e.g. `control_points[17].y`.
pub fn load(path: impl AsRef<Path>) -> Result<Surface, ModelFileError> {
    let path = path.as_ref();
    let bytes = read_capped(path)?;
    from_bytes(path, &bytes)
}

/// A model file's contents, checked as [`load`] checks them; `path` only names the file in errors.
/// (The fuzz tests call this directly.)
pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Surface, ModelFileError> {
    if bytes.len() as u64 > MAX_MODEL_BYTES {
        return Err(ModelFileError::TooLarge {
            path: path.to_owned(),
            size: bytes.len() as u64,
            max: MAX_MODEL_BYTES,
        });
    }
    let not_a_model = |reason: String| ModelFileError::NotAModel {
        path: path.to_owned(),
        reason,
    };
    // Syntax first (without building anything), so a broken file is "not JSON", not "not a model".
    serde_json::from_slice::<serde::de::IgnoredAny>(bytes).map_err(|e| {
        ModelFileError::NotJson {
            path: path.to_owned(),
            reason: describe(&e, None) + mesh_hint(path),
        }
    })?;
    if bytes.iter().find(|b| !b.is_ascii_whitespace()) != Some(&b'{') {
        return Err(not_a_model("the JSON is not an object".into()));
    }
    let header: ModelHeader = serde_json::from_slice(bytes).map_err(|e| {
        not_a_model(format!(
            "it has no valid \"format\" and \"version\" fields ({})",
            describe(&e, None)
        ))
    })?;
    header.check().map_err(|e| match e {
        EmbeddingError::FutureVersion { version, supported } => ModelFileError::FutureVersion {
            path: path.to_owned(),
            version,
            supported,
        },
        EmbeddingError::NotAModel(format) => not_a_model(format!(
            "its format is \"{}\", not \"{}\"",
            shorten(&format),
            embedding::MODEL_FORMAT
        )),
        other => not_a_model(other.to_string()),
    })?;
    if header.version == 0 {
        return Err(not_a_model(format!(
            "its version is 0; model versions start at 1 (this build reads 1 to {})",
            embedding::MODEL_VERSION
        )));
    }
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let model: Model = serde_path_to_error::deserialize(&mut de)
        .map_err(|e| not_a_model(describe(e.inner(), Some(&field_path(e.path())))))?;
    // Absurd coordinates (beyond embedding's MAX_COORDINATE) are refused with the point's index.
    model
        .check_control_points()
        .and_then(|()| Surface::from_model(&model))
        .map_err(|source| ModelFileError::Inconsistent {
            path: path.to_owned(),
            source,
        })
}

/// The file's bytes, if it is a regular file of at most [`MAX_MODEL_BYTES`].
fn read_capped(path: &Path) -> Result<Vec<u8>, ModelFileError> {
    let read = input::regular_file(path, MAX_MODEL_BYTES)
        .and_then(|meta| input::read_capped(path, &meta, MAX_MODEL_BYTES));
    read.map_err(|problem| {
        let path = path.to_owned();
        match problem {
            InputProblem::Missing => ModelFileError::Missing { path },
            InputProblem::Unreadable(source) => ModelFileError::Unreadable { path, source },
            InputProblem::NotRegular(kind) => ModelFileError::NotRegular { path, kind },
            InputProblem::TooLarge(size) => ModelFileError::TooLarge {
                path,
                size,
                max: MAX_MODEL_BYTES,
            },
        }
    })
}

/// For a file named like a mesh (any of the export formats' extensions) given where a model
/// belongs: what makes a model of it.
fn mesh_hint(path: &Path) -> &'static str {
    if crate::io::export::Format::from_path(path).is_ok() {
        " (it looks like a mesh: `ntori fit` makes a model of one)"
    } else {
        ""
    }
}

/// A serde_json error as one line: the field path where known, the problem with long quotes cut,
/// and the place in the file.
fn describe(e: &serde_json::Error, field: Option<&str>) -> String {
    let text = e.to_string();
    // serde_json ends its messages with " at line L column C"; say the place once, at the end.
    let problem = match text.rfind(" at line ") {
        Some(i) if e.line() > 0 => &text[..i],
        _ => &text[..],
    };
    let problem = shorten_quotes(problem);
    let place = if e.line() > 0 {
        format!(" (line {}, column {})", e.line(), e.column())
    } else {
        String::new()
    };
    match field {
        Some(field) if !field.is_empty() && field != "." => format!("{field}: {problem}{place}"),
        _ => format!("{problem}{place}"),
    }
}

/// A field path as a user reads it: `control_points[17].y` for the second coordinate of point 17.
fn field_path(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    let mut in_points = false;
    let mut depth = 0;
    for segment in path.iter() {
        depth += 1;
        match segment {
            Segment::Map { key } => {
                if !out.is_empty() {
                    out.push('.');
                }
                out.push_str(&shorten(key));
                in_points = depth == 1 && key == "control_points";
            }
            Segment::Seq { index } if in_points && depth == 3 && *index < 3 => {
                out.push('.');
                out.push(['x', 'y', 'z'][*index]);
            }
            Segment::Seq { index } => out.push_str(&format!("[{index}]")),
            Segment::Enum { variant } => {
                out.push('.');
                out.push_str(&shorten(variant));
            }
            Segment::Unknown => out.push_str(".?"),
        }
    }
    out
}

/// At most [`MAX_QUOTE`] characters of `s`, with "…" and the full length where cut.
fn shorten(s: &str) -> String {
    let count = s.chars().count();
    if count <= MAX_QUOTE {
        return s.to_owned();
    }
    let head: String = s.chars().take(MAX_QUOTE).collect();
    format!("{head}… ({count} characters)")
}

/// Every backquoted or double-quoted run in a message shortened (serde echoes the offending
/// string or key whole).
fn shorten_quotes(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(1024));
    let mut rest = message;
    while let Some(open) = rest.find(['"', '`']) {
        let quote = rest.as_bytes()[open] as char;
        out.push_str(&rest[..=open]);
        let after = &rest[open + 1..];
        match after.find(quote) {
            Some(close) => {
                out.push_str(&shorten(&after[..close]));
                out.push(quote);
                rest = &after[close + 1..];
            }
            None => {
                out.push_str(&shorten(after));
                return out;
            }
        }
    }
    out.push_str(&shorten(rest));
    out
}

/// Writes a surface's model file atomically (a file that exists is replaced; callers decide whether
/// it may).
pub fn save(path: impl AsRef<Path>, surface: &Surface) -> Result<(), ModelFileError> {
    let path = path.as_ref();
    let text = model_text(path, surface)?;
    write_atomically(path, text.as_bytes())?;
    Ok(())
}

/// Writes a surface's model file atomically where no file exists: one that appeared meanwhile is
/// kept and [`FileError::Exists`] returned.
pub fn save_new(path: impl AsRef<Path>, surface: &Surface) -> Result<(), ModelFileError> {
    let path = path.as_ref();
    let text = model_text(path, surface)?;
    write_new_with(path, |w| w.write_all(text.as_bytes()))?;
    Ok(())
}

fn model_text(path: &Path, surface: &Surface) -> Result<String, ModelFileError> {
    let model = surface.to_model();
    // What `load` would refuse is not written.
    model
        .check_control_points()
        .map_err(|source| ModelFileError::Unloadable {
            path: path.to_owned(),
            source,
        })?;
    let mut text = serde_json::to_string(&model).map_err(|source| ModelFileError::Serialize {
        path: path.to_owned(),
        source,
    })?;
    text.push('\n');
    Ok(text)
}
