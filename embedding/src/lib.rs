//! # embedding: the surface layer of ntori
//!
//! The paper's section 5.1: S(p) = Σ_c b_c(α_c(p)) E_c(α_c(p)) / Σ_c b_c(α_c(p)), with a tensor-product
//! B-spline patch E_c : chart → R³ and a blend function b_c per chart; normalised, the blends are a
//! partition of unity. The surface is linear in its control points, so re-embedding a fixed set of
//! surface points after an edit is a sparse product (`stencil`).
//!
//! ```
//! use charts::{Atlas, ChartId, ChartPoint};
//! use embedding::{Layout, Model, Point3, SplineSettings};
//! use num_complex::Complex64;
//!
//! let atlas = Atlas::new(2)?;
//! let layout = Layout::new(&atlas, SplineSettings::default())?;
//! // Every control point at the same place: the surface is that point.
//! let model = Model::constant(&layout, Point3::new(1.0, 0.0, 0.0));
//! let s = layout.eval(&model.points(), ChartPoint::new(ChartId(2), Complex64::new(0.1, 0.2)));
//! assert!((s.pos - Point3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! This crate builds on [`charts`]; it knows nothing of files, windows or GPUs.

mod bending;
pub mod brush;
pub mod bspline;
pub mod edit;
pub mod evaluate;
pub mod fit;
pub mod floater;
pub mod harmonic;
pub mod holed;
pub mod integrals;
mod least_squares;
mod marking;
pub mod mesh_fit;
pub mod model;
pub mod quality;
pub mod remesh;
mod sphere_map;
pub mod spline_surface;
pub mod stencil;
pub mod surface;

pub use evaluate::{Curvatures, Sample, SampleSink, Wants, evaluate, evaluate_rows};
pub use model::{
    DISK_GRID_VERSION, MODEL_FORMAT, MODEL_VERSION, Model, ModelHeader, ModelPin, PINS_VERSION,
};
pub use spline_surface::{ControlId, Surface};
pub use stencil::{
    ColumnIndex, ControlFrame, Stencil, StencilKernel, TensorStencil, tangent_words,
};
pub use surface::{
    ControlGrids, Jet, Layout, Point3, SplineSettings, SurfaceJet, Vector3, Weight, bounding_box,
};

pub use charts;

/// What can go wrong when building an embedding.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EmbeddingError {
    #[error("spline degree {0} is not supported (1 to {max})", max = bspline::MAX_DEGREE)]
    Degree(usize),
    #[error("a control grid of {count} per side cannot carry degree {degree} (needs {} to 4096)", .degree + 1)]
    GridSize { count: usize, degree: usize },
    #[error("continuity order {0} is not supported (1 to 4)")]
    Continuity(usize),
    #[error("this is not an ntori model (format \"{0}\")")]
    NotAModel(String),
    #[error(
        "this model was written by a newer ntori (format version {version}; this build reads up to {supported})"
    )]
    FutureVersion { version: u32, supported: u32 },
    #[error("the model's genus or spline settings do not match the layout")]
    Mismatch,
    #[error(
        "the settings give the disk charts a grid of {grid}, which a version {version} model cannot hold (disk grids need version {need})",
        need = model::DISK_GRID_VERSION
    )]
    DiskGridVersion { grid: usize, version: u32 },
    #[error("the model has {found} control points, its settings need {expected}")]
    ControlCount { found: usize, expected: usize },
    #[error("control point {0} has a coordinate that is not a finite number")]
    NotFinite(usize),
    #[error(
        "control point {index} has a coordinate of {value:e}, beyond the ±{max:e} a model may hold"
    )]
    OutOfRange { index: usize, value: f64, max: f64 },
    #[error("pin {index} {problem}")]
    BadPin { index: usize, problem: String },
    #[error("constraint {0} asks for a position that is not a finite point")]
    BadTarget(usize),
    #[error("the surface's tessellation cannot be checked: {0}")]
    Tessellation(#[from] mesh::spatial::SpatialError),
    #[error("the edit's constraints could not be solved")]
    Unsolvable,
    #[error("the {0} brush has no dab: it follows the pointer")]
    NoDab(&'static str),
    #[error(
        "genus {genus} at mesh resolution {resolution} makes {}{triangles} input triangles, which would take about {:.1} GB to fit ({} bytes a triangle, measured); the fit takes at most {max} triangles: {}",
        if *.at_least { "more than " } else { "" },
        *.triangles as f64 * fit::FIT_BYTES_PER_TRIANGLE as f64 / 1e9,
        fit::FIT_BYTES_PER_TRIANGLE,
        if *.resolution > 8 { "lower the resolution" } else { "even the lowest resolution (8) is too fine for this genus" }
    )]
    FitTooLarge {
        genus: u32,
        resolution: usize,
        triangles: usize,
        /// The count is where meshing stopped: the mesh would have more.
        at_least: bool,
        max: usize,
    },
    #[error(
        "a tolerance of {0} is out of range ({min} to {max} of the surface's diagonal)",
        min = remesh::QualitySettings::MIN_TOLERANCE,
        max = remesh::QualitySettings::MAX_TOLERANCE
    )]
    Tolerance(f64),
    #[error("cannot parameterize the mesh: {0}")]
    Parameterization(String),
    #[error(transparent)]
    Chart(#[from] charts::ChartsError),
}
