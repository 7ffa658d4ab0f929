//! Geometric checks on triangle meshes in R³, for acceptance tests of fitted surfaces: pairs of
//! triangles that intersect where they should not, degenerate triangles, and the Hausdorff distance
//! between two meshes.
//!
//! Plain data in, plain data out: positions are `&[[f64; 3]]`, triangles `&[[u32; 3]]` indexing them.
//! Every entry point validates its input first (indices in range, finite coordinates) and returns a
//! [`SpatialError`] rather than panicking.
//!
//! **Exactness.** The intersection tests decide everything with Shewchuk's adaptive predicates
//! (`orient3d`, `orient2d` from the `robust` crate), so the answer is the exact one for the f64 input:
//! a point contact is found, and a mesh that merely comes close is not flagged. (As with any such
//! predicate, this holds while no intermediate product overflows or underflows, i.e. for coordinates
//! and their differences well inside 1e±90.) Distances are plain f64 arithmetic.
//!
//! **Broad phase.** Both checks put the triangles into an R-tree (`rstar`): boxes that touch are
//! tested pairwise, and distance queries walk the tree nearest first. No parallelism. For 2·10⁵
//! triangles, self-intersections take 0.25 s and the Hausdorff distance between two such meshes
//! 0.75 s in an optimised build; this package's unoptimised dev profile (its tests) is 5–7 times
//! slower, which is why the tree walks below are plain loops.

use robust::{Coord, Coord3D, orient2d, orient3d};
use rstar::{
    AABB, DefaultParams, ParentNode, PointDistance, RTree, RTreeNode, RTreeObject, RTreeParams,
};

type Point = [f64; 3];

/// Malformed mesh input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpatialError {
    #[error(
        "triangle {triangle} refers to vertex {index}, but there are only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        vertex_count: usize,
    },
    #[error("vertex {vertex} has a non-finite coordinate: {position:?}")]
    NonFinite { vertex: usize, position: [f64; 3] },
    #[error("a mesh without triangles has no surface to measure a distance to")]
    NoTriangles,
}

/// Checks that every index is in range and every coordinate (referenced or not) is finite.
pub fn validate(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Result<(), SpatialError> {
    if let Some(vertex) = positions
        .iter()
        .position(|p| !p.iter().all(|x| x.is_finite()))
    {
        return Err(SpatialError::NonFinite {
            vertex,
            position: positions[vertex],
        });
    }
    for (triangle, t) in triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(SpatialError::IndexOutOfRange {
                triangle,
                index,
                vertex_count: positions.len(),
            });
        }
    }
    Ok(())
}

fn corners(positions: &[[f64; 3]], t: [u32; 3]) -> [Point; 3] {
    t.map(|i| positions[i as usize])
}

// ---------------------------------------------------------------------------------------------------
// Exact predicates
// ---------------------------------------------------------------------------------------------------

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

