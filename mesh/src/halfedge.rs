//! A half-edge mesh built from any polygon list, and its topology checks.
//!
//! Connectivity knows no positions: everything here runs on vertex indices alone. Building never fails
//! on bad topology; it records it, and [`HalfEdgeMesh::topology`] reports it (edges with more than two
//! faces, faces that disagree on an edge's direction, vertices whose link is not one cycle or one fan).
//! Only malformed input (an index out of range, a face with fewer than three distinct vertices) is an
//! error.
//!
//! ```
//! use mesh::HalfEdgeMesh;
//! // A tetrahedron: closed, orientable, genus 0.
//! let faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
//! let mesh = HalfEdgeMesh::from_polygons(4, faces.iter().map(|f| &f[..])).unwrap();
//! let t = mesh.topology();
//! assert_eq!((t.euler_characteristic, t.genus), (2, Some(0)));
//! assert!(t.closed && t.manifold && t.orientable);
//! ```

use std::collections::HashMap;

use serde::Serialize;

const NONE: u32 = u32::MAX;

/// An undirected edge: its endpoints (smaller first) and its label.
type EdgeKey = (u32, u32, u32);

/// Malformed polygon input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("face {face} refers to vertex {index}, but there are only {vertex_count} vertices")]
    IndexOutOfRange {
        face: usize,
        index: u32,
        vertex_count: usize,
    },
    #[error("face {face} has fewer than three distinct vertices: {vertices:?}")]
    DegenerateFace { face: usize, vertices: Vec<u32> },
    #[error("face {face} has {sides} sides but {labels} edge labels")]
    LabelCount {
        face: usize,
        sides: usize,
        labels: usize,
    },
    #[error("{0} vertices or half-edges is more than this mesh can index")]
    TooLarge(usize),
}

/// Half-edges stored as parallel arrays; face f's half-edges are `face_start[f]..face_start[f + 1]`,
/// in order, so `next` is implicit.
#[derive(Clone, Debug)]
pub struct HalfEdgeMesh {
    vertex_count: usize,
    origin: Vec<u32>,
    /// Per half-edge: the label of its edge (0 unless built from labelled polygons).
    label: Vec<u32>,
    twin: Vec<u32>,
    face_of: Vec<u32>,
    face_start: Vec<u32>,
    nonmanifold_edges: usize,
    misoriented_edges: usize,
}

/// What [`HalfEdgeMesh::topology`] finds.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Topology {
    pub vertices: usize,
    pub edges: usize,
    pub faces: usize,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Edges with more than two faces.
    pub nonmanifold_edges: usize,
    /// Edges whose two faces run along them in the same direction.
    pub misoriented_edges: usize,
    /// Vertices (used by some face) whose link is not a single cycle or a single fan.
    pub nonmanifold_vertices: usize,
    /// Vertices no face uses.
    pub isolated_vertices: usize,
    /// Connected components (isolated vertices count as components).
    pub components: usize,
    pub boundary_loops: usize,
    /// Whether the faces can be oriented consistently (flipping some if need be).
    pub orientable: bool,
    /// Every edge has two faces.
    pub closed: bool,
    /// No non-manifold edges or vertices.
    pub manifold: bool,
    pub euler_characteristic: i64,
    /// For a connected orientable manifold: (2 − χ − boundary loops)/2.
    pub genus: Option<u32>,
}

