//! Tests of `mesh::spatial`: self-intersections by what triangles share (hand-made pairs, closed
//! meshes, meshes broken on purpose, and property tests against an independent separating-axis test),
//! degenerate triangles, input errors, and the sampled Hausdorff distance against a brute-force
//! reference.

use std::collections::HashMap;

use mesh::spatial::{
    MeshRef, SpatialError, bounding_box_diagonal, closest_point_on_triangle, degenerate_triangles,
    hausdorff, self_intersections,
};
use proptest::prelude::*;

type P = [f64; 3];
type Mesh = (Vec<P>, Vec<[u32; 3]>);

// ---------------------------------------------------------------------------------------------------
// Fixtures
// ---------------------------------------------------------------------------------------------------

fn octahedron() -> Mesh {
    let positions = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let triangles = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    (positions, triangles)
}

fn normalize(p: P) -> P {
    let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    p.map(|x| x / n)
}

/// The icosahedron, each triangle split in four `levels` times, vertices pushed onto the unit sphere.
fn icosphere(levels: u32) -> Mesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut positions: Vec<P> = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ]
    .map(normalize)
    .to_vec();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<P>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                positions.push(normalize([0, 1, 2].map(|k| p[k] + q[k])));
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(4 * triangles.len());
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    (positions, triangles)
}

/// The surface of the cube [−1, 1]³, each face an n × n grid of squares cut in two.
fn cube(n: u32) -> Mesh {
    let mut index: HashMap<[i64; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let n = i64::from(n);
    for axis in 0..3 {
        for side in [-1i64, 1] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut vertex = |i: i64, j: i64| {
                let mut g = [0i64; 3];
                g[axis] = side * n;
                g[u] = 2 * i - n;
                g[v] = 2 * j - n;
                *index.entry(g).or_insert_with(|| {
                    positions.push(g.map(|x| x as f64 / n as f64));
                    positions.len() as u32 - 1
                })
            };
            for i in 0..n {
                for j in 0..n {
                    let q = [
                        vertex(i, j),
                        vertex(i + 1, j),
                        vertex(i + 1, j + 1),
                        vertex(i, j + 1),
                    ];
                    // Outward orientation is irrelevant here; keep the two sides consistent anyway.
                    if side > 0 {
                        triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
                    } else {
                        triangles.extend([[q[0], q[2], q[1]], [q[0], q[3], q[2]]]);
                    }
                }
            }
        }
    }
    (positions, triangles)
}

/// A torus of radii 2 and 0.7, an n × m grid of squares cut in two.
fn torus(n: u32, m: u32) -> Mesh {
    let tau = std::f64::consts::TAU;
    let mut positions = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (a, b) = (
                tau * f64::from(i) / f64::from(n),
                tau * f64::from(j) / f64::from(m),
            );
            let r = 2.0 + 0.7 * b.cos();
            positions.push([r * a.cos(), r * a.sin(), 0.7 * b.sin()]);
        }
    }
    let id = |i: u32, j: u32| (i % n) * m + (j % m);
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    (positions, triangles)
}

fn intersections(positions: &[P], triangles: &[[u32; 3]]) -> Vec<(usize, usize)> {
    self_intersections(positions, triangles).unwrap()
}

// ---------------------------------------------------------------------------------------------------
// Hand-made pairs
// ---------------------------------------------------------------------------------------------------

