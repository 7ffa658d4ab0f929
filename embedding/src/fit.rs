//! The initial surface (the paper's section 5.1): an n-holed mesh is cut along its canonical loops
//! into a disk, the disk is flattened onto the fundamental polygon with Floater's mean value
//! parameterization, and every chart's control points are fitted at once so that S(p_i) ≈ P_i at the
//! surface point p_i of each mesh vertex.
//!
//! Floater's map is a bijection only onto a convex boundary. The hyperbolic polygon is concave in the
//! Poincaré disk but convex in the Klein model (geodesics are chords there), so the disk is flattened
//! in Klein coordinates and mapped to the Poincaré disk afterwards, vertex by vertex. The boundary is
//! pinned at hyperbolic arc length along each side, so partner sides' vertices are images of each
//! other under the side pairings (isometries preserve arc length) and the seams agree.
//!
//! Genus 0 needs no cut: the sphere is mapped to the Riemann sphere by stereographic projection.
//!
//! ```
//! use embedding::fit::{FitSettings, initial_model};
//! use embedding::SplineSettings;
//!
//! let fit = initial_model(2, 24, SplineSettings::default(), FitSettings::default())?;
//! assert_eq!(fit.surface.genus(), 2);
//! assert!(fit.rms_residual < 0.01 * fit.mesh_diagonal);
//! # Ok::<(), embedding::EmbeddingError>(())
//! ```

use std::collections::HashMap;
use std::sync::Arc;

use charts::{Atlas, ChartId, ChartPoint, Geometry, Lft, ModelPoint, Polygon};
use faer::Mat;
use faer::sparse::Triplet;
use mesh::HalfEdgeMesh;
use num_complex::Complex64;

use crate::harmonic::Convergence;
use crate::holed::HoledMesh;
use crate::least_squares::{Analysis, LeastSquares, NormalAnalysis};
use crate::spline_surface::Surface;
use crate::surface::{Layout, Point3, SplineSettings};
use crate::{EmbeddingError, floater};

/// The mesh cut open along its loops: a triangulated disk whose vertices are copies of mesh vertices.
#[derive(Clone, Debug)]
pub struct CutDisk {
    /// The mesh vertex each disk vertex copies.
    pub original: Vec<u32>,
    pub triangles: Vec<[u32; 3]>,
    /// The boundary, counter-clockwise (the disk on the left), as disk vertices.
    pub boundary: Vec<u32>,
    /// For each of the 4n boundary arcs in order: (first index in `boundary`, polygon side).
    pub arcs: Vec<(usize, usize)>,
}

/// Every mesh vertex's surface point, and the flattened disk it came from.
#[derive(Clone, Debug)]
pub struct Parameterization {
    /// One chart point per mesh vertex (in its deepest chart).
    pub points: Vec<ChartPoint>,
    /// The cut (absent for genus 0).
    pub disk: Option<CutDisk>,
    /// Positions of the disk's vertices in the plane where Floater's map was solved: the Klein model
    /// for n ≥ 2, the square itself for the torus.
    pub flat: Vec<[f64; 2]>,
    /// One lift per mesh vertex in the model (Poincaré disk or plane) after relaxation.
    pub lifts: Vec<Complex64>,
    /// Every disk copy's position after relaxation: its vertex's lift carried by the group element
    /// that glues the copy's side (so the disk's triangles can be drawn and measured as one piece).
    pub copies: Vec<Complex64>,
    /// Disk triangles that the relaxed map folds over (0 for a bijection).
    pub folded: usize,
    /// Gauss–Seidel sweeps run: before Newton's method, or for the sphere the whole relaxation.
    pub sweeps: usize,
    /// Rounds of the sphere's map solved in the plane to even its area out, where they were taken
    /// (genus 0's long limbs; not the evening of a mesh of thin triangles); 0 elsewhere.
    pub planar_rounds: usize,
    /// Whether the sphere's map was built coarse to fine (a limb the conformal map squeezed beyond
    /// what its rounds undo: `sphere_map::progressive`) rather than from the conformal map.
    pub coarse_to_fine: bool,
    /// Rounds of the sphere's density-equalizing flow whose map was taken (0: none, or not the
    /// sphere).
    pub equalizing_rounds: usize,
    /// Newton's solve of the map, over every reweighting round (`None` for the sphere, whose map is
    /// relaxed by sweeps, or solved in the plane in its planar rounds).
    pub newton: Option<Convergence>,
    /// The map's distortion where there is no cut disk to measure it on (a user's mesh, mapped
    /// closed: each triangle in the frame its corners were solved in, or on the sphere against its
    /// chord triangle); `None` otherwise.
    pub map_distortion: Option<Distortion>,
}

/// How far a map of the mesh onto the model is from conformal and from area-preserving, per
/// triangle (each measured in a frame where the model is flat to first order: the isometry taking
/// its first corner to the origin).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Distortion {
    /// σ₁/σ₂ of the affine map from the 3D triangle to its image (1: angles kept), area-weighted
    /// mean and largest.
    pub angle_mean: f64,
    pub angle_max: f64,
    /// The image's area over the triangle's, relative to the whole surface's ratio, as a factor
    /// ≥ 1 either way (2: twice or half as large as average): area-weighted geometric mean and
    /// largest.
    pub area_mean: f64,
    pub area_max: f64,
    /// The triangle whose area factor is `area_max`: an index into the triangles measured (the
    /// cut disk's, or a user's mesh's), to say where a map squeezes most.
    pub area_max_triangle: usize,
}

impl Parameterization {
    /// The map's [`Distortion`] over the cut disk's triangles, or for a user's mesh (no disk) over
    /// its own ([`Parameterization::map_distortion`]). `positions` are the mesh's; `geometry` the
    /// model's (`Atlas::geometry`; unused without a disk).
    pub fn distortion(&self, positions: &[Point3], geometry: Geometry) -> Option<Distortion> {
        let Some(disk) = self.disk.as_ref() else {
            return self.map_distortion;
        };
        let hyperbolic = geometry == Geometry::Hyperbolic;
        let triangles: Vec<_> = disk
            .triangles
            .iter()
            .map(|t| {
                let p = t.map(|v| positions[disk.original[v as usize] as usize]);
                triangle_distortion(p, t.map(|v| self.copies[v as usize]), hyperbolic)
            })
            .collect();
        Distortion::of(&triangles)
    }
}

impl Distortion {
    /// The summary of each triangle's (3D area, σ₁/σ₂, model area over 3D area).
    pub(crate) fn of(triangles: &[(f64, f64, f64)]) -> Option<Distortion> {
        let total3: f64 = triangles.iter().map(|t| t.0).sum();
        let total2: f64 = triangles.iter().map(|t| t.0 * t.2).sum();
        if triangles.is_empty() || total3 <= 0.0 {
            return None;
        }
        let ratio = total2 / total3;
        let (mut angle_sum, mut angle_max, mut log_sum, mut log_max) = (0.0, 1.0f64, 0.0, 0.0f64);
        let mut area_max_triangle = 0;
        for (t, &(area, angle, jac)) in triangles.iter().enumerate() {
            let log = (jac / ratio).abs().ln().abs();
            let angle = if angle.is_finite() {
                angle
            } else {
                f64::INFINITY
            };
            angle_sum += area * angle;
            angle_max = angle_max.max(angle);
            log_sum += area * log;
            if log > log_max {
                (log_max, area_max_triangle) = (log, t);
            }
        }
        Some(Distortion {
            angle_mean: angle_sum / total3,
            angle_max,
            area_mean: (log_sum / total3).exp(),
            area_max: log_max.exp(),
            area_max_triangle,
        })
    }
}

/// One triangle's (3D area, σ₁/σ₂, model area over 3D area) for corners `p` mapped to `z` in the
/// model (Poincaré disk or plane).
pub(crate) fn triangle_distortion(
    p: [Point3; 3],
    z: [Complex64; 3],
    hyperbolic: bool,
) -> (f64, f64, f64) {
    let [a, b, c] = p;
    // The model triangle, flat to first order: in the Poincaré disk, moved so its first corner is
    // at the origin, where lengths are twice Euclidean ones.
    let w = if hyperbolic {
        let to = |q: Complex64| 2.0 * (q - z[0]) / (Complex64::ONE - z[0].conj() * q);
        [Complex64::ZERO, to(z[1]), to(z[2])]
    } else {
        [Complex64::ZERO, z[1] - z[0], z[2] - z[0]]
    };
    // The 3D triangle in its own plane: e1 along ab.
    let (ab, ac) = (b - a, c - a);
    let e1 = ab.normalize();
    let normal = ab.cross(&ac);
    let area3 = normal.norm() / 2.0;
    let e2 = normal.normalize().cross(&e1);
    // M maps (|ab|, 0) ↦ w1 and (ac·e1, ac·e2) ↦ w2.
    let (p, q) = ((ab.norm(), 0.0), (ac.dot(&e1), ac.dot(&e2)));
    let det = p.0 * q.1 - p.1 * q.0;
    let m = [
        [
            (w[1].re * q.1 - w[2].re * p.1) / det,
            (w[2].re * p.0 - w[1].re * q.0) / det,
        ],
        [
            (w[1].im * q.1 - w[2].im * p.1) / det,
            (w[2].im * p.0 - w[1].im * q.0) / det,
        ],
    ];
    let jac = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    // σ₁,₂ = (|conformal part| ± |anti-conformal part|): no cancellation near conformal.
    let conformal = (m[0][0] + m[1][1]).hypot(m[1][0] - m[0][1]) / 2.0;
    let anti = (m[0][0] - m[1][1]).hypot(m[1][0] + m[0][1]) / 2.0;
    let (s1, s2) = (conformal + anti, (conformal - anti).abs());
    (area3, s1 / s2, jac)
}

/// The map is solved until no vertex is further than this from its neighbours' weighted average
/// (in its own frame: the unit disk with the vertex at the origin); the screening sweeps stop when
/// no vertex moves further than this.
pub const RELAX_TOLERANCE: f64 = 1e-8;

/// How [`Lifts::settle_rounds_by`] settles a round's map to a tolerance: [`Lifts::settle`], or a
/// test's stand-in.
pub(crate) type SettleRound<'a> = dyn FnMut(
        &mut Lifts,
        f64,
        &mut Option<crate::harmonic::KeptJacobian>,
    ) -> Result<Convergence, EmbeddingError>
    + 'a;

/// The tolerance of the stretch rounds before the last (`Lifts::settle_rounds`): their maps
/// only measure the stretch that reweights the next, and a vertex off by this (in frame units,
/// where neighbours are 10⁻² to 10⁻¹ apart) changes a triangle's area by about 10⁻⁴ of itself.
pub const EARLY_ROUND_TOLERANCE: f64 = 1e-6;

/// Gauss–Seidel sweeps before Newton's method takes over. From Floater's map, whose kinks along the
/// cuts are far from the fixed point, Newton's first steps are short (damped); sweeps are cheap
/// there and bring it close. Measured (plates at resolution 32, map time in s, 0 / 100 / 300
/// sweeps): genus 2 1.26 / 1.03 / 0.83, genus 8 15.3 / 2.6 / 3.0, genus 16 not converged in 60
/// steps / 27 / 21.
const WARMUP_SWEEPS: usize = 300;

/// The largest σ₁/σ₂ [`Lifts::log_anisotropy`] counts a triangle with (a collapsed one has ∞).
const MAX_ANISOTROPY: f64 = 1e6;

/// The power of the stretch that divides the weights. The full power (Yoshizawa et al.) evens the
/// area out most, but distorts the flat parts enough that the coarse t = 8 tessellation's thin
/// triangles fold (genus 3 to 5 at grid 16); 0.75 for one round keeps every genus 0 to 7 clean
/// while removing the ringing along the rims that the plain mean value map leaves.
const STRETCH_EXPONENT: f64 = 0.75;

/// The weight of the smoothness term of the fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitSettings {
    /// λ in ‖A c − P‖²_W + λ · (N / R) · ‖D c‖²: N data rows (area-weighted, mean weight 1), R
    /// second-difference rows (u, v and mixed differences of every chart's control grid). λ = 0 leaves
    /// control points without data undetermined; larger values trade fidelity for fairness.
    pub smoothness: f64,
    /// Weight μ of the patch terms: every chart's own patch E_c is also fitted to the points in its
    /// domain, weighted by its normalised blend (μ Σ_i Σ_c w_i b̂_c(p_i) |E_c(p_i) − P_i|²). Without
    /// them only the blend of the patches is fitted, and where two patches overlap they may disagree
    /// in ways that cancel at the data but ripple in between (the blend's derivative times their
    /// difference shows in the normals).
    pub patch_weight: f64,
    /// Rounds of stretch-minimizing reweighting of the parameterization (0: the mean value map).
    pub stretch_rounds: usize,
    /// The most Gauss–Seidel sweeps per round of a genus-0 mesh's map onto the sphere (it stops
    /// earlier once converged). Maps onto the polygon are solved by Newton's method instead.
    pub sweeps: usize,
    /// Rounds of evening a user's mesh out along its own surface before its map onto the polygon
    /// is made ([`crate::mesh_fit::mesh_model`], genus ≥ 1; 0: the map follows the mesh's own
    /// triangles). The plates are even already and ignore it.
    pub even_rounds: usize,
    /// Measure the smoothness term in the surface's own arc length (`bending.rs`), with the metric
    /// of a first fit (on grids [`FitSettings::metric_coarsening`] times coarser, or on the same
    /// grids; see [`fit`]). For maps that stretch the surface more one way than the other (a
    /// user's tubes and limbs), and for `new`'s plates up to genus 15
    /// ([`plate_surface_smoothness`]), whose eased rims it smooths.
    pub surface_smoothness: bool,
    /// How many times coarser (per side) the grids of the first fit that gives the arc-length term
    /// its metric are: 1, the same grids (the metric from the control points' differences); 2,
    /// half as fine (from the patches' derivatives at the grid points), for a quarter of the
    /// control points. `new`'s plates take 2 ([`FitSettings::for_plate`]; the same |κ|, normals
    /// and flat faces at genus 3 and 10 to within 0.01, 1.4 s less at genus 10). A user's mesh
    /// keeps 1: the gear's needle walls (`assets/meshes/gear-genus-1.obj`) read a coarse fit's
    /// metric badly (normals 70° off its mesh's at the 90th percentile at λ = 0.002, against 28°).
    pub metric_coarsening: usize,
    /// Where the fitted surface is rough by `ntori fit`'s shape checks, fit again with a larger
    /// smoothness (a user's mesh: [`crate::mesh_fit`]'s `smooth_enough`); off where the user
    /// chose λ.
    pub raise_smoothness: bool,
    /// Where the fitted surface passes those checks but crosses itself, fit again with the
    /// agreement rows raised ([`crate::mesh_fit::RAISED_AGREEMENTS`]); off where the user chose
    /// the agreement weight.
    pub raise_agreement: bool,
    /// Weight of the agreement rows (0: none): where two charts' blends overlap, their own
    /// patches are also made to agree with each other at a lattice of points between the data
    /// ([`AGREEMENT_STEP`]), not only each with the data at the data's points (the patch terms).
    /// Where the charts' supports barely overlap (the coverage margin falls with the genus) the
    /// blend turns from one patch to the other within a fraction of the input's spacing, and its
    /// derivatives times the patches' difference draw ridges of curvature along the fringe.
    /// `new`'s plates take it from genus [`PLATE_AGREEMENT_FROM`] ([`FitSettings::for_plate`]).
    pub agreement: f64,
    /// Weight of the edge samples as fit targets besides the vertices (0: none; 1: a third of the
    /// data's weight): on `new`'s plates one point of the intended surface between the ends of
    /// each edge ([`HoledMesh::edge_samples`]), on a user's mesh each edge's middle on the smooth
    /// curve its ends' normals say (`mesh_fit`, `ntori fit --edge-samples`;
    /// [`crate::mesh_fit::MESH_EDGE_SAMPLES`] by default there).
    /// Where a chart's cells are finer than the input's spacing, the vertices alone leave its
    /// patch free to ripple between them, which the mean curvature draws as hairlines. `new`'s
    /// plates take [`plate_edge_samples`].
    pub edge_samples: f64,
}

impl Default for FitSettings {
    fn default() -> Self {
        FitSettings {
            smoothness: 1e-4,
            patch_weight: 1.0,
            stretch_rounds: 1,
            sweeps: 5000,
            even_rounds: crate::mesh_fit::EVEN_ROUNDS,
            surface_smoothness: false,
            metric_coarsening: 1,
            raise_smoothness: false,
            raise_agreement: false,
            agreement: 0.0,
            edge_samples: 0.0,
        }
    }
}

/// A fitted model and how well it fits.
#[derive(Clone, Debug)]
pub struct InitialFit {
    pub surface: Surface,
    pub mesh: HoledMesh,
    pub parameterization: Parameterization,
    /// Root mean square and largest distance |S(p_i) − P_i| over the mesh vertices.
    pub rms_residual: f64,
    pub max_residual: f64,
    /// The input mesh's bounding-box diagonal (the model's size).
    pub mesh_diagonal: f64,
    /// The edge samples the fit also targeted ([`FitSettings::edge_samples`]; 0 where none).
    pub edge_samples: usize,
}

