//! Self-checks of an atlas that the command line reports and the tests assert: how well the charts
//! cover the surface, and how consistent the transition functions are.
//!
//! Tolerance policy: chart coordinates are O(1), so errors are absolute, in chart units. A
//! representation closer than [`BOUNDARY_BAND`] to its chart's boundary may be found from one chart and
//! not from another (rounding decides which side of the open boundary it falls); such
//! representations are skipped when comparing, never counted as errors.

use num_complex::Complex64;
use serde::Serialize;

use crate::{Atlas, ChartPoint, Geometry, ModelPoint};

/// Representations this close to a chart boundary (chart units) are not compared.
pub const BOUNDARY_BAND: f64 = 1e-9;

/// The coverage of a set of points: the smallest margin and where it occurs.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Coverage {
    pub points: usize,
    /// min over points of (max over the point's charts of the distance to that chart's boundary).
    pub min_margin: f64,
    /// A point (in the model space) where the minimum occurs.
    pub worst_point: Complex64,
    /// The most charts any point lies in.
    pub max_charts: usize,
}

/// Consistency of the transition functions over a set of points.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Consistency {
    pub points: usize,
    /// Largest |ψ_ii(w) − w| over the stored ψ_ii (they are the identity matrix).
    pub identity_error: f64,
    /// Largest |ψ_ji(ψ_ij(w)) − w|.
    pub inverse_error: f64,
    /// Largest |ψ_jk(ψ_ij(w)) − ψ_ik(w)| on triple overlaps.
    pub cocycle_error: f64,
    /// Representations (away from boundaries) that one chart's view found and another's missed.
    pub missing: usize,
}

impl Consistency {
    /// The largest of the three errors (infinite if any representation went missing).
    pub fn worst(&self) -> f64 {
        if self.missing > 0 {
            return f64::INFINITY;
        }
        self.identity_error
            .max(self.inverse_error)
            .max(self.cocycle_error)
    }

    fn merge(&mut self, o: Consistency) {
        self.points += o.points;
        self.identity_error = self.identity_error.max(o.identity_error);
        self.inverse_error = self.inverse_error.max(o.inverse_error);
        self.cocycle_error = self.cocycle_error.max(o.cocycle_error);
        self.missing += o.missing;
    }
}

/// `count` model points spread over the whole surface, deterministically: for genus ≥ 2, uniform in
/// the Klein model over the 4n triangles (origin, corner c, corner c+1), which reaches into the
/// polygon's thin corners; for genus 1 uniform over the square; for genus 0 uniform on the sphere.
/// The polygon's corners, edge midpoints and the point β come first.
pub fn spread_points(atlas: &Atlas, count: usize) -> Vec<ModelPoint> {
    let mut out = Vec::with_capacity(count);
    if let Some(poly) = atlas.polygon() {
        let c = poly.constants();
        out.push(ModelPoint(Complex64::ZERO));
        for (k, &corner) in poly.corners().iter().enumerate() {
            out.push(ModelPoint(corner * (1.0 - 1e-12)));
            out.push(ModelPoint(Complex64::from_polar(
                c.gamma,
                k as f64 * c.omega,
            )));
            out.push(ModelPoint(
                c.beta * Complex64::from_polar(1.0, k as f64 * c.omega),
            ));
        }
    }
    let remaining = count.saturating_sub(out.len());
    let seq = (0..remaining).map(r2);
    match (atlas.geometry(), atlas.polygon()) {
        (Geometry::Hyperbolic, Some(poly)) => {
            let sides = poly.sides();
            let klein: Vec<Complex64> = poly
                .corners()
                .iter()
                .map(|&z| z * (2.0 / (1.0 + z.norm_sqr())))
                .collect();
            out.extend(seq.enumerate().map(|(i, (u, v))| {
                let tri = i % sides;
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                let k = klein[tri] * u + klein[(tri + 1) % sides] * v;
                ModelPoint(k / (1.0 + (1.0 - k.norm_sqr()).max(0.0).sqrt()))
            }));
        }
        (Geometry::Euclidean, _) => {
            out.extend(seq.map(|(u, v)| ModelPoint(Complex64::new(u - 0.5, v - 0.5))));
        }
        _ => {
            out.extend(seq.map(|(u, v)| {
                let z = 2.0 * u - 1.0;
                let rho = (1.0 - z * z).max(0.0).sqrt();
                let (s, c) = (std::f64::consts::TAU * v).sin_cos();
                // Stereographic projection from the north pole; z = 1 exactly never occurs.
                ModelPoint(Complex64::new(rho * c, rho * s) / (1.0 - z).max(1e-300))
            }));
        }
    }
    out.truncate(count);
    out
}

