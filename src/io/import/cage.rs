//! A Catmull–Clark control cage read as its limit surface (`ntori fit --cage`): the cage's
//! polygons, checked as a closed oriented manifold, are refined uniformly by OpenSubdiv (the
//! `anchors` crate) and every vertex of the finest level is moved onto the limit surface, with the
//! limit normal there. The result is a dense quad mesh on the surface the cage stands for, split
//! into triangles, which the fit then takes like any other mesh, with the limit normals as the
//! intended shape's.

use embedding::fit::MAX_FIT_TRIANGLES;
use embedding::{Point3, Vector3};

use super::{ImportError, ImportedMesh, Polygons, ValidMesh};

/// The triangles the finest level should reach (the fewest levels that do, from 2): enough that
/// the fit sees the limit surface, not the cage, and no more than a fit of `new`'s plates takes.
pub const CAGE_TRIANGLES: usize = 12_000;
/// The most levels of refinement.
pub const MAX_CAGE_LEVEL: u32 = 6;

/// A cage's limit surface as a mesh.
#[derive(Clone, Debug)]
pub struct LimitSurface {
    /// Triangles (each refined quad cut along its shorter diagonal), outward.
    pub mesh: ImportedMesh,
    /// The limit surface's unit outward normal at each vertex.
    pub normals: Vec<Vector3>,
    /// The cage's faces, and how many of them are not quads.
    pub cage_faces: usize,
    pub cage_non_quads: usize,
    /// Levels of uniform refinement.
    pub level: u32,
    /// Whether the cage was inside out (its faces were then turned), and how many of its vertices
    /// no face uses (left out).
    pub flipped: bool,
    pub unused_vertices: usize,
}

/// The limit surface of `cage`, whose triangulation passed validation as `valid` (closed, one
/// manifold component, orientable). `level` is how many times to refine (1 to 6), or `None` for
/// the fewest levels from 2 that reach [`CAGE_TRIANGLES`].
pub fn limit_surface(
    cage: &ImportedMesh,
    valid: &ValidMesh,
    level: Option<u32>,
) -> Result<LimitSurface, ImportError> {
    if valid.reoriented_triangles > 0 {
        return Err(ImportError::CageOrientation {
            triangles: valid.reoriented_triangles,
        });
    }
    // Polygons as a reader made them add up; a hand-made `ImportedMesh` might not.
    let total: usize = cage.polygons.sides.iter().map(|&s| s as usize).sum();
    let n = cage.positions.len();
    if total != cage.polygons.corners.len()
        || cage.polygons.corners.iter().any(|&c| c as usize >= n)
    {
        return Err(ImportError::Subdivision(anchors::Error::Failed(
            "read the cage's polygons (corner counts or indices out of range)",
        )));
    }
    // The cage's faces, outward, over the vertices they use (the unused are left out, as OpenSubdiv
    // would give them no limit point).
    let mut polygons = cage.polygons.clone();
    if valid.flipped {
        let mut start = 0;
        for &s in &polygons.sides {
            polygons.corners[start..start + s as usize].reverse();
            start += s as usize;
        }
    }
    let (positions, corners) = used_vertices(&cage.positions, &polygons);
    let corner_count: usize = polygons.sides.iter().map(|&s| s as usize).sum();
    let level = level.unwrap_or_else(|| default_level(corner_count));
    if !(1..=MAX_CAGE_LEVEL).contains(&level)
        || triangles_at(corner_count, level) > MAX_FIT_TRIANGLES
    {
        return Err(ImportError::CageTooFine {
            level,
            triangles: triangles_at(corner_count, level),
            max: MAX_FIT_TRIANGLES,
        });
    }
    let unused_vertices = cage.positions.len() - positions.len();
    let refiner = anchors::Refiner::from_polygons(positions.len(), &polygons.sides, &corners)
        .map_err(ImportError::Subdivision)?;
    let base: Vec<[f64; 3]> = positions.iter().map(|p| [p.x, p.y, p.z]).collect();
    let limit = refiner
        .limit_mesh(level, &base)
        .map_err(ImportError::Subdivision)?;
    let positions: Vec<Point3> = limit.positions.iter().map(|&p| Point3::from(p)).collect();
    let normals = limit
        .normals
        .iter()
        .map(|&n| {
            Vector3::from(n)
                .try_normalize(0.0)
                .unwrap_or_else(Vector3::zeros)
        })
        .collect();
    let triangles = limit
        .faces
        .iter()
        .flat_map(|q| split_quad(&positions, *q))
        .collect();
    Ok(LimitSurface {
        mesh: ImportedMesh {
            positions,
            triangles,
            ..ImportedMesh::default()
        },
        normals,
        cage_faces: polygons.sides.len(),
        cage_non_quads: polygons.sides.iter().filter(|&&s| s != 4).count(),
        flipped: valid.flipped,
        unused_vertices,
        level,
    })
}