/// Peak memory of `ntori new` per input triangle (release): 1.29 GB for genus 2's 169 556
/// triangles (resolution 128), where the map's sparse LU factorizations dominate; 4.4 GB for genus
/// 64's 223 516 (resolution 8), where the disk charts' grids of 384 and the agreement rows add to
/// the fit's (1.99 GB before them). Rounded up. (With the fit's least squares by sparse QR, before
/// the seminormal equations, genus 2 at 128 took 3.56 GB.)
pub const FIT_BYTES_PER_TRIANGLE: u64 = 20_000;
/// The most input triangles [`initial_model`] and [`crate::mesh_fit::mesh_model`] fit: about 8 GB
/// at the rate above (less at low genus). Every genus up to 64 fits at resolution 8 (genus 64:
/// 223 516 triangles).
pub const MAX_FIT_TRIANGLES: usize = 400_000;
/// The most input triangles [`default_resolution`] chooses: the map's time grows faster than its
/// size (genus 2: 0.65 s for 10 948 triangles, 6.8 s for 42 732, 100 s for 169 556 measured
/// before the symbolic analysis was reused, which saved about a fifth), so a genus
/// whose default mesh would be finer gets a coarser one; `--resolution` can go up to the cap.
///
/// 300 000, not 200 000 as it was: from genus 25 the budget sets the plates' resolution, and at
/// high genus the largest |κ| follows the input's sampling of the rims (the fit goes through the
/// input's vertices). With 200 000 → 300 000 triangles (and λ = 1e-2, [`PLATE_SMOOTHNESS_UP_TO`]),
/// `ntori new`'s largest |κ| against the input's: genus 25 1.53× → 1.28×, 26 1.57× → 1.30×, 27
/// 1.51× → 1.38×, 28 1.53× → 1.43×, 29 1.66× → 1.40×, 30 1.74× → 1.53×, 31 2.25× → 1.96×, 32
/// 2.33× → 1.88×, 33 2.94× → 2.57×, 34 2.68× → 1.94×, 35 2.82× → 2.17×, 36 3.10× → 2.22×, 37
/// 2.95× → 2.35×, 40 3.7× → 2.84× (written now), the flat faces' |H| × half-thickness at
/// most 0.0098 from 25 to 40 (0.0129–0.0168 before) and the normals at most 0.28° at the 90th
/// percentile (0.34–0.44°). With the rims' rings from genus 31 to 40 as well
/// ([`crate::holed::RIM_REFINEMENT_UP_TO`]) genus 32 reads 1.70× (293 208 triangles). It costs
/// time and memory: `ntori new` at genus 32 39 s → 57 s (3.6 GB peak; 2.6–3.2 GB was recorded for
/// genus 17 to 33 before), genus 25 to 31 34–41 s → 46–56 s, 34 to 40 50–60 s → 67–74 s.
pub const DEFAULT_FIT_TRIANGLES: usize = 300_000;

/// The budget [`default_resolution`] keeps [`HIGH_GRID_GENERA`]'s plates within: their finer
/// grid needs the data as dense. With it genus 30 takes resolution 32 (373 176 triangles), 31
/// takes 31 (377 734; at 30, 356 334 triangles, its largest |κ| read 1.59× the input's, at 31
/// 1.45×, at 32 1.38× but 398 366 triangles) and 32 takes 30 (377 252; 399 564 at 31). On the
/// plate of wide bands ([`crate::holed::PLATE_BAND`]), whose plan is larger, 395 000 gave genus 30
/// resolution 31 (377 096 triangles) and its largest |κ| read 1.53× the input's; at 30 (357 416)
/// 1.37×. So the budget is now 377 000: genus 30 takes 30, 31 takes 29 (353 280, 1.43×; at 30,
/// 378 396 and 1.38×) and 32 takes 29 (372 392, 1.42×).
pub const HIGH_GRID_FIT_TRIANGLES: usize = 377_000;
const _: () = assert!(HIGH_GRID_FIT_TRIANGLES <= MAX_FIT_TRIANGLES);

/// The most input triangles [`default_resolution`] chooses for `genus`.
pub fn fit_triangle_budget(genus: u32) -> usize {
    if HIGH_GRID_GENERA.contains(&genus) {
        HIGH_GRID_FIT_TRIANGLES
    } else {
        DEFAULT_FIT_TRIANGLES
    }
}

/// A stage of [`initial_model_with_progress`], for progress displays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitStage {
    Meshing,
    /// Cutting the mesh of `triangles` triangles open and flattening it onto the polygon.
    Flattening {
        triangles: usize,
    },
    /// Relaxing the map on the closed surface: round `round` of `rounds` (each up to the sweep cap).
    Relaxing {
        round: usize,
        rounds: usize,
    },
    /// Genus 0: building a second map onto the sphere, coarse to fine, where the fit through the
    /// first did not pass.
    MappingCoarseToFine,
    /// The least-squares fit of the control points.
    Fitting,
}

impl std::fmt::Display for FitStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FitStage::Meshing => write!(f, "meshing the input"),
            FitStage::Flattening { triangles } => {
                write!(f, "cutting and flattening the mesh ({triangles} triangles)")
            }
            FitStage::Relaxing { round, rounds } => {
                write!(
                    f,
                    "relaxing the map on the surface (round {round} of {rounds})"
                )
            }
            FitStage::MappingCoarseToFine => {
                write!(f, "mapping the mesh onto the sphere again, coarse to fine")
            }
            FitStage::Fitting => write!(f, "fitting the control points"),
        }
    }
}

/// The input mesh's resolution where none is chosen (points round each hole).
pub const DEFAULT_RESOLUTION: usize = 32;

/// The finer resolution [`default_resolution`] gives genus 3 to 16
/// ([`FINE_RESOLUTION_GENERA`]).
pub const FINE_RESOLUTION: usize = 40;

/// The torus's default input mesh resolution ([`default_resolution`]). At 32 (1590 vertices
/// against 4096 control points) its patches were free between the data: the largest |κ| read
/// 1.54× the input's at the top of the tube, where the vertex chart's patch fades in 5e-3 off the
/// surface, and the normals 0.27° off at the 90th percentile. At 48 (3468 vertices): 1.07× and
/// 0.07°, patches 0.046% → 0.020% of the diagonal, in the same 1.0 s (64: 1.03×, 1.7 s).
pub const TORUS_RESOLUTION: usize = 48;

/// The genera whose default input mesh is [`FINE_RESOLUTION`]: where at [`DEFAULT_RESOLUTION`] the
/// fit's largest curvature or its flat faces miss issue 12's targets (they follow how finely the
/// rims are sampled), and the time allows it. Genus 10 met them at 32 too (1.28×, flat faces'
/// |H|·T 0.0175 at the 90th percentile) and kept it while its fit took 4.7 s at 32 (the bench's
/// `initial_fit/10`; issue 12 asks for 5 s). Since `LeastSquares` builds Aᵀ without sorting, 40
/// fits within it (`initial_fit/10` 4.85 s, against 3.66 s at 32 the same day), and reads 1.20×,
/// normals 0.21° against 0.28° at the 90th percentile, flat faces 0.0159, Hausdorff 0.125%
/// against 0.183% of the diagonal, and fewer hairlines of mean curvature between the holes and the
/// outer rim (pictures looked at); `ntori new` 8.2 → 9.7 s.
pub const FINE_RESOLUTION_GENERA: [std::ops::RangeInclusive<u32>; 1] = [3..=16];

/// The control grid `ntori new` uses for `genus` where none is chosen: the default 32
/// ([`SplineSettings::default`]) for the sphere and the torus, 48 from genus 2 on (with a stronger
/// smoothness weight there: [`default_plate_smoothness`]). The plates' flat faces ripple where a chart's
/// grid is too coarse for the map, which the coarse rims make anisotropic (σ₁/σ₂ 2.5–2.7 on
/// average), and the inside chart carries more of the plate as the genus grows. Measured with
/// `ntori new` (release; patch disagreement, largest |κ| against the input's, normals from the
/// intended shape at the 90th percentile; issue 12's targets 0.2%, 1.5×, 1°; genus 2 at 48 with
/// the shape_report example):
///
/// | genus | grid 32, λ = 1e-4 | grid 48, λ = 2e-3 |
/// |---|---|---|
/// | 2 | 0.150%, 1.17×, 0.72° | 0.044%, 1.21×, 0.36° |
/// | 3 | 0.188%, 1.57×, 1.00° | 0.087%, 1.40×, 0.51° |
/// | 5 | 0.276%, 1.57×, 1.36° | 0.131%, 1.36×, 0.58° |
/// | 10 | 0.201%, 2.13×, 1.39° | 0.084%, 1.29×, 0.73° |
/// | 16 | 0.016%, 1.64×, 1.25° | 0.004%, 1.30×, 0.76° |
///
/// Genus 20 and 24 pass every check at 48 as well (largest |κ| 1.21× and 1.27×, normals 0.66° and
/// 0.65°; Gauss–Bonnet 9.2e-5 and 1.2e-4).
///
/// Genus 2 meets those three targets at 32 too, but not the flat faces': with the arc-length
/// smoothness ([`plate_surface_smoothness`]) the shape_report example read |H| times the
/// half-thickness 0.0292 at the 90th percentile there (issue 12 asks for 0.02), and the normals
/// 0.51° off ±z. λ (3e-4, 1e-3) and the input's resolution (40) left it; the grid moved it
/// (shape_report: patches, largest |κ|, normals at the 90th percentile, flat faces' |H|·T, fit
/// time on two cores):
///
/// | genus-2 grid (disk charts') | patches | \|κ\| | normals | flat faces | fit |
/// |---|---|---|---|---|---|
/// | 32 | 0.150% | 4.85 | 0.70° | 0.0292 | 0.7 s |
/// | 40 | 0.104% | 4.44 | 0.42° | 0.0194 | 0.8 s |
/// | 48 | 0.038% | 4.60 | 0.31° | 0.0125 | 0.9 s |
/// | 48 (64) | 0.031% | 4.54 | 0.28° | 0.0095 | 1.1 s |
/// | 48 (96) | 0.040% | 4.57 | 0.26° | 0.0085 | 1.5 s |
/// | 32 (64) | 0.075% | 5.03 | 0.49° | 0.0148 | 0.9 s |
///
/// So genus 2 takes 48 with its disk charts on the same grid: the bench's `initial_fit/2` reads
/// 0.79 s against 0.61 s at 32 (issue 12 asks for 1 s), and `ntori new` 1.16× the input's
/// curvature against 1.31×. The editor pays for it, as it did from genus 3 on (`benches/editor.rs`
/// at 10⁵ vertices, 32 → 48: a drag event 25 → 50 µs, a press 13 → 38 ms, a stroke's step 4.8 →
/// 9.0 ms; at 10⁶ a press 55 → 62 ms). At 32 genus 24 missed Gauss–Bonnet by 7% and crossed
/// itself (K spiked between samples).
///
/// Genus 32 fails at every grid tried. At 48 (λ = 2e-3), Gauss–Bonnet is off by 6.4e-2, the
/// largest |κ| is 63× the input's and 97 triangle pairs cross at t = 64; at 40 it is worse. At 64
/// every check passes but curvature (3.65×, and 4.19× with λ = 6e-3). The spike sits where the
/// inside or the vertex chart (blend ≥ 0.89) carries the outer rim, at |z| ≈ 0.48, with
/// |E_u| ≈ 70–80 against the edge charts' 3–6 (the `spot_report` example): there one grid cell
/// spans about 2 model units, more than the rim's rounded edge. The lever is a finer grid in those
/// two charts, or blends that hand the rim to the edge charts, not a finer grid everywhere.
///
/// Genus 30 to 32 ([`HIGH_GRID_GENERA`]) take [`HIGH_GRID`], genus 5 to 16
/// ([`FINE_DISK_GENERA`]) the coarser [`FINE_DISK_EDGE_GRID`] with finer disk charts.
pub fn default_grid(genus: u32) -> usize {
    if genus <= 1 {
        SplineSettings::default().grid
    } else if HIGH_GRID_GENERA.contains(&genus) {
        HIGH_GRID
    } else if FINE_DISK_GENERA.contains(&genus) {
        FINE_DISK_EDGE_GRID
    } else {
        FINE_GRID
    }
}

/// The genera whose control points are moved from the edge charts to the disk charts: their
/// edge charts take [`FINE_DISK_EDGE_GRID`] ([`default_grid`]) and their disk charts three to
/// five times that ([`default_disk_grid`]).
///
/// From genus 5 the vertex chart carries the flat faces' strips between the holes and the outer
/// rim near its own rim, where its Poincaré coordinates stretch: a cell there spanned 0.21–0.31
/// model units at genus 10 (disk grid 96), against 0.05–0.12 in the edge charts beside it. That
/// patch rippled at its cells' scale, by about 10⁻⁴ in z, and the ripple showed as the
/// mean-curvature pictures' hairlines, in red and blue stripes along its fringe (the patch's own
/// H carried them; the blend's derivatives added little). A finer disk grid removes them; a finer
/// edge grid barely matters, so the edge charts pay for it and genus 10's fit keeps its time
/// (the fit bench's 5 s).
///
/// Measured with `ntori new` (largest |κ| against the input's; the flat faces' |H|·T at the 90th
/// percentile at the input's vertices) and, for the hairlines, |H| times the half-thickness T over
/// a t = 128 tessellation's points on the top face at least 0.05 inside its flat part (about a
/// million at genus 10): the 99.9th percentile, the largest, and how many points exceed 0.05.
/// Edge grid and disk grid before → after:
///
/// | genus | grids | \|κ\| | flat faces | 99.9% | largest | > 0.05 |
/// |---|---|---|---|---|---|---|
/// | 5 | 48/96 → 40/120 | 1.10× → 1.11× | 0.0080 → 0.0076 | 0.043 → 0.026 | 0.079 → 0.062 | 188 → 16 |
/// | 8 | 48/96 → 40/120 | 1.10× → 1.11× | 0.0101 → 0.0073 | 0.066 → 0.042 | 0.093 → 0.085 | 2978 → 311 |
/// | 10 | 48/96 → 40/120 | 1.12× → 1.14× | 0.0112 → 0.0080 | 0.067 → 0.049 | 0.106 → 0.085 | 4023 → 939 |
/// | 12 | 48/96 → 40/160 | 1.23× → 1.12× | 0.0137 → 0.0060 | 0.078 → 0.039 | 0.143 → 0.082 | 8360 → 270 |
/// | 15 | 48/96 → 40/160 | 1.34× → 1.19× | 0.0145 → 0.0060 | 0.089 → 0.045 | 0.202 → 0.086 | 11919 → 973 |
/// | 16 | 48/128 → 40/160 | 1.20× → 1.17× | 0.0112 → 0.0075 | 0.079 → 0.064 | 0.216 → 0.184 | 9038 → 4474 |
///
/// Genus 10's fit (the `initial_fit` bench's pipeline, best of two, runs alternated): 4.81 s at
/// 48/96, 4.77–4.85 s at 40/120, 5.27–5.41 s at 44/120 and 5.47–5.52 s at 44/128. 44/136 and
/// 44/160 (genus 10, 12, 15) were a little smoother still, for 0.5–1.3 s more. Genus 3 and 4
/// keep 48/96: they showed no hairline (no point above 0.05 at genus 3, 8 at genus 4), and at
/// 40/120 genus 3's |κ| rose from 1.12× to 1.15×. Genus 16 keeps ripples at its outer rim's ends
/// in its edge charts' own patches, where their cells (0.04–0.10 units) are finer than the
/// input's spacing; so do genus 17 and up (genus 24: 32 537 points above 0.05, 15 155 at
/// resolution 40; λ three times larger 27 968).
pub const FINE_DISK_GENERA: std::ops::RangeInclusive<u32> = 5..=16;

/// The edge charts' grid for [`FINE_DISK_GENERA`].
pub const FINE_DISK_EDGE_GRID: usize = 40;

/// The grid [`default_grid`] gives from genus 2 on, but for [`FINE_DISK_GENERA`] and
/// [`HIGH_GRID_GENERA`].
pub const FINE_GRID: usize = 48;

/// The genera whose plates take the finer grid [`HIGH_GRID`] (and, with it, the finer input mesh
/// of [`HIGH_GRID_FIT_TRIANGLES`]).
///
/// Why: at genus 32 on the grid of 48 the largest |κ| (1.70× the input's, over the Gauss–Bonnet
/// quadrature's points; 1.54× over a t = 128 tessellation's) sat on the outer rim's rounded edge
/// inside an edge chart (blend 0.92–0.94), where that chart's own patch bent to κ = −6.7 against
/// the rim's 4.0, its parameterization sheared there (E_u and E_v 148° apart). A finer input mesh
/// alone left it (resolution 26 → 28 → 30: 1.70× → 1.70× → 1.69×); a finer grid alone helped at
/// 56 (1.54×) and hurt at 64 (1.83×: the data grew sparse between knots); both together brought
/// it under 1.5× (`ntori new --genus G --grid g --resolution r`: largest |κ| against the input's,
/// flat faces' |H| × half-thickness and normals at the 90th percentile, time):
///
/// | genus | grid 48, defaults | grid 64, resolution | flat faces | normals | time |
/// |---|---|---|---|---|---|
/// | 30 | 1.53× | 1.31×, 31 | 0.0068 | 0.14° | 63 s |
/// | 31 | 1.71× | 1.49×, 30 | 0.0075 | 0.17° | 63 s |
/// | 32 | 1.70× (43 s) | 1.47×, 30 | 0.0070 | 0.16° | 67 s |
///
/// (grid 56 at resolution 30: genus 32 1.51×; 60: 1.48×.) Genus 29 and below read 1.40× and less
/// on 48 already.
pub const HIGH_GRID_GENERA: std::ops::RangeInclusive<u32> = 30..=32;

/// The edge charts' grid for [`HIGH_GRID_GENERA`] (the disk charts' follows it,
/// [`default_disk_grid`]).
pub const HIGH_GRID: usize = 64;

