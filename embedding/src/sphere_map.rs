//! A genus-0 mesh mapped onto the unit sphere: the sphere's counterpart of the equivariant Tutte map
//! that [`crate::mesh_fit`] builds for genus ≥ 1.
//!
//! 1. One triangle is taken out and the rest, a disk, is flattened by Floater's mean value map with
//!    the triangle's corners pinned to an equilateral triangle: a bijection onto the triangle's
//!    inside. Inverse stereographic projection puts it on the sphere with the removed triangle
//!    round the north pole, after a scale that puts half the surface's area on either hemisphere.
//! 2. Relaxation on the closed sphere: every vertex moves to the mean value average of its
//!    neighbours, taken in its own conformal frame (stereographic projection from its antipode onto
//!    its tangent plane, the sphere's counterpart of the Poincaré disk's frame at the origin).
//! 3. Harmonic maps of the sphere are conformal, and the conformal maps of the sphere form a
//!    six-dimensional (Möbius) family: nothing stops the relaxation from sliding the whole map
//!    towards one point. After every sweep a Möbius transformation of the ball brings the centre of
//!    the surface's area back to the centre of the sphere (Möbius centering), which leaves the
//!    balanced map to converge.
//! 4. The plates' stretch reweighting (Yoshizawa, Belyaev and Seidel) evens the area out, then the
//!    relaxation runs again.

use nalgebra::Vector3;

use crate::EmbeddingError;
use crate::fit::{relative_stretch, stretch_divisor};
use crate::floater;
use crate::surface::Point3;

/// Every vertex of a genus-0 mesh on the unit sphere.
#[derive(Clone, Debug)]
pub(crate) struct SphereMap {
    /// One unit vector per mesh vertex.
    pub points: Vec<Vector3<f64>>,
    /// Triangles that are not counter-clockwise seen from outside the sphere (0 for a bijection).
    pub folded: usize,
    /// Relaxation sweeps run in all rounds.
    pub sweeps: usize,
}

/// Rounds of stretch reweighting the sphere takes beyond what the settings ask of the polygon's maps:
/// the sphere's conformal map squeezes the ends of a long shape far more than the polygon's maps
/// squeeze a plate (an ellipsoid 2.8 : 1 with lobes fitted to 1.5% of its diagonal with one round,
/// within 1% with three).
pub(crate) const EXTRA_ROUNDS: usize = 2;

/// The map, relaxed for at most `sweeps` sweeps per round, with `stretch_rounds` +
/// [`EXTRA_ROUNDS`] rounds of reweighting after the first. `areas` are the mesh's vertex areas (the mass that is centred).
pub(crate) fn sphere_map(
    positions: &[Point3],
    triangles: &[[u32; 3]],
    areas: &[f64],
    sweeps: usize,
    stretch_rounds: usize,
    tolerance: f64,
) -> Result<SphereMap, EmbeddingError> {
    let mut neighbours = floater::mean_value_weights(positions, triangles)?
        .into_iter()
        .map(|list| list.into_iter().map(|(u, w)| (w, u)).collect::<Vec<_>>())
        .collect::<Vec<_>>();
    let mut points = initial_map(positions, triangles, areas)?;
    let mut used = 0;
    for round in 0..=stretch_rounds + EXTRA_ROUNDS {
        if round > 0 {
            let stretch = stretch(&points, positions, triangles);
            for list in &mut neighbours {
                for (w, u) in list.iter_mut() {
                    *w /= stretch_divisor(stretch[*u as usize]);
                }
            }
        }
        used += relax(&mut points, &neighbours, areas, sweeps, tolerance);
    }
    let folded = triangles
        .iter()
        .filter(|t| orientation(&points, t) <= 0.0)
        .count();
    Ok(SphereMap {
        points,
        folded,
        sweeps: used,
    })
}

