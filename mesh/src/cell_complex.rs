//! The cell-complex view of a 2-dimensional mesh, after the interface in
//! `discrete-manifolds-cell-complex-interface.txt`: cells by dimension, each with its faces (cells one
//! dimension down) and cofaces (one dimension up), and *oriented* 1-cells: for E edges, oriented edge k
//! < E runs from its first face (endpoint) to its second, and its mirror twin k + E runs back. In two
//! dimensions the 1-cells are also the (n−1)-cells, whose two cofaces are their left and right faces;
//! the twin swaps them.
//!
//! A complex can come from tables (which may be inconsistent: [`CellComplex::validate`] reports every
//! inconsistency) or from a [`HalfEdgeMesh`].
//!
//! ```
//! use mesh::cell_complex::CellComplex;
//! use mesh::HalfEdgeMesh;
//! let faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
//! let mesh = HalfEdgeMesh::from_polygons(4, faces.iter().map(|f| &f[..])).unwrap();
//! let complex = CellComplex::from_mesh(&mesh);
//! assert!(complex.validate().is_empty());
//! assert_eq!(complex.euler_characteristic(), 2);
//! // Oriented edge k and its mirror twin k + E.
//! let (a, b) = complex.oriented_edge(0);
//! assert_eq!(complex.oriented_edge(complex.count(1) as u32), (b, a));
//! ```

use std::collections::HashMap;

use serde::Serialize;

use crate::halfedge::HalfEdgeMesh;

/// One cell: the cells of one dimension lower on its boundary, and those one higher it bounds.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Cell {
    pub faces: Vec<u32>,
    pub cofaces: Vec<u32>,
}

/// A 2-dimensional cell complex: `cells[d]` are the d-cells.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CellComplex {
    pub cells: [Vec<Cell>; 3],
}

/// One inconsistency found by [`CellComplex::validate`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Inconsistency {
    /// A cell names a face that does not exist.
    UnknownFace { dim: usize, cell: u32, face: u32 },
    /// A cell names a coface that does not exist.
    UnknownCoface { dim: usize, cell: u32, coface: u32 },
    /// `cell` lists `face`, but `face` does not list `cell` among its cofaces.
    FaceNotReciprocated { dim: usize, cell: u32, face: u32 },
    /// `cell` lists `coface`, but `coface` does not list `cell` among its faces.
    CofaceNotReciprocated { dim: usize, cell: u32, coface: u32 },
    /// A cell lists the same neighbour twice.
    Repeated { dim: usize, cell: u32, entry: u32 },
    /// A 1-cell without exactly two endpoints.
    EdgeEnds { cell: u32, count: usize },
    /// A 1-cell without exactly two faces on its sides (a closed surface has two everywhere).
    EdgeSides { cell: u32, count: usize },
    /// A 2-cell whose edges do not close into one loop.
    OpenBoundary { cell: u32 },
}

impl std::fmt::Display for Inconsistency {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::UnknownFace { dim, cell, face } => {
                write!(
                    f,
                    "{dim}-cell {cell} has face {face}, but there is no {}-cell {face}",
                    dim - 1
                )
            }
            Self::UnknownCoface { dim, cell, coface } => {
                write!(
                    f,
                    "{dim}-cell {cell} is a face of {coface}, but there is no {}-cell {coface}",
                    dim + 1
                )
            }
            Self::FaceNotReciprocated { dim, cell, face } => write!(
                f,
                "{dim}-cell {cell} has face {face}, but {}-cell {face} does not list {cell} among the cells it is a face of",
                dim - 1
            ),
            Self::CofaceNotReciprocated { dim, cell, coface } => write!(
                f,
                "{dim}-cell {cell} is listed as a face of {coface}, but {}-cell {coface} does not have {cell} among its faces",
                dim + 1
            ),
            Self::Repeated { dim, cell, entry } => {
                write!(f, "{dim}-cell {cell} lists {entry} twice")
            }
            Self::EdgeEnds { cell, count } => {
                write!(f, "1-cell {cell} has {count} endpoints, not 2")
            }
            Self::EdgeSides { cell, count } => {
                write!(f, "1-cell {cell} bounds {count} 2-cells, not 2")
            }
            Self::OpenBoundary { cell } => {
                write!(f, "the edges of 2-cell {cell} do not close into one loop")
            }
        }
    }
}

