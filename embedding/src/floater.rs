//! Floater's mean value parameterization: a triangulated disk in R³ mapped into the plane with its
//! boundary pinned to given positions. Every interior vertex becomes the weighted average of its
//! neighbours, with the mean value weights w_ij = (tan(α/2) + tan(β/2)) / |p_j − p_i| (α, β the angles
//! at p_i on either side of the edge ij). The weights are positive, so for a convex boundary the map
//! is a bijection (Floater 2003) — the fundamental polygon is convex in the Klein model, not in the
//! Poincaré disk, so that is where the initial fit flattens its mesh. Planar meshes are reproduced
//! exactly (linear precision).

use faer::prelude::*;
use faer::sparse::{SparseColMat, Triplet};

use crate::EmbeddingError;
use crate::surface::Point3;

/// Positions in the plane of every vertex: `boundary` gives the pinned ones (vertex, position); the
/// rest are solved for. Vertices must all be reachable from the boundary through the triangles.
pub fn parameterize(
    positions: &[Point3],
    triangles: &[[u32; 3]],
    boundary: &[(u32, [f64; 2])],
) -> Result<Vec<[f64; 2]>, EmbeddingError> {
    solve_pinned(&mean_value_weights(positions, triangles)?, boundary)
}

/// [`parameterize`] with the weights given: `weights[v]` lists v's neighbours with positive weights
/// (not necessarily symmetric). Every free vertex becomes the weighted mean of its neighbours, so
/// with a convex boundary the map is still a bijection (Floater's theorem asks only for positive
/// weights): what lets a reweighted map keep that guarantee.
pub fn solve_pinned(
    weights: &[Vec<(u32, f64)>],
    boundary: &[(u32, [f64; 2])],
) -> Result<Vec<[f64; 2]>, EmbeddingError> {
    let n = weights.len();
    if boundary.is_empty() {
        return Err(EmbeddingError::Parameterization(
            "no boundary vertices were given".into(),
        ));
    }
    let mut pinned: Vec<Option<[f64; 2]>> = vec![None; n];
    for &(v, uv) in boundary {
        let slot = pinned.get_mut(v as usize).ok_or_else(|| {
            EmbeddingError::Parameterization(format!("boundary vertex {v} does not exist"))
        })?;
        *slot = Some(uv);
    }
    // Unknowns: the interior vertices, numbered densely.
    let mut unknown = vec![u32::MAX; n];
    let mut interior = Vec::new();
    for v in 0..n {
        if pinned[v].is_none() {
            unknown[v] = interior.len() as u32;
            interior.push(v);
        }
    }
    let m = interior.len();
    let mut triplets = Vec::new();
    let mut rhs = Mat::<f64>::zeros(m, 2);
    for (row, &v) in interior.iter().enumerate() {
        let mut diagonal = 0.0;
        for &(j, w) in &weights[v] {
            diagonal += w;
            match pinned[j as usize] {
                Some(uv) => {
                    rhs[(row, 0)] += w * uv[0];
                    rhs[(row, 1)] += w * uv[1];
                }
                None => triplets.push(Triplet::new(row, unknown[j as usize] as usize, -w)),
            }
        }
        if diagonal == 0.0 {
            return Err(EmbeddingError::Parameterization(format!(
                "vertex {v} belongs to no triangle"
            )));
        }
        triplets.push(Triplet::new(row, row, diagonal));
    }
    let mut out: Vec<[f64; 2]> = pinned.iter().map(|p| p.unwrap_or([0.0; 2])).collect();
    if m > 0 {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &triplets)
            .map_err(|e| EmbeddingError::Parameterization(format!("{e:?}")))?;
        let lu = a.sp_lu().map_err(|e| {
            EmbeddingError::Parameterization(format!(
                "the system is singular ({e:?}): is every vertex connected to the boundary?"
            ))
        })?;
        let x = lu.solve(&rhs);
        for (row, &v) in interior.iter().enumerate() {
            out[v] = [x[(row, 0)], x[(row, 1)]];
        }
        if out.iter().flatten().any(|c| !c.is_finite()) {
            return Err(EmbeddingError::Parameterization(
                "the solve produced non-finite positions: is every vertex connected to the boundary?".into(),
            ));
        }
    }
    Ok(out)
}