/// The disk charts' grid `ntori new` uses for `genus` and an edge-chart `grid` where none is
/// chosen (`None`: the same as the edge charts'): twice `grid` at genus 3 and 4 (96 at their 48),
/// three times from genus 5, four times from 11 and five times at 16 (120, 160 and 200 at
/// [`FINE_DISK_EDGE_GRID`], see [`FINE_DISK_GENERA`]; genus 16 with its edge samples, see
/// [`PLATE_EDGE_SAMPLE_GENERA`]), 16/3 from genus 17 and 8 times from genus 34 (256 and 384 at 48),
/// rounded up to a multiple of 8. (Genus 16 took 8/3 of 48, 128, before [`FINE_DISK_GENERA`].)
///
/// The inside and vertex charts are each a disk about a point whose hyperbolic neighbourhood
/// holds well over half the surface: the plate's bottom and top faces and, at their rims, the
/// sides of every hole nearest the centre and the outer rim between holes, where no edge chart
/// reaches far. Their coordinates are the Poincaré disk's, scaled, so a grid cell at a disk
/// chart's rim spans 1/(1 − r²) times what one at its centre does (r the image's radius: 0.76 at
/// genus 3, 0.92 at genus 10, 0.98 at genus 32): at genus 32, |E_u| reached 70–80 there against
/// the edge charts' 3–6, one cell spanned the rim's whole rounding, and the fit spiked. At
/// genus 3 to 10 the same coarse rims drew the ripples on the flat faces beside the holes (the
/// streaks of the mean-curvature pictures). There are only two disk charts against 2n edge
/// charts, so a finer grid there costs little: at genus 10, 96 adds 27% control points and
/// 0.5 s of fitting.
///
/// Measured with `ntori new` and the shape_report example (patch disagreement as % of the
/// diagonal; largest |κ| against the input's; normals from the intended shape at the 90th
/// percentile; flat faces' |H|·T at the 90th percentile; issue 12's targets 0.2%, 1.5×, 1°, 0.02):
///
/// | genus | disk grid 48 (the edge charts') | disk grid 96 | 128 |
/// |---|---|---|---|
/// | 3 | 0.087%, 1.40×, 0.51°, 0.029 | 0.023%, 1.42×, 0.38°, 0.016 | |
/// | 5 | 0.131%, 1.37×, 0.58°, 0.044 | 0.027%, 1.44×, 0.40°, 0.021 | 0.017%, 0.019 |
/// | 10 | 0.153%, 1.31×, 0.73°, 0.046 | 0.042%, 1.20×, 0.35°, 0.019 | |
/// | 16 | 0.005%, 1.47×, 0.76°, 0.038 | 0.005%, 1.26×, 0.40° | 0.004%, 1.24×, 0.30° |
/// | 32 | fails: Gauss–Bonnet 6.4e-2, 63× | | 0.015%, 1.89×, 0.47°; Gauss–Bonnet 3.2e-5 |
///
/// From genus 17 it is 16/3 of the grid (256). Genus 32 (21 points round each hole) read 3.37×
/// at 128, which fails `new`'s curvature check, and at 256 0.015%, 2.88×, 0.39°, Gauss–Bonnet
/// 1.0e-6 (63 s and 2.4 GB against 52 s and 1.7 GB). Genus 48 reads Gauss–Bonnet 6.6e-5 at 256
/// (|κ| 21× the input's). From genus 17 to 31 the 128 of genus 16 left the largest |κ| rising with
/// the genus, and `new` refused genus 27, 28, 29 and 31 (`ntori new`, largest |κ| against the
/// input's; the flat faces' |H|·T; time and memory on two cores, other work running):
///
/// | genus | disk grid 128 | 256 |
/// |---|---|---|
/// | 17 | 1.56×, 0.0179, 18 s, 1.4 GB | 1.41×, 0.0100, 23 s, 2.3 GB |
/// | 20 | 1.79×, 0.0180, 24 s, 1.6 GB | 1.50×, 0.0091, 29 s, 2.4 GB |
/// | 24 | 2.01×, 0.0188, 28 s, 1.6 GB | 1.70×, 0.0105, 30 s, 2.4 GB |
/// | 28 | 3.31× (refused), 0.0180 | 3.09× (refused), 0.0128 |
/// | 31 | 5.17× (refused), 0.0216 | 4.28× (refused), 0.0187 |
///
/// With 256 the agreement rows pay from genus 17 ([`plate_agreement`]), which bring 28 and 31
/// within `new`'s check; at 128 they made the peaks worse. Genus 16 kept 128 then: 256 left its largest
/// |κ| where it was (1.33×) for 0.9 GB more, though its flat faces read 0.0075 against 0.0149.
/// It now takes 160 on edge charts of 40 ([`FINE_DISK_GENERA`]).
///
/// From genus 34 it is 8 times the grid (384): with the agreement rows, genus 34 to 39 read 3.1× to
/// 4.1× at 256, which `new` refuses (3×), and 2.7× to 2.9× at 384 (34, 35, 37), for about 4.1 GB
/// against 3 GB and 50 to 60 s; genus 40, 44 and 48 read 8.9×, 4.4× and 5.8× at 256 and 3.7×,
/// 4.0× and 3.8× at 384 (40 at 512: 3.7×, 5.0 GB). Genus 64 at 256 read Gauss–Bonnet 2.7e-3 (issue
/// 12 asks for 1e-3) and at 384 6.9e-4, in 174 s and 3.4 GB against 165 s and 2.4 GB (at 128
/// 3.9e-2). Its largest |κ| stays about 110 times the input's at either grid, and a finer input
/// mesh (10 points round each hole, 275k triangles) left both as they were (2.1e-3, 105×): the spot
/// is where an edge chart's rim, sheared (its E_u and E_v 31° to 41° apart), blends with a disk
/// chart whose cells span 60 to 150 model units per chart unit there, the two patches 0.03 apart.
/// The agreement rows ([`plate_agreement`]) tie such patches together: at 384 with them genus 64
/// reads 5.3×, Gauss–Bonnet 1.1e-5 and patches within 0.001% of the diagonal (78 s, 4.4 GB).
///
/// Genus 2's disk charts keep the edge charts' grid: at 48 a disk grid of 64 smoothed the flat
/// faces' |H|·T from 0.0125 to 0.0095 but took the fit from 0.9 to 1.1 s, past issue 12's 1 s (see
/// [`default_grid`]).
pub fn default_disk_grid(genus: u32, grid: usize) -> Option<usize> {
    let (num, den) = match genus {
        0..=2 => return None,
        3..=4 => (2, 1),
        5..=10 => (3, 1),
        11..=15 => (4, 1),
        16 => (5, 1),
        17..=33 => (16, 3),
        _ => (8, 1),
    };
    Some((grid * num).div_ceil(8 * den).max(1) * 8)
}

/// The smoothness weight λ for a control grid where none is chosen: [`FitSettings::default`]'s
/// 1e-4 up to 32 per side, 2e-3 above. The second differences of a given surface's control grid
/// shrink as the grid's spacing squared, so the same weight smooths a finer grid less (by
/// (32/48)⁴ ≈ 0.2 at 48), and the finer grid has more freedom between the input's vertices: at 48
/// with 1e-4 the genus-3 plate's largest |κ| was 2.70× the input's, with 2e-3 1.42×; 5e-3 changed
/// no measure by more than 0.1 (shape_report, genus 2, 3, 5, 10; at 40, 2e-3 gave 1.18×, 1.50×,
/// 1.37×, 1.34×).
pub fn default_smoothness(grid: usize) -> f64 {
    if grid <= SplineSettings::default().grid {
        FitSettings::default().smoothness
    } else {
        2e-3
    }
}

/// The smoothness weight λ for `ntori new`'s plate of `genus` on a grid of `grid` where none is
/// chosen: [`PLATE_SMOOTHNESS`] on grids finer than 32 from genus 2 to
/// [`PLATE_SMOOTHNESS_UP_TO`] ([`STIFF_PLATE_SMOOTHNESS`] for [`STIFF_PLATE_GENERA`]),
/// [`default_smoothness`] otherwise (the sphere and the torus too).
pub fn default_plate_smoothness(genus: u32, grid: usize) -> f64 {
    if STIFF_PLATE_GENERA.contains(&genus) && grid > SplineSettings::default().grid {
        STIFF_PLATE_SMOOTHNESS
    } else if (2..=PLATE_SMOOTHNESS_UP_TO).contains(&genus) && grid > SplineSettings::default().grid
    {
        PLATE_SMOOTHNESS
    } else {
        default_smoothness(grid)
    }
}

/// The highest genus whose plate takes [`PLATE_SMOOTHNESS`]. `ntori new`'s largest |κ| (over the
/// Gauss–Bonnet quadrature's points too) against the input's, 2e-3 → 1e-2: genus 5 1.23× →
/// 1.14×, 8 1.27× → 1.25×, but 10 1.28× → 1.31×, 16 1.48× → 1.49×, 24 2.01× → 2.10× and 32
/// 2.88× → 2.92× (its check allows 3×), the peaks on the outer rim where an edge chart's patch
/// fades out, which the stronger weight does not reach (genus 10 and 16 at resolution 32; at 40,
/// genus 10's default now, 1.20× → 1.24×). Genus 9 is neutral (1.25× → 1.26×) and its normals
/// improve (0.21° → 0.20° at the 90th percentile), like genus 2 to 8's.
///
/// With the rims sampled finer across (`holed::RIM_REFINEMENT`) the data hold the rims more
/// tightly, and at 2e-3 the flat faces beside them rippled more (genus 10, |H| × half-thickness
/// at the 90th percentile over a t = 64 tessellation's points on the flat faces, the flat_report
/// example: 0.0193 with the plain mesh, 0.0212 with the rings). So from then on genus 10 to 16
/// take 1e-2 too; with the rings, 2e-3 → 1e-2 (`ntori new`'s largest |κ| against the input's,
/// and flat_report's |H| × half-thickness at the 90th percentile):
///
/// | genus | 10 | 11 | 12 | 13 | 14 | 15 | 16 |
/// |---|---|---|---|---|---|---|---|
/// | \|κ\| | 1.14× → 1.16× | 1.19× → 1.19× | 1.20× → 1.23× | 1.25× → 1.26× | 1.29× → 1.32× | 1.40× → 1.43× | 1.23× → 1.24× |
/// | flat faces | 0.0212 → 0.0197 | 0.0216 → 0.0197 | 0.0239 → 0.0230 | 0.0237 → 0.0227 | 0.0226 → 0.0223 | 0.0238 → 0.0233 | 0.0220 → 0.0209 |
///
/// Genus 17 to 30 (their rims sampled finer too, the agreement rows on, the grids' term) gained
/// most: 2e-3 → 1e-2, `ntori new`'s largest |κ| against the input's, and its flat faces' |H| ×
/// half-thickness at the 90th percentile at the input's vertices (normals within 0.01° of what
/// they were, patches within 0.0003% of the diagonal, the same time):
///
/// | genus | 17 | 18 | 19 | 20 | 21 | 22 | 23 |
/// |---|---|---|---|---|---|---|---|
/// | \|κ\| | 1.34× → 1.29× | 1.29× → 1.24× | 1.53× → 1.30× | 1.32× → 1.27× | 1.43× → 1.37× | 1.47× → 1.41× | 1.43× → 1.39× |
/// | flat faces | 0.0106 → 0.0085 | 0.0104 → 0.0086 | 0.0100 → 0.0080 | 0.0084 → 0.0076 | 0.0090 → 0.0083 | 0.0107 | 0.0122 |
///
/// | genus | 24 | 25 | 26 | 27 | 28 | 29 | 30 |
/// |---|---|---|---|---|---|---|---|
/// | \|κ\| | 1.73× → 1.42× | 1.67× → 1.53× | 1.66× → 1.57× | 1.74× → 1.51× | 1.58× → 1.53× | 1.85× → 1.66× | 1.92× → 1.74× |
/// | flat faces | 0.0127 → 0.0114 | 0.0134 | 0.0151 | 0.0168 | 0.0156 | 0.0158 | 0.0155 |
///
/// (The flat faces at 2e-3 were not recorded one by one from genus 22 to 30 but lay between 0.0125
/// and 0.0191.)
/// 3e-2 was no better (24 1.44×, 25 1.50×, 26 1.65×, 29 1.63×, 30 1.77×). From genus 31, whose
/// rims are sampled as the faces are, 1e-2 did not help on meshes of 200 000 triangles (31 2.21×
/// → 2.25×, 32 2.30× → 2.33×, 33 to 37 2.68–3.10×, genus 36 failing the curvature check), but on
/// the finer meshes of [`DEFAULT_FIT_TRIANGLES`] it did: genus 32 read 2.18× at 2e-3 and 1.88× at
/// 1e-2 (280 068 triangles), and 1e-2 gave 1.94–2.57× from 31 to 37 and 2.84× at 40, which was
/// refused before (3.7×). Genus 48 failed at 4.05× on the narrow bands; on the wide ones
/// (`holed::PLATE_BAND`) it passes at 2.97×, and genus 64 reads 3.23× at 2e-3, 3.17× at 1e-3 and
/// 13× at 3e-2 (all against the mesh's estimate of the input's |κ|, 3.09; against the eased rims'
/// own 4.15, which `new` takes since 2026-11-30, 2.40× at 2e-3).
pub const PLATE_SMOOTHNESS_UP_TO: u32 = 40;

/// The plates' smoothness weight on grids finer than 32 up to genus [`PLATE_SMOOTHNESS_UP_TO`]
/// ([`default_plate_smoothness`]), five times [`default_smoothness`]'s 2e-3 there. At 2e-3 genus 2's eased rims round the holes carried
/// fanned streaks of mean curvature along the input's rim vertices (32 round each hole), which
/// 1e-2 smooths away (pictures looked at, shaded and in mean curvature; a finer input mesh did
/// the same, 40 round each hole, but took the fit past issue 12's 1 s). Measured with the
/// shape_report example (largest |κ|, normals from the intended shape at the 90th percentile,
/// the flat faces' |H| times the half-thickness at the 90th percentile; patches within 0.005% of
/// the diagonal of what they were; the same time):
///
/// | genus | λ = 2e-3 | λ = 1e-2 |
/// |---|---|---|
/// | 2 | 4.60, 0.31°, 0.0125 | 4.37, 0.28°, 0.0131 |
/// | 3 | 4.71, 0.23°, 0.0119 | 4.55, 0.19°, 0.0112 |
/// | 5 | 4.61, 0.22°, 0.0141 | 4.44, 0.20°, 0.0128 |
/// | 10 | 4.89, 0.28°, 0.0175 | 4.91, 0.27°, 0.0164 |
/// | 16 | 5.22, 0.30°, 0.0181 | 5.22, 0.32°, 0.0182 |
/// | 24 | 6.36, 0.37°, 0.0188 | 5.87, 0.38°, 0.0175 |
/// | 32 | 7.84, 0.39°, 0.0165 | 7.27, 0.39°, 0.0130 |
///
/// At genus 2, 5e-2 went too far (patches 0.034% → 0.068%, flat faces 0.0159). The largest |κ|
/// here is over a t = 32 tessellation's vertices; `ntori new`'s, over the Gauss–Bonnet
/// quadrature's points too, rose from genus 10 on, which kept 2e-3 until their rims were sampled
/// finer ([`PLATE_SMOOTHNESS_UP_TO`]).
pub const PLATE_SMOOTHNESS: f64 = 1e-2;

/// The genera whose plates take [`STIFF_PLATE_SMOOTHNESS`] on grids finer than 32.
///
/// With their edge samples ([`PLATE_EDGE_SAMPLE_GENERA`]) the fit follows the rims more closely,
/// and from genus 27 its peaks of |κ| at the rims' start rose past issue 12's 1.5×. Measured with
/// `ntori new` (largest |κ| against the input's; points of the top face above 0.05 in |H| ×
/// half-thickness, of about two million, as in [`PLATE_EDGE_SAMPLE_GENERA`]), λ = 1e-2 → 3e-2:
///
/// | genus | 17 | 20 | 22 | 24 | 26 | 27 | 28 | 29 | 30 | 32 |
/// |---|---|---|---|---|---|---|---|---|---|---|
/// | \|κ\| | 1.43× → 1.21× | 1.33× → 1.19× | 1.27× → 1.29× | 1.31× → 1.36× | 1.35× → 1.39× | 1.51× → 1.47× | 1.47× → 1.37× | 1.54× → 1.35× | 1.67× → 1.33× | 1.81× → 1.44× |
/// | > 0.05 | 77 → 288 | 215 → 660 | 587 → 837 | 682 → 2072 | 3206 → 6634 | 3749 → 7715 | 3334 → 6943 | 3618 → 8077 | 348 → 843 | 1487 → 2381 |
///
/// The stronger weight costs hairlines everywhere, so it is kept where the peaks need it. Genus 31
/// read 1.59× at 3e-2 on resolution 30 (1.52× at 1e-1, 1.55× at 5e-2, 1.61× with the samples at
/// weight 1, 1.56× at weight 3, 1.80× without them; 1.49× before, with eased rims and no samples),
/// and reads 1.45× on 31, the finest within its budget ([`default_resolution`]). (30 to 32 have a grid of 64, whose second
/// differences are (48/64)² of 48's for the same bending: at the same λ they are smoothed a third
/// as much.)
pub const STIFF_PLATE_GENERA: std::ops::RangeInclusive<u32> = 27..=32;

/// The plates' smoothness weight for [`STIFF_PLATE_GENERA`], three times [`PLATE_SMOOTHNESS`].
pub const STIFF_PLATE_SMOOTHNESS: f64 = 3e-2;

/// `ntori new`'s spline and fit settings for `genus` where none are chosen: the default degree and
/// continuity, [`default_grid`], [`default_disk_grid`], and that grid's fit settings
/// ([`FitSettings::for_plate`]).
pub fn default_settings(genus: u32) -> (SplineSettings, FitSettings) {
    let grid = default_grid(genus);
    let spline = SplineSettings {
        grid,
        disk_grid: default_disk_grid(genus, grid),
        ..SplineSettings::default()
    };
    (spline, FitSettings::for_plate(genus, spline))
}

/// [`FitSettings::metric_coarsening`] for `new`'s plates.
pub const PLATE_METRIC_COARSENING: usize = 2;

