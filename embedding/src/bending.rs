//! The fit's smoothness term measured on the surface, not on the control grids.
//!
//! The plain term ([`crate::fit::smoothness_rows`]) sums the squared second differences of every
//! chart's control grid: a thin-plate energy in the chart's parameters. Where a map stretches the
//! surface one way (a tube 12 times longer than round mapped onto the square torus: its
//! triangles are 12 times longer one way than the other in the model), that energy charges bending
//! along the squeezed direction 12⁴ times more than across it. Then the fit smooths away the tube's
//! real bends and leaves ripples round it free: CGAL's `knot.off` fitted with |κ| 71 times its
//! mesh's and normals 13.7° off at the 90th percentile.
//!
//! Here the same energy is taken in the surface's arc length, ∫ |∇²S|² dA, with the metric read
//! off a first fit. At each interior control point the metric g = [[E, F], [F, G]] comes from the
//! first fit's grid differences there, or on a coarser grid its patch's derivatives (S_u and S_v
//! per grid step), averaged with its neighbours;
//! then with M = g^(-1/2) and H the grid's Hessian (centred second differences), the rows are
//! the entries of M H M, times the area element's square root. The metric is scaled so that its
//! median area element is 1, so a uniform isotropic map gives the plain energy back and the
//! smoothness weight keeps its meaning.

use crate::surface::{Layout, Point3, Vector3};

/// How far (as a factor either way) a point's metric may stray from the median in either
/// principal direction: a first fit that wandered off (no data near) gives no trustworthy metric.
pub(crate) const METRIC_CLAMP: f64 = 1e4;

/// Rounds of averaging each grid point's metric with its four neighbours.
const METRIC_SMOOTHING: usize = 2;

/// One grid point's metric [E, F, G] (per grid step).
pub(crate) type Metric = [f64; 3];

/// Each chart's metric (per grid step, at each of its grid points in order) from the control points
/// of a fit on `layout` itself: central differences of its grid (one-sided at the sides), then
/// [`smoothed`].
pub(crate) fn grid_metrics(layout: &Layout, control: &[Point3]) -> Vec<Vec<Metric>> {
    layout
        .atlas()
        .charts()
        .iter()
        .map(|chart| {
            let g = layout.grid(chart.id());
            let at = |i: usize, j: usize| control[layout.control_index(chart.id(), i, j)];
            let mut metric = Vec::with_capacity(g * g);
            for j in 0..g {
                for i in 0..g {
                    let (i0, i1) = (i.saturating_sub(1), (i + 1).min(g - 1));
                    let (j0, j1) = (j.saturating_sub(1), (j + 1).min(g - 1));
                    let su = (at(i1, j) - at(i0, j)) / (i1 - i0) as f64;
                    let sv = (at(i, j1) - at(i, j0)) / (j1 - j0) as f64;
                    metric.push([su.dot(&su), su.dot(&sv), sv.dot(&sv)]);
                }
            }
            smoothed(metric, g)
        })
        .collect()
}

/// Each chart's metric (per grid step of `layout`, at each of its grid points in order), read off
/// the surface with control points `control` on `source`, a layout over the same atlas (perhaps
/// with coarser grids): the first derivatives of the chart's own patch there, at the grid points'
/// Greville abscissae (the parameters the control points sit over; clamped into the chart), then
/// [`smoothed`].
pub(crate) fn patch_metrics(
    layout: &Layout,
    source: &Layout,
    control: &[Point3],
) -> Vec<Vec<Metric>> {
    layout
        .atlas()
        .charts()
        .iter()
        .map(|chart| {
            let (fine, coarse) = (layout.basis(chart.id()), source.basis(chart.id()));
            let p = fine.degree();
            // Knots are h apart, so function i's Greville abscissa is its knot i + (p + 1)/2 steps.
            let h = fine.knot(1) - fine.knot(0);
            let greville = |i: usize| fine.knot(i as isize) + 0.5 * (p + 1) as f64 * h;
            let g = fine.count();
            let q = coarse.degree() + 1;
            let mut metric = Vec::with_capacity(g * g);
            for j in 0..g {
                let (fv, nv) = coarse.eval(greville(j), 1);
                for i in 0..g {
                    let (fu, nu) = coarse.eval(greville(i), 1);
                    let (mut su, mut sv) = (Vector3::zeros(), Vector3::zeros());
                    for (b, (&v, &dv)) in nv[0][..q].iter().zip(&nv[1][..q]).enumerate() {
                        for (a, (&u, &du)) in nu[0][..q].iter().zip(&nu[1][..q]).enumerate() {
                            let c = control[source.control_index(chart.id(), fu + a, fv + b)];
                            su += c.coords * (du * v);
                            sv += c.coords * (u * dv);
                        }
                    }
                    let (su, sv) = (su * h, sv * h);
                    metric.push([su.dot(&su), su.dot(&sv), sv.dot(&sv)]);
                }
            }
            smoothed(metric, g)
        })
        .collect()
}

