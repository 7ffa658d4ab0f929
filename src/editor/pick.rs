//! Picking: a ray cast against a bounding volume hierarchy over the tessellation's triangles, exact
//! to the triangle and its barycentric coordinates (f64 throughout), and the manifold point there.
//!
//! The hierarchy is built once per tessellation (median splits along the longest axis of the
//! centroids' box) and *refitted* after an edit: the triangles keep their places in the tree and only
//! the boxes grow or shrink, which is O(n) and keeps picking exact; a drag changes the shape little,
//! so the tree stays good. (An R-tree, as `spatial` uses, would have to be rebuilt after every edit.)
//! After a brush's dab, which moves a small part of a large mesh, only the leaves holding a moved
//! vertex and their ancestors are refitted ([`Bvh::refit_vertices`]): at 10⁶ vertices a whole
//! refit takes about 30 ms, longer than the dab.

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
    /// Made at the first partial refit: each node's parent, and each vertex's leaves.
    links: Option<Links>,
}

/// What a partial refit walks: from a moved vertex to the leaves holding its triangles, and up.
#[derive(Clone, Debug, Default)]
struct Links {
    /// Per node, its parent (the root's is itself).
    parents: Vec<u32>,
    /// Vertex v's leaves are `leaves[starts[v]..starts[v + 1]]`.
    starts: Vec<u32>,
    leaves: Vec<u32>,
    /// The triangles' corners in the tree's order (`order`), so a leaf's are read in one run.
    corners: Vec<[u32; 3]>,
}

impl Links {
    fn new(bvh: &Bvh, triangles: &[[u32; 3]], vertex_count: usize) -> Links {
        let mut parents = vec![0u32; bvh.nodes.len()];
        let mut leaf_of = vec![0u32; triangles.len()];
        for (i, node) in bvh.nodes.iter().enumerate() {
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for &t in &bvh.order[range] {
                    leaf_of[t as usize] = i as u32;
                }
            } else {
                parents[i + 1] = i as u32;
                parents[node.first as usize] = i as u32;
            }
        }
        // Each vertex's (leaf) pairs, grouped by vertex and without repeats.
        let mut pairs: Vec<(u32, u32)> = triangles
            .iter()
            .zip(&leaf_of)
            .flat_map(|(t, &leaf)| t.map(|v| (v, leaf)))
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        let mut starts = vec![0u32; vertex_count + 1];
        for &(v, _) in &pairs {
            starts[v as usize + 1] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        let leaves = pairs.into_iter().map(|(_, leaf)| leaf).collect();
        let corners = bvh.order.iter().map(|&t| triangles[t as usize]).collect();
        Links {
            parents,
            starts,
            leaves,
            corners,
        }
    }
}

const LEAF: usize = 4;