impl CellComplex {
    /// How many d-cells.
    pub fn count(&self, dim: usize) -> usize {
        self.cells[dim].len()
    }

    /// V − E + F.
    pub fn euler_characteristic(&self) -> i64 {
        self.count(0) as i64 - self.count(1) as i64 + self.count(2) as i64
    }

    /// Endpoints of oriented 1-cell k ∈ [0, 2E): k < E from its first face to its second, k + E back.
    ///
    /// # Panics
    /// If k ≥ 2E or the 1-cell does not have two endpoints (run [`CellComplex::validate`] first).
    pub fn oriented_edge(&self, k: u32) -> (u32, u32) {
        let e = self.count(1) as u32;
        let f = &self.cells[1][(k % e) as usize].faces;
        if k < e { (f[0], f[1]) } else { (f[1], f[0]) }
    }

    /// The 2-cells on either side of oriented (n−1)-cell k ∈ [0, 2E): (left, right) for k < E as
    /// listed, swapped for its twin k + E.
    pub fn oriented_sides(&self, k: u32) -> (u32, u32) {
        let e = self.count(1) as u32;
        let c = &self.cells[1][(k % e) as usize].cofaces;
        if k < e { (c[0], c[1]) } else { (c[1], c[0]) }
    }

    /// The boundary of 2-cell `face` as oriented 1-cells chained head to tail, or `None` if its edges
    /// do not form one loop.
    pub fn oriented_boundary(&self, face: u32) -> Option<Vec<u32>> {
        let e = self.count(1) as u32;
        let edges = &self.cells[2].get(face as usize)?.faces;
        let ends = |k: u32| self.cells[1].get(k as usize).filter(|c| c.faces.len() == 2);
        let first = *edges.first()?;
        let mut loop_ = vec![first];
        let (start, mut at) = (ends(first)?.faces[0], ends(first)?.faces[1]);
        let mut used = vec![false; edges.len()];
        used[0] = true;
        while loop_.len() < edges.len() {
            let (i, &k) = edges
                .iter()
                .enumerate()
                .find(|&(i, &k)| !used[i] && ends(k).is_some_and(|c| c.faces.contains(&at)))?;
            used[i] = true;
            let f = &ends(k)?.faces;
            if f[0] == at {
                loop_.push(k);
                at = f[1];
            } else {
                loop_.push(k + e);
                at = f[0];
            }
        }
        (at == start).then_some(loop_)
    }

    /// Every inconsistency in the tables, in a stable order (by kind of check, dimension, cell).
    pub fn validate(&self) -> Vec<Inconsistency> {
        let mut found = Vec::new();
        for dim in 0..3 {
            for (c, cell) in self.cells[dim].iter().enumerate() {
                let c = c as u32;
                for (list, _) in [(&cell.faces, 0), (&cell.cofaces, 1)] {
                    let mut seen = list.clone();
                    seen.sort_unstable();
                    for w in seen.windows(2).filter(|w| w[0] == w[1]) {
                        found.push(Inconsistency::Repeated {
                            dim,
                            cell: c,
                            entry: w[0],
                        });
                    }
                }
                if dim > 0 {
                    for &f in &cell.faces {
                        match self.cells[dim - 1].get(f as usize) {
                            None => found.push(Inconsistency::UnknownFace {
                                dim,
                                cell: c,
                                face: f,
                            }),
                            Some(down) if !down.cofaces.contains(&c) => {
                                found.push(Inconsistency::FaceNotReciprocated {
                                    dim,
                                    cell: c,
                                    face: f,
                                })
                            }
                            Some(_) => {}
                        }
                    }
                }
                if dim < 2 {
                    for &u in &cell.cofaces {
                        match self.cells[dim + 1].get(u as usize) {
                            None => found.push(Inconsistency::UnknownCoface {
                                dim,
                                cell: c,
                                coface: u,
                            }),
                            Some(up) if !up.faces.contains(&c) => {
                                found.push(Inconsistency::CofaceNotReciprocated {
                                    dim,
                                    cell: c,
                                    coface: u,
                                })
                            }
                            Some(_) => {}
                        }
                    }
                }
            }
        }
        for (c, cell) in self.cells[1].iter().enumerate() {
            if cell.faces.len() != 2 {
                found.push(Inconsistency::EdgeEnds {
                    cell: c as u32,
                    count: cell.faces.len(),
                });
            }
            if cell.cofaces.len() != 2 {
                found.push(Inconsistency::EdgeSides {
                    cell: c as u32,
                    count: cell.cofaces.len(),
                });
            }
        }
        for f in 0..self.count(2) as u32 {
            if self.oriented_boundary(f).is_none() {
                found.push(Inconsistency::OpenBoundary { cell: f });
            }
        }
        found
    }