impl HalfEdgeMesh {
    /// Builds the mesh; faces are vertex-index cycles (any length ≥ 3). Edges are identified by their
    /// two endpoints.
    pub fn from_polygons<'a>(
        vertex_count: usize,
        polygons: impl IntoIterator<Item = &'a [u32]>,
    ) -> Result<HalfEdgeMesh, MeshError> {
        Self::from_labelled_polygons(vertex_count, polygons.into_iter().map(|p| (p, None)))
    }

    /// Like [`HalfEdgeMesh::from_polygons`], for complexes where two different edges may join the same
    /// two vertices (a cell complex's coarsest level often does): each face comes with a label per
    /// side (side i runs from corner i to corner i + 1), and edges are identified by their endpoints
    /// and label together.
    pub fn from_labelled_polygons<'a>(
        vertex_count: usize,
        polygons: impl IntoIterator<Item = (&'a [u32], Option<&'a [u32]>)>,
    ) -> Result<HalfEdgeMesh, MeshError> {
        if vertex_count >= NONE as usize {
            return Err(MeshError::TooLarge(vertex_count));
        }
        let (mut origin, mut face_of, mut face_start) = (Vec::new(), Vec::new(), vec![0u32]);
        let mut label = Vec::new();
        for (f, (poly, labels)) in polygons.into_iter().enumerate() {
            if let Some(&bad) = poly.iter().find(|&&v| v as usize >= vertex_count) {
                return Err(MeshError::IndexOutOfRange {
                    face: f,
                    index: bad,
                    vertex_count,
                });
            }
            let mut distinct = poly.to_vec();
            distinct.sort_unstable();
            distinct.dedup();
            if poly.len() < 3 || distinct.len() != poly.len() {
                return Err(MeshError::DegenerateFace {
                    face: f,
                    vertices: poly.to_vec(),
                });
            }
            origin.extend_from_slice(poly);
            match labels {
                Some(l) if l.len() == poly.len() => label.extend_from_slice(l),
                Some(l) => {
                    return Err(MeshError::LabelCount {
                        face: f,
                        sides: poly.len(),
                        labels: l.len(),
                    });
                }
                None => label.extend(std::iter::repeat_n(0, poly.len())),
            }
            face_of.extend(std::iter::repeat_n(f as u32, poly.len()));
            if origin.len() >= NONE as usize {
                return Err(MeshError::TooLarge(origin.len()));
            }
            face_start.push(origin.len() as u32);
        }
        let mut mesh = HalfEdgeMesh {
            vertex_count,
            twin: vec![NONE; origin.len()],
            origin,
            label,
            face_of,
            face_start,
            nonmanifold_edges: 0,
            misoriented_edges: 0,
        };
        mesh.pair_twins();
        Ok(mesh)
    }

    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }
    pub fn face_count(&self) -> usize {
        self.face_start.len() - 1
    }
    pub fn halfedge_count(&self) -> usize {
        self.origin.len()
    }

    /// The half-edge after h in its face.
    pub fn next(&self, h: u32) -> u32 {
        let f = self.face_of[h as usize] as usize;
        if h + 1 == self.face_start[f + 1] {
            self.face_start[f]
        } else {
            h + 1
        }
    }

    /// The half-edge before h in its face.
    pub fn prev(&self, h: u32) -> u32 {
        let f = self.face_of[h as usize] as usize;
        if h == self.face_start[f] {
            self.face_start[f + 1] - 1
        } else {
            h - 1
        }
    }

    /// The face half-edge h belongs to.
    pub fn face(&self, h: u32) -> u32 {
        self.face_of[h as usize]
    }

    /// Face f's half-edges, in order: side i runs from corner i to corner i + 1.
    pub fn face_halfedges(&self, f: u32) -> std::ops::Range<u32> {
        self.face_start[f as usize]..self.face_start[f as usize + 1]
    }

    /// Every vertex's outgoing half-edges (unordered).
    pub fn outgoing(&self) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.vertex_count];
        for (h, &v) in self.origin.iter().enumerate() {
            out[v as usize].push(h as u32);
        }
        out
    }

    pub fn origin(&self, h: u32) -> u32 {
        self.origin[h as usize]
    }
    pub fn target(&self, h: u32) -> u32 {
        self.origin[self.next(h) as usize]
    }
    /// The opposite half-edge, if the edge has exactly two consistently oriented faces.
    pub fn twin(&self, h: u32) -> Option<u32> {
        Some(self.twin[h as usize]).filter(|&t| t != NONE)
    }

    fn key(&self, h: u32) -> EdgeKey {
        let (a, b) = (self.origin(h), self.target(h));
        (a.min(b), a.max(b), self.label[h as usize])
    }

    /// Groups half-edges by undirected edge and pairs the well-behaved ones.
    fn edge_groups(&self) -> HashMap<EdgeKey, Vec<u32>> {
        let mut groups: HashMap<EdgeKey, Vec<u32>> = HashMap::with_capacity(self.origin.len());
        for h in 0..self.origin.len() as u32 {
            groups.entry(self.key(h)).or_default().push(h);
        }
        groups
    }

    fn pair_twins(&mut self) {
        let groups = self.edge_groups();
        for hs in groups.values() {
            match hs[..] {
                [a, b] if self.origin(a) == self.target(b) => {
                    self.twin[a as usize] = b;
                    self.twin[b as usize] = a;
                }
                [_, _] => self.misoriented_edges += 1,
                [_] => {}
                _ => self.nonmanifold_edges += 1,
            }
        }
    }

    /// All the checks, on indices alone.
    pub fn topology(&self) -> Topology {
        let groups = self.edge_groups();
        let edges = groups.len();
        let boundary_edges = groups.values().filter(|hs| hs.len() == 1).count();
        let faces = self.face_count();
        let euler = self.vertex_count as i64 - edges as i64 + faces as i64;
        let (used, nonmanifold_vertices) = self.vertex_links();
        let isolated = used.iter().filter(|&&u| !u).count();
        let components = self.face_components() + isolated;
        let orientable = self.orientable(&groups);
        let boundary_loops = self.boundary_loops(&groups);
        let manifold = self.nonmanifold_edges == 0 && nonmanifold_vertices == 0;
        let genus = (manifold && orientable && components == 1 && isolated == 0)
            .then(|| 2 - euler - boundary_loops as i64)
            .filter(|g| *g >= 0 && g % 2 == 0)
            .map(|g| (g / 2) as u32);
        Topology {
            vertices: self.vertex_count,
            edges,
            faces,
            boundary_edges,
            nonmanifold_edges: self.nonmanifold_edges,
            misoriented_edges: self.misoriented_edges,
            nonmanifold_vertices,
            isolated_vertices: isolated,
            components,
            boundary_loops,
            orientable,
            closed: boundary_edges == 0 && self.nonmanifold_edges == 0,
            manifold,
            euler_characteristic: euler,
            genus,
        }
    }

    /// Which vertices are used, and how many used vertices are not manifold. The faces at a manifold
    /// vertex form one fan or one closed ring: its corners, joined whenever two share an edge at the
    /// vertex, are connected, and no edge there has more than two corners. Orientation plays no part
    /// (a misoriented edge still joins its two faces), and multigraphs work through edge labels.
    fn vertex_links(&self) -> (Vec<bool>, usize) {
        let mut corners: Vec<Vec<u32>> = vec![Vec::new(); self.vertex_count];
        for h in 0..self.origin.len() as u32 {
            corners[self.origin(h) as usize].push(h);
        }
        let used: Vec<bool> = corners.iter().map(|c| !c.is_empty()).collect();
        let bad = corners
            .iter()
            .filter(|c| !c.is_empty() && !self.corners_form_one_fan(c))
            .count();
        (used, bad)
    }

    /// Corner h at v touches two edges at v: its own (leaving v) and its predecessor's (arriving).
    fn corners_form_one_fan(&self, corners: &[u32]) -> bool {
        let mut by_edge: HashMap<EdgeKey, Vec<u32>> = HashMap::new();
        for (i, &h) in corners.iter().enumerate() {
            by_edge.entry(self.key(h)).or_default().push(i as u32);
            by_edge
                .entry(self.key(self.prev(h)))
                .or_default()
                .push(i as u32);
        }
        let mut uf = UnionFind::new(corners.len());
        for at in by_edge.values() {
            if at.len() > 2 {
                return false;
            }
            if let [a, b] = at[..] {
                uf.union(a, b);
            }
        }
        let root = uf.find(0);
        (0..corners.len() as u32).all(|i| uf.find(i) == root)
    }

    fn face_components(&self) -> usize {
        let mut uf = UnionFind::new(self.vertex_count);
        for h in 0..self.origin.len() as u32 {
            uf.union(self.origin(h), self.target(h));
        }
        let mut roots: Vec<u32> = (0..self.origin.len() as u32)
            .map(|h| uf.find(self.origin(h)))
            .collect();
        roots.sort_unstable();
        roots.dedup();
        roots.len()
    }

    /// Two-colours faces by orientation across every two-face edge; a conflict means non-orientable.
    fn orientable(&self, groups: &HashMap<EdgeKey, Vec<u32>>) -> bool {
        let faces = self.face_count();
        let mut neighbours: Vec<Vec<(u32, bool)>> = vec![Vec::new(); faces];
        for hs in groups.values() {
            if let [a, b] = hs[..] {
                let flip = self.origin(a) == self.origin(b);
                let (fa, fb) = (self.face_of[a as usize], self.face_of[b as usize]);
                neighbours[fa as usize].push((fb, flip));
                neighbours[fb as usize].push((fa, flip));
            }
        }
        let mut side: Vec<Option<bool>> = vec![None; faces];
        for start in 0..faces {
            if side[start].is_some() {
                continue;
            }
            side[start] = Some(false);
            let mut stack = vec![start as u32];
            while let Some(f) = stack.pop() {
                let s = side[f as usize].unwrap_or(false);
                for &(g, flip) in &neighbours[f as usize] {
                    match side[g as usize] {
                        None => {
                            side[g as usize] = Some(s ^ flip);
                            stack.push(g);
                        }
                        Some(t) if t != s ^ flip => return false,
                        Some(_) => {}
                    }
                }
            }
        }
        true
    }

    /// Counts boundary cycles: from each unvisited boundary half-edge, walk to the boundary half-edge
    /// leaving its target.
    fn boundary_loops(&self, groups: &HashMap<EdgeKey, Vec<u32>>) -> usize {
        let boundary: Vec<u32> = groups
            .values()
            .filter(|hs| hs.len() == 1)
            .map(|hs| hs[0])
            .collect();
        let leaving: HashMap<u32, u32> = boundary.iter().map(|&h| (self.origin(h), h)).collect();
        let mut seen: HashMap<u32, bool> = boundary.iter().map(|&h| (h, false)).collect();
        let mut loops = 0;
        for &h in &boundary {
            if seen[&h] {
                continue;
            }
            loops += 1;
            let mut cur = h;
            while let Some(flag) = seen.get_mut(&cur) {
                if *flag {
                    break;
                }
                *flag = true;
                match leaving.get(&self.target(cur)) {
                    Some(&n) => cur = n,
                    None => break,
                }
            }
        }
        loops
    }
}