impl Bvh {
    pub fn build(positions: &[Point3], triangles: &[[u32; 3]]) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * triangles.len() / LEAF + 1),
            order: (0..triangles.len() as u32).collect(),
            links: None,
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
            self.fit_node(i, positions, triangles);
        }
    }

    /// Recomputes the boxes that hold a vertex of `moved` (each vertex index in any order, as
    /// often as it comes): the leaves with a triangle at one, then their ancestors, children
    /// before parents (a node's children follow it in the array). The same boxes as
    /// [`Bvh::refit`] where only those vertices moved.
    pub fn refit_vertices(
        &mut self,
        positions: &[Point3],
        triangles: &[[u32; 3]],
        moved: impl IntoIterator<Item = u32>,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let links = self
            .links
            .take()
            .unwrap_or_else(|| Links::new(self, triangles, positions.len()));
        let mut marked = vec![0u64; self.nodes.len().div_ceil(64)];
        for v in moved {
            let v = v as usize;
            for &leaf in &links.leaves[links.starts[v] as usize..links.starts[v + 1] as usize] {
                let mut i = leaf as usize;
                // Up to the root, or to a node already marked (its ancestors are too).
                while marked[i / 64] & (1 << (i % 64)) == 0 {
                    marked[i / 64] |= 1 << (i % 64);
                    i = links.parents[i] as usize;
                }
            }
        }
        // Children first: a node's children follow it in the array.
        for (w, &word) in marked.iter().enumerate().rev() {
            let mut bits = word;
            while bits != 0 {
                let top = 63 - bits.leading_zeros() as usize;
                self.fit_node_from(w * 64 + top, positions, &links.corners);
                bits &= !(1 << top);
            }
        }
        self.links = Some(links);
    }

    /// Node `i`'s box anew, from its triangles (a leaf) or its children's boxes.
    fn fit_node(&mut self, i: usize, positions: &[Point3], triangles: &[[u32; 3]]) {
        let node = self.nodes[i];
        let range = node.first as usize..(node.first + node.count) as usize;
        let corners = self.order[range].iter().map(|&t| &triangles[t as usize]);
        (self.nodes[i].lo, self.nodes[i].hi) = self.node_box(i, positions, corners);
    }

    /// [`Bvh::fit_node`] with the triangles' corners in the tree's order ([`Links::corners`]).
    fn fit_node_from(&mut self, i: usize, positions: &[Point3], corners: &[[u32; 3]]) {
        let node = self.nodes[i];
        let range = node.first as usize..(node.first + node.count) as usize;
        (self.nodes[i].lo, self.nodes[i].hi) = self.node_box(i, positions, corners[range].iter());
    }

    /// Node `i`'s box from the corners of its triangles (a leaf) or from its children's boxes.
    fn node_box<'a>(
        &self,
        i: usize,
        positions: &[Point3],
        corners: impl Iterator<Item = &'a [u32; 3]>,
    ) -> ([f64; 3], [f64; 3]) {
        let node = self.nodes[i];
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        if node.count > 0 {
            for triangle in corners {
                for &v in triangle {
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
        (lo, hi)
    }

    /// The nearest hit in front of the ray's origin, if any, with every box grown by `pad` on
    /// each side (vertices may have moved by that much since the boxes were fitted: the hit is
    /// still exact, the triangles are tested where they are).
    pub fn cast(
        &self,
        ray: &Ray,
        positions: &[Point3],
        triangles: &[[u32; 3]],
        pad: f64,
    ) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let inverse = [0, 1, 2].map(|a| 1.0 / ray.direction[a]);
        let mut best: Option<Hit> = None;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            let limit = best.map_or(f64::INFINITY, |h| h.t);
            if !slab(ray, &inverse, node, limit, pad) {
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

/// Does the ray meet the box, grown by `grow` on each side, before `limit`? (The slab test, with
/// a relative margin so that a ray grazing a flat box is not lost to rounding.)
fn slab(ray: &Ray, inverse: &[f64; 3], node: &Node, limit: f64, grow: f64) -> bool {
    let (mut t0, mut t1) = (0.0f64, limit);
    for (a, inv) in inverse.iter().enumerate() {
        let pad = grow
            + 1e-12
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// An n × n grid of vertices at given heights, two triangles per cell.
    fn grid(n: u32, heights: &[f64]) -> (Vec<Point3>, Vec<[u32; 3]>) {
        let positions = (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                Point3::new(
                    f64::from(i),
                    f64::from(j),
                    heights[k as usize % heights.len()],
                )
            })
            .collect();
        let triangles = (0..n - 1)
            .flat_map(|j| (0..n - 1).map(move |i| (i, j)))
            .flat_map(|(i, j)| {
                let k = j * n + i;
                [[k, k + 1, k + n + 1], [k, k + n + 1, k + n]]
            })
            .collect();
        (positions, triangles)
    }

    fn boxes(bvh: &Bvh) -> Vec<([f64; 3], [f64; 3])> {
        bvh.nodes.iter().map(|n| (n.lo, n.hi)).collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// After some vertices move (once or over several rounds, the links made at the first),
        /// refitting only their boxes gives every box a whole refit gives.
        #[test]
        fn a_partial_refit_gives_the_boxes_of_a_whole_one(
            n in 2u32..24,
            heights in prop::collection::vec(-1.0f64..1.0, 1..50),
            rounds in prop::collection::vec(
                prop::collection::vec((0usize..10_000, prop::array::uniform3(-3.0f64..3.0)), 0..40),
                1..4,
            ),
        ) {
            let (mut positions, triangles) = grid(n, &heights);
            let mut partial = Bvh::build(&positions, &triangles);
            for moves in rounds {
                for &(k, d) in &moves {
                    let v = k % positions.len();
                    positions[v] += embedding::Vector3::from(d);
                }
                let moved: Vec<u32> = moves.iter().map(|&(k, _)| (k % positions.len()) as u32).collect();
                partial.refit_vertices(&positions, &triangles, moved);
                let mut whole = partial.clone();
                whole.refit(&positions, &triangles);
                prop_assert_eq!(boxes(&partial), boxes(&whole));
            }
        }

        /// After vertices move by at most `pad` with the boxes left as they were, a ray cast
        /// against the boxes grown by `pad` hits what testing every triangle hits (a grid of
        /// rays over the mesh, tilted).
        #[test]
        fn a_grown_cast_finds_what_moved_out_of_its_box(
            n in 2u32..16,
            heights in prop::collection::vec(-1.0f64..1.0, 1..50),
            moves in prop::collection::vec((0usize..10_000, prop::array::uniform3(-1.0f64..1.0)), 1..60),
            pad in 0.2f64..2.0,
            tilt in prop::array::uniform2(-0.3f64..0.3),
        ) {
            let (mut positions, triangles) = grid(n, &heights);
            let bvh = Bvh::build(&positions, &triangles);
            // Each vertex once, by less than `pad`.
            let mut moved = vec![false; positions.len()];
            for &(k, d) in &moves {
                let v = k % positions.len();
                let d = embedding::Vector3::from(d);
                if !std::mem::replace(&mut moved[v], true) {
                    positions[v] += d * (pad / d.norm().max(1e-9) / 1.01);
                }
            }
            let direction = embedding::Vector3::new(tilt[0], tilt[1], -1.0).normalize();
            let steps = 4 * n;
            for k in 0..steps * steps {
                let (i, j) = (k % steps, k / steps);
                let at = |i: u32| f64::from(i) * f64::from(n) / f64::from(steps) - 0.5;
                let ray = Ray { origin: Point3::new(at(i), at(j), 5.0), direction };
                let found = bvh.cast(&ray, &positions, &triangles, pad);
                let truth = cast_all(&ray, &positions, &triangles);
                prop_assert_eq!(found.map(|h| h.t), truth.map(|h| h.t), "ray {}", k);
            }
        }
    }
}