/// The arc-length thin-plate rows of every chart's control grid, given each chart's `metrics`
/// ([`patch_metrics`]): three rows per interior grid point (the Hessian's uu, √2·uv and vv entries
/// in arc length).
pub(crate) fn arc_length_rows(layout: &Layout, metrics: &[Vec<Metric>]) -> Vec<Vec<(usize, f64)>> {
    let scale = median_area(metrics);
    let mut rows = Vec::new();
    for (chart, metric) in layout.atlas().charts().iter().zip(metrics) {
        let g = layout.grid(chart.id());
        let index = |i: usize, j: usize| layout.control_index(chart.id(), i, j);
        for j in 1..g.saturating_sub(1) {
            for i in 1..g - 1 {
                let (m, area) = inverse_root(metric[j * g + i].map(|v| v / scale));
                hessian_rows(index, i, j, m, area.sqrt(), |row| rows.push(row));
            }
        }
    }
    rows
}

/// The metric averaged [`METRIC_SMOOTHING`] times with each point's four neighbours: a first fit's
/// differences wobble from point to point.
fn smoothed(mut metric: Vec<Metric>, g: usize) -> Vec<Metric> {
    for _ in 0..METRIC_SMOOTHING {
        let before = metric.clone();
        for j in 0..g {
            for i in 0..g {
                let mut sum = [0.0; 3];
                let mut count = 0.0;
                // i − 1 or j − 1 wraps past g at the sides and is left out with i + 1 = g.
                let neighbours = [
                    (i, j),
                    (i + 1, j),
                    (i.wrapping_sub(1), j),
                    (i, j + 1),
                    (i, j.wrapping_sub(1)),
                ];
                for (a, b) in neighbours.into_iter().filter(|&(a, b)| a < g && b < g) {
                    let q = before[b * g + a];
                    (0..3).for_each(|k| sum[k] += q[k]);
                    count += 1.0;
                }
                metric[j * g + i] = sum.map(|v| v / count);
            }
        }
    }
    metric
}

/// The median area element √det g over every chart's grid (1 where none is positive).
fn median_area(metrics: &[Vec<Metric>]) -> f64 {
    let mut areas: Vec<f64> = metrics
        .iter()
        .flatten()
        .map(|m| (m[0] * m[2] - m[1] * m[1]).max(0.0).sqrt())
        .filter(|a| *a > 0.0 && a.is_finite())
        .collect();
    areas.sort_by(f64::total_cmp);
    areas.get(areas.len() / 2).copied().unwrap_or(1.0)
}

/// M = g^(-1/2) and the area element √det g, with g's eigenvalues clamped to
/// [1/[`METRIC_CLAMP`], [`METRIC_CLAMP`]].
fn inverse_root([e, f, g]: Metric) -> ([[f64; 2]; 2], f64) {
    let clamp = |l: f64| {
        if l.is_finite() {
            l.clamp(1.0 / METRIC_CLAMP, METRIC_CLAMP)
        } else {
            1.0
        }
    };
    let (mean, spread) = (0.5 * (e + g), (0.25 * (e - g) * (e - g) + f * f).sqrt());
    let (l1, l2) = (clamp(mean + spread), clamp(mean - spread));
    // The eigenvector of l1 at angle θ: M = R diag(l1^(-1/2), l2^(-1/2)) Rᵀ.
    let theta = 0.5 * (2.0 * f).atan2(e - g);
    let (c, s) = (theta.cos(), theta.sin());
    let (r1, r2) = (l1.powf(-0.5), l2.powf(-0.5));
    let m = [
        [c * c * r1 + s * s * r2, c * s * (r1 - r2)],
        [c * s * (r1 - r2), s * s * r1 + c * c * r2],
    ];
    (m, (l1 * l2).sqrt())
}

