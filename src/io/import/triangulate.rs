//! Polygons to triangles with the same winding, non-convex ones included.

use embedding::{Point3, Vector3};

use super::MAX_EAR_CLIPPED_SIDES;

/// Cuts a polygon (vertex indices into `positions`, all in range) into triangles with the same
/// winding: a fan when it is convex, else ear clipping in its best-fit plane (Newell's normal),
/// so non-convex polygons come out right; polygons of more than [`MAX_EAR_CLIPPED_SIDES`] sides,
/// and those with no plane (all corners on a line), are fanned.
pub fn triangulate(positions: &[Point3], polygon: &[u32]) -> Vec<[u32; 3]> {
    let mut out = Vec::with_capacity(polygon.len().saturating_sub(2));
    triangulate_into(positions, polygon, &mut out);
    out
}

pub(super) fn triangulate_into(positions: &[Point3], poly: &[u32], out: &mut Vec<[u32; 3]>) {
    let n = poly.len();
    if n < 3 {
        return;
    }
    let fan = |out: &mut Vec<[u32; 3]>| {
        for k in 1..n - 1 {
            out.push([poly[0], poly[k], poly[k + 1]]);
        }
    };
    if n == 3 || n > MAX_EAR_CLIPPED_SIDES {
        return fan(out);
    }
    let p = |k: usize| positions[poly[k] as usize];
    // Newell's normal and a basis of the plane.
    let mut normal = Vector3::zeros();
    for k in 0..n {
        let (a, b) = (p(k), p((k + 1) % n));
        normal.x += (a.y - b.y) * (a.z + b.z);
        normal.y += (a.z - b.z) * (a.x + b.x);
        normal.z += (a.x - b.x) * (a.y + b.y);
    }
    let Some(normal) = normal.try_normalize(0.0) else {
        return fan(out);
    };
    let helper = if normal.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = normal.cross(&helper).normalize();
    let v = normal.cross(&u);
    let flat: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let d = p(k) - p(0);
            [d.dot(&u), d.dot(&v)]
        })
        .collect();
    // Counter-clockwise in (u, v) seen along the normal.
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let convex = (0..n).all(|k| cross(flat[k], flat[(k + 1) % n], flat[(k + 2) % n]) >= 0.0);
    if convex {
        return fan(out);
    }
    // Corners within this of an ear's sides count as on them (so an ear never takes a corner lying
    // on its third side, which would leave a zero-area triangle behind).
    let size = flat
        .iter()
        .fold(0.0f64, |m, q| m.max(q[0].abs()).max(q[1].abs()));
    let eps = 1e-10 * size * size;
    let mut left: Vec<usize> = (0..n).collect();
    while left.len() > 3 {
        let m = left.len();
        let is_ear = |i: usize| {
            let (a, b, c) = (left[(i + m - 1) % m], left[i], left[(i + 1) % m]);
            if cross(flat[a], flat[b], flat[c]) <= eps {
                return false;
            }
            left.iter().all(|&q| {
                q == a
                    || q == b
                    || q == c
                    || !(cross(flat[a], flat[b], flat[q]) >= -eps
                        && cross(flat[b], flat[c], flat[q]) >= -eps
                        && cross(flat[c], flat[a], flat[q]) >= -eps)
            })
        };
        // No ear (a self-intersecting polygon): cut the most convex corner anyway.
        let i = (0..m).find(|&i| is_ear(i)).unwrap_or_else(|| {
            (0..m)
                .max_by(|&i, &j| {
                    let turn = |i: usize| {
                        cross(
                            flat[left[(i + m - 1) % m]],
                            flat[left[i]],
                            flat[left[(i + 1) % m]],
                        )
                    };
                    turn(i).total_cmp(&turn(j))
                })
                .unwrap_or(0)
        });
        let (a, b, c) = (left[(i + m - 1) % m], left[i], left[(i + 1) % m]);
        out.push([poly[a], poly[b], poly[c]]);
        left.remove(i);
    }
    out.push([poly[left[0]], poly[left[1]], poly[left[2]]]);
}
