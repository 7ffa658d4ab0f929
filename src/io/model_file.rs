//! Model files: an [`embedding::Model`] as JSON, read with every check a user's file needs and
//! written atomically.
//!
//! [`load`] reads the header (`format`, `version`) before the rest, so a file from a newer ntori is
//! refused as such rather than as malformed, then builds the [`Surface`] (which checks the model
//! against the layout its genus and settings define). Every error names the file.

use std::path::{Path, PathBuf};

use embedding::{EmbeddingError, Model, ModelHeader, Surface};
use serde::Deserialize as _;

use crate::io::atomic::{FileError, write_atomically, write_new_with};

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
    #[error("{} is not a JSON file: {source}", .path.display())]
    NotJson {
        path: PathBuf,
        source: serde_json::Error,
    },
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
    #[error("cannot write {}: {source}", .path.display())]
    Serialize {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error(transparent)]
    Write(#[from] FileError),
}

/// Reads and checks a model file: the surface it holds, validated once and for all.
pub fn load(path: impl AsRef<Path>) -> Result<Surface, ModelFileError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => ModelFileError::Missing {
            path: path.to_owned(),
        },
        _ => ModelFileError::Unreadable {
            path: path.to_owned(),
            source,
        },
    })?;
    let value: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|source| ModelFileError::NotJson {
            path: path.to_owned(),
            source,
        })?;
    let not_a_model = |reason: String| ModelFileError::NotAModel {
        path: path.to_owned(),
        reason,
    };
    if !value.is_object() {
        return Err(not_a_model("the JSON is not an object".into()));
    }
    let header = ModelHeader::deserialize(&value).map_err(|e| {
        not_a_model(format!(
            "it has no valid \"format\" and \"version\" fields ({e})"
        ))
    })?;
    header.check().map_err(|e| match e {
        EmbeddingError::FutureVersion { version, supported } => ModelFileError::FutureVersion {
            path: path.to_owned(),
            version,
            supported,
        },
        EmbeddingError::NotAModel(format) => not_a_model(format!(
            "its format is \"{format}\", not \"{}\"",
            embedding::MODEL_FORMAT
        )),
        other => not_a_model(other.to_string()),
    })?;
    let model = Model::deserialize(value).map_err(|e| not_a_model(e.to_string()))?;
    Surface::from_model(&model).map_err(|source| ModelFileError::Inconsistent {
        path: path.to_owned(),
        source,
    })
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
    let mut text = serde_json::to_string(&model).map_err(|source| ModelFileError::Serialize {
        path: path.to_owned(),
        source,
    })?;
    text.push('\n');
    Ok(text)
}