/// A point strictly inside chart `chart % count`'s domain from two numbers in [0, 1): the square
/// uniformly, the disk uniformly by area. For property tests and benches.
///
/// ```
/// let atlas = charts::Atlas::new(2).unwrap();
/// let p = charts::check::chart_point_from_unit(&atlas, 7, 0.3, 0.9);
/// assert!(atlas.locate(p).is_ok());
/// ```
pub fn chart_point_from_unit(atlas: &Atlas, chart: usize, u: f64, v: f64) -> ChartPoint {
    let id = crate::ChartId((chart % atlas.charts().len()) as u32);
    let w = match atlas.charts()[id.index()].domain() {
        crate::Domain::Square => Complex64::new(u - 0.5, v - 0.5) * (1.0 - 1e-9),
        crate::Domain::Disk => {
            Complex64::from_polar(0.5 * u.sqrt() * (1.0 - 1e-9), std::f64::consts::TAU * v)
        }
    };
    ChartPoint::new(id, w)
}

/// The R2 low-discrepancy sequence (Roberts), well spread in the unit square for any prefix.
fn r2(i: usize) -> (f64, f64) {
    const G: f64 = 1.324_717_957_244_746; // the plastic number
    let (a1, a2) = (1.0 / G, 1.0 / (G * G));
    let k = i as f64 + 0.5;
    ((k * a1).fract(), (k * a2).fract())
}

/// How many of the worst samples [`coverage`] refines by local search.
const REFINED: usize = 48;

/// The coverage margin: sampled at `points`, then refined. The margin is the maximum of a few chart
/// margins, so its minima sit at isolated points where charts' margins cross; sampling approaches them
/// only slowly (10^5 → 10^6 points still lowers the estimate by up to 20%), so a pattern search
/// descends from each of the worst samples to the local minimum near it.
pub fn coverage(atlas: &Atlas, points: &[ModelPoint]) -> Coverage {
    let margin_at = |z: Complex64| atlas.margin(&atlas.locate_model(ModelPoint(z)));
    let mut max_charts = 0;
    let mut sampled: Vec<(f64, Complex64)> = points
        .iter()
        .map(|&z| {
            let p = atlas.locate_model(z);
            max_charts = max_charts.max(p.representations().len());
            (atlas.margin(&p), z.0)
        })
        .collect();
    let scale = (points.len() as f64).sqrt().recip();
    let (min_margin, worst_point) = refinement_starts(atlas.geometry(), &mut sampled)
        .into_iter()
        .map(|(m, z)| descend(atlas.geometry(), &margin_at, z, m, scale))
        .fold((f64::INFINITY, Complex64::ZERO), |a, b| {
            if b.0 < a.0 { b } else { a }
        });
    Coverage {
        points: points.len(),
        min_margin,
        worst_point,
        max_charts,
    }
}

/// Up to [`REFINED`] of the worst samples, each well away from those picked before it, so that the
/// searches start in different basins rather than all in the deepest one.
fn refinement_starts(
    geometry: Geometry,
    sampled: &mut [(f64, Complex64)],
) -> Vec<(f64, Complex64)> {
    let pool = (50 * REFINED).min(sampled.len());
    if pool == 0 {
        return Vec::new();
    }
    sampled.select_nth_unstable_by(pool - 1, |a, b| a.0.total_cmp(&b.0));
    let pool = &mut sampled[..pool];
    pool.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let apart = |a: Complex64, b: Complex64| match geometry {
        // Pseudo-hyperbolic distance tanh(d/2) > 0.05.
        Geometry::Hyperbolic => (a - b).norm() > 0.05 * (Complex64::ONE - a.conj() * b).norm(),
        Geometry::Euclidean => (a - b).norm() > 0.02,
        Geometry::Spherical => (a - b).norm() > 0.02 * (1.0 + a.norm_sqr()),
    };
    let mut starts: Vec<(f64, Complex64)> = Vec::with_capacity(REFINED);
    for &(m, z) in pool.iter() {
        if starts.len() == REFINED {
            break;
        }
        if starts.iter().all(|s| apart(s.1, z)) {
            starts.push((m, z));
        }
    }
    starts
}

