//! Integrals over the whole surface, through the partition of unity: ∫_S f dA = Σ_c ∫_{chart c}
//! b̂_c f |S_u × S_v| du dv, each chart's integral taken over its own domain with a composite
//! Gauss–Legendre rule whose cells follow the spline's knot lines. No tessellation, no seams: the
//! normalised blends b̂_c sum to one everywhere and vanish smoothly at each chart's boundary.
//!
//! Gauss–Bonnet makes a sharp test of the whole surface layer (charts, blends, derivatives and
//! curvature): ∫ K dA = 2π(2 − 2n) for any closed surface of genus n.
//!
//! ```
//! use embedding::integrals::surface_integrals;
//! use embedding::fit::{FitSettings, initial_model};
//! use embedding::SplineSettings;
//!
//! let fit = initial_model(0, 16, SplineSettings::default(), FitSettings::default())?;
//! let surface = &fit.surface;
//! let sums = surface_integrals(&surface.layout(), surface.control_points(), 4);
//! assert!((sums.gaussian_curvature - 4.0 * std::f64::consts::PI).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use charts::ChartPoint;
use num_complex::Complex64;

use crate::surface::{Layout, Point3};

/// ∫ K dA, ∫ |K| dA and the area of a surface; and, since every quadrature point has the
/// surface's second derivatives at hand, the largest |κ| of a principal curvature over them (a
/// far denser look for a spike than a tessellation's vertices: every chart at several points per
/// knot interval of its grid).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceIntegrals {
    pub gaussian_curvature: f64,
    pub absolute_curvature: f64,
    pub area: f64,
    /// The largest |κ₁|, |κ₂| at the quadrature points (infinite where the normal is undefined),
    /// and the first point where it is reached.
    pub largest_curvature: f64,
    pub largest_curvature_at: Option<ChartPoint>,
}

impl SurfaceIntegrals {
    /// How far ∫K dA is from Gauss–Bonnet's 2π(2 − 2n) for a surface of `genus` n, relative to
    /// the larger of that and ∫|K| dA (the torus's 2π(2 − 2n) is 0).
    pub fn gauss_bonnet_error(&self, genus: u32) -> f64 {
        let expected = std::f64::consts::TAU * (2.0 - 2.0 * f64::from(genus));
        (self.gaussian_curvature - expected).abs() / expected.abs().max(self.absolute_curvature)
    }
}

/// Four-point Gauss–Legendre on [−1, 1].
const NODES: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
];

/// Cells per knot interval for [`surface_integrals`]: the fewest that put at least 116 cells
/// across a chart (8 per interval of a 16-point cubic grid gave 104), and at least 2 per interval:
/// the blends and the chart maps, not only the spline's knots, set how fine the rule must be, so a
/// finer grid needs no more cells across a chart. `ntori new`'s Gauss–Bonnet check uses it. At grid
/// 32 it gives 4 (116 cells across); measured on the genus-2 and genus-8 plates at that grid, ∫K dA
/// is within 3e-6 relative of 2π(2 − 2n) at 4 cells per knot, as at 8. At grid 48 it gives 3 (135
/// across): the genus-10 and genus-16 plates read 5.8e-6 and 9.4e-6 there, 1e-8 and 5.4e-6 at 4,
/// and at 2 (90 across, what rounding down gave) 2.1e-5 and 6.9e-5, which failed issue 12's 1e-5
/// for a quadrature too coarse, not the surface (`embedding/examples/gauss_bonnet.rs`).
pub fn cells_per_knot(settings: crate::SplineSettings) -> usize {
    const ACROSS: usize = 116;
    ACROSS
        .div_ceil(settings.grid.saturating_sub(settings.degree).max(1))
        .max(2)
}

