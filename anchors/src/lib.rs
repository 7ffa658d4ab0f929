//! The tools ntori is measured against, behind safe Rust types: today OpenSubdiv's Far stencils
//! (Catmull–Clark uniform refinement stencils and limit stencils) and its CPU evaluator, through a
//! small C++ shim over the system library (Debian's `libosd-dev`, OpenSubdiv 3.5).
//!
//! Benches and comparison tests use it, and `ntori fit --cage` reads a Catmull–Clark cage's limit
//! surface through [`Refiner::limit_mesh`]. Without the library the crate still builds and
//! [`available`] is false: every constructor then returns [`Error::Unavailable`], so a machine
//! without OpenSubdiv can build and test everything else.
//!
//! Bench inputs: [`QuadMesh::genus_cage`] makes a closed all-quad cage of any genus.

mod cage;
mod sys;

use std::ffi::c_void;

pub use cage::QuadMesh;

/// What went wrong in a call to OpenSubdiv.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum Error {
    #[error("OpenSubdiv is not available in this build (apt-get install libosd-dev, then rebuild)")]
    Unavailable,
    #[error("OpenSubdiv failed to {0}")]
    Failed(&'static str),
    #[error("the mesh is too large for OpenSubdiv's 32-bit indices")]
    TooLarge,
}

/// Whether this build links OpenSubdiv.
pub fn available() -> bool {
    cfg!(not(osd_missing))
}

fn int(n: usize) -> Result<i32, Error> {
    i32::try_from(n).map_err(|_| Error::TooLarge)
}

/// A Catmull–Clark topology refiner over a closed quad mesh.
pub struct Refiner {
    raw: *mut c_void,
    /// Vertices of the base mesh (what stencils are applied to).
    base_vertices: usize,
}

impl Refiner {
    /// A refiner for `mesh`'s topology (its positions are not needed until stencils are applied).
    pub fn new(mesh: &QuadMesh) -> Result<Refiner, Error> {
        let sides = vec![4; mesh.faces.len()];
        Refiner::from_polygons(mesh.positions.len(), &sides, mesh.faces.as_flattened())
    }

    /// A refiner for a closed polygon mesh of `vertices` vertices: polygon f has `sides[f]` corners,
    /// the next ones of `corners` (counter-clockwise seen from outside).
    pub fn from_polygons(
        vertices: usize,
        sides: &[u32],
        corners: &[u32],
    ) -> Result<Refiner, Error> {
        if !available() {
            return Err(Error::Unavailable);
        }
        let total: u64 = sides.iter().map(|&s| u64::from(s)).sum();
        if total != corners.len() as u64 || corners.iter().any(|&c| c as usize >= vertices) {
            return Err(Error::Failed(
                "read the polygons (corner counts or indices out of range)",
            ));
        }
        let counts = sides
            .iter()
            .map(|&s| int(s as usize))
            .collect::<Result<Vec<i32>, Error>>()?;
        let indices = corners
            .iter()
            .map(|&v| int(v as usize))
            .collect::<Result<Vec<i32>, Error>>()?;
        let (v, f) = (int(vertices)?, int(sides.len())?);
        // SAFETY: counts holds f entries summing to indices.len() (checked above), every index is
        // below v; the shim copies what it keeps.
        let raw = unsafe { sys::ntori_osd_refiner_new(v, f, counts.as_ptr(), indices.as_ptr()) };
        if raw.is_null() {
            return Err(Error::Failed("build the topology refiner"));
        }
        Ok(Refiner {
            raw,
            base_vertices: vertices,
        })
    }