/// The three rows (M H M)_uu, √2·(M H M)_uv, (M H M)_vv at interior grid point (i, j), each times
/// `scale`; H from the centred second differences.
fn hessian_rows(
    index: impl Fn(usize, usize) -> usize,
    i: usize,
    j: usize,
    m: [[f64; 2]; 2],
    scale: f64,
    mut push: impl FnMut(Vec<(usize, f64)>),
) {
    let uu = [(i - 1, j, 1.0), (i, j, -2.0), (i + 1, j, 1.0)];
    let vv = [(i, j - 1, 1.0), (i, j, -2.0), (i, j + 1, 1.0)];
    let uv = [
        (i + 1, j + 1, 0.25),
        (i - 1, j - 1, 0.25),
        (i + 1, j - 1, -0.25),
        (i - 1, j + 1, -0.25),
    ];
    for (a, b, weight) in [(0, 0, 1.0), (0, 1, std::f64::consts::SQRT_2), (1, 1, 1.0)] {
        // (M H M)_ab = Σ_cd M_ac H_cd M_db.
        let factors = [
            m[a][0] * m[0][b],
            m[a][0] * m[1][b] + m[a][1] * m[0][b],
            m[a][1] * m[1][b],
        ];
        let mut row = Vec::with_capacity(10);
        for (stencil, factor) in [
            (&uu[..], factors[0]),
            (&uv[..], factors[1]),
            (&vv[..], factors[2]),
        ] {
            for &(p, q, v) in stencil {
                row.push((index(p, q), v * factor * weight * scale));
            }
        }
        push(row);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    /// Sum of squares of `rows` applied to `control` (each coordinate).
    fn energy(rows: &[Vec<(usize, f64)>], control: &[Point3]) -> f64 {
        rows.iter()
            .map(|row| {
                row.iter()
                    .fold(nalgebra::Vector3::zeros(), |acc, &(c, v)| {
                        acc + control[c].coords * v
                    })
                    .norm_squared()
            })
            .sum()
    }

    /// A gently curved sheet z = ε q(x, y) laid on the grid through (x, y) = A (i, j) for random
    /// maps A of determinant 1 (stretched up to 12 times one way and sheared): the arc-length rows
    /// read the same bending per grid point whatever A is, 4ε²(a² + 2b² + c²) for q = a x² +
    /// 2b x y + c y², where the plain rows read it up to thousands of times larger or smaller.
    #[test]
    fn the_arc_length_energy_does_not_see_how_the_map_stretches() {
        let atlas = charts::Atlas::new(1).unwrap();
        let settings = crate::SplineSettings {
            grid: 12,
            ..crate::SplineSettings::default()
        };
        let layout = Layout::new(&atlas, settings).unwrap();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut random = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (eps, (a, b, c)) = (1e-4, (0.7, -0.3, 0.4));
        let exact = 4.0 * eps * eps * (a * a + 2.0 * b * b + c * c);
        let (mut plain_low, mut plain_high) = (f64::INFINITY, 0.0f64);
        for _ in 0..40 {
            let (stretch, shear, turn) = (1.0 + 11.0 * random(), random() - 0.5, 6.3 * random());
            let rotation = nalgebra::Rotation2::new(turn).into_inner();
            let map = rotation * Matrix2::new(stretch, shear, 0.0, 1.0 / stretch);
            let mut control = vec![Point3::origin(); layout.control_count()];
            for chart in atlas.charts() {
                let g = layout.grid(chart.id());
                for j in 0..g {
                    for i in 0..g {
                        let p = map * Vector2::new(i as f64, j as f64) / g as f64;
                        let z = eps * (a * p.x * p.x + 2.0 * b * p.x * p.y + c * p.y * p.y);
                        control[layout.control_index(chart.id(), i, j)] = Point3::new(p.x, p.y, z);
                    }
                }
            }
            let interior = (atlas.charts().len() * 10 * 10) as f64;
            // The metric is scaled to a median area element of 1: a grid step of 1/g in units where
            // the sheet's own bending is per unit length, so the grid's energy per point is g⁻⁴ of it.
            // Either metric: the grid's differences, or the patches' derivatives.
            for metrics in [
                grid_metrics(&layout, &control),
                patch_metrics(&layout, &layout, &control),
            ] {
                let read = energy(&arc_length_rows(&layout, &metrics), &control) / interior
                    * 12f64.powi(4);
                assert!(
                    (read - exact).abs() < 0.02 * exact,
                    "stretch {stretch:.2}, shear {shear:.2}: {read:e} against {exact:e}"
                );
            }
            let plain = energy(&crate::fit::smoothness_rows(&layout), &control) / interior;
            plain_low = plain_low.min(plain);
            plain_high = plain_high.max(plain);
        }
        assert!(
            plain_high > 100.0 * plain_low,
            "{plain_low:e} .. {plain_high:e}"
        );
    }
}