/// Compass search for a local minimum of `f` from z (value fz), with steps measured in the local
/// metric (scaled by 1 − |z|² in the Poincaré disk, so it works near the unit circle too).
fn descend(
    geometry: Geometry,
    f: &impl Fn(Complex64) -> f64,
    mut z: Complex64,
    mut fz: f64,
    start: f64,
) -> (f64, Complex64) {
    let metric = |z: Complex64| match geometry {
        Geometry::Hyperbolic => (1.0 - z.norm_sqr()).max(0.0),
        Geometry::Euclidean => 1.0,
        // The sphere coordinate: the spherical metric's scale 1 + |ζ|².
        Geometry::Spherical => 1.0 + z.norm_sqr(),
    };
    // The minimum lies where two or three chart margins cross, on creases at arbitrary angles; a fixed
    // set of directions stalls on a crease, so the set is turned by an irrational angle after each
    // failure, and the step halves only after two failures in a row.
    let mut turn = 0.0_f64;
    let (mut step, mut failures) = (start, 0);
    // Creeping along a crease can take many small successful steps; 400 rounds reach 1e-10 steps
    // from any start used here and bound the cost.
    for _ in 0..400 {
        if step <= 1e-10 {
            break;
        }
        let here = step * metric(z);
        let best = (0..16)
            .map(|k| z + Complex64::from_polar(here, turn + k as f64 * std::f64::consts::PI / 8.0))
            .filter(|&w| geometry != Geometry::Hyperbolic || w.norm() < 1.0)
            .map(|w| (f(w), w))
            .fold((fz, z), |a, b| if b.0 < a.0 { b } else { a });
        if best.0 < fz {
            (fz, z) = best;
            failures = 0;
        } else {
            turn += 0.618_033_988_749_895 * std::f64::consts::PI / 8.0;
            failures += 1;
            if failures == 2 {
                step *= 0.5;
                failures = 0;
            }
        }
    }
    (fz, z)
}

/// Compares the views of one surface point from each of its charts: locating it from any
/// representation must give every other representation (inverse and cocycle conditions).
pub fn consistency_at(atlas: &Atlas, p: ChartPoint) -> Consistency {
    let mut out = Consistency {
        points: 1,
        ..Consistency::default()
    };
    let Ok(base) = atlas.locate(p) else {
        return out;
    };
    let margin = |r: &ChartPoint| {
        atlas
            .chart(r.chart)
            .map(|c| c.domain().margin(r.coords))
            .unwrap_or(f64::NEG_INFINITY)
    };
    for via in base.representations().iter().filter(|r| r.chart != p.chart) {
        if margin(via) < BOUNDARY_BAND {
            continue;
        }
        let again = atlas.locate_unchecked(*via);
        for x in base
            .representations()
            .iter()
            .filter(|x| x.chart != via.chart)
        {
            if margin(x) < BOUNDARY_BAND {
                continue;
            }
            match again.in_chart(x.chart) {
                None => out.missing += 1,
                Some(w) => {
                    let err = (w - x.coords).norm();
                    if x.chart == p.chart {
                        out.inverse_error = out.inverse_error.max(err);
                    } else {
                        out.cocycle_error = out.cocycle_error.max(err);
                    }
                }
            }
        }
    }
    out
}

/// The full self-check over `points`: ψ_ii, and inverse/cocycle errors seen from each point's first
/// chart.
pub fn consistency(atlas: &Atlas, points: &[ModelPoint]) -> Consistency {
    let mut total = Consistency::default();
    for chart in atlas.charts() {
        let id = chart.id();
        for t in atlas.transitions(id, id) {
            let w = Complex64::new(0.3, -0.2);
            total.identity_error = total.identity_error.max((t.apply(w) - w).norm());
        }
    }
    for &z in points {
        let p = atlas.locate_model(z);
        // Start from the representation deepest in its chart, so that it is a valid chart point.
        if let Some(start) = p.representations().iter().max_by(|a, b| {
            let m = |r: &&ChartPoint| atlas.charts()[r.chart.index()].domain().margin(r.coords);
            m(a).total_cmp(&m(b))
        }) {
            total.merge(consistency_at(atlas, *start));
        }
    }
    total
}