/// The highest genus whose plate is fitted with the smoothness term in arc length
/// ([`plate_surface_smoothness`]).
pub const PLATE_SURFACE_SMOOTHNESS_UP_TO: u32 = 15;

/// Whether `ntori new`'s plate of `genus` on a control grid of `grid` is fitted with the
/// smoothness term measured in the surface's arc length ([`FitSettings::surface_smoothness`]):
/// up to genus [`PLATE_SURFACE_SMOOTHNESS_UP_TO`], on `new`'s own grids (32 and finer; the
/// assets' coarse grids of 8 and 16 keep the grids' term they were made with). On the grids'
/// term the eased rims round the holes carry swirls of mean curvature, fanned streaks along the
/// map's lines, which the arc-length term smooths away (mean-curvature pictures of genus 3, 12
/// and 16 looked at). Measured with `ntori new` (grids' term → arc length; largest |κ| against
/// the input's, normals against the intended shape's at the 90th percentile, time on two cores;
/// genus 0 to 5 and 24, 32 with the arc-length metric from a full-grid first fit, the rest from
/// the coarse one [`FitSettings::surface_smoothness`] now uses, which gives the same numbers at
/// genus 3 and 10 to within 0.01× and 0.01°):
///
/// | genus | \|κ\| / input's | normals (90%) | time |
/// |---|---|---|---|
/// | 0 | 1.01× → 1.02× | 0.01° → 0.01° | 0.21 → 0.22 s |
/// | 1 | 1.64× → 1.54× | 0.31° → 0.28° | 0.78 → 0.91 s |
/// | 2 | 1.44× → 1.31× | 0.72° → 0.70° | 1.97 → 2.18 s |
/// | 3 | 1.32× → 1.19× | 0.29° → 0.23° | 6.4 → 5.1 s |
/// | 4 | 1.30× → 1.13× | 0.25° → 0.20° | 5.7 → 7.0 s |
/// | 5 | 1.37× → 1.23× | 0.27° → 0.22° | 6.8 → 8.0 s |
/// | 6 | 1.32× → 1.17× | 0.27° → 0.22° | 7.1 → 7.6 s |
/// | 7 | 1.32× → 1.23× | 0.25° → 0.21° | 8.2 → 8.9 s |
/// | 8 | 1.24× → 1.27× | 0.25° → 0.21° | 9.4 → 10.1 s |
/// | 9 | 1.28× → 1.25× | 0.25° → 0.21° | 10.8 → 11.9 s |
/// | 10 | 1.36× → 1.28× | 0.35° → 0.28° | 9.8 → 10.7 s |
/// | 11 | 1.38× → 1.45× | 0.37° → 0.28° | 11.7 → 12.8 s |
/// | 12 | 1.42× → 1.51× | 0.39° → 0.29° | 13.4 → 14.1 s |
/// | 14 | 1.40× → 1.57× | 0.37° → 0.28° | 17.6 → 19.0 s |
/// | 16 | 1.48× → 1.98× | 0.30° → 0.23° | 22.9 → 25.6 s |
/// | 24 | 2.0× → 3.14× | 0.37° → 0.24° | 42 → 40 s |
/// | 32 | 2.88× → 5.40× (fails `new`'s 3×) | 0.39° → 0.24° | 54 → 66 s |
///
/// On the plates' flat faces (the shape_report example: |H| times the half-thickness at the 90th
/// percentile, issue 12 asks for 0.02) it takes genus 8 from 0.0201 to 0.0158, 10 from 0.0242 to
/// 0.0175, 12 from 0.0265 to 0.0194 and 14 from 0.0269 to 0.0186. Patches and the distance to the
/// input are the same to within 0.01% of the diagonal. The rows for genus 11 to 14 above are at
/// resolution 32: there the largest |κ| grows (past issue 12's 1.5× at 12 and 14), its peak on a
/// hole's rim where a disk chart's patch blends with an edge chart's, and follows the input's
/// sampling, not the metric (clamping it at 10 or 100 instead of 10⁴ left it, as did the disk
/// charts' own rows, the patch term's weight, a finer disk grid or λ up to 4 times larger). So
/// genus 11 to 15 take both the arc-length term and a finer input mesh ([`FINE_RESOLUTION_GENERA`],
/// where the numbers are), which brings every one of them within 1.5×. From genus 16 it raised the
/// peaks at any resolution tried (genus 20 at 40: 7.7 against the grids' term's 5.7 at 32).
pub fn plate_surface_smoothness(genus: u32, grid: usize) -> bool {
    genus <= PLATE_SURFACE_SMOOTHNESS_UP_TO && grid >= SplineSettings::default().grid
}

impl FitSettings {
    /// The defaults, with [`default_smoothness`] for `grid`.
    pub fn for_grid(grid: usize) -> FitSettings {
        FitSettings {
            smoothness: default_smoothness(grid),
            ..FitSettings::default()
        }
    }

    /// The defaults for `ntori new`'s plate of `genus` on the grids of `spline`: the weights
    /// [`default_plate_smoothness`] and [`plate_agreement`], and the smoothness term's form
    /// ([`FitSettings::plate_smoothness`]).
    pub fn for_plate(genus: u32, spline: SplineSettings) -> FitSettings {
        FitSettings {
            smoothness: default_plate_smoothness(genus, spline.grid),
            agreement: plate_agreement(genus, spline),
            edge_samples: plate_edge_samples(genus),
            ..FitSettings::default()
        }
        .plate_smoothness(genus, spline.grid)
    }

    /// These settings with the smoothness term a plate of `genus` on a grid of `grid` is fitted
    /// with: in arc length where [`plate_surface_smoothness`] says, its metric from a fit on
    /// grids [`PLATE_METRIC_COARSENING`] times coarser.
    pub fn plate_smoothness(self, genus: u32, grid: usize) -> FitSettings {
        FitSettings {
            surface_smoothness: plate_surface_smoothness(genus, grid),
            metric_coarsening: PLATE_METRIC_COARSENING,
            ..self
        }
    }
}

/// The genera whose plate's fit targets its edge samples ([`plate_edge_samples`]).
///
/// From genus 17 the edge charts' cells on the flat faces (0.04–0.10 model units at genus 24)
/// are as fine as the input's spacing there or finer (about 0.1), so between the vertices their
/// patches were held only by the smoothness term, and rippled: thin red and blue hairlines in a
/// mean-curvature picture (genus 32's gallery), with |H| × half-thickness up to 0.6–0.8 though
/// the 90th percentile at the vertices read under 0.01. The edge samples put three more targets
/// per vertex on the intended surface. Measured with `ntori new` (largest |κ| against the input's)
/// and, over a t = 128 tessellation's points on the top face at least 0.05 inside its flat part
/// (about two million from genus 17), |H| × half-thickness at the 99.9th percentile and how many
/// points exceed 0.05; time and peak memory of the whole `new`, before → after (the rims eased
/// from genus 22 before, smooth after, [`crate::holed::SMOOTH_RIMS_UP_TO`]):
///
/// | genus | \|κ\| | 99.9% | > 0.05 | time | memory |
/// |---|---|---|---|---|---|
/// | 17 | 1.29× → 1.43× | 0.104 → 0.030 | 10 719 → 77 | 24.5 → 26.2 s | 2.7 → 4.0 GB |
/// | 20 | 1.27× → 1.33× | 0.103 → 0.030 | 11 559 → 215 | 31.2 → 32.3 s | 3.2 → 4.6 GB |
/// | 22 | 1.28× → 1.27× | 0.190 → 0.035 | 29 467 → 587 | 33.7 → 36.9 s | 3.5 → 4.9 GB |
/// | 24 | 1.27× → 1.31× | 0.189 → 0.037 | 32 537 → 682 | 36.2 → 47.1 s | 3.6 → 5.2 GB |
/// | 26 | 1.30× → 1.35× | 0.182 → 0.050 | 36 197 → 3 206 | 43.6 → 46.1 s | 3.8 → 5.6 GB |
/// | 28 | 1.43× → 1.37× | 0.217 → 0.065 | 47 514 → 6 943 | 47.5 → 47.0 s | 3.6 → 5.5 GB |
/// | 30 | 1.27× → 1.33× | 0.212 → 0.036 | 45 206 → 843 | 59.8 → 70.1 s | 6.5 → 8.8 GB |
/// | 32 | 1.47× → 1.44× | 0.24 → 0.044 | 56 866 → 2 381 | 54.9 → 76.2 s | 6.4 → 9.1 GB |
///
/// (28 to 32 with [`STIFF_PLATE_SMOOTHNESS`]; the times from runs one after another, 32's alone.)
/// The samples cost up to half as much memory again, and at genus 32 double the fit's own stage
/// (15.4 → 29.4 s: A's nonzeros 20 → 46 million, AᵀA 1.4 → 6.0 s, its factorization 9.4 →
/// 14.9 s). Tried and left:
/// - weight 1 or 0.5 instead of 2 (genus 32, smooth rims, λ 1e-2: 1.66× and 1889 points, 1.52×
///   and 2991, against 1.81× and 1487); weight 4 on the flat faces alone at 24 read 3408;
/// - samples on the flat faces only: the rims' curvature peaks rose (genus 24 2.39×, 32 5.11×);
///   on the flat faces only 0.15 or more from the rims, the hairlines stayed (24: 16 887);
/// - with the rims eased as before, the peaks rose at the rims' start in the edge charts (24
///   1.43×, 32 2.37×); smooth rims without samples left the hairlines (24: 17 121, 32: 38 389);
/// - the samples at the middle of their ends' chart coordinates rather than the geodesic
///   midpoint: along the faces up to 0.027 model units from where the fit put them (0.015 at the
///   geodesic midpoint), the vertices' residual 0.035% of the diagonal against 0.019%;
/// - centroids of the flat faces' triangles as well (genus 24: 7832 → 6037 points, 1.37× → 1.40×).
///
/// Genus 5 to 16 have hairlines of another kind, fewer and fainter, along the vertex chart's
/// coarse rim cells ([`FINE_DISK_GENERA`]): there the samples alone helped less (16: 4474 → 2650
/// points, 1.17× → 1.26×, 1.3 GB more). Genus 16, in the gallery, takes them with a disk grid of
/// 200 instead of 160: 951 points, 99.9th percentile 0.064 → 0.044, 1.15×, 24.8 → 30.4 s, 2.0 →
/// 3.5 GB (the disk grid alone at 192 on 48: 2529 points). Left out for the samples beyond the
/// vertices: their chart patches' own rows (genus 24: 682 → 1602 points, 1.31× → 1.35×, 0.7 GB
/// less).
pub const PLATE_EDGE_SAMPLE_GENERA: std::ops::RangeInclusive<u32> = 16..=32;

/// The edge samples' weight ([`FitSettings::edge_samples`]) for `new`'s plates: together they
/// weigh as much as the vertices (see [`PLATE_EDGE_SAMPLE_GENERA`] for 1 and 0.5).
pub const PLATE_EDGE_SAMPLE_WEIGHT: f64 = 2.0;

/// [`FitSettings::edge_samples`] for `ntori new`'s plate of `genus`: [`PLATE_EDGE_SAMPLE_WEIGHT`]
/// for [`PLATE_EDGE_SAMPLE_GENERA`], none otherwise.
pub fn plate_edge_samples(genus: u32) -> f64 {
    if PLATE_EDGE_SAMPLE_GENERA.contains(&genus) {
        PLATE_EDGE_SAMPLE_WEIGHT
    } else {
        0.0
    }
}

/// The lowest genus whose plate is fitted with agreement rows ([`plate_agreement`]).
pub const PLATE_AGREEMENT_FROM: u32 = 17;

/// The agreement rows' weight for `new`'s plates ([`plate_agreement`]). Genus 31 with disk grids of
/// 256 (largest |κ| against the input's): 4.28× without, 2.19× at 0.1, 2.21× at 0.3, 2.54× at 1,
/// 3.65× at 10; genus 28: 1.82× at 0.1, 1.81× at 0.3.
pub const PLATE_AGREEMENT: f64 = 0.3;

/// The agreement rows' weight ([`FitSettings::agreement`]) for `ntori new`'s plate of `genus` on
/// the grids of `spline`: [`PLATE_AGREEMENT`] from genus [`PLATE_AGREEMENT_FROM`] where the disk
/// charts' grid is at least five times the edge charts' (as [`default_disk_grid`] makes it from
/// genus 17), none otherwise.
///
/// From genus 17 the charts' supports overlap by a coverage margin of 0.024 chart units or less
/// (0.018 at genus 24, 0.014 at 31 and 32, 0.007 at 64: `charts::scales`). Where a plate's rim
/// crosses such a fringe, the blend turns from a disk chart's patch to an edge chart's within a
/// few hundredths of a model unit, less than the input's spacing there, and the two patches, each
/// fitted to the data only at the data's points, part between them by a few thousandths: the
/// blend's second derivative times that gap drew a ridge of curvature along the fringe, a few
/// hundredths wide (the spot_report example, `NTORI_LINE=1`: at genus 31, |κ| 1.6 → 16.4 → 1.6
/// across it, each patch's own |κ| 4.4 and 1.3). The agreement rows tie the patches together
/// between the data. With disk grids coarser than that the disk charts' cells span the rim's
/// rounding there, and tying the edge charts' patches to them made it worse (genus 24 at 128:
/// 2.01× → 3.92×, 31: 5.17× → 6.07×). Measured with `ntori new` (largest |κ| against the
/// input's; `new` refuses above 3×):
///
/// | genus | disk grid 128 (8/3 of 48) | 256 | 256 with agreement 0.3 |
/// |---|---|---|---|
/// | 24 | 2.01× | 1.70× | 1.61× |
/// | 28 | 3.31× (refused) | 3.09× (refused) | 1.81× |
/// | 31 | 5.17× (refused) | 4.28× (refused) | 2.21× |
/// | 32 | — | 2.88× | 2.30× |
/// | 36 | — | 5.76× (refused) | 2.94× |
///
/// The patches' disagreement falls from 0.004–0.035% of the diagonal to 0.001–0.004%. From
/// genus 18 to 23 the rows gain a little (18: 1.58× → 1.52×, 21: 1.66× → 1.64×, 23: 1.94× →
/// 1.93×), but genus 20 loses (1.50× → 1.84×: its peak is in an edge chart's own patch, which the
/// rows pull towards the vertex chart's just inside that chart's fade), and the flat faces' |H|·T
/// rises by about a tenth (0.0097 → 0.0107 at genus 19); memory by 0.4 to 0.6 GB. Genus 36 takes
/// disk grids of 384 ([`default_disk_grid`]): 2.71×.
///
/// A user's mesh (`ntori fit`) keeps none by default: on issue 14's test meshes weight 1 left them
/// as they were or worse (the acceptance example: the cube with tunnels 3.10% → 4.17% of the
/// diagonal off), though it brings the gear (`assets/meshes/gear-genus-1.obj`) within every check
/// (patches 2.16% → 0.81% apart).
pub fn plate_agreement(genus: u32, spline: SplineSettings) -> f64 {
    if genus >= PLATE_AGREEMENT_FROM && spline.disk_grid() >= 5 * spline.grid {
        PLATE_AGREEMENT
    } else {
        0.0
    }
}

/// The resolution `ntori new` and the editor use for `genus`: [`TORUS_RESOLUTION`] for the torus,
/// [`FINE_RESOLUTION`] for genus 3 to 16, [`DEFAULT_RESOLUTION`] for the others, or where that
/// mesh has more triangles than the genus's budget ([`fit_triangle_budget`]; from genus 27), the
/// finest within it: genus 27 gets 30, 28 gets 29, 29 gets 28, 31 and 32 get 29, 48 gets 16, 64
/// gets 10. Where even resolution 8 has more, 8 (no genus up to 64 does: genus 64 has
/// 223 516 triangles at 8).
///
/// Until 2026-11-29 the step down aimed 3% under the budget and left genus 27 to 29 and 31 one to
/// three resolutions coarser (30, 29, 28, 30). On the finest within it, `ntori new`'s largest |κ|
/// against the input's read: genus 27 1.47× → 1.43×, 28 1.37× → 1.44×, 29 1.35× → 1.42×, 31
/// 1.59× → 1.45× (issue 12's target 1.5×), its flat-face points above 0.05 in |H| × half-thickness
/// 2872 → 2310, for about 6% more triangles.
///
/// Why 40 from genus 3 (to 9 at first; 10 to 16 below): there the fit's largest curvature sits on a hole's rim between the
/// input's vertices (0.1 apart on a rim of radius 0.25 at 32), and its size follows the rim's
/// sampling, not the grid (genus 5 with a grid of 56 and disk grid 112 read 1.56×, a smoothness
/// 1000 times larger moved it from 6.05 to 5.77). Measured with `ntori new` (largest |κ| over the
/// Gauss–Bonnet quadrature's points against the input's; issue 12's target 1.5×) and the
/// shape_report example (the flat faces' |H|·T at the 90th percentile, weighted by area; target
/// 0.02), release, this machine:
///
/// | genus | 32 | 36 | 40 | time of `ntori new`, 32 → 40 |
/// |---|---|---|---|---|
/// | 3 | 1.52×; 0.018 | 1.33× | 1.32×; 0.013 | 4.9 → 5.3 s |
/// | 4 | 1.43× | 1.41× | 1.30× | 5.1 → 6.3 s |
/// | 5 | 1.54×; 0.025 | 1.53× | 1.37×; 0.017 | 6.6 → 8.0 s |
/// | 6, 7, 8, 9 | 1.40–1.46× | | 1.32×, 1.32×, 1.24×, 1.28× | |
/// | 10 | 1.36×; 0.024 | | 1.24×; 0.020 | 13.3 → 17.5 s |
///
/// Normals from the intended shape (90th percentile) improve too (genus 5: 0.40° → 0.27°), and the
/// patches' disagreement stays within 0.02–0.04% of the diagonal. Genus 10 takes 40 since its fit
/// became fast enough (see [`FINE_RESOLUTION_GENERA`]). Genus 11 to 15 take 40 with the arc-length smoothness
/// ([`plate_surface_smoothness`]), which at 32 raised their peaks; `ntori new`, 32 with the grids'
/// term → 40 in arc length (largest |κ| against the input's, normals at the 90th percentile,
/// time):
///
/// | genus | \|κ\| / input's | normals (90%) | time |
/// |---|---|---|---|
/// | 11 | 1.38× → 1.34× | 0.37° → 0.22° | 11.3 → 15.9 s |
/// | 12 | 1.42× → 1.46× | 0.39° → 0.24° | 13.2 → 19.2 s |
/// | 13 | 1.51× → 1.44× | 0.38° → 0.24° | 15.9 → 21.4 s |
/// | 14 | 1.40× → 1.44× | 0.37° → 0.23° | 17.5 → 23.8 s |
/// | 15 | 1.55× → 1.49× | 0.40° → 0.24° | 19.9 → 28.8 s |
///
/// and the flat faces' |H|·T at the 90th percentile (shape_report) at genus 12 0.0265 → 0.0185,
/// at 14 0.0269 → 0.0172. Genus 16 (the grids' term) takes 40 too: its largest |κ| sat on the
/// outer rim inside one edge chart (blend 0.99997) at 1.48–1.49× the input's; at 40 it reads
/// 1.32×, normals 0.30° → 0.22° at the 90th percentile, flat faces' |H|·T 0.0182 → 0.0149, in
/// 24.2 s against 17.8 s and 1.5 GB against 1.3 GB (172 100 triangles, 189 516 with the rims'
/// rings, within [`DEFAULT_FIT_TRIANGLES`]). Genus 20 at 32 read 1.79×, and at 40 1.63× (252 692 triangles,
/// past the budget of then, 200 000), so from 17 the plates keep 32, or less where the budget says. A finer mesh
/// only near the rims (the flat faces at 1.5 or 2 times the rims' spacing) was tried: it kept the curvature gain at genus 5 (1.33×) at the time of
/// resolution 32, but the flat faces rippled (|H|·T 0.044–0.061), and genus 32 with rims at 32
/// read 3.66× against 3.37× (its peak is not on a rim's samples).
pub fn default_resolution(genus: u32) -> Result<usize, EmbeddingError> {
    default_mesh(genus).map(|(resolution, _)| resolution)
}

