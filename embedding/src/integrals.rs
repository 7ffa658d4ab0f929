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

    /// The largest |κ| over the quadrature's points and where it is, as the shape checks take it.
    pub fn curvature_peak(&self) -> crate::quality::CurvatureExtreme {
        crate::quality::CurvatureExtreme {
            max_abs: self.largest_curvature,
            at: self.largest_curvature_at,
        }
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
    surface_integrals_over(layout, control, cells_per_knot, &|_| false).0
}

/// How much of a region's area has each size of mean curvature |H| (model units⁻¹): a histogram
/// over bins 1% wide (each edge [`HISTOGRAM_RATIO`] times the last, from [`HISTOGRAM_FLOOR`]; one
/// bin below it and one above the last edge). Its quantiles are within 1% of the exact weighted
/// ones, at a fixed size however many points it holds (millions at the quadrature's density).
#[derive(Clone, Debug, PartialEq)]
pub struct CurvatureHistogram {
    /// The area in each bin: below the floor, then [floor·rᵏ⁻¹, floor·rᵏ) for k ≥ 1, the last
    /// open above.
    area: Vec<f64>,
    points: usize,
    max: f64,
}

/// The first bin edge of a [`CurvatureHistogram`] (model units⁻¹): a millionth of a unit sphere's
/// curvature, far below any ripple a designer sees.
pub const HISTOGRAM_FLOOR: f64 = 1e-6;
/// The ratio between consecutive bin edges of a [`CurvatureHistogram`].
pub const HISTOGRAM_RATIO: f64 = 1.01;
/// Bins: the edges reach past 1e6 (a radius of a millionth of a unit), then one open bin.
const HISTOGRAM_BINS: usize = 2800;

impl Default for CurvatureHistogram {
    fn default() -> Self {
        CurvatureHistogram {
            area: vec![0.0; HISTOGRAM_BINS],
            points: 0,
            max: 0.0,
        }
    }
}

impl CurvatureHistogram {
    /// Counts `area` (≥ 0) at mean curvature `h` (its size is taken; NaN counts as infinite).
    pub fn add(&mut self, h: f64, area: f64) {
        let h = if h.is_nan() { f64::INFINITY } else { h.abs() };
        let bin = if h < HISTOGRAM_FLOOR {
            0
        } else {
            let k = ((h / HISTOGRAM_FLOOR).ln() / HISTOGRAM_RATIO.ln()).floor();
            // Saturates: infinity lands in the open bin.
            (1 + k as usize).min(HISTOGRAM_BINS - 1)
        };
        self.area[bin] += area.max(0.0);
        self.points += 1;
        self.max = self.max.max(h);
    }

    /// Adds `other`'s points to these.
    pub fn merge(&mut self, other: &CurvatureHistogram) {
        for (a, b) in self.area.iter_mut().zip(&other.area) {
            *a += b;
        }
        self.points += other.points;
        self.max = self.max.max(other.max);
    }

    pub fn points(&self) -> usize {
        self.points
    }

    /// The region's area (the points' areas summed).
    pub fn area(&self) -> f64 {
        self.area.iter().sum()
    }

    /// The largest |H| counted (0 for none).
    pub fn max(&self) -> f64 {
        self.max
    }

    /// The |H| below which at least `q` (0 to 1) of the area lies: the upper edge of the bin where
    /// the area reaches it, or the largest |H| where that is smaller; so at least the exact
    /// weighted quantile and less than 1% above it (or at most [`HISTOGRAM_FLOOR`]). 0 for none.
    pub fn quantile(&self, q: f64) -> f64 {
        let target = q * self.area();
        let mut seen = 0.0;
        for (k, a) in self.area.iter().enumerate() {
            seen += a;
            if *a > 0.0 && seen >= target {
                let edge = HISTOGRAM_FLOOR * HISTOGRAM_RATIO.powi(k as i32);
                return if k + 1 == HISTOGRAM_BINS {
                    self.max
                } else {
                    edge.min(self.max)
                };
            }
        }
        self.max
    }
}

