//! Splitting a closed triangle mesh's long edges at their midpoints, longest first, until none is
//! longer than a limit. The surface (the piecewise-linear one the triangles make) does not move:
//! each new vertex lies on the edge it splits, and each split replaces the edge's two triangles by
//! four that tile them.
//!
//! Why: a fit through a mesh's vertices sees only its vertices. CAD tessellations put vertices on
//! the sharp edges alone and span each flat or ruled face with needles (a gear's tooth walls are
//! single triangles from the top rim to the bottom one), so nothing tells the fit where the surface
//! is between the rims, and it can bulge there freely. Split edges sample those faces as densely
//! as the rest of the mesh.
//!
//! Longest-edge bisection never makes a triangle's smallest angle much smaller than the worst
//! the mesh had (Rivara), so needles turn into strips of ordinary triangles.

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

type Point = [f64; 3];

/// What [`split_long_edges`] made.
#[derive(Clone, Debug, PartialEq)]
pub struct Refined {
    /// The mesh's vertices, then the new ones (each the midpoint of the edge it split).
    pub positions: Vec<Point>,
    pub triangles: Vec<[u32; 3]>,
    /// Vertices added (one per split).
    pub added: usize,
    /// Whether an edge longer than the limit is left because `max_vertices` was reached.
    pub capped: bool,
}

/// An edge waiting to be split, ordered by length (then by its vertices, so the order is the same
/// on every run).
#[derive(PartialEq)]
struct Long {
    length: f64,
    edge: (u32, u32),
}

impl Eq for Long {}

impl Ord for Long {
    fn cmp(&self, other: &Self) -> Ordering {
        self.length
            .total_cmp(&other.length)
            .then_with(|| other.edge.cmp(&self.edge))
    }
}

impl PartialOrd for Long {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Splits every edge of the closed, consistently oriented manifold mesh (`positions`,
/// `triangles`) that is longer than `limit`, the longest first, until none is or the mesh has
/// `max_vertices` vertices. An edge with a single triangle (a boundary) is left alone.
pub fn split_long_edges(
    positions: &[Point],
    triangles: &[[u32; 3]],
    limit: f64,
    max_vertices: usize,
) -> Refined {
    let mut positions = positions.to_vec();
    let mut triangles = triangles.to_vec();
    // Each directed edge's triangle: a closed oriented mesh has each edge once in either direction.
    let mut owner: HashMap<(u32, u32), u32> = HashMap::with_capacity(3 * triangles.len());
    let mut queue = BinaryHeap::new();
    let length = |p: &[Point], a: u32, b: u32| distance(p[a as usize], p[b as usize]);
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            owner.insert((a, b), t as u32);
            let l = length(&positions, a, b);
            if a < b && l > limit {
                queue.push(Long {
                    length: l,
                    edge: (a, b),
                });
            }
        }
    }
    let original = positions.len();
    let mut capped = false;
    while let Some(Long { edge: (a, b), .. }) = queue.pop() {
        // An edge split already is gone (its pair never comes back: new edges end at new vertices).
        let (Some(&t1), Some(&t2)) = (owner.get(&(a, b)), owner.get(&(b, a))) else {
            continue;
        };
        if positions.len() >= max_vertices {
            capped = true;
            break;
        }
        let m = positions.len() as u32;
        positions.push(midpoint(positions[a as usize], positions[b as usize]));
        let c = third(triangles[t1 as usize], a, b);
        let d = third(triangles[t2 as usize], b, a);
        // (a, b, c) → (a, m, c), (m, b, c); (b, a, d) → (b, m, d), (m, a, d).
        let (t3, t4) = (triangles.len() as u32, triangles.len() as u32 + 1);
        triangles[t1 as usize] = [a, m, c];
        triangles[t2 as usize] = [b, m, d];
        triangles.push([m, b, c]);
        triangles.push([m, a, d]);
        owner.remove(&(a, b));
        owner.remove(&(b, a));
        for (edge, t) in [
            ((a, m), t1),
            ((m, c), t1),
            ((m, b), t3),
            ((b, c), t3),
            ((c, m), t3),
            ((b, m), t2),
            ((m, d), t2),
            ((m, a), t4),
            ((a, d), t4),
            ((d, m), t4),
        ] {
            owner.insert(edge, t);
        }
        for other in [a, b, c, d] {
            let l = length(&positions, m, other);
            if l > limit {
                queue.push(Long {
                    length: l,
                    edge: (m.min(other), m.max(other)),
                });
            }
        }
    }
    Refined {
        added: positions.len() - original,
        positions,
        triangles,
        capped,
    }
}