/// Floater's map of the mesh less its largest triangle, lifted to the sphere and centred.
fn initial_map(
    positions: &[Point3],
    triangles: &[[u32; 3]],
    areas: &[f64],
) -> Result<Vec<Vector3<f64>>, EmbeddingError> {
    let area = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        (b - a).cross(&(c - a)).norm()
    };
    let removed = (0..triangles.len())
        .max_by(|&a, &b| area(&triangles[a]).total_cmp(&area(&triangles[b])))
        .ok_or_else(|| EmbeddingError::Parameterization("the mesh has no triangles".into()))?;
    let disk: Vec<[u32; 3]> = triangles
        .iter()
        .enumerate()
        .filter(|&(t, _)| t != removed)
        .map(|(_, t)| *t)
        .collect();
    // The disk's boundary runs against the removed triangle's orientation: its corners go clockwise.
    let pins: Vec<(u32, [f64; 2])> = triangles[removed]
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            let angle = -(k as f64) * std::f64::consts::TAU / 3.0;
            (v, [angle.cos(), angle.sin()])
        })
        .collect();
    let flat = floater::parameterize(positions, &disk, &pins)?;
    // Half the area inside radius s: then |w/s| < 1 is the southern hemisphere.
    let mut by_radius: Vec<(f64, f64)> = flat
        .iter()
        .zip(areas)
        .map(|(w, &a)| (w[0].hypot(w[1]), a))
        .collect();
    by_radius.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = areas.iter().sum::<f64>() / 2.0;
    let mut seen = 0.0;
    let scale = by_radius
        .iter()
        .find(|(_, a)| {
            seen += a;
            seen >= half
        })
        .map_or(1.0, |(r, _)| *r)
        .max(f64::MIN_POSITIVE);
    // Inverse stereographic projection from the north pole. It reverses orientation seen from
    // outside, and the pins' clockwise order reverses it once more.
    let mut points: Vec<Vector3<f64>> = flat
        .iter()
        .map(|w| {
            let (x, y) = (w[0] / scale, w[1] / scale);
            let r2 = x * x + y * y;
            Vector3::new(2.0 * x, 2.0 * y, r2 - 1.0) / (r2 + 1.0)
        })
        .collect();
    let positive = triangles
        .iter()
        .filter(|t| orientation(&points, t) > 0.0)
        .count();
    if 2 * positive < triangles.len() {
        // A mesh whose triangles turn the other way round: mirror the map to keep it orientation
        // preserving (the atlas's charts are counter-clockwise seen from outside).
        points.iter_mut().for_each(|p| p.y = -p.y);
    }
    centre(&mut points, areas);
    Ok(points)
}

/// Over-relaxed Gauss–Seidel sweeps, each followed by Möbius centering, until no vertex moves more
/// than `tolerance` in a sweep (centering included) or `sweeps` run out. Returns the sweeps used.
fn relax(
    points: &mut [Vector3<f64>],
    neighbours: &[Vec<(f64, u32)>],
    areas: &[f64],
    sweeps: usize,
    tolerance: f64,
) -> usize {
    // The same over-relaxation and step cap as the polygon's relaxation (`Lifts::relax`).
    const OVER: f64 = 1.3;
    const MAX_STEP: f64 = 0.25;
    for sweep in 0..sweeps {
        let before = points.to_vec();
        for v in 0..points.len() {
            let x = points[v];
            let (mut sum, mut total) = (Vector3::zeros(), 0.0);
            for &(w, u) in &neighbours[v] {
                sum += to_frame(x, points[u as usize]) * w;
                total += w;
            }
            if total <= 0.0 {
                continue;
            }
            let mut d = sum / total * OVER;
            if d.norm() > MAX_STEP {
                d *= MAX_STEP / d.norm();
            }
            points[v] = from_frame(x, d);
        }
        centre(points, areas);
        let moved = points
            .iter()
            .zip(&before)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        if moved < tolerance {
            return sweep + 1;
        }
    }
    sweeps
}

/// y seen from x's frame: stereographic projection from −x onto the tangent plane at x (a tangent
/// vector; x itself goes to 0, points a quarter turn away to unit length).
fn to_frame(x: Vector3<f64>, y: Vector3<f64>) -> Vector3<f64> {
    let along = y.dot(&x);
    // y = −x exactly would go to infinity; a neighbour is never there in a map worth relaxing, and
    // the step cap bounds what it would do.
    (y - x * along) / (1.0 + along).max(1e-12)
}