/// For each vertex, its neighbours with their (unnormalised) mean value weights.
pub fn mean_value_weights(
    positions: &[Point3],
    triangles: &[[u32; 3]],
) -> Result<Vec<Vec<(u32, f64)>>, EmbeddingError> {
    let mut weights: Vec<Vec<(u32, f64)>> = vec![Vec::new(); positions.len()];
    let mut add = |i: u32, j: u32, w: f64| {
        let list = &mut weights[i as usize];
        match list.iter_mut().find(|e| e.0 == j) {
            Some(e) => e.1 += w,
            None => list.push((j, w)),
        }
    };
    for (t, tri) in triangles.iter().enumerate() {
        if tri.iter().any(|&v| v as usize >= positions.len()) {
            return Err(EmbeddingError::Parameterization(format!(
                "triangle {t} refers to a missing vertex"
            )));
        }
        for k in 0..3 {
            let (i, j, l) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let (pi, pj, pl) = (
                positions[i as usize],
                positions[j as usize],
                positions[l as usize],
            );
            let (a, b) = (pj - pi, pl - pi);
            let (la, lb) = (a.norm(), b.norm());
            if la == 0.0 || lb == 0.0 {
                return Err(EmbeddingError::Parameterization(format!(
                    "triangle {t} is degenerate"
                )));
            }
            // tan(θ/2) = |a × b| / (|a||b| + a·b), stable for small and obtuse angles alike.
            let half = a.cross(&b).norm() / (la * lb + a.dot(&b));
            add(i, j, half / la);
            add(i, l, half / lb);
        }
    }
    Ok(weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A polar grid on the unit disk (rings × sectors), lifted by `height`; boundary = outer ring.
    fn disk(
        rings: usize,
        sectors: usize,
        height: impl Fn(f64, f64) -> f64,
    ) -> (Vec<Point3>, Vec<[u32; 3]>, Vec<u32>) {
        let mut pos = vec![Point3::new(0.0, 0.0, height(0.0, 0.0))];
        for r in 1..=rings {
            for s in 0..sectors {
                let (rad, t) = (
                    r as f64 / rings as f64,
                    std::f64::consts::TAU * (s as f64 + 0.3 * r as f64) / sectors as f64,
                );
                let (x, y) = (rad * t.cos(), rad * t.sin());
                pos.push(Point3::new(x, y, height(x, y)));
            }
        }
        let id = |r: usize, s: usize| {
            if r == 0 {
                0
            } else {
                (1 + (r - 1) * sectors + s % sectors) as u32
            }
        };
        let mut tris = Vec::new();
        for s in 0..sectors {
            tris.push([0, id(1, s), id(1, s + 1)]);
        }
        for r in 1..rings {
            for s in 0..sectors {
                tris.push([id(r, s), id(r + 1, s), id(r + 1, s + 1)]);
                tris.push([id(r, s), id(r + 1, s + 1), id(r, s + 1)]);
            }
        }
        let boundary = (0..sectors).map(|s| id(rings, s)).collect();
        (pos, tris, boundary)
    }

    fn signed_area(p: &[[f64; 2]], t: &[u32; 3]) -> f64 {
        let (a, b, c) = (p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]);
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }

    #[test]
    fn planar_meshes_are_reproduced_exactly() {
        let (pos, tris, boundary) = disk(6, 17, |_, _| 0.0);
        let pins: Vec<(u32, [f64; 2])> = boundary
            .iter()
            .map(|&v| (v, [pos[v as usize].x, pos[v as usize].y]))
            .collect();
        let uv = parameterize(&pos, &tris, &pins).unwrap();
        for (p, q) in pos.iter().zip(&uv) {
            assert!((p.x - q[0]).abs() < 1e-12 && (p.y - q[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn a_curved_disk_onto_a_convex_polygon_flips_nothing() {
        // A bumpy cap, its boundary spread over a regular octagon (a convex boundary).
        let (pos, tris, boundary) = disk(12, 40, |x, y| {
            (1.0 - x * x - y * y).max(0.0).sqrt() + 0.3 * (5.0 * x).sin() * y
        });
        let corner = |k: usize| {
            let t = std::f64::consts::TAU * k as f64 / 8.0;
            [t.cos(), t.sin()]
        };
        let pins: Vec<(u32, [f64; 2])> = boundary
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                let f = i as f64 * 8.0 / boundary.len() as f64;
                let (k, s) = (f.floor() as usize, f.fract());
                let (a, b) = (corner(k), corner(k + 1));
                (v, [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])])
            })
            .collect();
        let uv = parameterize(&pos, &tris, &pins).unwrap();
        let smallest = tris
            .iter()
            .map(|t| signed_area(&uv, t))
            .fold(f64::INFINITY, f64::min);
        assert!(
            smallest > 0.0,
            "a triangle flipped or collapsed: {smallest:e}"
        );
    }

    #[test]
    fn bad_input_is_an_error() {
        let (pos, tris, _) = disk(3, 8, |_, _| 0.0);
        assert!(parameterize(&pos, &tris, &[]).is_err());
        assert!(parameterize(&pos, &tris, &[(999, [0.0, 0.0])]).is_err());
        // A vertex no triangle uses cannot be placed.
        let mut lonely = pos.clone();
        lonely.push(Point3::new(5.0, 5.0, 0.0));
        let pins: Vec<(u32, [f64; 2])> = (17..25).map(|v| (v, [0.0, 0.0])).collect();
        assert!(parameterize(&lonely, &tris, &pins).is_err());
    }
}
