//! Chart sizes. The paper's literal sizes leave parts of the surface in no chart (see the notes), so
//! the sizes are a design choice, made per genus to maximise the coverage margin: the smallest, over
//! all surface points, of the largest distance to a chart boundary among the charts holding the point.
//!
//! The defaults for genus ≥ 2 come from `examples/tune_scales.rs`, a compass search that maximises the
//! margin measured on 12 000 points spread over the polygon, and prints [`DEFAULT_TABLE`]. Margins are
//! measured by `check::coverage`: sampled, then refined by local search from the worst samples (the
//! minima sit at isolated points where charts' margins cross, which sampling alone approaches slowly).
//! `tests/coverage.rs` re-measures every genus on 10^5 points. Chart units (disk radius and square
//! half-width are ½), against paper-like sizes (inside 0.95γ, σ = 7/8, vertex disk through β):
//!
//! | genus | ntori's margin | paper-like |
//! |-------|----------------|------------|
//! | 0     | 0.166 (caps reach 22.5° past the equator) | — |
//! | 1     | 0.122          | —          |
//! | 2     | 0.139          | 0.100      |
//! | 3     | 0.110          | 0.072      |
//! | 5     | 0.079          | 0.050      |
//! | 8     | 0.053          | 0.029      |
//! | 16    | 0.026          | 0.006      |
//! | 32    | 0.014          | gaps       |
//! | 64    | 0.0070         | gaps       |
//!
//! So: ≥ 0.02 up to genus 8 as required (in fact ≥ 0.05), and ≥ [`ChartScales::MARGIN_FLOOR`] = 0.006
//! up to genus 64 (smallest estimate 0.0070, at genus 64; the floor leaves room for minima the search
//! may not reach). The inside disk ends up almost touching the edges (radius ≈ 0.998γ), the vertex
//! disk reaches a little past β, and σ stays near 0.98. `default_for` then grows the vertex disk where
//! needed so that it holds the tessellation's vertex wheel (module `tessellation`), up to just below
//! its injectivity limit (hyperbolic radius half the edge length); growing a chart can only raise the
//! margins above. The tuner's objective was sampled only;
//! re-tuning against the refined margin would raise the high-genus figures somewhat.
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

/// Tuned defaults for genus 2..=64 as (genus, inside, edge, vertex, margin), printed by
/// `cargo run --release -p charts --example tune_scales`. `margin` is the coverage margin of these
/// scales: the smaller of the refined estimates from 10^5 and 10^6 sample points (`tune_scales measure`).
#[rustfmt::skip]
pub const DEFAULT_TABLE: &[(u32, f64, f64, f64, f64)] = &[
    (2, 0.641985, 0.910156, 0.641948, 0.13940),
    (3, 0.756511, 0.962500, 0.759487, 0.11041),
    (4, 0.805161, 0.979688, 0.809841, 0.08988),
    (5, 0.852241, 0.981250, 0.848465, 0.07943),
    (6, 0.875835, 0.990625, 0.871149, 0.07045),
    (7, 0.890921, 0.993359, 0.885709, 0.06222),
    (8, 0.905772, 0.987500, 0.891524, 0.05277),
    (9, 0.915881, 0.994531, 0.911089, 0.05207),
    (10, 0.924020, 0.996875, 0.922521, 0.04936),
    (11, 0.930717, 0.996875, 0.926315, 0.04463),
    (12, 0.936324, 0.987500, 0.934198, 0.04166),
    (13, 0.941088, 0.987500, 0.940914, 0.03979),
    (14, 0.945185, 0.996875, 0.943817, 0.03768),
    (15, 0.948748, 0.987500, 0.928533, 0.02694),
    (16, 0.951874, 0.987500, 0.932857, 0.02553),
    (17, 0.954639, 0.988281, 0.936687, 0.02432),
    (18, 0.957102, 0.978125, 0.940103, 0.02249),
    (19, 0.959311, 0.975000, 0.943170, 0.02128),
    (20, 0.961302, 0.999219, 0.945937, 0.02185),
    (21, 0.963107, 0.975000, 0.948448, 0.01951),
    (22, 0.964750, 0.994531, 0.950735, 0.01986),
    (23, 0.966252, 0.975000, 0.952828, 0.01802),
    (24, 0.967631, 0.993750, 0.954751, 0.01837),
    (25, 0.968901, 0.975000, 0.956523, 0.01675),
    (26, 0.970075, 0.975000, 0.958161, 0.01617),
    (27, 0.971162, 0.978125, 0.959680, 0.01579),
    (28, 0.972174, 0.995312, 0.961093, 0.01610),
    (29, 0.973116, 0.993750, 0.962410, 0.01553),
    (30, 0.973996, 0.994531, 0.963641, 0.01510),
    (31, 0.974820, 0.975000, 0.964793, 0.01381),
    (32, 0.975593, 0.987500, 0.965875, 0.01395),
    (33, 0.976320, 0.990625, 0.969914, 0.01509),
    (34, 0.977004, 0.993750, 0.973900, 0.01623),
    (35, 0.977650, 0.993750, 0.971783, 0.01450),
    (36, 0.978260, 0.999219, 0.972641, 0.01439),
    (37, 0.978838, 0.975000, 0.976485, 0.01457),
    (38, 0.979385, 0.975000, 0.977257, 0.01429),
    (39, 0.979905, 0.975000, 0.978750, 0.01438),
    (40, 0.980398, 0.978125, 0.978688, 0.01388),
    (41, 0.980868, 0.981250, 0.980872, 0.01444),
    (42, 0.981316, 0.996875, 0.973896, 0.01120),
    (43, 0.981743, 0.987500, 0.974496, 0.01065),
    (44, 0.982151, 0.996875, 0.975068, 0.01073),
    (45, 0.982541, 0.987500, 0.975616, 0.01021),
    (46, 0.982914, 0.990625, 0.976140, 0.01010),
    (47, 0.983272, 0.993750, 0.976641, 0.01000),
    (48, 0.983614, 0.975000, 0.977123, 0.00924),
    (49, 0.983943, 0.975000, 0.977584, 0.00906),
    (50, 0.984258, 0.981250, 0.978028, 0.00907),
    (51, 0.984562, 0.993750, 0.978454, 0.00927),
    (52, 0.984854, 0.989062, 0.978864, 0.00897),
    (53, 0.985134, 0.987500, 0.979259, 0.00876),
    (54, 0.985405, 0.996875, 0.979639, 0.00887),
    (55, 0.985666, 0.975000, 0.980006, 0.00813),
    (56, 0.985917, 0.987500, 0.980359, 0.00832),
    (57, 0.986160, 0.975000, 0.980700, 0.00786),
    (58, 0.986394, 0.987500, 0.981030, 0.00805),
    (59, 0.986621, 0.975000, 0.981349, 0.00761),
    (60, 0.986840, 0.987500, 0.981657, 0.00780),
    (61, 0.987051, 0.993750, 0.981955, 0.00783),
    (62, 0.987257, 0.975781, 0.982243, 0.00728),
    (63, 0.987455, 0.987500, 0.982523, 0.00745),
    (64, 0.987648, 0.975000, 0.982793, 0.00705),
];