/// Disjoint sets of indices (path halving), for the mesh's own checks.
pub(crate) struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
        }
    }
    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
        }
        x
    }
    /// Joins the sets of a and b; false if they were one already.
    pub(crate) fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra as usize] = rb;
        }
        ra != rb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(n: usize, faces: &[&[u32]]) -> HalfEdgeMesh {
        HalfEdgeMesh::from_polygons(n, faces.iter().copied()).unwrap()
    }

    #[test]
    fn a_single_triangle_is_a_disk() {
        let t = mesh(3, &[&[0, 1, 2]]).topology();
        assert_eq!(
            (t.boundary_edges, t.boundary_loops, t.euler_characteristic),
            (3, 1, 1)
        );
        assert!(t.manifold && t.orientable && !t.closed);
        assert_eq!(t.genus, Some(0));
    }

    #[test]
    fn an_open_book_is_not_a_manifold() {
        // Three triangles on one edge.
        let t = mesh(5, &[&[0, 1, 2], &[1, 0, 3], &[0, 1, 4]]).topology();
        assert_eq!(t.nonmanifold_edges, 1);
        assert!(!t.manifold);
    }

    #[test]
    fn a_bow_tie_vertex_is_not_a_manifold() {
        // Two triangles sharing only vertex 0.
        let t = mesh(5, &[&[0, 1, 2], &[0, 3, 4]]).topology();
        assert_eq!(t.nonmanifold_vertices, 1);
        assert_eq!(t.components, 1);
    }

    #[test]
    fn a_flipped_face_is_misoriented_but_orientable() {
        let t = mesh(4, &[&[0, 1, 2], &[0, 1, 3]]).topology();
        assert_eq!(t.misoriented_edges, 1);
        assert!(t.orientable);
    }

    #[test]
    fn a_moebius_strip_is_not_orientable() {
        // Five-triangle Möbius band on vertices 0..5.
        let faces: [&[u32]; 5] = [&[0, 1, 2], &[1, 2, 3], &[2, 3, 4], &[3, 4, 0], &[4, 0, 1]];
        let t = mesh(5, &faces).topology();
        assert!(!t.orientable);
        assert_eq!(t.boundary_loops, 1);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(matches!(
            HalfEdgeMesh::from_polygons(3, [&[0u32, 1, 5][..]]),
            Err(MeshError::IndexOutOfRange { index: 5, .. })
        ));
        assert!(matches!(
            HalfEdgeMesh::from_polygons(3, [&[0u32, 1, 1][..]]),
            Err(MeshError::DegenerateFace { .. })
        ));
    }

    #[test]
    fn labels_tell_apart_two_edges_between_the_same_vertices() {
        // A sphere cut into two lunes by two different edges from 0 to 1 (labels 1 and 2), with
        // vertex 2 inside one lune and 3 inside the other. Without labels the two edges 0–1 merge
        // into one edge with four faces.
        let faces: [&[u32]; 4] = [&[0, 1, 2], &[1, 0, 2], &[1, 0, 3], &[0, 1, 3]];
        let plain = mesh(4, &faces).topology();
        assert_eq!(plain.nonmanifold_edges, 1);
        let labels: [&[u32]; 4] = [&[1, 0, 0], &[2, 0, 0], &[1, 0, 0], &[2, 0, 0]];
        let labelled = HalfEdgeMesh::from_labelled_polygons(
            4,
            faces.iter().copied().zip(labels.iter().map(|l| Some(*l))),
        )
        .unwrap()
        .topology();
        assert!(
            labelled.manifold && labelled.closed && labelled.orientable,
            "{labelled:?}"
        );
        assert_eq!(labelled.euler_characteristic, 4 - 6 + 4);
    }

    #[test]
    fn isolated_vertices_are_counted() {
        let t = mesh(4, &[&[0, 1, 2]]).topology();
        assert_eq!((t.isolated_vertices, t.components), (1, 2));
        assert_eq!(t.genus, None);
    }
}
