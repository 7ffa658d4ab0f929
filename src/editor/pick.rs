//! Picking: a ray cast against a bounding volume hierarchy over the tessellation's triangles, exact
//! to the triangle and its barycentric coordinates (f64 throughout), and the manifold point there.
//!
//! The hierarchy is built once per tessellation (median splits along the longest axis of the
//! centroids' box) and *refitted* after an edit: the triangles keep their places in the tree and only
//! the boxes grow or shrink, which is O(n) and keeps picking exact; a drag changes the shape little,
//! so the tree stays good. (An R-tree, as `spatial` uses, would have to be rebuilt after every edit.)

use charts::ChartPoint;

use super::mesh::ChartTriangles;
use embedding::Point3;
use num_complex::Complex64;

use super::camera::Ray;

/// What the ray hit: the triangle, the barycentric coordinates of the hit on it (they sum to 1,
/// weighting its corners in order), and the ray parameter (distance from the eye).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub triangle: u32,
    pub bary: [f64; 3],
    pub t: f64,
}

impl Hit {
    /// The hit as a chart point: the barycentric combination of the triangle's corners in its home
    /// chart (the chart domains are convex, so the point lies in that chart).
    pub fn chart_point(&self, tessellation: &ChartTriangles) -> ChartPoint {
        let k = self.triangle as usize;
        let corners = tessellation.triangle_coords[k];
        let coords: Complex64 = corners.iter().zip(self.bary).map(|(c, b)| c * b).sum();
        ChartPoint::new(tessellation.triangle_charts[k], coords)
    }
}

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Leaf: first index into `order`; inner: the right child (the left one is the next node).
    first: u32,
    /// Leaf: how many triangles (≥ 1); inner: 0.
    count: u32,
}

/// A bounding volume hierarchy over triangles.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const LEAF: usize = 4;

impl Bvh {
    pub fn build(positions: &[Point3], triangles: &[[u32; 3]]) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * triangles.len() / LEAF + 1),
            order: (0..triangles.len() as u32).collect(),
        };
        if triangles.is_empty() {
            return bvh;
        }
        let centroids: Vec<[f64; 3]> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| positions[v as usize]);
                let m = (a.coords + b.coords + c.coords) / 3.0;
                [m.x, m.y, m.z]
            })
            .collect();
        build_node(&mut bvh, &centroids, 0, triangles.len());
        bvh.refit(positions, triangles);
        bvh
    }

    /// Recomputes every box from the current positions (same triangles, same tree).
    pub fn refit(&mut self, positions: &[Point3], triangles: &[[u32; 3]]) {
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for &t in &self.order[range] {
                    for &v in &triangles[t as usize] {
                        let p = positions[v as usize];
                        for a in 0..3 {
                            lo[a] = lo[a].min(p[a]);
                            hi[a] = hi[a].max(p[a]);
                        }
                    }
                }
            } else {
                for child in [i + 1, node.first as usize] {
                    for a in 0..3 {
                        lo[a] = lo[a].min(self.nodes[child].lo[a]);
                        hi[a] = hi[a].max(self.nodes[child].hi[a]);
                    }
                }
            }
            self.nodes[i].lo = lo;
            self.nodes[i].hi = hi;
        }
    }

    /// The nearest hit in front of the ray's origin, if any.
    pub fn cast(&self, ray: &Ray, positions: &[Point3], triangles: &[[u32; 3]]) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let inverse = [0, 1, 2].map(|a| 1.0 / ray.direction[a]);
        let mut best: Option<Hit> = None;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            let limit = best.map_or(f64::INFINITY, |h| h.t);
            if !slab(ray, &inverse, node, limit) {
                continue;
            }
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for &t in &self.order[range] {
                    let corners = triangles[t as usize].map(|v| positions[v as usize]);
                    if let Some((s, bary)) = intersect(ray, corners)
                        && s < best.map_or(f64::INFINITY, |h| h.t)
                    {
                        best = Some(Hit {
                            triangle: t,
                            bary,
                            t: s,
                        });
                    }
                }
            } else {
                stack.push(node.first as usize);
                stack.push(i + 1);
            }
        }
        best
    }

    /// Node count (for tests and the status bar).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// Builds the subtree over `order[start..end]` in pre-order (left child right after its parent) and