/// The inverse of [`to_frame`]: the sphere point of tangent vector d at x.
fn from_frame(x: Vector3<f64>, d: Vector3<f64>) -> Vector3<f64> {
    let d2 = d.norm_squared();
    ((x * (1.0 - d2) + d * 2.0) / (1.0 + d2)).normalize()
}

/// Möbius centering: ball isometries that move the area-weighted centroid of the points to the
/// origin (each T_a sends a to 0 and the sphere to itself, spreading the points round a/|a| apart).
fn centre(points: &mut [Vector3<f64>], areas: &[f64]) {
    const STEPS: usize = 20;
    let total: f64 = areas.iter().sum();
    for _ in 0..STEPS {
        let c = points
            .iter()
            .zip(areas)
            .fold(Vector3::zeros(), |s, (p, &a)| s + p * a)
            / total;
        if c.norm() < 1e-12 {
            return;
        }
        // The centroid of a measure is not the point the isometry must move, but close to it for
        // small offsets; capped at half way to the sphere so one step never crushes a hemisphere.
        let a = if c.norm() > 0.5 {
            c * (0.5 / c.norm())
        } else {
            c
        };
        points.iter_mut().for_each(|p| *p = ball_isometry(a, *p));
    }
}

/// T_a(x) = (1 − |a|²)(x − a)/|x − a|² − a for |x| = 1: a Möbius transformation of the unit ball that
/// maps the sphere onto itself and a to the origin.
fn ball_isometry(a: Vector3<f64>, x: Vector3<f64>) -> Vector3<f64> {
    let u = x - a;
    ((u * (1.0 - a.norm_squared())) / u.norm_squared() - a).normalize()
}

/// Twice the signed volume a·(b × c): positive where the triangle runs counter-clockwise seen from
/// outside the sphere.
fn orientation(points: &[Vector3<f64>], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| points[v as usize]);
    a.dot(&b.cross(&c))
}

/// Per vertex: √(3D area / spherical area) of its triangles, relative to the whole surface's ratio.
fn stretch(points: &[Vector3<f64>], positions: &[Point3], triangles: &[[u32; 3]]) -> Vec<f64> {
    let n = points.len();
    let (mut surface, mut sphere) = (vec![0.0; n], vec![0.0; n]);
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let area3 = (b - a).cross(&(c - a)).norm() / 2.0;
        let [p, q, r] = t.map(|v| points[v as usize]);
        // Van Oosterom and Strackee: tan(E/2) = p·(q × r) / (1 + p·q + q·r + r·p).
        let excess = 2.0
            * p.dot(&q.cross(&r))
                .atan2(1.0 + p.dot(&q) + q.dot(&r) + r.dot(&p));
        for &v in t {
            surface[v as usize] += area3;
            sphere[v as usize] += excess.max(0.0);
        }
    }
    relative_stretch(&surface, &sphere)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_invert_each_other() {
        let x = Vector3::new(0.3, -0.5, 0.8).normalize();
        for y in [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(-0.2, 0.9, 0.1).normalize(),
            Vector3::new(0.31, -0.49, 0.81).normalize(),
        ] {
            let back = from_frame(x, to_frame(x, y));
            assert!((back - y).norm() < 1e-12, "{back} vs {y}");
        }
    }

    #[test]
    fn ball_isometries_keep_the_sphere_and_move_a_to_the_centre() {
        let a = Vector3::new(0.2, 0.1, -0.3);
        for x in [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, -0.6, 0.8),
            Vector3::new(0.48, 0.6, 0.64),
        ] {
            assert!((ball_isometry(a, x).norm() - 1.0).abs() < 1e-12);
        }
        // On the axis through a, the points ±a/|a| stay put.
        let n = a.normalize();
        assert!((ball_isometry(a, n) - n).norm() < 1e-12);
        assert!((ball_isometry(a, -n) + n).norm() < 1e-12);
    }
}