const BASE: [P; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// BASE as triangle 0 (vertices 0, 1, 2) and the given corners as triangle 1 (vertices 3, 4, 5).
fn base_and(other: [P; 3]) -> Vec<(usize, usize)> {
    let positions: Vec<P> = BASE.iter().chain(other.iter()).copied().collect();
    intersections(&positions, &[[0, 1, 2], [3, 4, 5]])
}

#[test]
fn disjoint_triangles_do_not_intersect() {
    assert!(base_and(BASE.map(|[x, y, z]| [x, y, z + 1.0])).is_empty());
    // Parallel and just off the plane: exact predicates see the gap.
    assert!(base_and(BASE.map(|[x, y, z]| [x, y, z + 1e-100])).is_empty());
    // Coplanar, beside each other.
    assert!(base_and(BASE.map(|[x, y, z]| [x + 1.5, y, z])).is_empty());
}

#[test]
fn crossing_triangles_are_one_pair() {
    let other = [[0.2, 0.2, -1.0], [0.2, 0.2, 1.0], [3.0, 3.0, 0.0]];
    assert_eq!(base_and(other), vec![(0, 1)]);
}

#[test]
fn a_point_contact_without_a_shared_index_counts() {
    // A corner of the second triangle on the inside of the first.
    assert_eq!(
        base_and([[0.25, 0.25, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]]),
        vec![(0, 1)]
    );
    // A corner at the same position as a corner of the first, under another index.
    assert_eq!(
        base_and([[1.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 0.0, 1.0]]),
        vec![(0, 1)]
    );
    // Edge touching edge at one point: the second triangle lies in the plane x = 0.5 and meets
    // z = 0 in a segment ending at (0.5, 0, 0) on the first triangle's edge.
    assert_eq!(
        base_and([[0.5, -1.0, 1.0], [0.5, 1.0, -1.0], [0.5, -1.0, -1.0]]),
        vec![(0, 1)]
    );
    // Coplanar, corner to corner.
    assert_eq!(
        base_and([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]]),
        vec![(0, 1)]
    );
}

/// Two triangles over the edge 0–1 of BASE: (0, 1, 2) and (1, 0, 3) with vertex 3 at `b`.
fn edge_pair(b: P) -> Vec<(usize, usize)> {
    let positions = [BASE[0], BASE[1], BASE[2], b];
    intersections(&positions, &[[0, 1, 2], [1, 0, 3]])
}

#[test]
fn a_shared_edge_may_only_be_met_along_itself() {
    // Folded flat onto each other: found.
    assert_eq!(edge_pair([0.6, 0.5, 0.0]), vec![(0, 1)]);
    assert_eq!(edge_pair([0.0, 1.0, 0.0]), vec![(0, 1)]);
    // An ordinary dihedral angle, even a very sharp one, and the flat unfolded pair: fine.
    assert!(edge_pair([0.5, 0.5, 0.5]).is_empty());
    assert!(edge_pair([0.5, 1.0, 1e-12]).is_empty());
    assert!(edge_pair([0.6, -0.5, 0.0]).is_empty());
}

/// BASE scaled by 2 as (0, 1, 2) and (0, 3, 4): they share vertex 0 at the origin.
fn vertex_pair(b1: P, b2: P) -> Vec<(usize, usize)> {
    let positions = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], b1, b2];
    intersections(&positions, &[[0, 1, 2], [0, 3, 4]])
}

#[test]
fn a_shared_vertex_may_only_be_met_at_itself() {
    // Meeting only at the vertex: fine, also when an edge lies in the other's plane pointing away.
    assert!(vertex_pair([-1.0, 0.0, 1.0], [0.0, -1.0, 1.0]).is_empty());
    assert!(vertex_pair([-1.0, 0.0, 0.0], [0.0, -1.0, 1.0]).is_empty());
    assert!(vertex_pair([-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]).is_empty());
    // Crossing the other through a segment from the shared vertex: found.
    assert_eq!(vertex_pair([1.0, 0.5, 1.0], [1.0, 0.5, -1.0]), vec![(0, 1)]);
    // An edge from the shared vertex lying along the other's edge: found.
    assert_eq!(vertex_pair([1.0, 0.0, 0.0], [0.0, -1.0, 1.0]), vec![(0, 1)]);
    // Coplanar and overlapping: found.
    assert_eq!(vertex_pair([1.0, 1.0, 0.0], [3.0, -1.0, 0.0]), vec![(0, 1)]);
    // The far edge piercing the other away from the shared vertex: found.
    assert_eq!(vertex_pair([0.5, 0.5, 1.0], [0.5, 0.5, -1.0]), vec![(0, 1)]);
}