/// returns its index. Depth is about log2(n / LEAF), so recursion is safe.
fn build_node(bvh: &mut Bvh, centroids: &[[f64; 3]], start: usize, end: usize) -> usize {
    let node = bvh.nodes.len();
    bvh.nodes.push(empty_node());
    if end - start <= LEAF {
        bvh.nodes[node].first = start as u32;
        bvh.nodes[node].count = (end - start) as u32;
        return node;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &t in &bvh.order[start..end] {
        for a in 0..3 {
            lo[a] = lo[a].min(centroids[t as usize][a]);
            hi[a] = hi[a].max(centroids[t as usize][a]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let mid = (start + end) / 2;
    bvh.order[start..end].select_nth_unstable_by(mid - start, |&x, &y| {
        centroids[x as usize][axis].total_cmp(&centroids[y as usize][axis])
    });
    build_node(bvh, centroids, start, mid);
    let right = build_node(bvh, centroids, mid, end);
    bvh.nodes[node].first = right as u32;
    node
}

fn empty_node() -> Node {
    Node {
        lo: [0.0; 3],
        hi: [0.0; 3],
        first: 0,
        count: 0,
    }
}

/// Does the ray meet the box before `limit`? (The slab test, with a relative margin so that a ray
/// grazing a flat box is not lost to rounding.)
fn slab(ray: &Ray, inverse: &[f64; 3], node: &Node, limit: f64) -> bool {
    let (mut t0, mut t1) = (0.0f64, limit);
    for (a, inv) in inverse.iter().enumerate() {
        let pad = 1e-12
            * (node.hi[a] - node.lo[a])
                .abs()
                .max(node.lo[a].abs())
                .max(1.0);
        let (lo, hi) = (node.lo[a] - pad, node.hi[a] + pad);
        let (mut near, mut far) = ((lo - ray.origin[a]) * inv, (hi - ray.origin[a]) * inv);
        if near > far {
            std::mem::swap(&mut near, &mut far);
        }
        // NaN (the ray parallel to a slab and starting on its plane) keeps the box.
        if near > t0 {
            t0 = near;
        }
        if far < t1 {
            t1 = far;
        }
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Möller–Trumbore: the ray parameter and the barycentric coordinates of the hit, if the ray meets
/// the triangle in front of its origin. Edges count as inside (up to a relative 1e-12), so a ray
/// through a shared edge is not lost between two triangles.
pub fn intersect(ray: &Ray, [a, b, c]: [Point3; 3]) -> Option<(f64, [f64; 3])> {
    const EPS: f64 = 1e-12;
    let (e1, e2) = (b - a, c - a);
    let p = ray.direction.cross(&e2);
    let det = e1.dot(&p);
    if det.abs() <= f64::MIN_POSITIVE || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.origin - a;
    let u = s.dot(&p) * inv;
    if !(-EPS..=1.0 + EPS).contains(&u) {
        return None;
    }
    let q = s.cross(&e1);
    let v = ray.direction.dot(&q) * inv;
    if v < -EPS || u + v > 1.0 + EPS {
        return None;
    }
    let t = e2.dot(&q) * inv;
    (t > 0.0).then_some((t, [1.0 - u - v, u, v]))
}

/// Every triangle the ray meets, nearest first: the brute-force reference the tests compare with.
pub fn cast_all(ray: &Ray, positions: &[Point3], triangles: &[[u32; 3]]) -> Option<Hit> {
    triangles
        .iter()
        .enumerate()
        .filter_map(|(k, t)| {
            intersect(ray, t.map(|v| positions[v as usize])).map(|(s, bary)| Hit {
                triangle: k as u32,
                bary,
                t: s,
            })
        })
        .min_by(|x, y| x.t.total_cmp(&y.t))
}