/// The corner of `triangle` that is neither `a` nor `b`, where `a → b` is one of its edges.
fn third(triangle: [u32; 3], a: u32, b: u32) -> u32 {
    let k = triangle
        .iter()
        .position(|&v| v == a)
        .expect("the edge's triangle holds its first vertex");
    debug_assert_eq!(triangle[(k + 1) % 3], b);
    triangle[(k + 2) % 3]
}

fn midpoint(p: Point, q: Point) -> Point {
    [0, 1, 2].map(|k| 0.5 * (p[k] + q[k]))
}

fn distance(p: Point, q: Point) -> f64 {
    (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HalfEdgeMesh;
    use proptest::prelude::*;

    /// A box [0, sx] × [0, sy] × [0, sz] with two triangles per face, outward.
    fn boxed(size: Point) -> (Vec<Point>, Vec<[u32; 3]>) {
        let positions = (0..8)
            .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 1 { size[k] } else { 0.0 }))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (positions, triangles)
    }

    fn area_vector(positions: &[Point], triangles: &[[u32; 3]]) -> (f64, Point) {
        let mut total = 0.0;
        let mut moment = [0.0; 3];
        for t in triangles {
            let [p, q, r] = t.map(|v| positions[v as usize]);
            let u = [0, 1, 2].map(|k| q[k] - p[k]);
            let v = [0, 1, 2].map(|k| r[k] - p[k]);
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            total += 0.5 * distance(n, [0.0; 3]);
            // The divergence theorem: Σ (centroid · n) / 6 is the enclosed volume; per axis it is
            // sensitive to any triangle that leaves the surface or turns over.
            for k in 0..3 {
                moment[k] += (p[k] + q[k] + r[k]) / 3.0 * n[k] / 2.0;
            }
        }
        (total, moment)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Whatever the box's proportions and the limit, the split mesh is closed, oriented and of
        /// genus 0, covers the same area and volume (no triangle left the surface or turned
        /// over), has no edge longer than the limit, and its new vertices lie on the box.
        #[test]
        fn split_edges_keep_the_surface_and_meet_the_limit(
            sx in 0.05f64..3.0, sy in 0.05f64..3.0, sz in 0.05f64..3.0, fraction in 0.05f64..1.0
        ) {
            let (positions, triangles) = boxed([sx, sy, sz]);
            let longest = (sx * sx + sy * sy).max(sy * sy + sz * sz).max(sx * sx + sz * sz).sqrt();
            let limit = fraction * longest;
            let refined = split_long_edges(&positions, &triangles, limit, 1_000_000);
            prop_assert!(!refined.capped);
            prop_assert_eq!(refined.positions.len(), 8 + refined.added);
            prop_assert_eq!(refined.triangles.len(), 12 + 2 * refined.added);
            let mesh = HalfEdgeMesh::from_polygons(
                refined.positions.len(),
                refined.triangles.iter().map(|t| &t[..]),
            ).unwrap();
            let topology = mesh.topology();
            prop_assert!(topology.closed && topology.manifold && topology.orientable);
            prop_assert_eq!(topology.misoriented_edges, 0);
            prop_assert_eq!(topology.genus, Some(0));
            for t in &refined.triangles {
                for k in 0..3 {
                    let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
                    prop_assert!(distance(refined.positions[a], refined.positions[b]) <= limit);
                }
            }
            let (area, moment) = area_vector(&refined.positions, &refined.triangles);
            let (area0, moment0) = area_vector(&positions, &triangles);
            prop_assert!((area - area0).abs() <= 1e-9 * area0);
            for k in 0..3 {
                prop_assert!((moment[k] - moment0[k]).abs() <= 1e-9 * area0 * longest);
            }
            for p in &refined.positions {
                let on_a_face = (0..3).any(|k| p[k].abs() < 1e-12 || (p[k] - [sx, sy, sz][k]).abs() < 1e-12);
                prop_assert!(on_a_face);
            }
        }
    }

    #[test]
    fn a_mesh_with_no_long_edge_is_returned_as_it_is() {
        let (positions, triangles) = boxed([1.0, 1.0, 1.0]);
        let refined = split_long_edges(&positions, &triangles, 2.0, 100);
        assert_eq!(refined.added, 0);
        assert_eq!(refined.positions, positions);
        assert_eq!(refined.triangles, triangles);
    }

    #[test]
    fn the_vertex_cap_stops_the_splitting_and_says_so() {
        let (positions, triangles) = boxed([1.0, 1.0, 1.0]);
        let refined = split_long_edges(&positions, &triangles, 0.01, 50);
        assert!(refined.capped);
        assert_eq!(refined.positions.len(), 50);
    }
}