    /// The complex of a mesh: vertices, edges (endpoints in the order of the first half-edge met, the
    /// face of that half-edge on the left), faces.
    pub fn from_mesh(mesh: &HalfEdgeMesh) -> CellComplex {
        let mut cx = CellComplex::default();
        cx.cells[0] = vec![Cell::default(); mesh.vertex_count()];
        cx.cells[2] = vec![Cell::default(); mesh.face_count()];
        let mut edge_of: HashMap<u32, u32> = HashMap::new();
        for h in 0..mesh.halfedge_count() as u32 {
            let face = mesh.face(h);
            let e = match mesh.twin(h).and_then(|t| edge_of.get(&t).copied()) {
                Some(e) => e,
                None => {
                    let e = cx.cells[1].len() as u32;
                    cx.cells[1].push(Cell {
                        faces: vec![mesh.origin(h), mesh.target(h)],
                        cofaces: Vec::new(),
                    });
                    cx.cells[0][mesh.origin(h) as usize].cofaces.push(e);
                    cx.cells[0][mesh.target(h) as usize].cofaces.push(e);
                    e
                }
            };
            edge_of.insert(h, e);
            cx.cells[1][e as usize].cofaces.push(face);
            cx.cells[2][face as usize].faces.push(e);
        }
        cx
    }

    /// The faces as vertex cycles, for a [`HalfEdgeMesh`], oriented consistently where the complex is
    /// orientable: a breadth-first walk over faces reverses a neighbour that runs along a shared edge
    /// in the same direction. `None` if a boundary is open.
    pub fn polygons(&self) -> Option<Vec<Vec<u32>>> {
        let e = self.count(1) as u32;
        let mut loops: Vec<Vec<u32>> = (0..self.count(2) as u32)
            .map(|f| self.oriented_boundary(f))
            .collect::<Option<_>>()?;
        // Direction in which face f runs along 1-cell k: true if as listed.
        let runs = |loop_: &[u32], k: u32| loop_.iter().find(|&&o| o % e == k).map(|&o| o < e);
        let mut done = vec![false; loops.len()];
        for start in 0..loops.len() {
            if done[start] {
                continue;
            }
            done[start] = true;
            let mut queue = std::collections::VecDeque::from([start]);
            while let Some(f) = queue.pop_front() {
                for o in loops[f].clone() {
                    for &g in &self.cells[1][(o % e) as usize].cofaces {
                        let g = g as usize;
                        if g >= loops.len() || done[g] {
                            continue;
                        }
                        if runs(&loops[g], o % e) == Some(o < e) {
                            // Same direction as f: reverse g (reverse order, twin every edge).
                            loops[g] = loops[g].iter().rev().map(|&k| (k + e) % (2 * e)).collect();
                        }
                        done[g] = true;
                        queue.push_back(g);
                    }
                }
            }
        }
        Some(
            loops
                .iter()
                .map(|l| l.iter().map(|&k| self.oriented_edge(k).0).collect())
                .collect(),
        )
    }
}
