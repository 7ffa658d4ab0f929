//! The model: everything that defines a surface, as a versioned serde document.

use serde::{Deserialize, Serialize};

use crate::EmbeddingError;
use crate::surface::{Layout, Point3, SplineSettings};

/// The file format's name, and the newest version this build reads and writes.
pub const MODEL_FORMAT: &str = "ntori-model";
pub const MODEL_VERSION: u32 = 1;

/// A surface: genus, spline settings and every chart's control points (in [`Layout`] order).
/// Unknown fields are refused: a misspelt field would otherwise be ignored without a word.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Model {
    pub format: String,
    pub version: u32,
    pub genus: u32,
    pub settings: SplineSettings,
    pub control_points: Vec<[f64; 3]>,
}

/// The first fields of any model file, whatever its version: read these first, then the rest.
#[derive(Clone, Debug, Deserialize)]
pub struct ModelHeader {
    pub format: String,
    pub version: u32,
}

impl ModelHeader {
    /// Refuses other formats and versions newer than this build.
    pub fn check(&self) -> Result<(), EmbeddingError> {
        if self.format != MODEL_FORMAT {
            return Err(EmbeddingError::NotAModel(self.format.clone()));
        }
        if self.version > MODEL_VERSION {
            return Err(EmbeddingError::FutureVersion {
                version: self.version,
                supported: MODEL_VERSION,
            });
        }
        Ok(())
    }
}

impl Model {
    /// A model whose every control point is `point` (so the surface is that point).
    pub fn constant(layout: &Layout, point: Point3) -> Model {
        Model {
            format: MODEL_FORMAT.into(),
            version: MODEL_VERSION,
            genus: layout.atlas().genus(),
            settings: layout.settings(),
            control_points: vec![[point.x, point.y, point.z]; layout.control_count()],
        }
    }

    /// A model of `layout` with the given control points (in layout order).
    pub fn from_points(layout: &Layout, points: &[Point3]) -> Model {
        Model {
            control_points: points.iter().map(|p| [p.x, p.y, p.z]).collect(),
            ..Model::constant(layout, Point3::origin())
        }
    }

    /// The control points as positions.
    pub fn points(&self) -> Vec<Point3> {
        self.control_points
            .iter()
            .map(|p| Point3::new(p[0], p[1], p[2]))
            .collect()
    }

    /// Checks the header, the settings and the control point count against `layout`, and that every
    /// coordinate is finite.
    pub fn validate(&self, layout: &Layout) -> Result<(), EmbeddingError> {
        ModelHeader {
            format: self.format.clone(),
            version: self.version,
        }
        .check()?;
        if self.genus != layout.atlas().genus() || self.settings != layout.settings() {
            return Err(EmbeddingError::Mismatch);
        }
        if self.control_points.len() != layout.control_count() {
            return Err(EmbeddingError::ControlCount {
                found: self.control_points.len(),
                expected: layout.control_count(),
            });
        }
        if let Some(i) = self
            .control_points
            .iter()
            .position(|p| p.iter().any(|x| !x.is_finite()))
        {
            return Err(EmbeddingError::NotFinite(i));
        }
        Ok(())
    }
}