/// [`surface_integrals`], and the mean curvature at every quadrature point whose position lies in
/// `region`, weighted by the area the point stands for: that part of the surface looked at as
/// densely as the integrals look (several points per knot interval of every chart), where a
/// tessellation's or the input's vertices can miss a ripple narrower than their spacing.
pub fn surface_integrals_over(
    layout: &Layout,
    control: &[Point3],
    cells_per_knot: usize,
    region: &(dyn Fn(&Point3) -> bool + Sync),
) -> (SurfaceIntegrals, CurvatureHistogram) {
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
    // whatever the number of threads. The region's histogram is one per block of rows (a
    // histogram per row would hold hundreds of megabytes at once).
    const ROWS_PER_HISTOGRAM: usize = 64;
    let blocks: Vec<(Vec<SurfaceIntegrals>, Option<CurvatureHistogram>)> = rows
        .par_chunks(ROWS_PER_HISTOGRAM)
        .map(|block| {
            let mut histogram: Option<CurvatureHistogram> = None;
            let sums = block
                .iter()
                .map(|&(chart, cells, y, wy)| {
                    let mut sums = SurfaceIntegrals::default();
                    for (x, wx) in nodes(cells, 1.0 / cells as f64) {
                        let w = Complex64::new(x, y);
                        if !chart.domain().contains(w) {
                            continue;
                        }
                        // The chart's own raw blend first: where it vanishes the point adds
                        // nothing, and elsewhere its normalised blend is it over the sum the
                        // evaluation forms anyway.
                        let raw = layout.raw_blend_value(chart.domain(), w);
                        if raw == 0.0 {
                            continue;
                        }
                        let p = ChartPoint::new(chart.id(), w);
                        let reps = layout.atlas().locate_with_transitions(p);
                        let (s, sum) = layout.eval_located_with_sum(control, p, &reps);
                        let own = raw / sum;
                        let da = s.area_element() * wx * wy * own;
                        sums.add(&s, da, p);
                        if region(&s.pos) {
                            histogram
                                .get_or_insert_with(Default::default)
                                .add(s.mean_curvature(), da);
                        }
                    }
                    sums
                })
                .collect();
            (sums, histogram)
        })
        .collect();
    let mut total = SurfaceIntegrals::default();
    let mut histogram = CurvatureHistogram::default();
    for (sums, block_histogram) in blocks {
        for b in sums {
            total = total.plus(b);
        }
        if let Some(h) = block_histogram {
            histogram.merge(&h);
        }
    }
    (total, histogram)
}

impl SurfaceIntegrals {
    /// Counts the quadrature point `p`, where the surface is `s` and weighs `da`.
    fn add(&mut self, s: &crate::surface::SurfaceJet, da: f64, p: ChartPoint) {
        let k = s.gaussian_curvature();
        self.gaussian_curvature += k * da;
        self.absolute_curvature += k.abs() * da;
        self.area += da;
        let (k1, k2) = s.principal_curvatures();
        let largest = k1.abs().max(k2.abs());
        let largest = if largest.is_nan() {
            f64::INFINITY
        } else {
            largest
        };
        if largest > self.largest_curvature || self.largest_curvature_at.is_none() {
            self.largest_curvature = largest;
            self.largest_curvature_at = Some(p);
        }
    }

    /// These sums and `b`'s: the first of the two largest |κ| where they tie.
    fn plus(self, b: SurfaceIntegrals) -> SurfaceIntegrals {
        let (largest_curvature, largest_curvature_at) = if b.largest_curvature
            > self.largest_curvature
            || self.largest_curvature_at.is_none()
        {
            (b.largest_curvature, b.largest_curvature_at)
        } else {
            (self.largest_curvature, self.largest_curvature_at)
        };
        SurfaceIntegrals {
            gaussian_curvature: self.gaussian_curvature + b.gaussian_curvature,
            absolute_curvature: self.absolute_curvature + b.absolute_curvature,
            area: self.area + b.area,
            largest_curvature,
            largest_curvature_at,
        }
    }
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

