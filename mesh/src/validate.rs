//! Locating what [`HalfEdgeMesh::topology`] counts: which edge is non-manifold, which vertex, where a
//! boundary loop runs, where consistent orientation breaks down, which faces form a component.
//!
//! [`Topology`](crate::Topology) answers "is it closed, manifold, orientable"; the functions here
//! answer "where not", in indices only (a caller with positions turns them into places a person can
//! find). Every "first" is the first in face order, so answers are deterministic. Edges are
//! identified by their two endpoints (edge labels play no part: these are for plain meshes, such as
//! a user's file).
//!
//! ```
//! use mesh::HalfEdgeMesh;
//! use mesh::validate::{boundary_loops, orient};
//!
//! // Two triangles of a square, the second one flipped.
//! let faces = [[0u32, 1, 2], [0, 2, 3]];
//! let flipped = [[0u32, 1, 2], [0, 3, 2]];
//! let mesh = HalfEdgeMesh::from_polygons(4, flipped.iter().map(|f| &f[..])).unwrap();
//! assert_eq!(orient(&mesh), Ok(vec![false, true]));
//! let square = HalfEdgeMesh::from_polygons(4, faces.iter().map(|f| &f[..])).unwrap();
//! assert_eq!(boundary_loops(&square), vec![vec![0, 1, 2, 3]]);
//! ```

use std::collections::HashMap;

use crate::HalfEdgeMesh;
use crate::halfedge::UnionFind;

/// Half-edges grouped by undirected edge (smaller endpoint first), groups in order of their first
/// half-edge.
fn edge_groups(mesh: &HalfEdgeMesh) -> Vec<((u32, u32), Vec<u32>)> {
    let mut at: HashMap<(u32, u32), usize> = HashMap::with_capacity(mesh.halfedge_count());
    let mut groups: Vec<((u32, u32), Vec<u32>)> = Vec::new();
    for h in 0..mesh.halfedge_count() as u32 {
        let (a, b) = (mesh.origin(h), mesh.target(h));
        let key = (a.min(b), a.max(b));
        let slot = *at.entry(key).or_insert_with(|| {
            groups.push((key, Vec::new()));
            groups.len() - 1
        });
        groups[slot].1.push(h);
    }
    groups
}

/// Edges with more than two faces, as (smaller endpoint, larger endpoint, number of faces), in order
/// of first appearance.
pub fn nonmanifold_edges(mesh: &HalfEdgeMesh) -> Vec<(u32, u32, usize)> {
    edge_groups(mesh)
        .into_iter()
        .filter(|(_, hs)| hs.len() > 2)
        .map(|((a, b), hs)| (a, b, hs.len()))
        .collect()
}

/// Used vertices whose faces do not form one fan or one closed ring (a bow tie, two cones touching
/// at a point), in increasing order. Vertices on non-manifold edges count too.
pub fn nonmanifold_vertices(mesh: &HalfEdgeMesh) -> Vec<u32> {
    let mut corners: Vec<Vec<u32>> = vec![Vec::new(); mesh.vertex_count()];
    for h in 0..mesh.halfedge_count() as u32 {
        corners[mesh.origin(h) as usize].push(h);
    }
    corners
        .iter()
        .enumerate()
        .filter(|(_, c)| !c.is_empty() && !one_fan(mesh, c))
        .map(|(v, _)| v as u32)
        .collect()
}

/// Corner h at v touches two edges at v: its own (leaving v) and its predecessor's (arriving).
fn one_fan(mesh: &HalfEdgeMesh, corners: &[u32]) -> bool {
    let key = |h: u32| {
        let (a, b) = (mesh.origin(h), mesh.target(h));
        (a.min(b), a.max(b))
    };
    let mut by_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (i, &h) in corners.iter().enumerate() {
        by_edge.entry(key(h)).or_default().push(i as u32);
        by_edge.entry(key(mesh.prev(h))).or_default().push(i as u32);
    }
    let mut sets = UnionFind::new(corners.len());
    for at in by_edge.values() {
        if at.len() > 2 {
            return false;
        }
        if let [a, b] = at[..] {
            sets.union(a, b);
        }
    }
    let root = sets.find(0);
    (0..corners.len() as u32).all(|i| sets.find(i) == root)
}

/// The boundary loops, each as its vertices in order (a loop of n vertices has n edges). On a
/// manifold mesh every boundary vertex has one boundary edge out, and the loops are cycles; where
/// it does not, a walk stops where it would repeat itself.
pub fn boundary_loops(mesh: &HalfEdgeMesh) -> Vec<Vec<u32>> {
    let boundary: Vec<u32> = edge_groups(mesh)
        .into_iter()
        .filter(|(_, hs)| hs.len() == 1)
        .map(|(_, hs)| hs[0])
        .collect();
    let mut leaving: HashMap<u32, u32> = HashMap::with_capacity(boundary.len());
    for &h in &boundary {
        leaving.entry(mesh.origin(h)).or_insert(h);
    }
    let mut seen: HashMap<u32, bool> = boundary.iter().map(|&h| (h, false)).collect();
    let mut loops = Vec::new();
    for &h in &boundary {
        if seen[&h] {
            continue;
        }
        let mut cycle = Vec::new();
        let mut cur = h;
        while let Some(flag) = seen.get_mut(&cur) {
            if *flag {
                break;
            }
            *flag = true;
            cycle.push(mesh.origin(cur));
            match leaving.get(&mesh.target(cur)) {
                Some(&n) => cur = n,
                None => break,
            }
        }
        loops.push(cycle);
    }
    loops
}

