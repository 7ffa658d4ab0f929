//! How well shaped a triangle mesh is, as simulation, remeshing and shading see it: the triangles'
//! angles and the bend between neighbouring triangles.
//!
//! Plain data in, plain data out, like [`crate::spatial`]: positions `&[[f64; 3]]`, triangles
//! `&[[u32; 3]]`, validated first.

use std::collections::HashMap;

use crate::spatial::{SpatialError, validate};

/// Angle statistics of a triangle mesh, in degrees.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeshShape {
    pub triangles: usize,
    /// The smallest and largest angle of any triangle.
    pub smallest_angle: f64,
    pub largest_angle: f64,
    /// Triangles with an angle below 20°.
    pub below_20: usize,
    /// Triangles with an angle of 150° or more.
    pub above_150: usize,
    /// The largest angle between the normals of two triangles sharing an edge (0 for a flat
    /// mesh; a crease or a fold shows as a large one).
    pub largest_bend: f64,
}

impl MeshShape {
    /// The fraction of triangles whose every angle is at least 20°.
    pub fn well_shaped(&self) -> f64 {
        if self.triangles == 0 {
            return 1.0;
        }
        1.0 - self.below_20 as f64 / self.triangles as f64
    }
}

/// The angles of every triangle and the bend across every edge shared by two triangles (edges
/// met by one triangle or by more than two are skipped: they have no single bend).
pub fn mesh_shape(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<MeshShape, SpatialError> {
    validate(positions, triangles)?;
    let mut shape = MeshShape {
        triangles: triangles.len(),
        smallest_angle: 180.0,
        largest_angle: 0.0,
        below_20: 0,
        above_150: 0,
        largest_bend: 0.0,
    };
    let mut normals = Vec::with_capacity(triangles.len());
    for t in triangles {
        let p = t.map(|i| positions[i as usize]);
        let angles = [0, 1, 2].map(|k| angle(p[k], p[(k + 1) % 3], p[(k + 2) % 3]));
        let (lo, hi) = angles
            .iter()
            .fold((180.0f64, 0.0f64), |(lo, hi), &a| (lo.min(a), hi.max(a)));
        shape.smallest_angle = shape.smallest_angle.min(lo);
        shape.largest_angle = shape.largest_angle.max(hi);
        shape.below_20 += usize::from(lo < 20.0);
        shape.above_150 += usize::from(hi >= 150.0);
        normals.push(unit(cross(sub(p[1], p[0]), sub(p[2], p[0]))));
    }
    let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::with_capacity(triangles.len() * 2);
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push(t);
        }
    }
    for faces in edges.values() {
        if let [s, t] = faces[..] {
            let c = dot(normals[s], normals[t]).clamp(-1.0, 1.0);
            shape.largest_bend = shape.largest_bend.max(c.acos().to_degrees());
        }
    }
    Ok(shape)
}

/// The angle at `o` of triangle (o, p, q), in degrees (0 for a degenerate corner).
fn angle(o: [f64; 3], p: [f64; 3], q: [f64; 3]) -> f64 {
    let (u, v) = (sub(p, o), sub(q, o));
    let (nu, nv) = (dot(u, u).sqrt(), dot(v, v).sqrt());
    if nu == 0.0 || nv == 0.0 {
        return 0.0;
    }
    // atan2 of |u × v| and u · v: accurate for angles near 0 and 180° too.
    let c = cross(u, v);
    dot(c, c).sqrt().atan2(dot(u, v)).to_degrees()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n == 0.0 {
        return [0.0; 3];
    }
    a.map(|x| x / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tetrahedron_has_sixty_degree_angles_and_its_dihedral_bend() {
        let s = 1.0 / 2f64.sqrt();
        let p = [
            [1.0, 0.0, -s],
            [-1.0, 0.0, -s],
            [0.0, 1.0, s],
            [0.0, -1.0, s],
        ];
        let t = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        let shape = mesh_shape(&p, &t).unwrap();
        assert!((shape.smallest_angle - 60.0).abs() < 1e-9);
        assert!((shape.largest_angle - 60.0).abs() < 1e-9);
        assert_eq!((shape.below_20, shape.above_150), (0, 0));
        // The regular tetrahedron's faces meet at acos(1/3); their normals at 180° minus that.
        let bend = 180.0 - (1.0f64 / 3.0).acos().to_degrees();
        assert!(
            (shape.largest_bend - bend).abs() < 1e-9,
            "{}",
            shape.largest_bend
        );
        assert_eq!(shape.well_shaped(), 1.0);
    }

    #[test]
    fn a_sliver_and_a_flat_pair_are_counted() {
        // Two triangles in the plane z = 0 sharing edge 0–1: one fine, one a 170° sliver.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 0.8, 0.0],
            [0.5, -0.04, 0.0],
        ];
        let t = [[0, 1, 2], [1, 0, 3]];
        let shape = mesh_shape(&p, &t).unwrap();
        assert_eq!((shape.below_20, shape.above_150), (1, 1));
        assert!(shape.largest_bend < 1e-9);
        assert!(shape.largest_angle > 170.0);
        assert_eq!(shape.well_shaped(), 0.5);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(mesh_shape(&[[0.0; 3]], &[[0, 1, 2]]).is_err());
    }
}
