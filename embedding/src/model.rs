//! The model: everything that defines a surface, as a versioned serde document.

use serde::{Deserialize, Serialize};

use crate::EmbeddingError;
use crate::surface::{Layout, Point3, SplineSettings};

/// The file format's name, and the newest version this build reads and writes.
pub const MODEL_FORMAT: &str = "ntori-model";
pub const MODEL_VERSION: u32 = 3;

/// The first version that holds pins. A model is written as the oldest version that holds what it
/// has: version 1 (which every build reads) without pins or a disk grid, 2 with pins, 3 with a
/// disk grid.
pub const PINS_VERSION: u32 = 2;

/// The first version whose settings may give the disk charts their own grid
/// ([`SplineSettings::disk_grid`]).
pub const DISK_GRID_VERSION: u32 = 3;

/// A pinned surface point: a chart and coordinates in it (the editor holds pins in place while
/// dragging). Part of the model since version 2.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelPin {
    pub chart: u32,
    /// The point's coordinates in the chart (real and imaginary parts).
    pub at: [f64; 2],
}

/// The largest magnitude a control point coordinate may have in a model. Fitted models are a few
/// units across; 10⁹ leaves room for any sensible scale while keeping every product the
/// evaluation forms (squared lengths, cross products of tangents) far inside f64's range and
/// every position inside the 32-bit floats of exports and the GPU (±3.4e38). A coordinate of
/// 1e300 would load, draw nothing and export `inf`; beyond this bound a model is refused.
pub const MAX_COORDINATE: f64 = 1e9;

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
    /// Pinned surface points (version 2 on; absent when there are none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pins: Vec<ModelPin>,
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
        let settings = layout.settings();
        Model {
            format: MODEL_FORMAT.into(),
            // Without pins, the version every build reads, unless the settings need a newer one.
            version: if settings.disk_grid.is_some() {
                DISK_GRID_VERSION
            } else {
                1
            },
            genus: layout.atlas().genus(),
            settings,
            control_points: vec![[point.x, point.y, point.z]; layout.control_count()],
            pins: Vec::new(),
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

    /// Checks every control point: its coordinates are finite ([`EmbeddingError::NotFinite`]) and
    /// at most [`MAX_COORDINATE`] in magnitude ([`EmbeddingError::OutOfRange`]); the error names the
    /// first offending point's index.
    pub fn check_control_points(&self) -> Result<(), EmbeddingError> {
        for (index, p) in self.control_points.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(EmbeddingError::NotFinite(index));
            }
            if let Some(&value) = p.iter().find(|x| x.abs() > MAX_COORDINATE) {
                return Err(EmbeddingError::OutOfRange {
                    index,
                    value,
                    max: MAX_COORDINATE,
                });
            }
        }
        Ok(())
    }

    /// Checks the header, the settings and the control point count against `layout`, and every
    /// control point ([`Model::check_control_points`]).
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
        self.check_control_points()
    }
}