fn coord3(p: &Point) -> Coord3D<f64> {
    Coord3D {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

/// Exact side of `d` relative to the plane through `a`, `b`, `c`: 1, −1, or 0 when coplanar.
fn orient(a: &Point, b: &Point, c: &Point, d: &Point) -> i8 {
    sign(orient3d(coord3(a), coord3(b), coord3(c), coord3(d)))
}

/// The three corners strictly on one side of a plane (all signs +1, or all −1).
fn strictly_one_side(s: &[i8]) -> bool {
    s.iter().all(|&x| x > 0) || s.iter().all(|&x| x < 0)
}

/// Signs that disagree strictly: some +1 and some −1.
fn mixed(s: &[i8]) -> bool {
    s.contains(&1) && s.contains(&-1)
}

/// Dropping one coordinate maps a plane one-to-one onto a coordinate plane unless the plane contains
/// that axis' direction. We drop the axis along which the triangle's shadow is largest; since
/// projection is affine and one-to-one on the plane, exact `orient2d` of projected points of that plane
/// gives their exact in-plane orientation (up to one global sign, which the callers never rely on).
#[derive(Clone, Copy)]
struct Projection {
    u: usize,
    v: usize,
}

impl Projection {
    /// `None` exactly when the triangle is degenerate (its corners collinear): then every shadow has
    /// zero area, and no coordinate plane is one-to-one on "its plane".
    fn of(t: &[Point; 3]) -> Option<Projection> {
        let mut best: Option<(f64, Projection)> = None;
        for drop in 0..3 {
            let pr = Projection {
                u: (drop + 1) % 3,
                v: (drop + 2) % 3,
            };
            let area = pr.orient(&t[0], &t[1], &t[2]).abs();
            if area > 0.0 && best.is_none_or(|(a, _)| area > a) {
                best = Some((area, pr));
            }
        }
        best.map(|(_, pr)| pr)
    }

    fn apply(self, p: &Point) -> Coord<f64> {
        Coord {
            x: p[self.u],
            y: p[self.v],
        }
    }

    /// Exact 2D orientation of the shadows (its sign is exact; its magnitude is an estimate).
    fn orient(self, a: &Point, b: &Point, c: &Point) -> f64 {
        orient2d(self.apply(a), self.apply(b), self.apply(c))
    }

    fn sign(self, a: &Point, b: &Point, c: &Point) -> i8 {
        sign(self.orient(a, b, c))
    }
}

/// For p collinear with the segment rs: is it on the closed segment? Along a line, being between the
/// endpoints in both projected coordinates is the same as being between them on the line.
fn within_box(pr: Projection, r: &Point, s: &Point, p: &Point) -> bool {
    [pr.u, pr.v]
        .iter()
        .all(|&k| r[k].min(s[k]) <= p[k] && p[k] <= r[k].max(s[k]))
}

/// Closed segments pq and rs of one plane meet (the classic orientation test, collinear cases included).
fn coplanar_segments_meet(pr: Projection, p: &Point, q: &Point, r: &Point, s: &Point) -> bool {
    let d1 = pr.sign(r, s, p);
    let d2 = pr.sign(r, s, q);
    let d3 = pr.sign(p, q, r);
    let d4 = pr.sign(p, q, s);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true; // a proper crossing
    }
    (d1 == 0 && within_box(pr, r, s, p))
        || (d2 == 0 && within_box(pr, r, s, q))
        || (d3 == 0 && within_box(pr, p, q, r))
        || (d4 == 0 && within_box(pr, p, q, s))
}

/// p (in the plane of the non-degenerate t) lies in the closed triangle t: not strictly outside any edge.
fn coplanar_point_in_triangle(pr: Projection, p: &Point, t: &[Point; 3]) -> bool {
    let s = [0, 1, 2].map(|i| pr.sign(&t[i], &t[(i + 1) % 3], p));
    !mixed(&s)
}

/// The closed segment pq, lying in the plane of the non-degenerate t, meets the closed triangle t.
fn coplanar_segment_meets_triangle(p: &Point, q: &Point, t: &[Point; 3]) -> bool {
    // Degenerate triangles never reach the narrow phase; `false` keeps this total all the same.
    let Some(pr) = Projection::of(t) else {
        return false;
    };
    // Either the segment lies inside (then so does p), or it crosses or touches the boundary.
    coplanar_point_in_triangle(pr, p, t)
        || (0..3).any(|i| coplanar_segments_meet(pr, p, q, &t[i], &t[(i + 1) % 3]))
}

/// The closed segment pq meets the closed, non-degenerate triangle t. `sp`, `sq` are the sides of p
/// and q relative to t's plane (callers have computed them for their early exits already).
fn segment_meets_triangle(p: &Point, q: &Point, sp: i8, sq: i8, t: &[Point; 3]) -> bool {
    if sp * sq > 0 {
        return false; // both strictly on one side of the plane
    }
    if sp == 0 && sq == 0 {
        return coplanar_segment_meets_triangle(p, q, t);
    }
    // The segment reaches the plane at one point, where the line pq crosses it. That point lies in
    // the closed triangle iff the line passes no edge on the other side from the rest: the signs of
    // the line against the three edges (as tetrahedra) are not mixed. Not all three are zero, since the
    // line is not in the plane.
    let s = [0, 1, 2].map(|i| orient(p, q, &t[i], &t[(i + 1) % 3]));
    !mixed(&s)
}

/// Sides of the corners of `t` relative to the plane of `plane`.
fn sides(t: &[Point; 3], plane: &[Point; 3]) -> [i8; 3] {
    t.map(|p| orient(&plane[0], &plane[1], &plane[2], &p))
}

// ---------------------------------------------------------------------------------------------------
// Triangle pairs by what they share
// ---------------------------------------------------------------------------------------------------

/// Two non-degenerate triangles with no vertex in common: do they touch at all?
///
/// Their intersection, if any, is convex; each of its extreme points lies on an edge of one triangle
/// and in the other (in the transversal case it is a segment of the planes' common line whose ends
/// are where that line leaves one of the triangles; in the coplanar case a polygon whose corners are
/// corners or edge crossings). So testing the six edges against the other triangle decides it.
fn disjoint_pair_touches(t1: &[Point; 3], t2: &[Point; 3]) -> bool {
    let s1 = sides(t1, t2);
    if strictly_one_side(&s1) {
        return false;
    }
    let s2 = sides(t2, t1);
    if strictly_one_side(&s2) {
        return false;
    }
    let edges_hit = |ta: &[Point; 3], sa: &[i8; 3], tb: &[Point; 3]| {
        (0..3).any(|i| {
            let j = (i + 1) % 3;
            segment_meets_triangle(&ta[i], &ta[j], sa[i], sa[j], tb)
        })
    };
    edges_hit(t1, &s1, t2) || edges_hit(t2, &s2, t1)
}

/// Two non-degenerate triangles (v, a1, a2) and (v, b1, b2) sharing only the vertex v: do they meet
/// anywhere but at v? Exactly when the far edge of one (a1 a2 or b1 b2, which never contains v) meets
/// the other triangle.
///
/// Why that suffices: the intersection is convex and contains v, so if it is more than v it has an
/// extreme point q ≠ v. Transversal, it is a segment [v, q] of the planes' common line, and q is where
/// that line leaves one triangle — through its far edge, or at a far corner. Coplanar, q is a corner of
/// the intersection polygon: a far corner of one triangle (on its far edge) lying in the other, or a
/// crossing of two edges; two edges at v can only cross away from v by overlapping along one line,
/// and then the overlap ends at a far corner again.
fn vertex_pair_overlaps(v: &Point, a: [&Point; 2], b: [&Point; 2]) -> bool {
    let t1 = [*v, *a[0], *a[1]];
    let t2 = [*v, *b[0], *b[1]];
    let sa = [orient(v, b[0], b[1], a[0]), orient(v, b[0], b[1], a[1])];
    let sb = [orient(v, a[0], a[1], b[0]), orient(v, a[0], a[1], b[1])];
    // a1 and a2 strictly on one side of t2's plane: t1 meets that plane only at v.
    if sa[0] * sa[1] > 0 || sb[0] * sb[1] > 0 {
        return false;
    }
    segment_meets_triangle(a[0], a[1], sa[0], sa[1], &t2)
        || segment_meets_triangle(b[0], b[1], sb[0], sb[1], &t1)
}

/// Two non-degenerate triangles (u, w, a) and (u, w, b) sharing the edge uw: do they meet off it?
///
/// Unless the four points are coplanar, the planes meet in the line uw and each triangle meets that
/// line in the edge only. Coplanar, the triangles overlap iff a and b are on the same side of uw — the
/// surface folds back onto itself.
fn edge_pair_folds(u: &Point, w: &Point, a: &Point, b: &Point) -> bool {
    if orient(u, w, a, b) != 0 {
        return false;
    }
    let Some(pr) = Projection::of(&[*u, *w, *a]) else {
        return false;
    };
    pr.sign(u, w, a) == pr.sign(u, w, b)
}

/// Do two non-degenerate triangles intersect other than in what they share by vertex index?
fn pair_intersects(i1: [u32; 3], t1: &[Point; 3], i2: [u32; 3], t2: &[Point; 3]) -> bool {
    let in2 = i1.map(|i| i2.contains(&i));
    let in1 = i2.map(|i| i1.contains(&i));
    // Rotations (keeping each triangle's cycle) that put the shared corners first.
    let rot = |t: &[Point; 3], k: usize| [t[k], t[(k + 1) % 3], t[(k + 2) % 3]];
    let first = |m: [bool; 3], want: bool| m.iter().position(|&x| x == want).unwrap_or(0);
    match in2.iter().filter(|&&x| x).count() {
        0 => disjoint_pair_touches(t1, t2),
        1 => {
            let r1 = rot(t1, first(in2, true));
            let r2 = rot(t2, first(in1, true));
            vertex_pair_overlaps(&r1[0], [&r1[1], &r1[2]], [&r2[1], &r2[2]])
        }
        2 => {
            // The unshared corner last; the other two are the shared edge.
            let r1 = rot(t1, (first(in2, false) + 1) % 3);
            let r2 = rot(t2, (first(in1, false) + 1) % 3);
            edge_pair_folds(&r1[0], &r1[1], &r1[2], &r2[2])
        }
        // The same three vertices: the triangles coincide.
        _ => true,
    }
}

// ---------------------------------------------------------------------------------------------------
// Self-intersections and degenerate triangles
// ---------------------------------------------------------------------------------------------------

/// A triangle's bounding box in the broad-phase tree.
struct BoxEntry {
    envelope: AABB<Point>,
    triangle: usize,
}

impl RTreeObject for BoxEntry {
    type Envelope = AABB<Point>;

    fn envelope(&self) -> AABB<Point> {
        self.envelope
    }
}

/// Triangles whose corners are collinear (zero area), decided exactly: all three coordinate shadows
/// have zero signed area. Includes triangles that repeat a vertex index or a position.
///
/// ```
/// use mesh::spatial::degenerate_triangles;
/// let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0]];
/// let triangles = [[0, 1, 2], [0, 1, 3], [2, 2, 1]];
/// assert_eq!(degenerate_triangles(&positions, &triangles).unwrap(), vec![1, 2]);
/// ```
pub fn degenerate_triangles(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<usize>, SpatialError> {
    validate(positions, triangles)?;
    Ok(triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| Projection::of(&corners(positions, **t)).is_none())
        .map(|(i, _)| i)
        .collect())
}

/// Every pair `(i, j)`, `i < j`, of triangles that intersect other than in what they legitimately
/// share, sorted. Sharing is by vertex index:
///
/// - no vertex in common: any contact counts, even a single point;
/// - one vertex: they may meet only at that vertex;
/// - an edge: they may meet only along it, so a coplanar pair on the same side of it (a fold) counts;
/// - all three vertices (a duplicated triangle): counts.
///
/// Degenerate triangles (see [`degenerate_triangles`]) have no plane to test against and are left
/// out here; a clean mesh has neither.
///
/// ```
/// use mesh::spatial::self_intersections;
/// // Two triangles, the second piercing the first through its middle.
/// let positions = [
///     [0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0],
///     [1.0, 1.0, -1.0], [1.0, 1.0, 1.0], [2.0, 2.0, 0.0],
/// ];
/// let triangles = [[0, 1, 2], [3, 4, 5]];
/// assert_eq!(self_intersections(&positions, &triangles).unwrap(), vec![(0, 1)]);
/// // The same triangles sharing an edge at a dihedral angle are fine.
/// let triangles = [[0, 1, 2], [0, 1, 4]];
/// assert!(self_intersections(&positions, &triangles).unwrap().is_empty());
/// ```
pub fn self_intersections(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<(usize, usize)>, SpatialError> {
    validate(positions, triangles)?;
    let pts: Vec<[Point; 3]> = triangles.iter().map(|&t| corners(positions, t)).collect();
    let good: Vec<bool> = pts.iter().map(|t| Projection::of(t).is_some()).collect();
    let entries = (0..pts.len())
        .filter(|&i| good[i])
        .map(|i| BoxEntry {
            envelope: AABB::from_points(pts[i].iter()),
            triangle: i,
        })
        .collect();
    let tree: RTree<BoxEntry> = RTree::bulk_load(entries);
    let mut pairs = Vec::new();
    let mut candidates = Vec::new();
    for i in (0..pts.len()).filter(|&i| good[i]) {
        candidates.clear();
        overlapping(
            tree.root(),
            &AABB::from_points(pts[i].iter()),
            &mut candidates,
        );
        for &j in &candidates {
            if j > i && pair_intersects(triangles[i], &pts[i], triangles[j], &pts[j]) {
                pairs.push((i, j));
            }
        }
    }
    pairs.sort_unstable();
    Ok(pairs)
}

/// Every triangle whose box meets `query`, boxes taken closed so that touching ones (a point contact)
/// are candidates too. The same search as rstar's `locate_in_envelope_intersecting`, as a plain
/// recursion: see [`descend`] for why that matters in unoptimised builds (here 0.45 s against 1.8 s
/// for 2·10⁵ triangles).
fn overlapping(node: &ParentNode<BoxEntry>, query: &AABB<Point>, out: &mut Vec<usize>) {
    let (lo, hi) = (query.lower(), query.upper());
    for child in node.children() {
        let b = child.envelope();
        let (l, h) = (b.lower(), b.upper());
        let meets = l[0] <= hi[0] && l[1] <= hi[1] && l[2] <= hi[2];
        if meets && h[0] >= lo[0] && h[1] >= lo[1] && h[2] >= lo[2] {
            match child {
                RTreeNode::Leaf(entry) => out.push(entry.triangle),
                RTreeNode::Parent(inner) => overlapping(inner, query, out),
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// Distances
// ---------------------------------------------------------------------------------------------------

fn sub(a: &Point, b: &Point) -> Point {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: &Point, b: &Point) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a + t·d
fn along(a: &Point, t: f64, d: &Point) -> Point {
    [a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]]
}

fn distance_2(a: &Point, b: &Point) -> f64 {
    let d = sub(a, b);
    dot(&d, &d)
}

fn closest_point_on_segment(p: &Point, a: &Point, b: &Point) -> Point {
    let ab = sub(b, a);
    let len2 = dot(&ab, &ab);
    if len2 == 0.0 {
        return *a;
    }
    along(a, (dot(&sub(p, a), &ab) / len2).clamp(0.0, 1.0), &ab)
}

/// The point of the closed triangle t nearest to p.
///
/// The region-based algorithm (Ericson, *Real-Time Collision Detection*, 5.1.5): decide from a few dot
/// products which Voronoi region of t (a corner, an edge, the face) contains p, and project there. On
/// a degenerate triangle the face or edge formulas divide by zero; there the nearest point of the three
/// edges is the answer, since such a triangle is the union of its edges.
///
/// ```
/// use mesh::spatial::closest_point_on_triangle;
/// let t = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
/// assert_eq!(closest_point_on_triangle([0.5, 0.5, 3.0], t), [0.5, 0.5, 0.0]);
/// assert_eq!(closest_point_on_triangle([-1.0, -1.0, 0.0], t), [0.0, 0.0, 0.0]);
/// ```
pub fn closest_point_on_triangle(p: [f64; 3], t: [[f64; 3]; 3]) -> [f64; 3] {
    let q = voronoi_closest_point(&p, &t);
    if q.iter().all(|x| x.is_finite()) {
        return q;
    }
    (0..3)
        .map(|i| closest_point_on_segment(&p, &t[i], &t[(i + 1) % 3]))
        .min_by(|x, y| distance_2(&p, x).total_cmp(&distance_2(&p, y)))
        .unwrap_or(t[0])
}

/// The barycentric coordinates of `p` (a point of the triangle's plane) in the triangle; a
/// degenerate triangle's point is given to its nearest corner.
///
/// ```
/// use mesh::spatial::barycentric;
/// let t = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
/// assert_eq!(barycentric([0.5, 0.5, 0.0], t), [0.5, 0.25, 0.25]);
/// ```
pub fn barycentric(p: [f64; 3], [a, b, c]: [[f64; 3]; 3]) -> [f64; 3] {
    let (ab, ac, ap) = (sub(&b, &a), sub(&c, &a), sub(&p, &a));
    let (d00, d01, d11) = (dot(&ab, &ab), dot(&ab, &ac), dot(&ac, &ac));
    let (d20, d21) = (dot(&ap, &ab), dot(&ap, &ac));
    let det = d00 * d11 - d01 * d01;
    if det <= f64::EPSILON * d00 * d11 || !det.is_finite() {
        let d = [a, b, c].map(|q| distance_2(&p, &q));
        let k = (0..3).min_by(|&i, &j| d[i].total_cmp(&d[j])).unwrap_or(0);
        let mut w = [0.0; 3];
        w[k] = 1.0;
        return w;
    }
    let v = (d11 * d20 - d01 * d21) / det;
    let w = (d00 * d21 - d01 * d20) / det;
    [1.0 - v - w, v, w]
}

/// Ericson's ClosestPtPointTriangle, names as in the book; may return NaN on a degenerate triangle.
fn voronoi_closest_point(p: &Point, [a, b, c]: &[Point; 3]) -> Point {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let (d1, d2) = (dot(&ab, &ap), dot(&ac, &ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(&ab, &bp), dot(&ac, &bp));
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return along(a, d1 / (d1 - d3), &ab);
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(&ab, &cp), dot(&ac, &cp));
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return along(a, d2 / (d2 - d6), &ac);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return along(b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), &sub(c, b));
    }
    let denom = va + vb + vc;
    if denom <= 0.0 {
        return [f64::NAN; 3];
    }
    along(&along(a, vb / denom, &ab), vc / denom, &ac)
}

/// A triangle in the distance tree.
struct TriangleEntry {
    corners: [Point; 3],
    envelope: AABB<Point>,
}

impl RTreeObject for TriangleEntry {
    type Envelope = AABB<Point>;

    fn envelope(&self) -> AABB<Point> {
        self.envelope
    }
}

impl PointDistance for TriangleEntry {
    fn distance_2(&self, p: &Point) -> f64 {
        distance_2(p, &closest_point_on_triangle(*p, self.corners))
    }
}

/// A mesh borrowed as plain arrays.
#[derive(Clone, Copy, Debug)]
pub struct MeshRef<'a> {
    pub positions: &'a [[f64; 3]],
    pub triangles: &'a [[u32; 3]],
}

/// Sampled Hausdorff distances between meshes a and b (see [`hausdorff`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hausdorff {
    /// How far a strays from b: the largest distance from a sample of a to b's surface.
    pub a_to_b: f64,
    /// How far b strays from a.
    pub b_to_a: f64,
    /// The larger of the two.
    pub symmetric: f64,
}

fn midpoint(a: &Point, b: &Point) -> Point {
    [
        0.5 * (a[0] + b[0]),
        0.5 * (a[1] + b[1]),
        0.5 * (a[2] + b[2]),
    ]
}

/// The points of a mesh measured from: every triangle's centroid, every edge's midpoint (each edge
/// once) and every vertex some triangle uses.
fn samples(mesh: MeshRef) -> Vec<Point> {
    let (positions, triangles) = (mesh.positions, mesh.triangles);
    let mut out = Vec::with_capacity(3 * triangles.len());
    let mut used = vec![false; positions.len()];
    for t in triangles {
        let [a, b, c] = corners(positions, *t);
        out.push([0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0));
        for &v in t {
            used[v as usize] = true;
        }
    }
    // Edges bucketed by their smaller endpoint (a counting sort, linear and cheap in unoptimised
    // builds), then each bucket's few entries deduplicated by scanning.
    let edge = |t: &[u32; 3], i: usize| {
        let (u, v) = (t[i], t[(i + 1) % 3]);
        (u.min(v) as usize, u.max(v))
    };
    let mut start = vec![0usize; positions.len() + 1];
    for t in triangles {
        for i in 0..3 {
            start[edge(t, i).0 + 1] += 1;
        }
    }
    for v in 0..positions.len() {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut far = vec![0u32; 3 * triangles.len()];
    for t in triangles {
        for i in 0..3 {
            let (u, v) = edge(t, i);
            far[fill[u]] = v;
            fill[u] += 1;
        }
    }
    for u in 0..positions.len() {
        let bucket = &far[start[u]..start[u + 1]];
        for (k, &v) in bucket.iter().enumerate() {
            if !bucket[..k].contains(&v) {
                out.push(midpoint(&positions[u], &positions[v as usize]));
            }
        }
    }
    out.extend(
        (0..positions.len())
            .filter(|&u| used[u])
            .map(|u| positions[u]),
    );
    out
}

/// How far x lies outside [lo, hi] (0 inside).
fn outside(x: f64, lo: f64, hi: f64) -> f64 {
    if x < lo {
        lo - x
    } else if x > hi {
        x - hi
    } else {
        0.0
    }
}

/// Squared distance from p to the box (0 inside).
fn box_distance_2(b: &AABB<Point>, p: &Point) -> f64 {
    let (lo, hi) = (b.lower(), b.upper());
    // Spelt out: array `map` is slow in unoptimised builds, and this is the innermost loop.
    let x = outside(p[0], lo[0], hi[0]);
    let y = outside(p[1], lo[1], hi[1]);
    let z = outside(p[2], lo[2], hi[2]);
    x * x + y * y + z * z
}

/// The node fan-out of the distance tree, so that a node's children fit in an array on the stack.
const FAN_OUT: usize = <DefaultParams as RTreeParams>::MAX_SIZE;

/// Depth-first search for the triangle nearest to p, children nearest first so that `best` (a squared
/// distance, with `hit` the triangle attaining it) shrinks early and prunes the rest. Returns as soon
/// as `best <= stop`: the caller only needs to know that p is within `stop` of `to`.
///
/// Written as plain loops over rstar's nodes rather than with its nearest-neighbour iterators: generic
/// code is compiled with the calling crate's settings, and this package's dev profile (the tests') is
/// unoptimised, where those iterators are very slow. With the early exit this is what took Hausdorff
/// between two meshes of 2·10⁵ triangles from 47 s to 3.4 s there.
fn descend<'t>(
    node: &'t ParentNode<TriangleEntry>,
    p: &Point,
    best: &mut f64,
    hit: &mut Option<&'t TriangleEntry>,
    stop: f64,
) {
    // rstar keeps at most FAN_OUT children per node; chunks keep this exact if it ever did not.
    for chunk in node.children().chunks(FAN_OUT) {
        let mut box_2 = [f64::INFINITY; FAN_OUT];
        for (d, child) in box_2.iter_mut().zip(chunk) {
            *d = box_distance_2(&child.envelope(), p);
        }
        // Visit the nearest unvisited box while it could hold something nearer than `best`.
        loop {
            let mut next = None;
            let mut nearest = *best;
            for (i, &d) in box_2.iter().enumerate() {
                if d < nearest {
                    (next, nearest) = (Some(i), d);
                }
            }
            let Some(i) = next else { break };
            box_2[i] = f64::INFINITY;
            match &chunk[i] {
                RTreeNode::Leaf(t) => {
                    let d = t.distance_2(p);
                    if d < *best {
                        (*best, *hit) = (d, Some(t));
                    }
                }
                RTreeNode::Parent(child) => descend(child, p, best, hit, stop),
            }
            if *best <= stop {
                return;
            }
        }
    }
}

/// The largest distance from a sample of `from` to the surface of `to`.
///
/// Only the maximum matters, so a sample is dismissed as soon as any triangle is found within the
/// largest distance h seen so far (the early break of Taha and Hanbury's Hausdorff algorithm); only
/// samples that raise h need their exact nearest triangle. The first triangles tried are the last few
/// found nearest (samples come in mesh order, so neighbours follow each other), and a sparse first
/// pass over every 61st sample brings h close to its final value before the full pass.
fn one_sided(from: MeshRef, to: MeshRef) -> f64 {
    let entries = to
        .triangles
        .iter()
        .map(|&t| {
            let corners = corners(to.positions, t);
            TriangleEntry {
                corners,
                envelope: AABB::from_points(corners.iter()),
            }
        })
        .collect();
    let tree: RTree<TriangleEntry> = RTree::bulk_load(entries);
    let samples = samples(from);
    let mut h_2 = 0.0;
    // The last few nearest triangles found, tried before any search.
    let mut recent: [Option<&TriangleEntry>; 4] = [None; 4];
    let mut oldest = 0;
    for stride in [61, 1] {
        for p in samples.iter().step_by(stride) {
            let (mut best, mut hit) = (f64::INFINITY, None);
            for t in recent.iter().flatten() {
                let d = t.distance_2(p);
                if d < best {
                    (best, hit) = (d, Some(*t));
                }
            }
            if best > h_2 {
                let before = hit;
                descend(tree.root(), p, &mut best, &mut hit, h_2);
                if hit.map(std::ptr::from_ref) != before.map(std::ptr::from_ref) {
                    recent[oldest] = hit;
                    oldest = (oldest + 1) % recent.len();
                }
            }
            // A search that did not stop early found the exact nearest distance.
            h_2 = f64::max(h_2, best);
        }
    }
    h_2.sqrt()
}

/// Hausdorff distances between two meshes, measured from samples: each one-sided distance is the
/// largest, over every used vertex, every triangle centroid and every edge midpoint of one mesh, of
/// the exact (f64) distance to the closest point of the other mesh's triangles. It is a lower bound of
/// the true Hausdorff distance, tight to within the meshes' deviation from flat between the samples.
///
/// ```
/// use mesh::spatial::{MeshRef, hausdorff};
/// let square = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
/// let lifted = square.map(|[x, y, z]| [x, y, z + 0.25]);
/// let triangles = [[0, 1, 2], [0, 2, 3]];
/// let a = MeshRef { positions: &square, triangles: &triangles };
/// let b = MeshRef { positions: &lifted, triangles: &triangles[..1] };
/// let h = hausdorff(a, b).unwrap();
/// assert!((h.b_to_a - 0.25).abs() < 1e-15); // b lies right above a
/// assert!(h.a_to_b > 0.25); // a's second triangle is not above b
/// assert_eq!(h.symmetric, h.a_to_b);
/// ```
pub fn hausdorff(a: MeshRef, b: MeshRef) -> Result<Hausdorff, SpatialError> {
    for m in [a, b] {
        validate(m.positions, m.triangles)?;
        if m.triangles.is_empty() {
            return Err(SpatialError::NoTriangles);
        }
    }
    let (a_to_b, b_to_a) = (one_sided(a, b), one_sided(b, a));
    Ok(Hausdorff {
        a_to_b,
        b_to_a,
        symmetric: a_to_b.max(b_to_a),
    })
}

/// The length of the diagonal of the positions' axis-aligned bounding box (0 for none): the scale to
/// state distance tolerances against. Every position counts, used by a triangle or not.
///
/// ```
/// use mesh::spatial::bounding_box_diagonal;
/// let d = bounding_box_diagonal(&[[0.0, 0.0, 0.0], [1.0, 2.0, 2.0], [0.5, 0.5, 0.5]]).unwrap();
/// assert_eq!(d, 3.0);
/// ```
pub fn bounding_box_diagonal(positions: &[[f64; 3]]) -> Result<f64, SpatialError> {
    validate(positions, &[])?;
    let Some(first) = positions.first() else {
        return Ok(0.0);
    };
    let (lo, hi) = positions.iter().fold((*first, *first), |(lo, hi), p| {
        (
            [0, 1, 2].map(|k| lo[k].min(p[k])),
            [0, 1, 2].map(|k| hi[k].max(p[k])),
        )
    });
    Ok(distance_2(&hi, &lo).sqrt())
}