#[test]
fn duplicated_triangles_intersect() {
    let positions = BASE.to_vec();
    assert_eq!(
        intersections(&positions, &[[0, 1, 2], [2, 1, 0]]),
        vec![(0, 1)]
    );
}

// ---------------------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------------------

#[test]
fn closed_meshes_have_no_self_intersections() {
    for (positions, triangles) in [octahedron(), icosphere(3), cube(3), torus(48, 16)] {
        assert!(intersections(&positions, &triangles).is_empty());
        assert!(
            degenerate_triangles(&positions, &triangles)
                .unwrap()
                .is_empty()
        );
    }
}

#[test]
fn a_vertex_pushed_through_the_opposite_side_is_found() {
    let (mut positions, triangles) = icosphere(2);
    positions[0] = positions[0].map(|x| -1.3 * x);
    let pairs = intersections(&positions, &triangles);
    assert!(!pairs.is_empty());
    // Every pair involves a triangle that moved.
    let moved = |t: usize| triangles[t].contains(&0);
    assert!(pairs.iter().all(|&(i, j)| moved(i) || moved(j)));
}

#[test]
fn degenerate_triangles_are_reported_apart() {
    let positions = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.5, 0.0],
        [0.3, 0.3, -1.0],
    ];
    // 1 is collinear (vertex 3 is the midpoint of 1 and 2), 2 repeats an index.
    let triangles = [[0, 1, 2], [1, 2, 3], [4, 4, 0], [0, 1, 4]];
    assert_eq!(
        degenerate_triangles(&positions, &triangles).unwrap(),
        vec![1, 2]
    );
    // Triangle 1 lies on triangle 0's edge, but degenerate triangles are not tested for contact.
    assert!(intersections(&positions, &triangles).is_empty());
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, f64::NAN, 0.0]];
    assert!(matches!(
        self_intersections(&positions, &[[0, 1, 2]]),
        Err(SpatialError::NonFinite { vertex: 2, .. })
    ));
    let positions = BASE;
    assert!(matches!(
        self_intersections(&positions, &[[0, 1, 3]]),
        Err(SpatialError::IndexOutOfRange {
            triangle: 0,
            index: 3,
            vertex_count: 3
        })
    ));
    assert!(degenerate_triangles(&positions, &[[7, 0, 1]]).is_err());
    let ok = MeshRef {
        positions: &positions,
        triangles: &[[0, 1, 2]],
    };
    let empty = MeshRef {
        positions: &positions,
        triangles: &[],
    };
    assert_eq!(hausdorff(ok, empty), Err(SpatialError::NoTriangles));
    let bad = MeshRef {
        positions: &positions,
        triangles: &[[0, 1, 9]],
    };
    assert!(hausdorff(bad, ok).is_err());
    assert!(bounding_box_diagonal(&[[f64::INFINITY, 0.0, 0.0]]).is_err());
}

// ---------------------------------------------------------------------------------------------------
// Hausdorff
// ---------------------------------------------------------------------------------------------------

fn mesh_ref(m: &Mesh) -> MeshRef<'_> {
    MeshRef {
        positions: &m.0,
        triangles: &m.1,
    }
}

#[test]
fn a_mesh_is_at_distance_zero_from_itself() {
    let m = icosphere(3);
    let h = hausdorff(mesh_ref(&m), mesh_ref(&m)).unwrap();
    assert!(h.symmetric < 1e-12, "{h:?}");
}

#[test]
fn a_sphere_and_its_scaled_copy_are_about_the_difference_in_radius_apart() {
    let a = icosphere(4);
    let b = (
        a.0.iter().map(|p| p.map(|x| 1.1 * x)).collect(),
        a.1.clone(),
    );
    let h = hausdorff(mesh_ref(&a), mesh_ref(&b)).unwrap();
    // Exactly 0.1 between the vertices; the flat faces sag inwards by < 1e-3 at this resolution.
    for d in [h.a_to_b, h.b_to_a] {
        assert!((d - 0.1).abs() < 2e-3, "{h:?}");
    }
    assert_eq!(h.symmetric, h.a_to_b.max(h.b_to_a));
}