    /// Refines uniformly to `level` (1 to 8) and returns the finest level's mesh with every vertex
    /// moved to its place on the limit surface of the cage whose vertices are at `base` (one per
    /// base vertex). After one level every face of a Catmull–Clark mesh is a quad. The refiner is
    /// used up: a refiner refined before (by any call) is refused.
    pub fn limit_mesh(&self, level: u32, base: &[[f64; 3]]) -> Result<LimitMesh, Error> {
        if base.len() != self.base_vertices {
            return Err(Error::Failed("match the positions to the cage's vertices"));
        }
        if !(1..=8).contains(&level) {
            return Err(Error::Failed("refine to a level from 1 to 8"));
        }
        // SAFETY: raw is a live refiner; the shim refuses one refined before.
        let vertices = unsafe { sys::ntori_osd_refine_uniform_full(self.raw, level as i32) };
        if vertices <= 0 {
            return Err(Error::Failed("refine uniformly (once, from the cage)"));
        }
        let (mut faces, mut corners) = (0i32, 0i32);
        // SAFETY: raw is refined; the two outputs are plain ints.
        unsafe { sys::ntori_osd_finest_sizes(self.raw, &mut faces, &mut corners) };
        if corners != 4 * faces {
            return Err(Error::Failed("refine to quads"));
        }
        let mut counts = vec![0i32; faces.max(0) as usize];
        let mut indices = vec![0i32; corners.max(0) as usize];
        // SAFETY: the shim writes at most `faces` counts and `corners` indices, the lengths given.
        let ok = unsafe {
            sys::ntori_osd_finest_faces(
                self.raw,
                counts.as_mut_ptr(),
                faces,
                indices.as_mut_ptr(),
                corners,
            )
        };
        if ok != 1 {
            return Err(Error::Failed("read the refined faces"));
        }
        let mut positions = vec![[0.0f64; 3]; vertices as usize];
        let (mut du, mut dv) = (positions.clone(), positions.clone());
        // SAFETY: base holds base_vertices points; positions, du and dv `vertices` points each;
        // every point is three doubles; the shim checks both counts against the refiner's levels.
        let ok = unsafe {
            sys::ntori_osd_limit_positions(
                self.raw,
                base.as_flattened().as_ptr(),
                int(base.len())?,
                positions.as_flattened_mut().as_mut_ptr(),
                du.as_flattened_mut().as_mut_ptr(),
                dv.as_flattened_mut().as_mut_ptr(),
                vertices,
            )
        };
        if ok != 1 {
            return Err(Error::Failed("evaluate the limit positions"));
        }
        let faces = indices
            .chunks_exact(4)
            .map(|q| [q[0], q[1], q[2], q[3]].map(|v| v as u32))
            .collect();
        let normals = du.iter().zip(&dv).map(|(a, b)| cross(*a, *b)).collect();
        Ok(LimitMesh {
            positions,
            normals,
            faces,
        })
    }

    /// Uniform refinement to `level`, then the stencils of that level's vertices.
    pub fn uniform_stencils(mesh: &QuadMesh, level: u32) -> Result<StencilTable, Error> {
        let refiner = Refiner::new(mesh)?;
        refiner.refine_uniform(level)?;
        refiner.stencils()
    }

    /// Refines uniformly to `level`; returns that level's vertex count.
    pub fn refine_uniform(&self, level: u32) -> Result<usize, Error> {
        // SAFETY: raw is a live refiner.
        let n = unsafe { sys::ntori_osd_refine_uniform(self.raw, level.min(10) as i32) };
        if n <= 0 {
            return Err(Error::Failed("refine uniformly"));
        }
        Ok(n as usize)
    }

    /// Refines adaptively (isolating extraordinary vertices) to `level`, as limit stencils need.
    pub fn refine_adaptive(&self, level: u32) -> Result<(), Error> {
        // SAFETY: raw is a live refiner.
        match unsafe { sys::ntori_osd_refine_adaptive(self.raw, level.min(10) as i32) } {
            1 => Ok(()),
            _ => Err(Error::Failed("refine adaptively")),
        }
    }

    /// The uniform stencils of the finest level (after [`Refiner::refine_uniform`]).
    pub fn stencils(&self) -> Result<StencilTable, Error> {
        // SAFETY: raw is a live, refined refiner.
        let raw = unsafe { sys::ntori_osd_uniform_stencils(self.raw) };
        StencilTable::wrap(raw, self.base_vertices, false, "make uniform stencils")
    }