/// [`default_resolution`] and its mesh, which choosing it builds (`ntori new` fits that one rather
/// than building it again: a second or two at high genus).
pub fn default_mesh(genus: u32) -> Result<(usize, HoledMesh), EmbeddingError> {
    let mut resolution = if genus == 1 {
        TORUS_RESOLUTION
    } else if FINE_RESOLUTION_GENERA.iter().any(|g| g.contains(&genus)) {
        FINE_RESOLUTION
    } else {
        DEFAULT_RESOLUTION
    };
    let budget = fit_triangle_budget(genus);
    // The mesh at a resolution where it is within the budget, else its count of triangles (at
    // least that many where the fit refuses it as too fine at all): enough to scale down from.
    let within_budget = |resolution| -> Result<Result<HoledMesh, usize>, EmbeddingError> {
        match HoledMesh::new(genus, resolution) {
            Ok(mesh) if mesh.triangles.len() <= budget => Ok(Ok(mesh)),
            Ok(mesh) => Ok(Err(mesh.triangles.len())),
            Err(EmbeddingError::FitTooLarge { triangles, .. }) if resolution > 8 => {
                Ok(Err(triangles))
            }
            Err(e) => Err(e),
        }
    };
    // The coarsest resolution known to be over the budget.
    let mut over = None;
    let mut chosen = loop {
        match within_budget(resolution)? {
            Ok(mesh) => break mesh,
            Err(_) if resolution <= 8 => return Ok((resolution, HoledMesh::new(genus, 8)?)),
            Err(count) => {
                over = Some(resolution);
                let scale = (budget as f64 / count as f64).sqrt();
                resolution = ((scale * resolution as f64) as usize).clamp(8, resolution - 1);
            }
        }
    };
    // The step down rounds down, and the rims' rings make the count grow a little faster than the
    // square: the next finer resolution may fit as well (genus 27 to 29 and 31 were left one to
    // three resolutions under the budget by a step that aimed 3% below it).
    while let Some(over_budget) = over
        && resolution + 1 < over_budget
    {
        match within_budget(resolution + 1)? {
            Ok(finer) => {
                chosen = finer;
                resolution += 1;
            }
            Err(_) => break,
        }
    }
    Ok((resolution, chosen))
}

/// The whole pipeline: mesh (at `resolution`), cut, flatten, fit. Refuses, before the fit
/// allocates anything, an input mesh of more than [`MAX_FIT_TRIANGLES`] triangles
/// ([`EmbeddingError::FitTooLarge`]).
pub fn initial_model(
    genus: u32,
    resolution: usize,
    settings: SplineSettings,
    fit_settings: FitSettings,
) -> Result<InitialFit, EmbeddingError> {
    initial_model_with_progress(genus, resolution, settings, fit_settings, &|_| {})
}

/// [`initial_model`], telling `progress` each stage as it begins.
pub fn initial_model_with_progress(
    genus: u32,
    resolution: usize,
    settings: SplineSettings,
    fit_settings: FitSettings,
    progress: &dyn Fn(FitStage),
) -> Result<InitialFit, EmbeddingError> {
    progress(FitStage::Meshing);
    let mesh = HoledMesh::new(genus, resolution)?;
    initial_model_of(mesh, resolution, settings, fit_settings, progress)
}

/// [`initial_model_with_progress`] from its mesh, made at `resolution` (e.g. by [`default_mesh`]);
/// `progress` hears of the stages after the meshing.
pub fn initial_model_of(
    mesh: HoledMesh,
    resolution: usize,
    settings: SplineSettings,
    fit_settings: FitSettings,
    progress: &dyn Fn(FitStage),
) -> Result<InitialFit, EmbeddingError> {
    let genus = mesh.genus;
    let atlas = Arc::new(Atlas::new(genus)?);
    let layout = Layout::new(&atlas, settings)?;
    if mesh.triangles.len() > MAX_FIT_TRIANGLES {
        return Err(EmbeddingError::FitTooLarge {
            genus,
            resolution,
            triangles: mesh.triangles.len(),
            at_least: false,
            max: MAX_FIT_TRIANGLES,
        });
    }
    progress(FitStage::Flattening {
        triangles: mesh.triangles.len(),
    });
    let parameterization = match atlas.polygon() {
        None => stereographic(&atlas, &mesh),
        Some(polygon) => flatten(
            &atlas,
            polygon,
            &mesh,
            fit_settings.stretch_rounds,
            progress,
        )?,
    };
    progress(FitStage::Fitting);
    let weights = vertex_areas(&mesh.positions, &mesh.triangles);
    let samples = match fit_settings.edge_samples {
        w if w > 0.0 => edge_samples(&atlas, &mesh, &parameterization, &weights, w)?,
        _ => Samples::default(),
    };
    let control = fit(
        &layout,
        &[parameterization.points.as_slice(), &samples.points].concat(),
        &[mesh.positions.as_slice(), &samples.targets].concat(),
        &[weights.as_slice(), &samples.weights].concat(),
        fit_settings,
    )?;
    let (mut sum, mut max) = (0.0, 0.0f64);
    for (p, target) in parameterization.points.iter().zip(&mesh.positions) {
        let e = (layout.eval(&control, *p).pos - target).norm();
        sum += e * e;
        max = max.max(e);
    }
    let surface = Surface::new(Arc::clone(&atlas), settings, control)?;
    Ok(InitialFit {
        surface,
        rms_residual: (sum / mesh.positions.len() as f64).sqrt(),
        max_residual: max,
        mesh_diagonal: diagonal(&mesh.positions),
        edge_samples: samples.points.len(),
        mesh,
        parameterization,
    })
}

/// Fit targets besides the mesh's vertices: where they lie in the charts, where in space, and how
/// much each weighs (in the units of [`vertex_areas`]).
#[derive(Default)]
struct Samples {
    points: Vec<ChartPoint>,
    targets: Vec<Point3>,
    weights: Vec<f64>,
}

/// The plate's [`HoledMesh::edge_samples`] as fit targets, each at the hyperbolic (on the torus,
/// Euclidean) midpoint of its edge's ends in the map, weighing `weight` times a sixth of the mean
/// of its ends' [`vertex_areas`] (on an even mesh, a third of a triangle each way: 1 makes the
/// samples a third of the data's weight). The geodesic midpoint does not depend on the chart, as
/// the midpoint of chart coordinates does: at genus 24 that one lay up to 0.027 model units along
/// the face from where the fit put the edge's midpoint, against 0.015 for the geodesic one. The
/// sphere, mapped without a cut, has none.
fn edge_samples(
    atlas: &Atlas,
    mesh: &HoledMesh,
    parameterization: &Parameterization,
    areas: &[f64],
    weight: f64,
) -> Result<Samples, EmbeddingError> {
    let Some(disk) = &parameterization.disk else {
        return Ok(Samples::default());
    };
    let hyperbolic = atlas
        .polygon()
        .is_some_and(|p| p.geometry() == Geometry::Hyperbolic);
    // Each mesh edge's ends as disk copies of one triangle, so their positions lie in one frame.
    let mut copies = HashMap::with_capacity(3 * disk.triangles.len());
    for t in &disk.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            copies.insert(
                (disk.original[a as usize], disk.original[b as usize]),
                (a, b),
            );
        }
    }
    let mut samples = Samples::default();
    for e in &mesh.edge_samples {
        let [a, b] = e.ends;
        let Some(&(ca, cb)) = copies.get(&(a, b)).or_else(|| copies.get(&(b, a))) else {
            return Err(EmbeddingError::Parameterization(format!(
                "the edge sample between vertices {a} and {b} has no edge in the cut disk"
            )));
        };
        let (p, q) = (
            parameterization.copies[ca as usize],
            parameterization.copies[cb as usize],
        );
        let middle = map_midpoint(p, q, hyperbolic);
        samples.points.push(deepest(atlas, ModelPoint(middle))?);
        samples.targets.push(e.position);
        samples
            .weights
            .push(edge_sample_weight(weight, areas, e.ends));
    }
    Ok(samples)
}

/// The midpoint of the map's segment from `p` to `q`: the hyperbolic one in the Poincaré disk
/// ([`geodesic_midpoint`]), the Euclidean one in the torus's plane.
pub(crate) fn map_midpoint(p: Complex64, q: Complex64, hyperbolic: bool) -> Complex64 {
    if hyperbolic {
        geodesic_midpoint(p, q)
    } else {
        0.5 * (p + q)
    }
}

/// An edge sample's fit weight: `weight` times a sixth of the mean of its ends' [`vertex_areas`]
/// (on an even mesh, a third of a triangle each way: 1 makes the samples a third of the data's
/// weight).
pub(crate) fn edge_sample_weight(weight: f64, areas: &[f64], [a, b]: [u32; 2]) -> f64 {
    weight * (areas[a as usize] + areas[b as usize]) / 12.0
}

/// The midpoint of the hyperbolic segment from `p` to `q` in the Poincaré disk: the isometry
/// taking `p` to 0 takes the segment onto a radius, whose midpoint halves the distance
/// 2 artanh |q′|.
fn geodesic_midpoint(p: Complex64, q: Complex64) -> Complex64 {
    let one = Complex64::new(1.0, 0.0);
    let q1 = (q - p) / (one - p.conj() * q);
    let r = q1.norm();
    let m1 = if r > 0.0 {
        q1 * ((0.5 * r.atanh()).tanh() / r)
    } else {
        q1
    };
    (m1 + p) / (one + p.conj() * m1)
}

/// The bounding-box diagonal of a point set.
pub fn diagonal(points: &[Point3]) -> f64 {
    let (lo, hi) = crate::surface::bounding_box(points);
    (hi - lo).norm()
}

/// A third of the area of the triangles around each vertex.
pub fn vertex_areas(positions: &[Point3], triangles: &[[u32; 3]]) -> Vec<f64> {
    let mut areas = vec![0.0; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let third = (b - a).cross(&(c - a)).norm() / 6.0;
        for v in t {
            areas[*v as usize] += third;
        }
    }
    areas
}

// ------------------------------------------------------------------------------------------ cut

/// Cuts a closed mesh along its loops. Each vertex on a loop is split into one copy per wedge of
/// triangles between consecutive loop edges around it (p₀: 4n copies; other loop vertices: two).
pub fn cut(mesh: &HoledMesh) -> Result<CutDisk, EmbeddingError> {
    let fail = |what: &str| EmbeddingError::Parameterization(what.to_string());
    let n = mesh.positions.len();
    let he = HalfEdgeMesh::from_polygons(n, mesh.triangles.iter().map(|t| &t[..]))
        .map_err(|e| fail(&e.to_string()))?;
    let topology = he.topology();
    if topology.isolated_vertices > 0 {
        return Err(fail("a mesh vertex belongs to no triangle"));
    }
    if topology.misoriented_edges > 0 || topology.nonmanifold_edges > 0 {
        return Err(fail("an edge is used twice in the same direction"));
    }
    if !topology.closed {
        return Err(fail("the mesh has a boundary"));
    }
    let is_cut: std::collections::HashSet<(u32, u32)> = mesh
        .loops
        .iter()
        .flat_map(|l| l.windows(2).map(|w| (w[0].min(w[1]), w[0].max(w[1]))))
        .collect();
    let cut_edge = |h: u32| {
        let (a, b) = (he.origin(h), he.target(h));
        is_cut.contains(&(a.min(b), a.max(b)))
    };
    // A corner is named by its outgoing half-edge; triangle t's corner k is half-edge 3t + k.
    let mut copy = vec![u32::MAX; he.halfedge_count()];
    let mut original = Vec::new();
    for (v, fan) in he.outgoing().into_iter().enumerate() {
        // Wedges start at a corner whose outgoing edge is a loop edge, and turn clockwise (across
        // the incoming edge) until the next loop edge; a vertex off the loops is one wedge.
        let starts: Vec<u32> = fan.iter().copied().filter(|&h| cut_edge(h)).collect();
        let starts = if starts.is_empty() {
            vec![fan[0]]
        } else {
            starts
        };
        for mut h in starts {
            let id = original.len() as u32;
            original.push(v as u32);
            while copy[h as usize] == u32::MAX {
                copy[h as usize] = id;
                let incoming = he.prev(h);
                if cut_edge(incoming) {
                    break;
                }
                h = he
                    .twin(incoming)
                    .ok_or_else(|| fail("the mesh has a boundary"))?;
            }
        }
    }
    if copy.contains(&u32::MAX) {
        return Err(fail("the mesh is not a manifold at some vertex"));
    }
    let triangles: Vec<[u32; 3]> = (0..he.face_count() as u32)
        .map(|f| {
            let hs = he.face_halfedges(f);
            [0, 1, 2].map(|k| copy[(hs.start + k) as usize])
        })
        .collect();
    let start = original
        .iter()
        .position(|&o| o == mesh.base)
        .ok_or_else(|| fail("the base vertex is not on the cut"))?;
    let boundary =
        boundary_cycle(original.len(), &triangles, Some(start as u32)).map_err(|e| match e {
            EmbeddingError::Parameterization(why) => fail(&format!("the cut mesh: {why}")),
            other => other,
        })?;
    let arcs = label_arcs(mesh, &original, &boundary)?;
    Ok(CutDisk {
        original,
        triangles,
        boundary,
        arcs,
    })
}

/// The boundary of a disk of counter-clockwise triangles (its half-edges without a twin) as one
/// counter-clockwise cycle of vertices, from `start` (by default its smallest vertex). Vertices no
/// triangle uses are allowed.
pub(crate) fn boundary_cycle(
    vertex_count: usize,
    triangles: &[[u32; 3]],
    start: Option<u32>,
) -> Result<Vec<u32>, EmbeddingError> {
    let fail = |what: &str| EmbeddingError::Parameterization(what.to_string());
    let he = HalfEdgeMesh::from_polygons(vertex_count, triangles.iter().map(|t| &t[..]))
        .map_err(|e| fail(&e.to_string()))?;
    let mut next = HashMap::new();
    for h in (0..he.halfedge_count() as u32).filter(|&h| he.twin(h).is_none()) {
        if next.insert(he.origin(h), he.target(h)).is_some() {
            return Err(fail("not a disk (a boundary vertex repeats)"));
        }
    }
    let start = match start {
        Some(s) => s,
        None => *next.keys().min().ok_or_else(|| fail("no boundary"))?,
    };
    let mut cycle = vec![start];
    let mut v = *next
        .get(&start)
        .ok_or_else(|| fail("the base vertex is not on the boundary"))?;
    while v != start {
        cycle.push(v);
        v = *next
            .get(&v)
            .ok_or_else(|| fail("the boundary is not closed"))?;
        if cycle.len() > next.len() {
            return Err(fail("the boundary is not one cycle"));
        }
    }
    if cycle.len() != next.len() {
        return Err(fail("more than one boundary: not a disk"));
    }
    Ok(cycle)
}