    proptest::proptest! {
        /// Each quantile is at least the exact area-weighted one (the smallest value with that
        /// share of the area at or below it, by counting) and within a bin (1%) above it, or at
        /// most the floor; the totals are the points'.
        #[test]
        fn histogram_quantiles_are_within_a_bin_above_the_exact_ones(
            points in proptest::collection::vec((-8.0f64..3.0, 0.01f64..5.0), 1..80),
            q in 0.0f64..1.0,
        ) {
            // |H| from 1e-8 to 1000, both signs.
            let points: Vec<(f64, f64)> = points
                .iter()
                .enumerate()
                .map(|(i, &(e, a))| (if i % 2 == 0 { 1.0 } else { -1.0 } * 10f64.powf(e), a))
                .collect();
            let mut histogram = CurvatureHistogram::default();
            for &(h, a) in &points {
                histogram.add(h, a);
            }
            let total: f64 = points.iter().map(|p| p.1).sum();
            let exact = points
                .iter()
                .map(|p| p.0.abs())
                .filter(|&x| {
                    points.iter().filter(|p| p.0.abs() <= x).map(|p| p.1).sum::<f64>()
                        >= q * total * (1.0 - 1e-12)
                })
                .fold(f64::INFINITY, f64::min);
            let got = histogram.quantile(q);
            proptest::prop_assert!(got >= exact * (1.0 - 1e-12), "{got} < {exact}");
            proptest::prop_assert!(
                got <= (exact * HISTOGRAM_RATIO).max(HISTOGRAM_FLOOR) * (1.0 + 1e-12),
                "{got} for {exact}"
            );
            let largest = points.iter().map(|p| p.0.abs()).fold(0.0, f64::max);
            proptest::prop_assert_eq!(histogram.max(), largest);
            proptest::prop_assert_eq!(histogram.quantile(1.0), largest);
            proptest::prop_assert_eq!(histogram.points(), points.len());
            proptest::prop_assert!((histogram.area() - total).abs() <= 1e-12 * total);
            // Split in two and merged, the same histogram.
            let (mut first, mut second) = (CurvatureHistogram::default(), CurvatureHistogram::default());
            for (i, &(h, a)) in points.iter().enumerate() {
                if i < points.len() / 2 { first.add(h, a) } else { second.add(h, a) }
            }
            first.merge(&second);
            proptest::prop_assert_eq!(first.quantile(q), got);
            proptest::prop_assert_eq!(first.points(), histogram.points());
        }
    }

    /// On a sphere of radius 2 every point has |H| = ½, so every quantile of the whole surface
    /// is ½ within a bin, and the histogram's area is the sphere's; a region that holds nothing
    /// leaves it empty.
    #[test]
    fn a_spheres_whole_surface_has_one_mean_curvature() {
        let fit = crate::fit::initial_model(
            0,
            16,
            crate::SplineSettings::default(),
            crate::fit::FitSettings::default(),
        )
        .unwrap();
        let (layout, control) = (fit.surface.layout(), fit.surface.control_points().to_vec());
        let scaled: Vec<Point3> = control
            .iter()
            .map(|p| Point3::from(p.coords * 2.0))
            .collect();
        let (sums, all) = surface_integrals_over(&layout, &scaled, 4, &|_| true);
        let (plain, none) = surface_integrals_over(&layout, &scaled, 4, &|_| false);
        assert_eq!(sums, plain);
        assert_eq!((none.points(), none.area(), none.max()), (0, 0.0, 0.0));
        assert!((all.area() - sums.area).abs() < 1e-9 * sums.area);
        assert!(all.points() > 10_000);
        for q in [0.1, 0.5, 0.9, 0.999] {
            let h = all.quantile(q);
            assert!((h - 0.5).abs() < 0.02, "{q}: {h}");
        }
        // Only the upper half: about half the area.
        let (_, upper) = surface_integrals_over(&layout, &scaled, 4, &|p| p.z > 0.0);
        assert!(
            (upper.area() / all.area() - 0.5).abs() < 0.02,
            "{}",
            upper.area()
        );
    }
}