/// A face across an edge: the face, whether it must be reversed relative to this one, the edge.
type Neighbour = (u32, bool, (u32, u32));

/// For each face, whether to reverse it so that every edge with two faces is run along in opposite
/// directions by them (one orientation per component; the first face of each keeps its own). Edges
/// with one face or more than two play no part. A mesh that cannot be so oriented (a Möbius strip,
/// a Klein bottle) gives the edge, as (smaller endpoint, larger endpoint), where the search found
/// the conflict.
pub fn orient(mesh: &HalfEdgeMesh) -> Result<Vec<bool>, (u32, u32)> {
    let faces = mesh.face_count();
    let mut neighbours: Vec<Vec<Neighbour>> = vec![Vec::new(); faces];
    for (key, hs) in edge_groups(mesh) {
        if let [a, b] = hs[..] {
            let flip = mesh.origin(a) == mesh.origin(b);
            let (fa, fb) = (mesh.face(a), mesh.face(b));
            if fa == fb {
                // A face meeting itself along an edge: consistent only if it runs both ways.
                if flip {
                    return Err(key);
                }
                continue;
            }
            neighbours[fa as usize].push((fb, flip, key));
            neighbours[fb as usize].push((fa, flip, key));
        }
    }
    let mut side: Vec<Option<bool>> = vec![None; faces];
    for start in 0..faces {
        if side[start].is_some() {
            continue;
        }
        side[start] = Some(false);
        let mut queue = std::collections::VecDeque::from([start as u32]);
        while let Some(f) = queue.pop_front() {
            let s = side[f as usize].unwrap_or(false);
            for &(g, flip, key) in &neighbours[f as usize] {
                match side[g as usize] {
                    None => {
                        side[g as usize] = Some(s ^ flip);
                        queue.push_back(g);
                    }
                    Some(t) if t != s ^ flip => return Err(key),
                    Some(_) => {}
                }
            }
        }
    }
    Ok(side.into_iter().map(|s| s.unwrap_or(false)).collect())
}

/// Each polygon's connected component (polygons sharing a vertex are connected), numbered from 0 in
/// order of first appearance, and the number of components. Indices at or past `vertex_count` are
/// the caller's to have checked; they are ignored here.
pub fn face_components<'a>(
    vertex_count: usize,
    polygons: impl IntoIterator<Item = &'a [u32]> + Clone,
) -> (Vec<u32>, usize) {
    let mut sets = UnionFind::new(vertex_count);
    for poly in polygons.clone() {
        let mut inside = poly.iter().filter(|&&v| (v as usize) < vertex_count);
        if let Some(&first) = inside.next() {
            for &v in inside {
                sets.union(first, v);
            }
        }
    }
    let mut number: HashMap<u32, u32> = HashMap::new();
    let mut component = Vec::new();
    for poly in polygons {
        let root = poly
            .iter()
            .find(|&&v| (v as usize) < vertex_count)
            .map_or(u32::MAX, |&v| sets.find(v));
        let next = number.len() as u32;
        component.push(*number.entry(root).or_insert(next));
    }
    let count = number.len();
    (component, count)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(n: usize, faces: &[&[u32]]) -> HalfEdgeMesh {
        HalfEdgeMesh::from_polygons(n, faces.iter().copied()).unwrap()
    }

    #[test]
    fn an_open_book_names_its_spine() {
        let m = mesh(5, &[&[0, 1, 2], &[1, 0, 3], &[0, 1, 4]]);
        assert_eq!(nonmanifold_edges(&m), vec![(0, 1, 3)]);
        assert_eq!(nonmanifold_vertices(&m), vec![0, 1]);
    }

    #[test]
    fn a_bow_tie_names_its_knot() {
        let m = mesh(5, &[&[0, 1, 2], &[0, 3, 4]]);
        assert!(nonmanifold_edges(&m).is_empty());
        assert_eq!(nonmanifold_vertices(&m), vec![0]);
        assert_eq!(boundary_loops(&m).len(), 2);
    }

    #[test]
    fn a_moebius_strip_cannot_be_oriented() {
        let faces: [&[u32]; 5] = [&[0, 1, 2], &[1, 2, 3], &[2, 3, 4], &[3, 4, 0], &[4, 0, 1]];
        let m = mesh(5, &faces);
        assert!(orient(&m).is_err());
        let loops = boundary_loops(&m);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].len(), 5);
    }

    #[test]
    fn a_tetrahedron_with_a_flipped_face_is_put_right() {
        let faces: [&[u32]; 4] = [&[0, 2, 1], &[0, 1, 3], &[1, 2, 3], &[0, 2, 3]];
        let flips = orient(&mesh(4, &faces)).unwrap();
        // Either face 3 alone, or the other three, is reversed.
        assert!(flips == [false, false, false, true] || flips == [true, true, true, false]);
        assert!(boundary_loops(&mesh(4, &faces)).is_empty());
    }

    #[test]
    fn components_are_numbered_in_order() {
        let faces: [&[u32]; 3] = [&[3, 4, 5], &[0, 1, 2], &[5, 6, 7]];
        let (c, n) = face_components(8, faces.iter().copied());
        assert_eq!((c, n), (vec![0, 1, 0], 2));
    }
}