/// Splits the boundary at the copies of p₀ into 4n arcs and matches them to polygon sides: arcs that
/// run along the same loop must land on partner sides (4k + t ↔ 4k + t + 2).
fn label_arcs(
    mesh: &HoledMesh,
    original: &[u32],
    boundary: &[u32],
) -> Result<Vec<(usize, usize)>, EmbeddingError> {
    let fail = |what: String| EmbeddingError::Parameterization(what);
    let mut loop_of = HashMap::new();
    for (l, path) in mesh.loops.iter().enumerate() {
        for w in path.windows(2) {
            loop_of.insert((w[0].min(w[1]), w[0].max(w[1])), l);
        }
    }
    let starts: Vec<usize> = (0..boundary.len())
        .filter(|&i| original[boundary[i] as usize] == mesh.base)
        .collect();
    let sides = 4 * mesh.genus as usize;
    if starts.len() != sides {
        return Err(fail(format!(
            "the cut has {} corners, the polygon {sides}",
            starts.len()
        )));
    }
    let loops: Vec<usize> = starts
        .iter()
        .map(|&i| {
            let (a, b) = (
                original[boundary[i] as usize],
                original[boundary[(i + 1) % boundary.len()] as usize],
            );
            loop_of[&(a.min(b), a.max(b))]
        })
        .collect();
    let partner = |e: usize| 4 * (e / 4) + (e % 4 + 2) % 4;
    let shift = (0..sides)
        .find(|&s| {
            (0..sides).all(|i| loops[i] == loops[(partner((i + s) % sides) + sides - s) % sides])
        })
        .ok_or_else(|| fail("the loops do not read a1 b1 a1⁻¹ b1⁻¹ … around the cut".into()))?;
    Ok(starts
        .iter()
        .enumerate()
        .map(|(i, &start)| (start, (i + shift) % sides))
        .collect())
}

// ---------------------------------------------------------------------------------- flattening

/// Every mesh vertex's surface point: cut, pin the boundary to the polygon, Floater, locate.
///
/// Floater's map is solved on the closed surface (see [`crate::harmonic`]); `stretch_rounds` rounds
/// of stretch-minimizing reweighting follow (see `Lifts::reweight`).
pub fn parameterize(
    atlas: &Atlas,
    mesh: &HoledMesh,
    stretch_rounds: usize,
) -> Result<Parameterization, EmbeddingError> {
    if mesh.genus != atlas.genus() {
        return Err(EmbeddingError::Mismatch);
    }
    match atlas.polygon() {
        None => Ok(stereographic(atlas, mesh)),
        Some(polygon) => flatten(atlas, polygon, mesh, stretch_rounds, &|_| {}),
    }
}

/// Genus 0: the round sphere's own points.
fn stereographic(atlas: &Atlas, mesh: &HoledMesh) -> Parameterization {
    Parameterization {
        points: stereographic_points(atlas, &mesh.positions),
        disk: None,
        flat: Vec::new(),
        lifts: Vec::new(),
        copies: Vec::new(),
        folded: 0,
        sweeps: 0,
        planar_rounds: 0,
        coarse_to_fine: false,
        equalizing_rounds: 0,
        newton: None,
        map_distortion: None,
    }
}

/// The genus-0 atlas's chart points of points on a sphere round the origin: ζ = (x + iy)/(R + z),
/// the north cap around ζ = 0 (z ≥ 0), the south around ∞.
pub(crate) fn stereographic_points(atlas: &Atlas, sphere: &[Point3]) -> Vec<ChartPoint> {
    let (north, south) = (&atlas.charts()[0], &atlas.charts()[1]);
    sphere
        .iter()
        .map(|p| {
            let r = p.coords.norm();
            let xy = Complex64::new(p.x, p.y);
            if p.z >= 0.0 {
                ChartPoint::new(north.id(), xy / ((r + p.z) * north.scale()))
            } else {
                // 1/(λζ) = (x − iy)/(λ(R − z)): finite at the south pole.
                ChartPoint::new(south.id(), xy.conj() / ((r - p.z) * south.scale()))
            }
        })
        .collect()
}

fn flatten(
    atlas: &Atlas,
    polygon: &Polygon,
    mesh: &HoledMesh,
    stretch_rounds: usize,
    progress: &dyn Fn(FitStage),
) -> Result<Parameterization, EmbeddingError> {
    let hyperbolic = polygon.geometry() == Geometry::Hyperbolic;
    let (disk, flat, mut lifts) = floater_lifts(polygon, mesh)?;
    let solved = lifts.settle_rounds(&mesh.positions, hyperbolic, stretch_rounds, progress)?;
    let folded = lifts.folded_triangles(hyperbolic);
    let copies = (0..disk.original.len() as u32)
        .map(|c| lifts.copy_position(&disk, c))
        .collect();
    let points = lifts
        .home
        .iter()
        .map(|&z| deepest(atlas, ModelPoint(z)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Parameterization {
        points,
        disk: Some(disk),
        flat,
        lifts: lifts.home,
        copies,
        folded,
        sweeps: solved.sweeps,
        planar_rounds: 0,
        coarse_to_fine: false,
        equalizing_rounds: 0,
        newton: Some(solved),
        map_distortion: None,
    })
}

/// The plate cut into a disk, Floater's map of it onto the polygon (in the Klein model where
/// hyperbolic), and the lifts that map starts from.
pub(crate) fn floater_lifts(
    polygon: &Polygon,
    mesh: &HoledMesh,
) -> Result<(CutDisk, Vec<[f64; 2]>, Lifts), EmbeddingError> {
    let disk = cut(mesh)?;
    let hyperbolic = polygon.geometry() == Geometry::Hyperbolic;
    let pins = pin_boundary(polygon, mesh, &disk);
    let positions: Vec<Point3> = disk
        .original
        .iter()
        .map(|&o| mesh.positions[o as usize])
        .collect();
    let pins_flat: Vec<(u32, [f64; 2])> = pins
        .iter()
        .map(|&(v, w)| {
            let k = if hyperbolic { poincare_to_klein(w) } else { w };
            (v, [k.re, k.im])
        })
        .collect();
    let flat = floater::parameterize(&positions, &disk.triangles, &pins_flat)?;
    let model: Vec<Complex64> = flat
        .iter()
        .map(|k| {
            let k = Complex64::new(k[0], k[1]);
            if hyperbolic { klein_to_poincare(k) } else { k }
        })
        .collect();
    let lifts = Lifts::new(polygon, mesh, &disk, &model, &positions)?;
    Ok((disk, flat, lifts))
}

/// The mesh's vertices in the model (Poincaré disk or plane), one lift each (its *home*), with
/// the group elements that carry each disk copy's neighbours into that lift's frame. Floater's map
/// solves each side of a cut independently, so the flattening has a kink along every loop and a
/// cone-like singularity at p₀; relaxing on the closed surface (every vertex to the mean value
/// average of its neighbours, seen across the cuts through the side pairings) removes both.
pub(crate) struct Lifts {
    pub(crate) home: Vec<Complex64>,
    /// For each mesh vertex: its neighbours (weight, vertex, map from the neighbour's home lift
    /// into this vertex's frame).
    pub(crate) neighbours: Vec<Vec<(f64, u32, Lft)>>,
    /// For each triangle: its corners' mesh vertices and the group elements taking their home lifts
    /// into one frame where the triangle is whole.
    pub(crate) corners: Vec<[(u32, Lft); 3]>,
    /// For each disk copy: the group element taking its vertex's home lift onto it (empty where
    /// the map was not made from a cut disk).
    to_copy: Vec<Lft>,
    pub(crate) base: usize,
}

impl Lifts {
    fn new(
        polygon: &Polygon,
        mesh: &HoledMesh,
        disk: &CutDisk,
        model: &[Complex64],
        positions: &[Point3],
    ) -> Result<Lifts, EmbeddingError> {
        // The side of each boundary copy other than p₀'s.
        let mut side = vec![None; disk.original.len()];
        let len = disk.boundary.len();
        for (a, &(start, s)) in disk.arcs.iter().enumerate() {
            let end = disk.arcs.get(a + 1).map_or(len, |next| next.0);
            for &c in &disk.boundary[start + 1..end] {
                side[c as usize] = Some(s);
            }
        }
        // Home: the copy inside the disk, or on a side 4k or 4k + 1; copies on 4k + 2, 4k + 3 are
        // its images under cross(side), which maps the partner side onto that side. p₀'s home is
        // corner 0; its other copies are reached by walking round the vertex.
        let mut home_copy = vec![u32::MAX; mesh.positions.len()];
        let mut to_copy = vec![Lft::IDENTITY; disk.original.len()];
        let corner_maps = corner_maps(polygon);
        for &(start, s) in &disk.arcs {
            let c = disk.boundary[start] as usize;
            let corner = polygon.edge_corners(s).0;
            to_copy[c] = corner_maps[corner];
            if corner == 0 {
                home_copy[mesh.base as usize] = c as u32;
            }
        }
        for (c, &o) in disk.original.iter().enumerate() {
            match side[c] {
                _ if o == mesh.base => {}
                Some(s) if s % 4 >= 2 => to_copy[c] = *polygon.cross(s),
                _ => home_copy[o as usize] = c as u32,
            }
        }
        let home: Vec<Complex64> = home_copy
            .iter()
            .map(|&c| match c {
                u32::MAX => Complex64::new(f64::NAN, f64::NAN),
                c => model[c as usize],
            })
            .collect();
        if home.iter().any(|z| z.is_nan()) {
            return Err(EmbeddingError::Parameterization(
                "a vertex on the cut has no home copy".into(),
            ));
        }
        let weights = floater::mean_value_weights(positions, &disk.triangles)?;
        let mut neighbours = vec![Vec::new(); mesh.positions.len()];
        for (a, list) in weights.iter().enumerate() {
            let back = to_copy[a].inverse();
            for &(b, w) in list {
                let u = disk.original[b as usize];
                neighbours[disk.original[a] as usize].push((
                    w,
                    u,
                    back.compose(&to_copy[b as usize]),
                ));
            }
        }
        let corners = disk
            .triangles
            .iter()
            .map(|t| t.map(|c| (disk.original[c as usize], to_copy[c as usize])))
            .collect();
        Ok(Lifts {
            home,
            neighbours,
            corners,
            to_copy,
            base: mesh.base as usize,
        })
    }

    /// Lifts from their parts, for maps not made from a cut disk.
    pub(crate) fn from_parts(
        home: Vec<Complex64>,
        neighbours: Vec<Vec<(f64, u32, Lft)>>,
        corners: Vec<[(u32, Lft); 3]>,
        base: usize,
    ) -> Lifts {
        Lifts {
            home,
            neighbours,
            corners,
            to_copy: Vec::new(),
            base,
        }
    }

    /// Moves every vertex's home lift into the polygon (by the side pairings that bring it there),
    /// and the group elements that see its neighbours and its triangles along with it; the map on
    /// the surface is the same. A user's mesh starts with every vertex at the origin, and the
    /// sweeps then carry whole regions into tiles far from the polygon (the cube with tunnels of
    /// `embedding/tests/shapes`: |z| up to 1 − 4e-8), where the disk's coordinates lose the digits
    /// that tell neighbours apart; Newton's method stalled there (the residual stuck at 3e-5). Only
    /// for maps not made from a cut disk (whose copies are tied to the homes) and in the hyperbolic
    /// disk (the plane has no boundary to lose digits at).
    pub(crate) fn rehome(&mut self, polygon: &Polygon) {
        if !self.to_copy.is_empty() || polygon.geometry() != Geometry::Hyperbolic {
            return;
        }
        let moves: Vec<Lft> = self
            .home
            .iter_mut()
            .map(|z| {
                let (reduced, h) = polygon.reduce_with_map(*z);
                *z = reduced;
                h
            })
            .collect();
        let inverses: Vec<Lft> = moves.iter().map(Lft::inverse).collect();
        for (v, around) in self.neighbours.iter_mut().enumerate() {
            for (_, u, g) in around.iter_mut() {
                *g = moves[v].compose(&g.compose(&inverses[*u as usize]));
            }
        }
        for corners in &mut self.corners {
            for (v, g) in corners.iter_mut() {
                *g = g.compose(&inverses[*v as usize]);
            }
        }
    }

    /// The map at its fixed point ([`Lifts::settle`]), then `stretch_rounds` rounds of
    /// reweighting by the stretch against `positions` (the mesh's), each settled again; each round
    /// told to `progress`.
    ///
    /// A round before the last is solved only to [`EARLY_ROUND_TOLERANCE`]: its map serves only
    /// to measure the stretch, and the last round's fixed point is the map. A round whose map
    /// does not settle is dropped with those after it, and the map is the round before's
    /// ([`Convergence::rounds_dropped`]).
    pub(crate) fn settle_rounds(
        &mut self,
        positions: &[Point3],
        hyperbolic: bool,
        stretch_rounds: usize,
        progress: &dyn Fn(FitStage),
    ) -> Result<Convergence, EmbeddingError> {
        self.settle_rounds_by(
            positions,
            hyperbolic,
            stretch_rounds,
            progress,
            &mut |lifts, tolerance, kept| lifts.settle(hyperbolic, tolerance, kept),
        )
    }

    /// [`Lifts::settle_rounds`] with `settle` for [`Lifts::settle`] (a test makes a round fail).
    pub(crate) fn settle_rounds_by(
        &mut self,
        positions: &[Point3],
        hyperbolic: bool,
        stretch_rounds: usize,
        progress: &dyn Fn(FitStage),
        settle: &mut SettleRound,
    ) -> Result<Convergence, EmbeddingError> {
        let rounds = stretch_rounds + 1;
        let tolerance = |round: usize| {
            if round < rounds {
                EARLY_ROUND_TOLERANCE
            } else {
                RELAX_TOLERANCE
            }
        };
        progress(FitStage::Relaxing { round: 1, rounds });
        let mut kept = None;
        let mut solved = settle(self, tolerance(1), &mut kept)?;
        for round in 2..=rounds {
            progress(FitStage::Relaxing { round, rounds });
            let stretch = self.stretch(positions, hyperbolic);
            // Only the weights and the map change in a round: they are what a dropped round
            // puts back (the adjacency's vertices and pairings, five times the bytes, stay).
            let before = (self.home.clone(), self.weights());
            self.reweight(&stretch);
            match settle(self, tolerance(round), &mut kept) {
                Ok(next) => solved = solved.then(next),
                Err(EmbeddingError::Parameterization(why)) => {
                    // The reweighting moved the fixed point further than Newton's method goes
                    // from the round before's (a user's genus-16 mesh: round 1 settled in two
                    // steps, round 2's steps shrank to 1e-8 and stalled at a residual of 0.39).
                    // The rounds before stand: their map is a fixed point, settled here to the
                    // final tolerance.
                    tracing::info!(
                        round,
                        %why,
                        "a stretch round did not settle: the map keeps the rounds before it"
                    );
                    self.home = before.0;
                    self.set_weights(&before.1);
                    let mut fresh = None;
                    solved = solved.then(settle(self, RELAX_TOLERANCE, &mut fresh)?);
                    solved.rounds_dropped += rounds + 1 - round;
                    break;
                }
                Err(e) => return Err(e),
            }
        }
        Ok(solved)
    }

    /// The map at its fixed point by Newton's method to `tolerance` (see
    /// [`crate::harmonic`]), which leaves its last Jacobian in `kept` for the next round.
    ///
    /// A first round (nothing kept) starts from Floater's map, far from the fixed point:
    /// [`WARMUP_SWEEPS`] sweeps smooth it first. A later round starts at the round before's fixed
    /// point, its weights changed a little: there the kept Jacobian, as GMRES's preconditioner,
    /// takes it most of the way and sweeps only slow it down. Measured on `ntori new`'s second
    /// round (with chord steps then): genus 10 1.24 s (300 sweeps, 2 factorizations) → 0.57 s
    /// (none, 1), genus 32 12.2 s → 7.0 s; the map the same to the tolerance.
    pub(crate) fn settle(
        &mut self,
        hyperbolic: bool,
        tolerance: f64,
        kept: &mut Option<crate::harmonic::KeptJacobian>,
    ) -> Result<Convergence, EmbeddingError> {
        let swept = if kept.is_none() {
            let pattern = crate::harmonic::pattern(self, hyperbolic);
            let (swept, analysis) = rayon::join(
                || self.relax(hyperbolic, WARMUP_SWEEPS, RELAX_TOLERANCE),
                || crate::harmonic::KeptJacobian::analyse(pattern),
            );
            *kept = Some(analysis?);
            swept
        } else {
            0
        };
        let mut solved = crate::harmonic::solve(self, hyperbolic, tolerance, kept)?;
        solved.sweeps += swept;
        Ok(solved)
    }

    /// Over-relaxed Gauss–Seidel sweeps of the mean value average, taken in each vertex's own frame
    /// (the isometry moving it to the origin, where the Poincaré disk is conformal to the plane),
    /// until no vertex moves by more than `tolerance` (in frame units) in a sweep, or `sweeps` run
    /// out. Returns the sweeps used.
    pub(crate) fn relax(&mut self, hyperbolic: bool, sweeps: usize, tolerance: f64) -> usize {
        // Over-relaxation speeds the slow global modes up (1.3 is stable at every genus tried; 1.6
        // diverges at genus 8); the step is capped so that no vertex jumps out of its neighbourhood
        // (a step of length ≥ 1 would leave the disk).
        const OVER: f64 = 1.3;
        const MAX_STEP: f64 = 0.25;
        let anchor = self.home[self.base];
        let adjacency = Adjacency::new(&self.neighbours);
        for sweep in 0..sweeps {
            // The largest squared move of the sweep (compared squared: `hypot` per vertex was a
            // tenth of the map's time). The torus's shift below moves every vertex: its moves are
            // taken from a copy.
            let before = (!hyperbolic).then(|| self.home.clone());
            let mut moved = 0.0f64;
            for v in 0..self.home.len() {
                let z = self.home[v];
                let to_frame = |p: Complex64| {
                    if hyperbolic {
                        (p - z) / (Complex64::ONE - z.conj() * p)
                    } else {
                        p - z
                    }
                };
                let (mut sum, mut total) = (Complex64::ZERO, 0.0);
                for &(w, u, g) in adjacency.of(v) {
                    let p = self.home[u as usize];
                    // Only edges across the cut carry a side pairing; the identity's image is the
                    // point itself, bit for bit, so skipping it changes nothing but the time.
                    let p = match g {
                        Adjacency::IDENTITY => p,
                        g => adjacency.pairings[g as usize].apply(p),
                    };
                    sum += to_frame(p) * w;
                    total += w;
                }
                let mut d = sum / total * OVER;
                if d.norm_sqr() > MAX_STEP * MAX_STEP {
                    d *= MAX_STEP / d.norm();
                }
                let next = if hyperbolic {
                    (d + z) / (Complex64::ONE + z.conj() * d)
                } else {
                    d + z
                };
                moved = moved.max((next - z).norm_sqr());
                self.home[v] = next;
            }
            if let Some(before) = before {
                // The flat torus's harmonic maps are unique up to translation (a symmetry that
                // commutes with the pairings): keep p₀ where it started.
                let shift = self.home[self.base] - anchor;
                self.home.iter_mut().for_each(|z| *z -= shift);
                moved = self
                    .home
                    .iter()
                    .zip(&before)
                    .map(|(a, b)| (a - b).norm_sqr())
                    .fold(0.0, f64::max);
            }
            if moved.sqrt() < tolerance {
                return sweep + 1;
            }
        }
        sweeps
    }

    /// Per mesh vertex: √(3D area / model area) of its triangles, relative to the whole surface's
    /// ratio (1 where the map shrinks the surface by the average amount).
    pub(crate) fn stretch(&self, positions: &[Point3], hyperbolic: bool) -> Vec<f64> {
        let n = self.home.len();
        let (mut surface, mut model) = (vec![0.0; n], vec![0.0; n]);
        for t in &self.corners {
            let [a, b, c] = t.map(|(v, _)| positions[v as usize]);
            let area3 = (b - a).cross(&(c - a)).norm() / 2.0;
            let z = self.corner_positions(t);
            let area2 = if hyperbolic {
                charts::hyperbolic_area(z)
            } else {
                0.5 * ((z[1] - z[0]).conj() * (z[2] - z[0])).im
            }
            .max(0.0);
            for &(o, _) in t {
                surface[o as usize] += area3;
                model[o as usize] += area2;
            }
        }
        relative_stretch(&surface, &model)
    }

    /// Every neighbour's weight, vertex by vertex in [`Lifts::neighbours`]' order.
    fn weights(&self) -> Vec<f64> {
        self.neighbours.iter().flatten().map(|n| n.0).collect()
    }

    /// Puts back weights taken by [`Lifts::weights`].
    fn set_weights(&mut self, weights: &[f64]) {
        for (n, &w) in self.neighbours.iter_mut().flatten().zip(weights) {
            n.0 = w;
        }
    }

    /// Yoshizawa, Belyaev and Seidel's stretch-minimizing update, damped: each weight w_vu is divided
    /// by a power of the stretch at u, so where the map squeezes the surface the neighbourhood opens
    /// up. Weights stay positive, so the map stays a bijection.
    pub(crate) fn reweight(&mut self, stretch: &[f64]) {
        for list in &mut self.neighbours {
            for (w, u, _) in list.iter_mut() {
                *w /= stretch_divisor(stretch[*u as usize]);
            }
        }
    }

    /// A disk copy's position: its vertex's home lift carried onto the copy.
    fn copy_position(&self, disk: &CutDisk, c: u32) -> Complex64 {
        let o = disk.original[c as usize];
        self.to_copy[c as usize].apply(self.home[o as usize])
    }

    /// A triangle's corners in its frame.
    pub(crate) fn corner_positions(&self, t: &[(u32, Lft); 3]) -> [Complex64; 3] {
        t.map(|(v, g)| g.apply(self.home[v as usize]))
    }

    /// Each triangle's [`triangle_distortion`] (3D area, σ₁/σ₂, Jacobian), in its corners' frame.
    fn triangle_distortions<'a>(
        &'a self,
        positions: &'a [Point3],
        hyperbolic: bool,
    ) -> impl Iterator<Item = (f64, f64, f64)> + 'a {
        self.corners.iter().map(move |t| {
            let p = t.map(|(v, _)| positions[v as usize]);
            triangle_distortion(p, self.corner_positions(t), hyperbolic)
        })
    }

    /// The map's [`Distortion`] over every triangle, each in its corners' frame.
    pub(crate) fn distortion(&self, positions: &[Point3], hyperbolic: bool) -> Option<Distortion> {
        let triangles: Vec<_> = self.triangle_distortions(positions, hyperbolic).collect();
        Distortion::of(&triangles)
    }

    /// The area-weighted mean over the triangles of ln(σ₁/σ₂)², each in its corners' frame: 0 for
    /// a conformal map. A triangle the map collapses counts as σ₁/σ₂ = [`MAX_ANISOTROPY`]; a map
    /// with a lift that is not a number is infinitely bad.
    pub(crate) fn log_anisotropy(&self, positions: &[Point3], hyperbolic: bool) -> f64 {
        if self
            .home
            .iter()
            .any(|z| !(z.re.is_finite() && z.im.is_finite()))
        {
            return f64::INFINITY;
        }
        let (mut sum, mut total) = (0.0, 0.0);
        for (area, ratio, _) in self.triangle_distortions(positions, hyperbolic) {
            if area > 0.0 {
                let ratio = if ratio.is_nan() {
                    MAX_ANISOTROPY
                } else {
                    ratio.min(MAX_ANISOTROPY)
                };
                sum += area * ratio.ln().powi(2);
                total += area;
            }
        }
        if total > 0.0 {
            sum / total
        } else {
            f64::INFINITY
        }
    }

    /// Triangles whose lifted corners are not counter-clockwise (hyperbolic or Euclidean area ≤ 0):
    /// a relaxed map that is a bijection has none.
    pub(crate) fn folded_triangles(&self, hyperbolic: bool) -> usize {
        self.corners
            .iter()
            .filter(|t| {
                let p = self.corner_positions(t);
                let area = if hyperbolic {
                    charts::hyperbolic_area(p)
                } else {
                    0.5 * ((p[1] - p[0]).conj() * (p[2] - p[0])).im
                };
                area.is_nan() || area <= 0.0
            })
            .count()
    }
}