#[test]
fn a_sub_mesh_is_near_the_mesh_but_not_conversely() {
    let whole = icosphere(3);
    let north: Vec<[u32; 3]> = whole
        .1
        .iter()
        .copied()
        .filter(|t| t.iter().map(|&i| whole.0[i as usize][2]).sum::<f64>() > 0.0)
        .collect();
    // The same positions and one far away that no triangle uses: it must not count.
    let mut positions = whole.0.clone();
    positions.push([10.0, 10.0, 10.0]);
    let part = MeshRef {
        positions: &positions,
        triangles: &north,
    };
    let h = hausdorff(mesh_ref(&whole), part).unwrap();
    assert!(h.b_to_a < 1e-12, "{h:?}");
    // The south pole is about √2 from the equator.
    assert!(h.a_to_b > 1.3 && h.a_to_b < 1.5, "{h:?}");
}

#[test]
fn bounding_box_diagonal_of_a_cube() {
    let (positions, _) = cube(2);
    assert!((bounding_box_diagonal(&positions).unwrap() - 12f64.sqrt()).abs() < 1e-15);
    assert_eq!(bounding_box_diagonal(&[]).unwrap(), 0.0);
}

/// Independent point–triangle distance: the plane's foot point if its barycentric coordinates are all
/// non-negative, otherwise the nearest of the three edges.
fn reference_distance(p: P, t: [P; 3]) -> f64 {
    let sub = |a: P, b: P| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: P, b: P| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let segment = |a: P, b: P| {
        let ab = sub(b, a);
        let s = if dot(ab, ab) > 0.0 {
            (dot(sub(p, a), ab) / dot(ab, ab)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = sub(p, [0, 1, 2].map(|k| a[k] + s * ab[k]));
        dot(d, d).sqrt()
    };
    let edges = segment(t[0], t[1])
        .min(segment(t[1], t[2]))
        .min(segment(t[2], t[0]));
    // Barycentric coordinates of the foot point from the normal equations of the plane fit.
    let (e1, e2, w) = (sub(t[1], t[0]), sub(t[2], t[0]), sub(p, t[0]));
    let (a, b, c) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
    let det = a * c - b * b;
    if det <= 1e-12 * a * c {
        return edges;
    }
    let (r, s) = (dot(w, e1), dot(w, e2));
    let (u, v) = ((c * r - b * s) / det, (a * s - b * r) / det);
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
        let foot = [0, 1, 2].map(|k| t[0][k] + u * e1[k] + v * e2[k]);
        let d = sub(p, foot);
        dot(d, d).sqrt()
    } else {
        edges
    }
}

/// O(n·m) one-sided distance from the same samples (used vertices, centroids, edge midpoints).
fn brute_one_sided(from: &Mesh, to: &Mesh) -> f64 {
    let p = |i: u32| from.0[i as usize];
    let mut samples = Vec::new();
    for t in &from.1 {
        samples.push([0, 1, 2].map(|k| (p(t[0])[k] + p(t[1])[k] + p(t[2])[k]) / 3.0));
        for i in 0..3 {
            samples.push(p(t[i]));
            samples.push([0, 1, 2].map(|k| 0.5 * (p(t[i])[k] + p(t[(i + 1) % 3])[k])));
        }
    }
    let corners = |t: &[u32; 3]| t.map(|i| to.0[i as usize]);
    samples
        .iter()
        .map(|&s| {
            to.1.iter()
                .map(|t| reference_distance(s, corners(t)))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max)
}

fn small_mesh() -> impl Strategy<Value = Mesh> {
    (3usize..9).prop_flat_map(|n| {
        (
            proptest::collection::vec([-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], n),
            proptest::collection::vec([0..n as u32, 0..n as u32, 0..n as u32], 1..7),
        )
    })
}

// ---------------------------------------------------------------------------------------------------
// Property tests
// ---------------------------------------------------------------------------------------------------

fn rotate(q: [f64; 4], p: P) -> P {
    // p + 2 w (v × p) + 2 v × (v × p) for the unit quaternion (w, v).
    let [w, x, y, z] = q;
    let cross = |a: P, b: P| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let v = [x, y, z];
    let t = cross(v, p).map(|c| 2.0 * c);
    let u = cross(v, t);
    [0, 1, 2].map(|k| p[k] + w * t[k] + u[k])
}

/// Exact intersection of two closed non-degenerate triangles with small integer corners by the
/// separating axis theorem: face normals, edge × edge, and (for coplanar pairs) normal × edge.
fn sat_intersect(t1: [[i64; 3]; 3], t2: [[i64; 3]; 3]) -> bool {
    let sub = |a: [i64; 3], b: [i64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [i64; 3], b: [i64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [i64; 3], b: [i64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let edges = |t: [[i64; 3]; 3]| [sub(t[1], t[0]), sub(t[2], t[1]), sub(t[0], t[2])];
    let (e1, e2) = (edges(t1), edges(t2));
    let (n1, n2) = (cross(e1[0], e1[1]), cross(e2[0], e2[1]));
    let mut axes = vec![n1, n2];
    for a in e1 {
        axes.extend(e2.iter().map(|&b| cross(a, b)));
        axes.push(cross(n1, a));
    }
    axes.extend(e2.iter().map(|&b| cross(n2, b)));
    let span = |t: [[i64; 3]; 3], ax: [i64; 3]| {
        let d = t.map(|p| dot(p, ax));
        (*d.iter().min().unwrap(), *d.iter().max().unwrap())
    };
    !axes.iter().any(|&ax| {
        let ((lo1, hi1), (lo2, hi2)) = (span(t1, ax), span(t2, ax));
        hi1 < lo2 || hi2 < lo1
    })
}

fn small_int_point() -> impl Strategy<Value = [i64; 3]> {
    [-3i64..4, -3i64..4, -3i64..4]
}

/// An exact change of axes: permute them and flip some.
fn transform(p: [i64; 3], perm: [usize; 3], flip: [bool; 3]) -> [i64; 3] {
    [0, 1, 2].map(|k| if flip[k] { -p[perm[k]] } else { p[perm[k]] })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn rigid_motions_keep_a_clean_mesh_clean(
        q in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        shift in [-100.0..100.0f64, -100.0..100.0f64, -100.0..100.0f64],
        which in 0usize..2,
    ) {
        let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        prop_assume!(norm > 0.1);
        let q = q.map(|x| x / norm);
        let (positions, triangles) = if which == 0 { icosphere(2) } else { torus(24, 10) };
        let moved: Vec<P> = positions.iter().map(|&p| {
            let r = rotate(q, p);
            [0, 1, 2].map(|k| r[k] + shift[k])
        }).collect();
        prop_assert!(intersections(&moved, &triangles).is_empty());
    }

    #[test]
    fn a_triangle_through_a_face_of_a_cube_is_found(
        axis in 0usize..3,
        outward in any::<bool>(),
        at in [-0.6..0.6f64, -0.6..0.6f64],
        depth in 0.05..0.5f64,
        t1 in [-0.3..0.3f64, -0.3..0.3f64],
        t2 in [-0.3..0.3f64, -0.3..0.3f64],
    ) {
        prop_assume!((t1[0] - t2[0]).hypot(t1[1] - t2[1]) > 0.01);
        let (mut positions, mut triangles) = cube(3);
        prop_assert!(intersections(&positions, &triangles).is_empty());
        let side = if outward { 1.0 } else { -1.0 };
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let point = |height: f64, t: [f64; 2]| {
            let mut p = [0.0; 3];
            p[axis] = side * (1.0 + height);
            p[u] = at[0] + t[0];
            p[v] = at[1] + t[1];
            p
        };
        // One corner outside the face, two inside the cube: the triangle crosses the face.
        let n = positions.len() as u32;
        positions.extend([point(depth, [0.0, 0.0]), point(-depth, t1), point(-depth, t2)]);
        triangles.push([n, n + 1, n + 2]);
        let new = triangles.len() - 1;
        let pairs = intersections(&positions, &triangles);
        prop_assert!(!pairs.is_empty());
        prop_assert!(pairs.iter().all(|&(_, j)| j == new));
    }
}

// Single pairs and small meshes are cheap: many more cases.
proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn unshared_pairs_agree_with_separating_axes(
        t1 in [small_int_point(), small_int_point(), small_int_point()],
        t2 in [small_int_point(), small_int_point(), small_int_point()],
    ) {
        let positions: Vec<P> = t1.iter().chain(t2.iter()).map(|p| p.map(|x| x as f64)).collect();
        let triangles = [[0, 1, 2], [3, 4, 5]];
        prop_assume!(degenerate_triangles(&positions, &triangles).unwrap().is_empty());
        let found = !intersections(&positions, &triangles).is_empty();
        prop_assert_eq!(found, sat_intersect(t1, t2));
    }

    /// Pairs drawn from five shared integer points (so sharing, touching and coplanar cases are
    /// common): the answer does not depend on the order of the triangles, where each cycle starts or
    /// which way it runs, or an exact change of axes.
    #[test]
    fn pair_answers_do_not_depend_on_presentation(
        points in [small_int_point(), small_int_point(), small_int_point(), small_int_point(), small_int_point()],
        ia in Just(vec![0u32, 1, 2, 3, 4]).prop_shuffle(),
        ib in Just(vec![0u32, 1, 2, 3, 4]).prop_shuffle(),
        rot in 0usize..3,
        reverse in any::<bool>(),
        perm in Just([0usize, 1, 2]).prop_shuffle(),
        flip in [any::<bool>(), any::<bool>(), any::<bool>()],
    ) {
        let (ia, ib) = ([ia[0], ia[1], ia[2]], [ib[0], ib[1], ib[2]]);
        let positions: Vec<P> = points.iter().map(|p| p.map(|x| x as f64)).collect();
        prop_assume!(degenerate_triangles(&positions, &[ia, ib]).unwrap().is_empty());
        let base = !intersections(&positions, &[ia, ib]).is_empty();
        let mut ib2 = [ib[rot], ib[(rot + 1) % 3], ib[(rot + 2) % 3]];
        if reverse {
            ib2.swap(1, 2);
        }
        let moved: Vec<P> = points.iter().map(|&p| transform(p, perm, flip).map(|x| x as f64)).collect();
        prop_assert_eq!(!intersections(&moved, &[ib2, ia]).is_empty(), base);
    }

    #[test]
    fn hausdorff_agrees_with_brute_force(a in small_mesh(), b in small_mesh()) {
        let h = hausdorff(mesh_ref(&a), mesh_ref(&b)).unwrap();
        let (ab, ba) = (brute_one_sided(&a, &b), brute_one_sided(&b, &a));
        prop_assert!((h.a_to_b - ab).abs() < 1e-9, "{} vs {}", h.a_to_b, ab);
        prop_assert!((h.b_to_a - ba).abs() < 1e-9, "{} vs {}", h.b_to_a, ba);
    }

    #[test]
    fn closest_point_is_no_farther_than_any_sampled_point(
        p in [-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64],
        t in [[-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64]],
        bary in proptest::collection::vec([0.0..1.0f64, 0.0..1.0f64], 16),
    ) {
        let q = closest_point_on_triangle(p, t);
        let d = |x: P| ((x[0] - p[0]).powi(2) + (x[1] - p[1]).powi(2) + (x[2] - p[2]).powi(2)).sqrt();
        prop_assert!((d(q) - reference_distance(p, t)).abs() < 1e-9);
        for [s, r] in bary {
            let (s, r) = if s + r > 1.0 { (1.0 - s, 1.0 - r) } else { (s, r) };
            let x = [0, 1, 2].map(|k| t[0][k] + s * (t[1][k] - t[0][k]) + r * (t[2][k] - t[0][k]));
            prop_assert!(d(q) <= d(x) + 1e-12);
        }
    }
}

// Meshes with more samples than the sparse first pass's stride, so that it, the recently-found
// triangles and the early exit all take part: fewer, costlier cases.
proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn hausdorff_of_bumpy_spheres_agrees_with_brute_force(seed in any::<u64>(), shift in [-0.2..0.2f64, -0.2..0.2f64, -0.2..0.2f64]) {
        let a = icosphere(1);
        let mut x = seed | 1;
        let mut bumpy = a.clone();
        for p in &mut bumpy.0 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let r = 0.9 + 0.2 * (x >> 11) as f64 / (1u64 << 53) as f64;
            *p = [0, 1, 2].map(|k| r * p[k] + shift[k]);
        }
        // A different triangulation too: the icosahedron.
        let b = icosphere(0);
        for (m, n) in [(&a, &bumpy), (&bumpy, &b)] {
            let h = hausdorff(mesh_ref(m), mesh_ref(n)).unwrap();
            let (ab, ba) = (brute_one_sided(m, n), brute_one_sided(n, m));
            prop_assert!((h.a_to_b - ab).abs() < 1e-12 && (h.b_to_a - ba).abs() < 1e-12, "{h:?} vs {ab} {ba}");
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// Evening a mesh out along its own surface (mesh::even)
// ---------------------------------------------------------------------------------------------------

/// Triangles with an angle under 20°.
fn thin_triangles(positions: &[P], triangles: &[[u32; 3]]) -> usize {
    mesh::mesh_shape(positions, triangles).unwrap().below_20
}

fn unit_normal(p: [P; 3]) -> P {
    let (a, b) = (
        [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]],
        [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]],
    );
    normalize([
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ])
}

/// Checks what evening promises: every vertex on its host triangle of the original mesh (the
/// barycentric coordinates in [0, 1] reproduce it), no triangle turned against its original
/// normal, and the vertices that were not free exactly where they were.
fn assert_evened_on_the_mesh(original: &Mesh, evened: &mesh::even::Evened) {
    let (positions, triangles) = original;
    for (v, (&(t, b), p)) in evened.hosts.iter().zip(&evened.positions).enumerate() {
        let corners = triangles[t as usize].map(|c| positions[c as usize]);
        assert!(
            b.iter().all(|&x| x > -1e-9 && x < 1.0 + 1e-9),
            "vertex {v}: {b:?}"
        );
        for axis in 0..3 {
            let q: f64 = (0..3).map(|k| b[k] * corners[k][axis]).sum();
            assert!(
                (q - p[axis]).abs() < 1e-9,
                "vertex {v} is off its host triangle {t}"
            );
        }
    }
    for (i, t) in triangles.iter().enumerate() {
        let before = unit_normal(t.map(|c| positions[c as usize]));
        let after = unit_normal(t.map(|c| evened.positions[c as usize]));
        let turn: f64 = (0..3).map(|k| before[k] * after[k]).sum();
        assert!(turn > 0.0, "triangle {i} turned over");
    }
}

#[test]
fn a_mesh_without_thin_triangles_is_left_as_it_is() {
    let sphere = icosphere(3);
    assert_eq!(thin_triangles(&sphere.0, &sphere.1), 0);
    let evened = mesh::even::even_out(&sphere.0, &sphere.1, 10);
    assert_eq!((evened.free, evened.largest_move), (0, 0.0));
    assert_eq!(evened.positions, sphere.0);
}

/// The smallest angle of any triangle, in degrees.
fn smallest_angle(positions: &[P], triangles: &[[u32; 3]]) -> f64 {
    mesh::mesh_shape(positions, triangles)
        .unwrap()
        .smallest_angle
}

/// A number in [−1, 1) from a seed and an index (splitmix64), for jitter.
fn jitter(seed: u64, i: u64) -> f64 {
    let mut z = seed.wrapping_add(i.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// A box ten times longer than it is wide, each face a grid whose lines across the long axis are
/// moved at random by up to 0.4 of their spacing (edges included, so the box's edges stay
/// straight): thin, irregular triangles on the long faces. Evening rounds them (the smallest angle
/// grows), the vertices on the box's edges (sharp: 90°) stay where they are, and the rest slide
/// within their faces.
#[test]
fn a_long_box_keeps_its_edges_and_its_faces_flat() {
    let n = 6;
    let (cube_positions, triangles) = cube(n);
    let stretch = |x: f64| {
        // x = (2i − n)/n on the grid; inner lines are jittered, the ends stay.
        let i = ((x + 1.0) * f64::from(n) / 2.0).round() as u64;
        let moved = if i == 0 || i == u64::from(n) {
            x
        } else {
            x + 0.4 * jitter(7, i) * 2.0 / f64::from(n)
        };
        10.0 * moved
    };
    let positions: Vec<P> = cube_positions
        .iter()
        .map(|p| [stretch(p[0]), p[1], p[2]])
        .collect();
    let box_mesh = (positions.clone(), triangles.clone());
    let before = smallest_angle(&positions, &triangles);
    let evened = mesh::even::even_out(&positions, &triangles, 10);
    assert_evened_on_the_mesh(&box_mesh, &evened);
    let after = smallest_angle(&evened.positions, &triangles);
    assert!(after > before, "smallest angle {before}° -> {after}°");
    assert!(evened.pinned > 0 && evened.free > 0);
    let extreme = |p: &P| {
        (0..3)
            .filter(|&a| (p[a].abs() - [10.0, 1.0, 1.0][a]).abs() < 1e-12)
            .count()
    };
    for (v, (p, q)) in positions.iter().zip(&evened.positions).enumerate() {
        // On an edge of the box (two coordinates at their extremes): not moved. On a face: still on
        // that face.
        match extreme(p) {
            2.. => assert_eq!(p, q, "edge vertex {v} moved"),
            _ => assert!(extreme(q) >= 1, "vertex {v} left the box's faces: {q:?}"),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Tori whose grid is far finer around the ring than round the tube, each vertex moved along
    /// the ring (on the smooth torus) by up to 0.45 of the spacing at random: thin, irregular
    /// triangles and no sharp edges. Evened for any number of rounds, every vertex stays on the
    /// original mesh, no triangle turns over, and the smallest angle grows.
    #[test]
    fn evening_keeps_a_jittered_torus_on_itself_and_rounds_its_triangles(
        n in 100u32..200,
        m in 10u32..15,
        rounds in 1usize..16,
        seed in any::<u64>(),
    ) {
        let tau = std::f64::consts::TAU;
        let (_, triangles) = torus(n, m);
        let mut positions = Vec::new();
        for i in 0..n {
            for j in 0..m {
                let shift = 0.45 * jitter(seed, u64::from(i * m + j));
                let (a, b) = (
                    tau * (f64::from(i) + shift) / f64::from(n),
                    tau * f64::from(j) / f64::from(m),
                );
                let r = 2.0 + 0.7 * b.cos();
                positions.push([r * a.cos(), r * a.sin(), 0.7 * b.sin()]);
            }
        }
        let torus_mesh = (positions, triangles);
        let before = smallest_angle(&torus_mesh.0, &torus_mesh.1);
        let evened = mesh::even::even_out(&torus_mesh.0, &torus_mesh.1, rounds);
        assert_evened_on_the_mesh(&torus_mesh, &evened);
        prop_assert_eq!(evened.pinned, 0);
        let after = smallest_angle(&evened.positions, &torus_mesh.1);
        prop_assert!(after > before, "smallest angle {}° -> {}°", before, after);
    }
}