/// Triangles after `level` levels: after the first every face is a quad, one per corner of the
/// cage, then each level makes four of each; each quad is cut in two.
fn triangles_at(corners: usize, level: u32) -> usize {
    let per_corner = 1usize << (2 * level.clamp(1, 16) - 2);
    corners.saturating_mul(per_corner).saturating_mul(2)
}

/// The most triangles a cage's default level makes, for time: `new`'s plates' budget as it was
/// (`embedding::fit::DEFAULT_FIT_TRIANGLES`, now 300 000 for the high-genus plates, whose
/// curvature follows their rims' sampling; a user's cage was not measured at more).
const CAGE_FIT_TRIANGLES: usize = 200_000;

/// The fewest levels from 2 that make [`CAGE_TRIANGLES`], or, for a cage so fine that this is
/// more than a default fit takes ([`CAGE_FIT_TRIANGLES`], for time), the most within it (down
/// to 1; `--cage-level` may go up to [`MAX_FIT_TRIANGLES`]).
fn default_level(corners: usize) -> u32 {
    let wanted = (2..MAX_CAGE_LEVEL)
        .find(|&l| triangles_at(corners, l) >= CAGE_TRIANGLES)
        .unwrap_or(MAX_CAGE_LEVEL);
    (1..=wanted)
        .rev()
        .find(|&l| triangles_at(corners, l) <= CAGE_FIT_TRIANGLES)
        .unwrap_or(1)
}

/// The positions the polygons use, in their order, and the corners renumbered over them.
fn used_vertices(positions: &[Point3], polygons: &Polygons) -> (Vec<Point3>, Vec<u32>) {
    let mut index = vec![u32::MAX; positions.len()];
    let mut used = Vec::new();
    let corners = polygons
        .corners
        .iter()
        .map(|&c| {
            if index[c as usize] == u32::MAX {
                index[c as usize] = used.len() as u32;
                used.push(positions[c as usize]);
            }
            index[c as usize]
        })
        .collect();
    (used, corners)
}

/// A quad's two triangles, cut along its shorter diagonal (the better-shaped pair).
fn split_quad(positions: &[Point3], q: [u32; 4]) -> [[u32; 3]; 2] {
    let d = |a: u32, b: u32| (positions[a as usize] - positions[b as usize]).norm_squared();
    if d(q[0], q[2]) <= d(q[1], q[3]) {
        [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    } else {
        [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_level_reaches_the_target_within_the_fit() {
        // The slab cage's 200 corners: 6 400 triangles at 3, 25 600 at 4.
        assert_eq!(triangles_at(200, 3), 6_400);
        assert_eq!(default_level(200), 4);
        // A cage of 8 000 quads (32 000 corners): 256 000 triangles at 2 are more than a default
        // fit takes, 64 000 at 1 are not.
        assert_eq!(default_level(32_000), 1);
        // A tetrahedron's 12 corners: 12 · 4⁵ · 2 = 24 576 triangles at 6 (the most levels).
        assert_eq!(default_level(12), 6);
        assert_eq!(triangles_at(usize::MAX, 6), usize::MAX);
    }
}