/// Per vertex: √(3D area / model area) of its triangles (summed per vertex in `surface` and
/// `model`), relative to the whole surface's ratio and clamped to [0.1, 10].
pub(crate) fn relative_stretch(surface: &[f64], model: &[f64]) -> Vec<f64> {
    let ratio = surface.iter().sum::<f64>() / model.iter().sum::<f64>();
    surface
        .iter()
        .zip(model)
        .map(|(s, m)| {
            (s / (m * ratio).max(f64::MIN_POSITIVE))
                .sqrt()
                .clamp(0.1, 10.0)
        })
        .collect()
}

/// [`Lifts::neighbours`] packed for the sweeps: each vertex's (weight, neighbour, pairing) in one
/// array, the pairing an index into a table of the few that are not the identity. 16 bytes an
/// entry against the 80 of a (weight, vertex, Lft) triple, and no pointer to follow per vertex: a
/// sweep is memory-bound. Same sums in the same order as over `neighbours`.
struct Adjacency {
    start: Vec<usize>,
    entries: Vec<(f64, u32, u32)>,
    pairings: Vec<Lft>,
}

impl Adjacency {
    /// The pairing index of an edge within the cut disk (no pairing).
    const IDENTITY: u32 = u32::MAX;

    fn new(neighbours: &[Vec<(f64, u32, Lft)>]) -> Adjacency {
        let mut packed = Adjacency {
            start: Vec::with_capacity(neighbours.len() + 1),
            entries: Vec::with_capacity(neighbours.iter().map(Vec::len).sum()),
            pairings: Vec::new(),
        };
        packed.start.push(0);
        for list in neighbours {
            for &(w, u, g) in list {
                let pairing = if g == Lft::IDENTITY {
                    Self::IDENTITY
                } else {
                    packed.pairings.push(g);
                    (packed.pairings.len() - 1) as u32
                };
                packed.entries.push((w, u, pairing));
            }
            packed.start.push(packed.entries.len());
        }
        packed
    }

    fn of(&self, v: usize) -> &[(f64, u32, u32)] {
        &self.entries[self.start[v]..self.start[v + 1]]
    }
}

/// What a neighbour's weight is divided by where the map stretches the surface by `stretch` there
/// (see [`STRETCH_EXPONENT`]).
pub(crate) fn stretch_divisor(stretch: f64) -> f64 {
    stretch.powf(STRETCH_EXPONENT)
}

/// For each polygon corner c, the group element taking corner 0's neighbourhood onto corner c's: the
/// walk round the vertex goes from corner c_i to c_{i+1} = cross(e_i)⁻¹(c_i), so the map of c_{i+1}
/// is cross(e_i)⁻¹ after the map of c_i.
fn corner_maps(polygon: &Polygon) -> Vec<Lft> {
    let mut maps = vec![Lft::IDENTITY; polygon.sides()];
    let mut map = Lft::IDENTITY;
    for step in polygon.vertex_cycle() {
        maps[step.corner] = map;
        map = polygon.cross(step.leave_by).inverse().compose(&map);
    }
    maps
}

/// The representation of a model point that lies deepest inside its chart.
pub(crate) fn deepest(atlas: &Atlas, z: ModelPoint) -> Result<ChartPoint, EmbeddingError> {
    let m = atlas.locate_model(z);
    m.representations()
        .iter()
        .copied()
        .max_by(|a, b| {
            let depth = |p: &ChartPoint| atlas.charts()[p.chart.index()].domain().margin(p.coords);
            depth(a).total_cmp(&depth(b))
        })
        .ok_or_else(|| {
            EmbeddingError::Parameterization(format!("the model point {} lies in no chart", z.0))
        })
}

/// Boundary pins in the model (Poincaré disk or square): each arc's vertices at the fraction of their
/// loop's 3D arc length, measured along the side by hyperbolic (or Euclidean) length.
fn pin_boundary(polygon: &Polygon, mesh: &HoledMesh, disk: &CutDisk) -> Vec<(u32, Complex64)> {
    let fractions = loop_fractions(mesh);
    let mut pins = Vec::with_capacity(disk.boundary.len());
    let len = disk.boundary.len();
    for (a, &(start, side)) in disk.arcs.iter().enumerate() {
        let end = disk.arcs.get(a + 1).map_or(len, |next| next.0);
        let (c0, c1) = polygon.edge_corners(side);
        let (p, q) = (polygon.corners()[c0], polygon.corners()[c1]);
        let first = disk.original[disk.boundary[start] as usize];
        let second = disk.original[disk.boundary[(start + 1) % len] as usize];
        for i in start..end {
            let v = disk.boundary[i];
            let t = if i == start {
                0.0
            } else {
                let (f, forward) = fractions[&(disk.original[v as usize], first, second)];
                if forward { f } else { 1.0 - f }
            };
            pins.push((v, along_side(polygon.geometry(), p, q, t)));
        }
    }
    pins
}

/// For each loop vertex v (other than p₀), keyed by (v, first, second) where (first, second) is the
/// loop's first edge read in either direction: its arc-length fraction along the loop and whether
/// that key's direction is the loop's own.
fn loop_fractions(mesh: &HoledMesh) -> HashMap<(u32, u32, u32), (f64, bool)> {
    let mut out = HashMap::new();
    for path in &mesh.loops {
        let lengths: Vec<f64> = path
            .windows(2)
            .map(|w| (mesh.positions[w[1] as usize] - mesh.positions[w[0] as usize]).norm())
            .collect();
        let total: f64 = lengths.iter().sum();
        let (m, base) = (path.len() - 1, path[0]);
        let mut s = 0.0;
        for i in 1..m {
            s += lengths[i - 1];
            out.insert((path[i], base, path[1]), (s / total, true));
            out.insert((path[i], base, path[m - 1]), (s / total, false));
        }
    }
    out
}

/// The point at fraction t of the side from corner p to corner q, by hyperbolic length in the
/// Poincaré disk (through the isometry taking p to 0), by length in the plane.
fn along_side(geometry: Geometry, p: Complex64, q: Complex64, t: f64) -> Complex64 {
    match geometry {
        Geometry::Hyperbolic => {
            let to_origin = |z: Complex64| (z - p) / (Complex64::ONE - p.conj() * z);
            let back = |w: Complex64| (w + p) / (Complex64::ONE + p.conj() * w);
            let q0 = to_origin(q);
            let d = q0.norm().atanh();
            back(q0 / q0.norm() * (t * d).tanh())
        }
        _ => p + (q - p) * t,
    }
}

/// Poincaré disk → Klein disk: k = 2w / (1 + |w|²).
pub fn poincare_to_klein(w: Complex64) -> Complex64 {
    w * (2.0 / (1.0 + w.norm_sqr()))
}

/// Klein disk → Poincaré disk: w = k / (1 + √(1 − |k|²)).
pub fn klein_to_poincare(k: Complex64) -> Complex64 {
    k / (1.0 + (1.0 - k.norm_sqr()).max(0.0).sqrt())
}

// ------------------------------------------------------------------------------------------ fit

/// Least-squares control points: Σ_i w_i |S(p_i) − P_i|² + smoothness, solved at once for every
/// chart by one sparse factorisation (the three coordinates share it): the normal equations by
/// sparse Cholesky with one refinement step. `weights` are per-point weights (e.g. vertex areas;
/// normalised here to mean 1).
pub fn fit(
    layout: &Layout,
    points: &[ChartPoint],
    targets: &[Point3],
    weights: &[f64],
    settings: FitSettings,
) -> Result<Vec<Point3>, EmbeddingError> {
    if points.len() != targets.len() || points.len() != weights.len() || points.is_empty() {
        return Err(EmbeddingError::Parameterization(
            "the fit needs one target and weight per surface point".into(),
        ));
    }
    if !(settings.smoothness.is_finite() && settings.smoothness > 0.0) {
        return Err(EmbeddingError::Parameterization(format!(
            "the smoothness weight must be a positive number, got {}",
            settings.smoothness
        )));
    }
    let data = DataRows::with_agreement(layout, points, targets, weights, settings);
    if !settings.surface_smoothness {
        let alongside = || data.analysis(layout);
        let analysis = Analysis::Alongside(&alongside);
        return data.solve(
            layout,
            &smoothness_rows(layout),
            settings.smoothness,
            analysis,
        );
    }
    if settings.metric_coarsening <= 1 {
        // The first fit is on these grids with the plain rows, whose pattern the analysis holds
        // too: made on the other core while the first system is formed, it serves both fits,
        // where the first had analysed its own (`ntori fit` of the genus-4 bench mesh, 10 706
        // vertices: the fit's stage took 5.5 to 5.9 s, against 6.0 to 6.3 s).
        let make = || data.analysis(layout);
        let (control, analysis) = data.solve_keeping(
            layout,
            &smoothness_rows(layout),
            settings.smoothness,
            Analysis::Alongside(&make),
        )?;
        let metrics = crate::bending::grid_metrics(layout, &control);
        let smooth = crate::bending::arc_length_rows(layout, &metrics);
        let analysis = analysis.as_ref().map_or(Analysis::Here, Analysis::Ahead);
        return data.solve(layout, &smooth, settings.smoothness, analysis);
    }
    // The arc-length rows need a first fit, here on coarser grids; the normal equations' analysis
    // needs only which control points the rows reach, which the data rows and the rows' stencils
    // tell: both at once.
    let (smooth, analysis) = rayon::join(
        || coarse_arc_length_smoothness(layout, points, targets, weights, settings),
        || data.analysis(layout),
    );
    // Where the analysis could not be made, the solve makes its own (and reports what fails).
    let analysis = analysis.as_ref().map_or(Analysis::Here, Analysis::Ahead);
    data.solve(layout, &smooth?, settings.smoothness, analysis)
}

/// The smoothness rows in the surface's arc length ([`FitSettings::surface_smoothness`]), with the
/// metric read off a first fit with the plain rows on grids [`FitSettings::metric_coarsening`]
/// times coarser, from its patches' derivatives (at genus 10 the first fit on the full grids took
/// 1.8 s of the fit's 3.7 s; the coarse one about 0.6 s).
fn coarse_arc_length_smoothness(
    layout: &Layout,
    points: &[ChartPoint],
    targets: &[Point3],
    weights: &[f64],
    settings: FitSettings,
) -> Result<Vec<Vec<(usize, f64)>>, EmbeddingError> {
    let fine = layout.settings();
    let coarsening = settings.metric_coarsening;
    let coarser = |g: usize| (g / coarsening).max(fine.degree + 2);
    let coarse = SplineSettings {
        grid: coarser(fine.grid),
        disk_grid: fine.disk_grid.map(coarser),
        ..fine
    };
    let coarse_layout = Layout::new(layout.atlas(), coarse)?;
    // The plain rows' energy per unit of a surface's bending grows as the grid step to the fourth
    // power (λ (N / R) Σ (Δ²P)² with Δ²P ≈ h² S''), so the coarse grid takes λ scaled down by it.
    let step = |g: usize| 1.0 / (g - fine.degree) as f64;
    let plain = FitSettings {
        surface_smoothness: false,
        smoothness: settings.smoothness * (step(fine.grid) / step(coarse.grid)).powi(4),
        ..settings
    };
    // Here the other core is making the fine system's analysis (see `fit`): this one's is made
    // from its own AᵀA.
    let control = DataRows::with_agreement(&coarse_layout, points, targets, weights, plain).solve(
        &coarse_layout,
        &smoothness_rows(&coarse_layout),
        plain.smoothness,
        Analysis::Here,
    )?;
    Ok(crate::bending::arc_length_rows(
        layout,
        &crate::bending::patch_metrics(layout, &coarse_layout, &control),
    ))
}

/// The fit's data rows (the points and the patch terms): A's entries and the right-hand sides.
struct DataRows {
    triplets: Vec<Triplet<usize, usize, f64>>,
    rhs: Mat<f64>,
    /// The surface points fitted (N, which the smoothness weight is relative to).
    points: usize,
}