impl ChartScales {
    /// The coverage margin every default atlas keeps, genus 0 to 64 (chart units; re-measured on 10^5
    /// points by `tests/coverage.rs`). Genus ≤ 8 keeps at least 0.02 (in fact ≥ 0.05).
    pub const MARGIN_FLOOR: f64 = 0.006;

    /// The documented coverage margin of the default scales of `genus` (genus 2..=64).
    pub fn documented_margin(genus: u32) -> Option<f64> {
        DEFAULT_TABLE
            .iter()
            .find(|row| row.0 == genus)
            .map(|row| row.4)
    }

    /// ntori's default sizes for `genus`.
    pub fn default_for(genus: u32) -> Result<ChartScales, ChartsError> {
        match genus {
            // Each cap reaches 22.5° past the equator: |ζ| < tan(5π/16).
            0 => Ok(ChartScales::Sphere {
                cap: (5.0 * std::f64::consts::PI / 16.0).tan(),
            }),
            // The flat torus: the unit square with corners at distance √½ from its centre.
            // The vertex disk (radius 0.4) holds the tessellation's vertex wheel, which reaches √2/4.
            1 => Ok(ChartScales::Polygon {
                inside: 0.45,
                edge: 0.9,
                vertex: 0.4,
            }),
            n if n <= crate::MAX_GENUS => {
                let tuned = DEFAULT_TABLE
                    .iter()
                    .find(|row| row.0 == n)
                    .map(|&(_, inside, edge, vertex, _)| ChartScales::Polygon {
                        inside,
                        edge,
                        vertex,
                    })
                    .unwrap_or_else(|| Self::heuristic(n));
                Ok(tuned.holding_the_vertex_wheel(&crate::Polygon::hyperbolic(n)))
            }
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

    /// The tessellation's vertex wheel (bounded by the edge squares' sides b = ±s) must lie inside the
    /// vertex chart; the coverage tuning alone leaves its boundary right at the chart's edge. Growing a
    /// chart only raises coverage margins, so grow the vertex disk until the wheel reaches |w| ≤ 0.45.
    fn holding_the_vertex_wheel(self, poly: &crate::Polygon) -> ChartScales {
        let ChartScales::Polygon {
            inside,
            edge,
            vertex,
        } = self
        else {
            return self;
        };
        let frame = poly.edge_frame_exact(0).to_lft();
        let to_corner = poly.corner_frame_exact(0).to_lft().inverse();
        let w_beta = frame.inverse().apply(poly.constants().beta) / edge;
        let s = 0.5 * (w_beta.im - w_beta.re);
        // The side b = +s of edge chart a₁ is the wheel's arc about corner 0 (all arcs are congruent).
        let reach = (0..=64)
            .map(|k| {
                let a = -s + 2.0 * s * f64::from(k) / 64.0;
                let z = frame.apply(num_complex::Complex64::new(a, s) * edge);
                to_corner.apply(z).norm()
            })
            .fold(0.0, f64::max);
        // The disk must stay injective: its hyperbolic radius below half the edge length L (the
        // nearest other lifts of the vertex are the adjacent corners), i.e. below tanh(L/4).
        let (c0, c1) = (poly.corners()[0], poly.corners()[1]);
        let d = (c0 - c1).norm() / (num_complex::Complex64::ONE - c0.conj() * c1).norm();
        let limit = d / (1.0 + (1.0 - d * d).sqrt());
        ChartScales::Polygon {
            inside,
            edge,
            vertex: vertex.max((reach / 0.9).min(0.995 * limit)),
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
                        return bad(format!(
                            "the {name} scale must lie in (0, {max:.4}), got {v}"
                        ));
                    }
                }
                Ok(())
            }
        }
    }
}
