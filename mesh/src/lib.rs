//! # mesh: connectivity and exact geometric checks on polygon meshes
//!
//! The layer of ntori that knows meshes and nothing else: no charts, no splines, no files, no GPU.
//!
//! - [`HalfEdgeMesh`] is built from any polygon list and reports its topology (closed, manifold,
//!   orientable, components, χ, genus) from indices alone: connectivity knows no positions.
//! - [`cell_complex`] views a mesh as a cell complex with oriented 1-cells and validates one.
//! - [`spatial`] checks triangle meshes in R³: exact self-intersections, degenerate triangles and
//!   Hausdorff distances.
//! - [`refine`] splits a mesh's long edges (the surface stays where it is).
//! - [`validate`] locates what the topology counts: the first non-manifold edge or vertex, the
//!   boundary loops, where orientation breaks down, each face's component.
//!
//! ```
//! use mesh::HalfEdgeMesh;
//!
//! // A tetrahedron: closed, orientable, genus 0.
//! let faces = [[0u32, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
//! let mesh = HalfEdgeMesh::from_polygons(4, faces.iter().map(|f| &f[..]))?;
//! let topology = mesh.topology();
//! assert!(topology.closed && topology.orientable);
//! assert_eq!(topology.euler_characteristic, 2);
//! # Ok::<(), mesh::MeshError>(())
//! ```

pub mod cell_complex;
pub mod even;
pub mod halfedge;
pub mod refine;
pub mod schema;
pub mod shape;
pub mod spatial;
pub mod validate;

pub use cell_complex::CellComplex;
pub use halfedge::{HalfEdgeMesh, MeshError, Topology};
pub use shape::{MeshShape, mesh_shape};