/// The surface's integrals with `cells_per_knot` cells (of 4 × 4 Gauss points) per knot interval of
/// each chart's spline, in each direction.
pub fn surface_integrals(
    layout: &Layout,
    control: &[Point3],
    cells_per_knot: usize,
) -> SurfaceIntegrals {
    use rayon::prelude::*;
    let degree = layout.settings().degree;
    // A chart's cells follow its own grid, so a finer disk grid gets a finer rule.
    let cells_of =
        |chart: &charts::Chart| (layout.grid(chart.id()) - degree) * cells_per_knot.max(1);
    let rows: Vec<(&charts::Chart, usize, f64, f64)> = layout
        .atlas()
        .charts()
        .iter()
        .flat_map(|chart| {
            let cells = cells_of(chart);
            nodes(cells, 1.0 / cells as f64).map(move |(y, wy)| (chart, cells, y, wy))
        })
        .collect();
    // One row of Gauss points per task, summed in order afterwards: all cores, and the same sums
    // whatever the number of threads.
    let row_sums: Vec<SurfaceIntegrals> = rows
        .par_iter()
        .map(|&(chart, cells, y, wy)| {
            let mut sums = SurfaceIntegrals::default();
            for (x, wx) in nodes(cells, 1.0 / cells as f64) {
                let w = Complex64::new(x, y);
                if !chart.domain().contains(w) {
                    continue;
                }
                // The chart's own raw blend first: where it vanishes the point adds nothing, and
                // elsewhere its normalised blend is it over the sum the evaluation forms anyway.
                let raw = layout.raw_blend_value(chart.domain(), w);
                if raw == 0.0 {
                    continue;
                }
                let p = ChartPoint::new(chart.id(), w);
                let reps = layout.atlas().locate_with_transitions(p);
                let (s, sum) = layout.eval_located_with_sum(control, p, &reps);
                let own = raw / sum;
                let da = s.area_element() * wx * wy * own;
                let k = s.gaussian_curvature();
                sums.gaussian_curvature += k * da;
                sums.absolute_curvature += k.abs() * da;
                sums.area += da;
                let (k1, k2) = s.principal_curvatures();
                let largest = k1.abs().max(k2.abs());
                let largest = if largest.is_nan() {
                    f64::INFINITY
                } else {
                    largest
                };
                if largest > sums.largest_curvature || sums.largest_curvature_at.is_none() {
                    sums.largest_curvature = largest;
                    sums.largest_curvature_at = Some(p);
                }
            }
            sums
        })
        .collect();
    row_sums.iter().fold(SurfaceIntegrals::default(), |a, b| {
        let (largest_curvature, largest_curvature_at) =
            if b.largest_curvature > a.largest_curvature || a.largest_curvature_at.is_none() {
                (b.largest_curvature, b.largest_curvature_at)
            } else {
                (a.largest_curvature, a.largest_curvature_at)
            };
        SurfaceIntegrals {
            gaussian_curvature: a.gaussian_curvature + b.gaussian_curvature,
            absolute_curvature: a.absolute_curvature + b.absolute_curvature,
            area: a.area + b.area,
            largest_curvature,
            largest_curvature_at,
        }
    })
}

/// Quadrature points and weights along [−½, ½] in `cells` cells of width `h`.
fn nodes(cells: usize, h: f64) -> impl Iterator<Item = (f64, f64)> {
    (0..cells).flat_map(move |c| {
        let mid = -0.5 + (c as f64 + 0.5) * h;
        NODES
            .iter()
            .map(move |&(t, w)| (mid + 0.5 * h * t, 0.5 * h * w))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_per_knot_keeps_the_cells_across_a_chart_and_a_floor() {
        let at = |grid| {
            cells_per_knot(crate::SplineSettings {
                grid,
                ..Default::default()
            })
        };
        // The density the check used at the default grid is unchanged there.
        assert_eq!(at(32), 4);
        assert_eq!(at(16), 9);
        assert_eq!(at(48), 3);
        for grid in 4..200 {
            let (cells, knots) = (at(grid), grid - 3);
            assert!(cells >= 2, "grid {grid}");
            assert!(cells * knots >= 116, "grid {grid}: {cells} × {knots}");
            // The fewest that do.
            assert!(
                cells == 2 || (cells - 1) * knots < 116,
                "grid {grid}: {cells}"
            );
        }
    }
}