    /// Limit stencils at `(face, s, t)` locations (after [`Refiner::refine_adaptive`]); locations of
    /// one face must be consecutive. With `derivatives`, the tables also carry ∂/∂s and ∂/∂t.
    pub fn limit_stencils(
        &self,
        locations: &[(u32, f32, f32)],
        derivatives: bool,
    ) -> Result<StencilTable, Error> {
        let faces = locations
            .iter()
            .map(|l| int(l.0 as usize))
            .collect::<Result<Vec<i32>, Error>>()?;
        let s: Vec<f32> = locations.iter().map(|l| l.1).collect();
        let t: Vec<f32> = locations.iter().map(|l| l.2).collect();
        // SAFETY: the three arrays hold locations.len() entries; the shim reads them during the call.
        let raw = unsafe {
            sys::ntori_osd_limit_stencils(
                self.raw,
                int(locations.len())?,
                faces.as_ptr(),
                s.as_ptr(),
                t.as_ptr(),
                i32::from(derivatives),
            )
        };
        StencilTable::wrap(raw, self.base_vertices, derivatives, "make limit stencils")
    }
}

impl Drop for Refiner {
    fn drop(&mut self) {
        // SAFETY: raw came from ntori_osd_refiner_new and is freed once.
        unsafe { sys::ntori_osd_refiner_free(self.raw) }
    }
}

