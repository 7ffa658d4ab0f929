//! Typed points: a chart point is not a model point, and neither is a point in R^3 (that type lives in
//! the embedding layer).

use num_complex::Complex64;
use serde::Serialize;

/// Index of a chart in an [`crate::Atlas`]: 0 is the inside chart (genus ≥ 1) or the north cap (genus 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub struct ChartId(pub u32);

impl ChartId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl std::fmt::Display for ChartId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "chart {}", self.0)
    }
}

/// Coordinates in one chart's domain (the open disk |w| < ½ or the open square (−½, ½)²).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ChartPoint {
    pub chart: ChartId,
    pub coords: Complex64,
}

impl ChartPoint {
    pub fn new(chart: ChartId, coords: Complex64) -> Self {
        Self { chart, coords }
    }
}

/// A point of the model space the charts map into: the Poincaré disk (genus ≥ 2), the Euclidean plane
/// (genus 1) or the Riemann sphere's affine coordinate (genus 0). Many model points (an orbit of the
/// side-pairing group) are one surface point; see [`crate::ManifoldPoint`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ModelPoint(pub Complex64);

/// The Poincaré-disk name for a model point, as the paper uses it.
pub type DiskPoint = ModelPoint;
