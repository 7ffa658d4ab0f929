//! # charts: the manifold layer of ntori
//!
//! A closed orientable surface of genus n, as Grimm and Hughes build it: the regular hyperbolic 4n-gon
//! (n ≥ 2) whose side pairings generate a group G acting on the Poincaré disk, the surface being the
//! quotient; 2n + 2 charts (inside, vertex, 2n edge) each mapped into the disk by one linear fractional
//! transformation; and transition functions between charts that are LFTs on each connected overlap
//! component. Genus 1 uses the Euclidean analogue (the unit square and translations), genus 0 the
//! Riemann sphere covered by two caps glued by an inversion.
//!
//! ```
//! use charts::{Atlas, ChartId, ChartPoint};
//! use num_complex::Complex64;
//!
//! let atlas = Atlas::new(3)?;
//! // A point near the middle of edge chart a1 ...
//! let p = atlas.locate(ChartPoint::new(ChartId(2), Complex64::new(-0.05, 0.0)))?;
//! // ... is in several charts, and the transition functions agree (the cocycle condition).
//! for rep in p.representations() {
//!     let again = atlas.locate(*rep)?;
//!     for (a, b) in p.representations().iter().zip(again.representations()) {
//!         assert_eq!(a.chart, b.chart);
//!         assert!((a.coords - b.coords).norm() < 1e-12);
//!     }
//! }
//! # Ok::<(), charts::ChartsError>(())
//! ```
//!
//! Precision: every matrix the atlas stores is formed in double-double arithmetic and rounded to f64
//! once (module `dd`), so chart-to-chart maps stay accurate to ~1e-15 even at genus 64, where naive
//! f64 products of the side pairings lose up to 12 digits.
//!
//! This crate knows nothing of splines, meshes or pixels.

mod atlas;
pub mod check;
mod dd;
mod lft;
mod overlap;
mod points;
mod polygon;
mod scales;
mod tessellation;

pub use atlas::{Atlas, Chart, ChartKind, Domain, MAX_GENUS, ManifoldPoint, Transition};
pub use lft::Lft;
pub use points::{ChartId, ChartPoint, DiskPoint, ModelPoint};
pub use polygon::{Geometry, Polygon, PolygonConstants, VertexStep};
pub use scales::{ChartScales, DEFAULT_TABLE};
pub use tessellation::{
    EDGE_INNER, EDGE_INSIDE_ARC, EDGE_VERTEX_ARC, MAX_RESOLUTION, MAX_TRIANGLES, Region,
    Tessellation, hyperbolic_area,
};

/// What can go wrong when asking the charts layer for something.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChartsError {
    #[error(
        "genus {genus} is not supported: the charts are built and validated for genus 0 to {max}"
    )]
    UnsupportedGenus { genus: u32, max: u32 },
    #[error("there is no chart {index}: this atlas has charts 0 to {}", .count - 1)]
    NoSuchChart { index: u32, count: usize },
    #[error("chart coordinates ({re}, {im}) are not finite numbers")]
    NotFinite { re: f64, im: f64 },
    #[error("({re}, {im}) lies outside the domain of {chart} (by {margin:.3e} chart units)", margin = -.margin)]
    OutsideChart {
        chart: ChartId,
        re: f64,
        im: f64,
        margin: f64,
    },
    #[error("invalid chart scales: {0}")]
    InvalidScales(String),
    #[error("cannot tessellate: {0}")]
    InvalidTessellation(String),
}