/// A uniformly refined Catmull–Clark mesh with its vertices on the limit surface.
#[derive(Clone, Debug, PartialEq)]
pub struct LimitMesh {
    pub positions: Vec<[f64; 3]>,
    /// The limit surface's normal at each vertex: the cross product of its two limit tangents (not
    /// unit length), on the side the faces' counter-clockwise order makes outward.
    pub normals: Vec<[f64; 3]>,
    /// Quads, oriented as the cage's faces.
    pub faces: Vec<[u32; 4]>,
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A table of stencils (rows of weights on the base mesh's vertices), uniform or limit.
pub struct StencilTable {
    raw: *mut c_void,
    base_vertices: usize,
    rows: usize,
    derivatives: bool,
}

impl StencilTable {
    fn wrap(
        raw: *mut c_void,
        base_vertices: usize,
        derivatives: bool,
        what: &'static str,
    ) -> Result<StencilTable, Error> {
        if raw.is_null() {
            return Err(Error::Failed(what));
        }
        // SAFETY: raw is a live table.
        let rows = unsafe { sys::ntori_osd_stencil_count(raw) }.max(0) as usize;
        Ok(StencilTable {
            raw,
            base_vertices,
            rows,
            derivatives,
        })
    }

    /// Number of stencils (output points).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of stored weights (for the position; derivatives have as many again each).
    pub fn weights(&self) -> usize {
        // SAFETY: raw is a live table.
        unsafe { sys::ntori_osd_weight_count(self.raw) }.max(0) as usize
    }

    /// Bytes the position evaluation streams per output point: an i32 index and an f32 weight per
    /// weight, a size and an offset per row, and the written float3.
    pub fn bytes_per_row(&self) -> f64 {
        8.0 * self.weights() as f64 / self.rows.max(1) as f64 + 8.0 + 12.0
    }

    fn check(&self, src: &[[f32; 3]], outputs: &[&[[f32; 3]]]) {
        assert_eq!(
            src.len(),
            self.base_vertices,
            "one source point per base vertex"
        );
        for out in outputs {
            assert_eq!(out.len(), self.rows, "one output point per stencil");
        }
    }

    /// `dst[i]` = stencil i applied to `src` (OpenSubdiv's single-threaded CPU evaluator).
    pub fn apply(&self, src: &[[f32; 3]], dst: &mut [[f32; 3]]) -> Result<(), Error> {
        self.evaluate(src, dst, sys::ntori_osd_apply)
    }

    /// [`StencilTable::apply`] on (x, y, z, w) points: the evaluator's SIMD kernel for 4 floats.
    pub fn apply4(&self, src: &[[f32; 4]], dst: &mut [[f32; 4]]) -> Result<(), Error> {
        self.evaluate(src, dst, sys::ntori_osd_apply4)
    }

    /// Every stencil applied to `src` by `kernel` (one of the shim's evaluator calls, for points of
    /// N floats).
    fn evaluate<const N: usize>(
        &self,
        src: &[[f32; N]],
        dst: &mut [[f32; N]],
        kernel: unsafe extern "C" fn(*const c_void, *const f32, *mut f32, i32, i32) -> i32,
    ) -> Result<(), Error> {
        assert_eq!(
            src.len(),
            self.base_vertices,
            "one source point per base vertex"
        );
        assert_eq!(dst.len(), self.rows, "one output point per stencil");
        // SAFETY: src holds the base vertices and dst one point per stencil (checked above), both of
        // the N floats the kernel reads and writes per point.
        let ok = unsafe {
            kernel(
                self.raw,
                src.as_ptr().cast(),
                dst.as_mut_ptr().cast(),
                0,
                self.rows as i32,
            )
        };
        if ok == 1 {
            Ok(())
        } else {
            Err(Error::Failed("apply stencils"))
        }
    }

    /// [`StencilTable::apply`] through Far's own `StencilTable::UpdateValues` template (inlined
    /// into the shim) instead of the CPU evaluator.
    pub fn update_values(&self, src: &[[f32; 3]], dst: &mut [[f32; 3]]) -> Result<(), Error> {
        self.check(src, &[&*dst]);
        // SAFETY: as in apply.
        unsafe {
            sys::ntori_osd_update_values(self.raw, src.as_ptr().cast(), dst.as_mut_ptr().cast())
        };
        Ok(())
    }

    /// [`StencilTable::apply`] with the first derivatives, for limit stencils made with them.
    pub fn apply_with_derivatives(
        &self,
        src: &[[f32; 3]],
        dst: &mut [[f32; 3]],
        du: &mut [[f32; 3]],
        dv: &mut [[f32; 3]],
    ) -> Result<(), Error> {
        if !self.derivatives {
            return Err(Error::Failed(
                "apply derivatives of a table made without them",
            ));
        }
        self.check(src, &[&*dst, &*du, &*dv]);
        // SAFETY: as in apply; du and dv hold one float3 per stencil too.
        let ok = unsafe {
            sys::ntori_osd_apply_with_derivatives(
                self.raw,
                src.as_ptr().cast(),
                dst.as_mut_ptr().cast(),
                du.as_mut_ptr().cast(),
                dv.as_mut_ptr().cast(),
                0,
                self.rows as i32,
            )
        };
        if ok == 1 {
            Ok(())
        } else {
            Err(Error::Failed("apply limit stencils with derivatives"))
        }
    }
}

impl Drop for StencilTable {
    fn drop(&mut self) {
        // SAFETY: raw came from the shim and is freed once.
        unsafe { sys::ntori_osd_stencils_free(self.raw) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tests below run only where OpenSubdiv is linked; CI links it (and says so here).
    fn linked() -> bool {
        if !available() && std::env::var_os("NTORI_REQUIRE_TOOLS").is_some() {
            panic!("NTORI_REQUIRE_TOOLS is set but OpenSubdiv is not linked");
        }
        available()
    }

    #[test]
    fn uniform_stencils_have_a_row_per_refined_vertex_and_reproduce_affine_maps() {
        if !linked() {
            return;
        }
        for genus in 0..=3 {
            let cage = QuadMesh::genus_cage(genus);
            for level in 1..=4 {
                let table = Refiner::uniform_stencils(&cage, level).unwrap();
                assert_eq!(table.rows(), cage.refined_vertex_count(level));
                // Catmull–Clark reproduces affine functions of the control points: a translated
                // and scaled cage refines to the same points translated and scaled.
                let moved: Vec<[f32; 3]> = cage
                    .positions
                    .iter()
                    .map(|p| [2.0 * p[0] + 1.0, 2.0 * p[1], 2.0 * p[2] - 3.0])
                    .collect();
                let mut a = vec![[0.0; 3]; table.rows()];
                let mut b = a.clone();
                table.apply(&cage.positions, &mut a).unwrap();
                table.apply(&moved, &mut b).unwrap();
                // Far's template and the evaluator's 4-float kernel give the same points.
                let mut c = a.clone();
                table.update_values(&cage.positions, &mut c).unwrap();
                let four: Vec<[f32; 4]> = cage
                    .positions
                    .iter()
                    .map(|p| [p[0], p[1], p[2], 1.0])
                    .collect();
                let mut d = vec![[0.0; 4]; table.rows()];
                table.apply4(&four, &mut d).unwrap();
                for ((p, q), r) in a.iter().zip(&c).zip(&d) {
                    for k in 0..3 {
                        assert!((p[k] - q[k]).abs() < 1e-5 && (p[k] - r[k]).abs() < 1e-5);
                    }
                    assert!((r[3] - 1.0).abs() < 1e-5, "weights sum to one");
                }
                for (p, q) in a.iter().zip(&b) {
                    let want = [2.0 * p[0] + 1.0, 2.0 * p[1], 2.0 * p[2] - 3.0];
                    for d in 0..3 {
                        assert!((want[d] - q[d]).abs() < 1e-4, "genus {genus} level {level}");
                    }
                }
            }
        }
    }

    /// The limit stencils' derivative rows agree with central differences of their position rows.
    #[test]
    fn limit_derivatives_match_differences_of_positions() {
        if !linked() {
            return;
        }
        let cage = QuadMesh::genus_cage(2);
        let refiner = Refiner::new(&cage).unwrap();
        refiner.refine_adaptive(4).unwrap();
        let h = 1e-3f32;
        let mut locations = Vec::new();
        for (f, s, t) in cage.limit_locations(3) {
            locations.extend([
                (f, s, t),
                (f, s + h, t),
                (f, s - h, t),
                (f, s, t + h),
                (f, s, t - h),
            ]);
        }
        let table = refiner.limit_stencils(&locations, true).unwrap();
        let n = table.rows();
        assert_eq!(n, locations.len());
        let (mut p, mut du, mut dv) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
        table
            .apply_with_derivatives(&cage.positions, &mut p, &mut du, &mut dv)
            .unwrap();
        for k in (0..n).step_by(5) {
            for d in 0..3 {
                let fd_s = (p[k + 1][d] - p[k + 2][d]) / (2.0 * h);
                let fd_t = (p[k + 3][d] - p[k + 4][d]) / (2.0 * h);
                assert!(
                    (fd_s - du[k][d]).abs() < 2e-2,
                    "row {k}: {fd_s} vs {}",
                    du[k][d]
                );
                assert!(
                    (fd_t - dv[k][d]).abs() < 2e-2,
                    "row {k}: {fd_t} vs {}",
                    dv[k][d]
                );
            }
        }
        // Inside the cage's box, and not all at one point.
        assert!(
            p.iter()
                .all(|q| q.iter().all(|c| (-0.01..=5.01).contains(c)))
        );
        assert!(p.iter().any(|q| (q[0] - p[0][0]).abs() > 0.5));
    }

    /// The limit mesh's vertices lie where the limit stencils (an independent path through
    /// OpenSubdiv) put them: a base vertex's descendant at the corner (0, 0) of a face that starts
    /// there, and every vertex at the limit whatever the level.
    #[test]
    fn limit_mesh_vertices_are_on_the_limit_surface() {
        if !linked() {
            return;
        }
        for genus in [0, 2] {
            let cage = QuadMesh::genus_cage(genus);
            let base: Vec<[f64; 3]> = cage.positions.iter().map(|p| p.map(f64::from)).collect();
            let coarse = Refiner::new(&cage).unwrap().limit_mesh(2, &base).unwrap();
            let fine = Refiner::new(&cage).unwrap().limit_mesh(4, &base).unwrap();
            assert_eq!(fine.positions.len(), cage.refined_vertex_count(4));
            assert_eq!(fine.faces.len(), cage.faces.len() * 256);
            // Vertices are numbered vertex children first, so the first ones descend from the base
            // vertices at every level; their limit points do not depend on the level.
            for v in 0..base.len() {
                for k in 0..3 {
                    let (a, b) = (coarse.positions[v][k], fine.positions[v][k]);
                    assert!(
                        (a - b).abs() < 1e-12,
                        "genus {genus}, vertex {v}: {a} vs {b}"
                    );
                }
            }
            let refiner = Refiner::new(&cage).unwrap();
            refiner.refine_adaptive(4).unwrap();
            let corners: Vec<(u32, f32, f32)> = (0..cage.faces.len() as u32)
                .map(|f| (f, 0.0, 0.0))
                .collect();
            let table = refiner.limit_stencils(&corners, false).unwrap();
            let mut at = vec![[0.0f32; 3]; corners.len()];
            table.apply(&cage.positions, &mut at).unwrap();
            for (f, face) in cage.faces.iter().enumerate() {
                let mine = fine.positions[face[0] as usize];
                for k in 0..3 {
                    assert!(
                        (mine[k] - f64::from(at[f][k])).abs() < 1e-5,
                        "genus {genus}, face {f}: {mine:?} vs {:?}",
                        at[f]
                    );
                }
            }
            // The limit normals point the way the quads face (the faces are tiny against the
            // curvature at level 4).
            for q in &fine.faces {
                let p = q.map(|v| fine.positions[v as usize]);
                let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
                let facing = cross(sub(p[1], p[0]), sub(p[3], p[0]));
                for &v in q {
                    let n = fine.normals[v as usize];
                    let dot: f64 = (0..3).map(|k| n[k] * facing[k]).sum();
                    assert!(dot > 0.0, "genus {genus}: vertex {v} faces away");
                }
            }
            // Closed: every edge of the quads is shared by two of them, in opposite directions.
            let mut edges = std::collections::HashMap::new();
            for q in &fine.faces {
                for i in 0..4 {
                    *edges.entry((q[i], q[(i + 1) % 4])).or_insert(0) += 1;
                }
            }
            assert!(
                edges
                    .iter()
                    .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
            );
        }
    }

    /// A refiner refined before is refused, not read past its levels.
    #[test]
    fn a_refiner_is_refined_for_a_limit_mesh_once() {
        if !linked() {
            return;
        }
        let cage = QuadMesh::genus_cage(1);
        let base: Vec<[f64; 3]> = cage.positions.iter().map(|p| p.map(f64::from)).collect();
        let refiner = Refiner::new(&cage).unwrap();
        refiner.limit_mesh(3, &base).unwrap();
        assert!(refiner.limit_mesh(2, &base).is_err());
        assert!(refiner.limit_mesh(4, &base).is_err());
        let refiner = Refiner::new(&cage).unwrap();
        refiner.refine_adaptive(2).unwrap();
        assert!(refiner.limit_mesh(2, &base).is_err());
        let refiner = Refiner::new(&cage).unwrap();
        assert!(refiner.limit_mesh(0, &base).is_err());
        assert!(refiner.limit_mesh(2, &base[1..]).is_err());
    }

    #[test]
    fn polygons_that_do_not_add_up_are_refused() {
        if !linked() {
            return;
        }
        assert!(Refiner::from_polygons(4, &[4, 3], &[0, 1, 2, 3, 0, 1]).is_err());
        assert!(Refiner::from_polygons(3, &[3], &[0, 1, 7]).is_err());
    }

    #[test]
    fn unavailable_is_said_not_panicked() {
        if available() {
            return;
        }
        let cage = QuadMesh::genus_cage(2);
        assert_eq!(Refiner::new(&cage).err(), Some(Error::Unavailable));
    }
}