impl DataRows {
    /// The rows of [`DataRows::new`], and the agreement rows where `settings` asks for them.
    fn with_agreement(
        layout: &Layout,
        points: &[ChartPoint],
        targets: &[Point3],
        weights: &[f64],
        settings: FitSettings,
    ) -> DataRows {
        let start = std::time::Instant::now();
        let mut data = DataRows::new(layout, points, targets, weights, settings.patch_weight);
        if settings.agreement > 0.0 {
            data.append_agreement(layout, settings.agreement);
        }
        tracing::debug!(
            points = points.len(),
            controls = layout.control_count(),
            seconds = start.elapsed().as_secs_f64(),
            "the fit's data rows built"
        );
        data
    }

    /// The rows fitting each point of `points` to its target (weighted by `weights`, relative to
    /// their mean) and, at `patch_weight`, each chart's own patch to the same target where the
    /// chart's blend is positive (weighted by it).
    fn new(
        layout: &Layout,
        points: &[ChartPoint],
        targets: &[Point3],
        weights: &[f64],
        patch_weight: f64,
    ) -> DataRows {
        let mean_weight = weights.iter().sum::<f64>() / weights.len() as f64;
        let mut triplets = Vec::new();
        let mut row_weights = Vec::new();
        for (r, p) in points.iter().enumerate() {
            let scale = (weights[r] / mean_weight).sqrt();
            row_weights.clear();
            layout.weight_values(*p, &mut row_weights);
            for &(control, weight) in &row_weights {
                triplets.push(Triplet::new(r, control as usize, scale * weight));
            }
        }
        let mut data_rows = points.len();
        let mut patch_targets = Vec::new();
        if patch_weight > 0.0 {
            let mut basis = Vec::new();
            for (r, p) in points.iter().enumerate() {
                let scale = patch_weight * weights[r] / mean_weight;
                let blends = layout.blends(*p);
                for (rep, _) in layout.atlas().locate_with_transitions(*p) {
                    let own = blends
                        .iter()
                        .find(|b| b.0 == rep.chart)
                        .map_or(0.0, |b| b.1);
                    if own <= 0.0 {
                        continue;
                    }
                    let row_scale = (scale * own).sqrt();
                    basis.clear();
                    layout.patch_weights(rep, &mut basis);
                    for &(c, v) in &basis {
                        triplets.push(Triplet::new(data_rows, c as usize, row_scale * v));
                    }
                    patch_targets.push((row_scale, targets[r]));
                    data_rows += 1;
                }
            }
        }
        let mut rhs = Mat::<f64>::zeros(data_rows, 3);
        for (r, t) in targets.iter().enumerate() {
            let scale = (weights[r] / mean_weight).sqrt();
            for d in 0..3 {
                rhs[(r, d)] = scale * t[d];
            }
        }
        for (k, (scale, t)) in patch_targets.iter().enumerate() {
            for d in 0..3 {
                rhs[(points.len() + k, d)] = scale * t[d];
            }
        }
        DataRows {
            triplets,
            rhs,
            points: points.len(),
        }
    }

    /// The agreement rows ([`FitSettings::agreement`]) appended, with zero right-hand sides: at
    /// the points of a lattice over each chart's fringe ([`AGREEMENT_STEP`] knot spacings apart,
    /// within [`AGREEMENT_FRINGE`] of the chart's edge), for each pair of charts whose normalised
    /// blends there are both at least [`AGREEMENT_MIN_BLEND`], √(weight b̂_c b̂_d) (E_c − E_d).
    fn append_agreement(&mut self, layout: &Layout, weight: f64) {
        let start = std::time::Instant::now();
        let first = self.rhs.nrows();
        let mut rows = first;
        for chart in layout.atlas().charts() {
            agreement_rows(layout, chart, weight, |pair| {
                for &(c, v) in pair {
                    self.triplets.push(Triplet::new(rows, c as usize, v));
                }
                rows += 1;
            });
        }
        tracing::debug!(
            rows = rows - first,
            seconds = start.elapsed().as_secs_f64(),
            "the fit's agreement rows built"
        );
        self.rhs.resize_with(rows, 3, |_, _| 0.0);
    }

    /// The control points fitting these rows with the smoothness rows `smooth` at weight λ
    /// (`smoothness`; [`DataRows::with_smoothness`]), with the normal equations' analysis made
    /// ahead where there is one ([`DataRows::analysis`]).
    fn solve(
        &self,
        layout: &Layout,
        smooth: &[Vec<(usize, f64)>],
        smoothness: f64,
        analysis: Analysis<'_>,
    ) -> Result<Vec<Point3>, EmbeddingError> {
        Ok(self.solve_keeping(layout, smooth, smoothness, analysis)?.0)
    }

    /// As [`DataRows::solve`], also returning the normal equations' analysis where `analysis`
    /// asked for one to be made alongside.
    fn solve_keeping(
        &self,
        layout: &Layout,
        smooth: &[Vec<(usize, f64)>],
        smoothness: f64,
        analysis: Analysis<'_>,
    ) -> Result<(Vec<Point3>, Option<NormalAnalysis>), EmbeddingError> {
        let (rows, triplets, rhs) = self.with_smoothness(smooth, smoothness);
        let system = LeastSquares::new(rows, layout.control_count(), &triplets, analysis)?;
        let x = system.solve(&rhs);
        Ok((control_points(&x, smoothness)?, system.into_analysis()))
    }

    /// The normal equations' analysis for these rows with any smoothness rows whose each row
    /// stays within the 3 × 3 block of one grid point whose neighbours are all on the grid: the
    /// plain rows (second differences, and the twist's 2 × 2) and the arc-length rows (the
    /// Hessian's stencils at interior points) both do.
    fn analysis(&self, layout: &Layout) -> Result<NormalAnalysis, EmbeddingError> {
        let data_rows = self.rhs.nrows();
        let mut blocks = Vec::new();
        for chart in layout.atlas().charts() {
            let g = layout.grid(chart.id());
            for j in 1..g.saturating_sub(1) {
                for i in 1..g - 1 {
                    let row = data_rows + blocks.len() / 9;
                    for (di, dj) in (0..3).flat_map(|a| (0..3).map(move |b| (a, b))) {
                        blocks.push((
                            row,
                            layout.control_index(chart.id(), i + di - 1, j + dj - 1),
                        ));
                    }
                }
            }
        }
        let rows = data_rows + blocks.len() / 9;
        let entries = self.triplets.iter().map(|t| (t.row, t.col));
        NormalAnalysis::new(rows, layout.control_count(), entries.chain(blocks))
    }

    /// The whole system with the smoothness rows `smooth` at weight λ (`smoothness`) appended:
    /// λ (N / R) ‖D c‖² for N points and R rows. Its row count, entries and right-hand sides.
    fn with_smoothness(
        &self,
        smooth: &[Vec<(usize, f64)>],
        smoothness: f64,
    ) -> (usize, Vec<Triplet<usize, usize, f64>>, Mat<f64>) {
        let data_rows = self.rhs.nrows();
        let root = (smoothness * self.points as f64 / smooth.len() as f64).sqrt();
        let mut triplets = self.triplets.clone();
        for (k, row) in smooth.iter().enumerate() {
            for &(c, v) in row {
                triplets.push(Triplet::new(data_rows + k, c, root * v));
            }
        }
        let rows = data_rows + smooth.len();
        let mut rhs = Mat::<f64>::zeros(rows, 3);
        rhs.as_mut()
            .subrows_mut(0, data_rows)
            .copy_from(self.rhs.as_ref());
        (rows, triplets, rhs)
    }
}

/// The agreement rows' lattice spacing, in knot spacings of the chart it covers: two points per
/// cell, so two patches cannot part between them by more than the cubic's bend over half a cell.
pub const AGREEMENT_STEP: f64 = 0.5;

/// How deep into a chart (its margin, chart units) the agreement rows' lattice reaches: where
/// another chart's blend can still be steep. The coverage margins from genus 17 on are 0.024 and
/// less (`charts::scales`), so this is several times the fringe.
pub const AGREEMENT_FRINGE: f64 = 0.15;

/// The smallest normalised blend of either chart of a pair that gets an agreement row. Below it the
/// fainter patch barely shows in the surface, and its control points there, which the data hardly
/// reach, would be dragged by rows they cannot follow (with every pair tied, however faint,
/// genus 24's fit folded).
pub const AGREEMENT_MIN_BLEND: f64 = 0.05;

/// The agreement rows of the lattice over `chart`'s fringe, each handed to `row` as its entries
/// (control point, value): E_c(p) − E_d(p) for each pair of charts c < d holding the lattice point
/// p with normalised blends b̂_c, b̂_d ≥ [`AGREEMENT_MIN_BLEND`], scaled by √(weight b̂_c b̂_d).
fn agreement_rows(
    layout: &Layout,
    chart: &charts::Chart,
    weight: f64,
    mut row: impl FnMut(&[(u32, f64)]),
) {
    let atlas = layout.atlas();
    let step = AGREEMENT_STEP * layout.basis(chart.id()).spacing();
    let n = (1.0 / step).ceil() as usize;
    let (mut reps, mut entries, mut patch) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..=n {
        for i in 0..=n {
            let w = Complex64::new(-0.5 + i as f64 * step, -0.5 + j as f64 * step);
            let margin = chart.domain().margin(w);
            if margin <= 0.0 || margin > AGREEMENT_FRINGE {
                continue;
            }
            atlas.locate_with_transitions_into(ChartPoint::new(chart.id(), w), &mut reps);
            let blends = layout.blends_located(&reps);
            for (a, &(ca, ba)) in blends.iter().enumerate() {
                for &(cb, bb) in &blends[a + 1..] {
                    if ba < AGREEMENT_MIN_BLEND || bb < AGREEMENT_MIN_BLEND {
                        continue;
                    }
                    let scale = (weight * ba * bb).sqrt();
                    entries.clear();
                    for (c, sign) in [(ca, scale), (cb, -scale)] {
                        let rep = reps.iter().find(|r| r.0.chart == c).expect("located").0;
                        patch.clear();
                        layout.patch_weights(rep, &mut patch);
                        entries.extend(patch.iter().map(|&(k, v)| (k, sign * v)));
                    }
                    row(&entries);
                }
            }
        }
    }
}

/// The control points in a solution's rows, checked finite.
fn control_points(x: &Mat<f64>, smoothness: f64) -> Result<Vec<Point3>, EmbeddingError> {
    let control: Vec<Point3> = (0..x.nrows())
        .map(|c| Point3::new(x[(c, 0)], x[(c, 1)], x[(c, 2)]))
        .collect();
    if control.iter().any(|c| !c.iter().all(|v| v.is_finite())) {
        // Not `Unsolvable` (that is the edit's): say what of the fit's input can cause it.
        return Err(EmbeddingError::Parameterization(format!(
            "the least-squares fit gave control points that are not finite numbers \
             (smoothness weight {smoothness}: far too large or too small for the data?)"
        )));
    }
    Ok(control)
}

/// Second differences of every chart's control grid: along u, along v, and the mixed difference
/// (scaled by √2, so the sum of squares is the discrete thin-plate energy).
pub(crate) fn smoothness_rows(layout: &Layout) -> Vec<Vec<(usize, f64)>> {
    let mut rows = Vec::new();
    for chart in layout.atlas().charts() {
        let g = layout.grid(chart.id());
        for j in 0..g {
            for i in 0..g {
                smoothness_rows_at(layout, chart.id(), i, j, |row| rows.push(row.to_vec()));
            }
        }
    }
    rows
}

/// The rows of [`smoothness_rows`] whose first control point is (i, j) of `chart`'s grid: none to
/// three, each handed to `row`.
pub(crate) fn smoothness_rows_at(
    layout: &Layout,
    chart: ChartId,
    i: usize,
    j: usize,
    mut row: impl FnMut(&[(usize, f64)]),
) {
    let g = layout.grid(chart);
    let at = |i: usize, j: usize| layout.control_index(chart, i, j);
    if i + 2 < g {
        row(&[(at(i, j), 1.0), (at(i + 1, j), -2.0), (at(i + 2, j), 1.0)]);
    }
    if j + 2 < g {
        row(&[(at(i, j), 1.0), (at(i, j + 1), -2.0), (at(i, j + 2), 1.0)]);
    }
    if i + 1 < g && j + 1 < g {
        let s = std::f64::consts::SQRT_2;
        row(&[
            (at(i, j), s),
            (at(i + 1, j), -s),
            (at(i, j + 1), -s),
            (at(i + 1, j + 1), s),
        ]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The hyperbolic distance between two points of the Poincaré disk.
    fn distance(p: Complex64, q: Complex64) -> f64 {
        2.0 * ((q - p) / (Complex64::new(1.0, 0.0) - p.conj() * q))
            .norm()
            .atanh()
    }

    proptest! {
        /// The geodesic midpoint halves the distance and lies on the segment (the two halves add
        /// up to the whole), anywhere in the disk, however far apart the ends.
        #[test]
        fn the_geodesic_midpoint_halves_the_segment(
            r1 in 0.0f64..0.99, a1 in 0.0f64..std::f64::consts::TAU,
            r2 in 0.0f64..0.99, a2 in 0.0f64..std::f64::consts::TAU,
        ) {
            let (p, q) = (Complex64::from_polar(r1, a1), Complex64::from_polar(r2, a2));
            let m = geodesic_midpoint(p, q);
            let (whole, first, second) = (distance(p, q), distance(p, m), distance(m, q));
            prop_assert!(m.norm() < 1.0);
            prop_assert!((first - second).abs() < 1e-9 * (1.0 + whole), "{first} {second}");
            prop_assert!((first + second - whole).abs() < 1e-9 * (1.0 + whole), "{first} + {second} ≠ {whole}");
        }
    }

    /// A plate fitted to its edge samples too lies closer to the intended surface between its
    /// vertices than one fitted to the vertices alone (the same mesh and map); `InitialFit`
    /// counts the samples.
    #[test]
    fn edge_samples_bring_the_fit_closer_between_the_vertices() {
        let spline = SplineSettings::default();
        let plain = FitSettings::for_grid(spline.grid);
        let sampled = FitSettings {
            edge_samples: PLATE_EDGE_SAMPLE_WEIGHT,
            ..plain
        };
        let [without, with] = [plain, sampled].map(|s| initial_model(3, 12, spline, s).unwrap());
        assert_eq!(
            (without.edge_samples, with.edge_samples),
            (0, with.mesh.edge_samples.len())
        );
        let between = |fit: &InitialFit| {
            let areas = vertex_areas(&fit.mesh.positions, &fit.mesh.triangles);
            let atlas = fit.surface.atlas();
            let samples =
                edge_samples(atlas, &fit.mesh, &fit.parameterization, &areas, 1.0).unwrap();
            let layout = fit.surface.layout();
            let off: Vec<f64> = samples
                .points
                .iter()
                .zip(&samples.targets)
                .map(|(p, t)| (layout.eval(fit.surface.control_points(), *p).pos - t).norm())
                .collect();
            (
                off.iter().sum::<f64>() / off.len() as f64,
                off.iter().copied().fold(0.0, f64::max),
            )
        };
        let (before, after) = (between(&without), between(&with));
        eprintln!(
            "between the vertices (mean, max): {before:?} → {after:?}; at them {} → {}",
            without.max_residual, with.max_residual
        );
        // The vertices give a little for it (0.0046 → 0.0135 model units at most, where the
        // map's midpoint and the fit's disagree along the surface); the worst over both halves.
        assert!(after.0 < 0.5 * before.0, "{before:?} → {after:?}");
        let worst = |fit: &InitialFit, between: (f64, f64)| fit.max_residual.max(between.1);
        assert!(worst(&with, after) < 0.5 * worst(&without, before));
    }

    /// The analysis the fit makes ahead from the data rows and the smoothness stencils holds
    /// the whole system's AᵀA, with the plain rows and with the arc-length rows (their metric
    /// from a coarse first fit, as `new`'s plates take it, and from a first fit on the same
    /// grids, as a user's mesh does, where one analysis serves both fits), on the plates and
    /// grids `new` uses for genus 2, 5, 8 and 12 (else the fit would analyse it again and lose
    /// the time the analysis saves).
    #[test]
    fn the_analysis_made_ahead_holds_the_fit_s_systems() {
        for genus in [2, 5, 8, 12] {
            let (spline, settings) = default_settings(genus);
            let atlas = Arc::new(Atlas::new(genus).unwrap());
            let layout = Layout::new(&atlas, spline).unwrap();
            let mesh = HoledMesh::new(genus, 8).unwrap();
            let parameterization = parameterize(&atlas, &mesh, 1).unwrap();
            let weights = vertex_areas(&mesh.positions, &mesh.triangles);
            let (points, targets) = (&parameterization.points, &mesh.positions);
            let data = DataRows::with_agreement(&layout, points, targets, &weights, settings);
            let analysis = data.analysis(&layout).unwrap();
            let arc = FitSettings {
                surface_smoothness: true,
                ..settings
            };
            let coarse_rows =
                coarse_arc_length_smoothness(&layout, points, targets, &weights, arc).unwrap();
            let plain = smoothness_rows(&layout);
            let first = data
                .solve(&layout, &plain, settings.smoothness, Analysis::Here)
                .unwrap();
            let grid_rows = crate::bending::arc_length_rows(
                &layout,
                &crate::bending::grid_metrics(&layout, &first),
            );
            for (name, smooth) in [
                ("plain", plain),
                ("arc length, coarse metric", coarse_rows),
                ("arc length, grid metric", grid_rows),
            ] {
                let (rows, triplets, _) = data.with_smoothness(&smooth, settings.smoothness);
                let formed =
                    crate::least_squares::form(rows, layout.control_count(), &triplets).unwrap();
                let crate::least_squares::Gram::Whole(whole) = &formed.gram else {
                    unreachable!("form makes the whole AᵀA")
                };
                assert!(
                    analysis.spread(whole).is_some(),
                    "genus {genus}, {name} rows: AᵀA reaches outside the analysis"
                );
            }
        }
    }
}
