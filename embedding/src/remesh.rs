//! A quality tessellation: well-shaped triangles whose size follows the surface's curvature.
//!
//! The paper's t_e/t_r scheme (`charts::tessellation`) is regular in the charts, so its triangles
//! are slivers wherever a chart is stretched on the surface, and its size ignores curvature. This
//! module remeshes on the surface itself, the isotropic remeshing of Botsch and Kobbelt (2004) with
//! a curvature-adaptive target edge length:
//!
//! 1. start from the squares of a coarse t_e/t_r tessellation, its wheels retriangulated (see
//!    `remesh/start.rs`): a closed mesh of the right topology;
//! 2. repeat: split edges longer than 4/3 of the target length, collapse edges shorter than 4/5 of
//!    it, flip edges towards valence 6, and move every vertex towards the area-weighted centre of
//!    its triangles, within the tangent plane;
//! 3. split edges until every triangle's chordal error (the distance between the flat triangle's
//!    centre and the surface point at its corners' mean chart coordinates) is within the
//!    tolerance, then flip edges that are not locally Delaunay where that keeps the error;
//! 4. collapse edges shorter than the smallest target length (bisection at a curvature spike
//!    leaves caps below it), then mend what is left under 20° or over 150° by flips and
//!    collapses that keep the error.
//!
//! Passes are incremental: after a pass over the whole mesh, the next looks only at the triangles
//! around vertices the one before changed. The surface evaluations of a pass (midpoints, chordal
//! tests, smoothing targets) and its search for candidates are made first, on all cores; the
//! topology changes then run in order, each tested again against the mesh as it is by then.
//!
//! Every vertex stays a chart point, kept in its deepest chart: midpoints are taken in a chart
//! holding both ends, and a vertex moves in chart coordinates (the tangent-plane step pulled back
//! through the surface's Jacobian), so it never leaves the surface. Stencils, picking and UVs work
//! on this mesh as on the t_e/t_r one.
//!
//! The target edge length at a point with largest principal curvature |κ| is the smallest of
//! √(3·tol/|κ|) (the chordal error of an equilateral triangle of side L on a sphere of radius R is
//! about L²/(6R), and edges reach 4/3 of the target), `bend/|κ|` (neighbouring triangles' normals
//! then differ by about `bend`), and a longest edge; it is graded so it grows by at most
//! [`GRADATION`] of the distance between neighbours.
//!
//! The topology never changes: every operation keeps the mesh closed, manifold and oriented, so
//! χ = 2 − 2n holds exactly (tested).

use std::collections::HashSet;

use charts::{ChartId, ChartPoint};
use num_complex::Complex64;
use rayon::prelude::*;

use crate::{EmbeddingError, Point3, Surface, Vector3};

mod quads;
mod start;

pub use quads::{TOLERANCE_FACTOR as QUAD_TOLERANCE_FACTOR, quad_mesh, quad_of, quads_of};

/// How fast the target edge length may grow from one vertex to its neighbour, per unit distance.
pub const GRADATION: f64 = 0.35;

/// The t_e of the tessellation whose squares the remesher starts from.
pub const START_RESOLUTION: u32 = 8;

/// The largest angle (degrees) between neighbouring triangles' normals the remesher leaves by
/// default ([`QualitySettings::max_bend`]).
pub const MAX_BEND: f64 = 18.0;

/// The most passes of one operation in a row (each pass changes every edge it can; a handful
/// settle a round).
const MAX_PASSES: usize = 12;

/// The angle (radians) a triangle should not reach: a cap, whose other two angles are under 30°.
const CAP_ANGLE: f64 = 150.0 * std::f64::consts::PI / 180.0;

/// How far under [`CAP_ANGLE`] a triangle's largest angle already counts as a cap to remove.
const UNCAP_MARGIN: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// The smallest angle (radians) an uncapping flip may leave, where half the old one is smaller.
const UNCAP_FLOOR: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// A smoothing step shorter than this fraction of the target length is not made.
const MOVE_SKIPPED: f64 = 0.02;

/// A smoothing step shorter than this fraction of the target length does not count as a change
/// (the next round does not look at the vertex again for it).
const MOVE_NOTICED: f64 = 0.1;

/// The most passes of collapses or valence flips in one round (their last passes change a few
/// edges each, back and forth).
const POLISH_PASSES: usize = 3;

/// What the quality tessellation aims for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QualitySettings {
    /// Largest chordal error, as a fraction of the surface's bounding-box diagonal.
    pub tolerance: f64,
    /// Angle (radians) the sizing lets the normal turn across one edge.
    pub bend: f64,
    /// Longest edge, as a fraction of the diagonal.
    pub max_edge: f64,
    /// The largest angle (degrees) between neighbouring triangles' normals: edges bending more
    /// are split.
    pub max_bend: f64,
    /// Rounds of split, collapse, flip and smooth.
    pub rounds: usize,
}

impl Default for QualitySettings {
    fn default() -> Self {
        QualitySettings {
            tolerance: 1e-3,
            bend: 0.22,
            max_edge: 0.05,
            max_bend: MAX_BEND,
            rounds: 3,
        }
    }
}

impl QualitySettings {
    /// The smallest tolerance accepted (below it the triangle counts explode).
    pub const MIN_TOLERANCE: f64 = 1e-5;
    /// The largest tolerance accepted.
    pub const MAX_TOLERANCE: f64 = 0.1;

    /// The defaults at chordal tolerance `tolerance` (a fraction of the diagonal).
    pub fn with_tolerance(tolerance: f64) -> QualitySettings {
        QualitySettings {
            tolerance,
            ..QualitySettings::default()
        }
    }

    /// Checks the settings' ranges.
    pub fn check(&self) -> Result<(), EmbeddingError> {
        let t = self.tolerance;
        if !(Self::MIN_TOLERANCE..=Self::MAX_TOLERANCE).contains(&t) {
            return Err(EmbeddingError::Tolerance(t));
        }
        Ok(())
    }
}

/// A tessellation of the surface whose vertices are chart points.
#[derive(Clone, Debug, Default)]
pub struct QualityMesh {
    /// Each vertex in its deepest chart.
    pub vertices: Vec<ChartPoint>,
    /// The vertices' positions on the surface.
    pub positions: Vec<Point3>,
    /// Counter-clockwise seen from outside (the side S_u × S_v points to).
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's home chart: one holding all three corners, the deepest such.
    pub triangle_charts: Vec<ChartId>,
    /// Each triangle's corners in its home chart's coordinates.
    pub triangle_coords: Vec<[Complex64; 3]>,
    /// Whether the triangles are halves of quads ([`quad_mesh`]): triangles 2k and 2k + 1 share
    /// an edge, the diagonal of quad k, in one chart ([`quad_of`] puts the quad together).
    pub quads: bool,
}

/// How closely a [`QualityMesh`] follows its surface, measured at each triangle's centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fidelity {
    /// The largest distance between a flat triangle's centre and the surface at its corners' mean
    /// chart coordinates, as a fraction of the mesh's bounding-box diagonal.
    pub chordal_error: f64,
    /// Triangles whose normal points against the surface's there.
    pub facing_away: usize,
}

impl QualityMesh {
    /// The quads, where the triangles are their halves ([`QualityMesh::quads`]); none otherwise.
    pub fn quad_faces(&self) -> Vec<[u32; 4]> {
        if !self.quads {
            return Vec::new();
        }
        quads_of(&self.triangles)
    }

    /// Measures the mesh against the exact surface (not through the remesher's own bookkeeping).
    pub fn fidelity(&self, surface: &Surface) -> Fidelity {
        let diagonal = crate::fit::diagonal(&self.positions);
        let mut f = Fidelity {
            chordal_error: 0.0,
            facing_away: 0,
        };
        for (t, tri) in self.triangles.iter().enumerate() {
            let mean = self.triangle_coords[t].iter().sum::<Complex64>() / 3.0;
            let exact = surface.eval(ChartPoint::new(self.triangle_charts[t], mean));
            let [a, b, c] = tri.map(|i| self.positions[i as usize]);
            let flat = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            f.chordal_error = f.chordal_error.max((exact.pos - flat).norm() / diagonal);
            if (b - a).cross(&(c - a)).dot(&exact.normal()) <= 0.0 {
                f.facing_away += 1;
            }
        }
        f
    }
}

/// How many vertices the remesher starts from on this atlas (the squares of the t_e =
/// [`START_RESOLUTION`] tessellation and the triangulated wheels).
pub fn start_vertex_count(atlas: &charts::Atlas) -> Result<usize, EmbeddingError> {
    Ok(start::start_mesh(atlas, START_RESOLUTION)?.vertices.len())
}

/// A vertex being remeshed. What every test reads (position, normal, target length) comes first
/// and the vertex starts a cache line, so those take one line to fetch.
#[derive(Clone, Debug)]
#[repr(C, align(64))]
struct Vertex {
    pos: Point3,
    normal: Vector3,
    /// Target edge length here.
    size: f64,
    point: ChartPoint,
    /// Every chart's coordinates of the point (charts hold a point at most once).
    reps: Vec<ChartPoint>,
    /// S_u and S_v in `point`'s chart.
    du: Vector3,
    dv: Vector3,
}

const DEAD: u32 = u32::MAX;

/// The remesher's state: vertices, triangles and the triangles around each vertex, which every
/// operation keeps up to date.
struct Remesher<'a> {
    surface: &'a Surface,
    /// Absolute tolerance and edge-length bounds.
    tolerance: f64,
    bend: f64,
    /// Radians.
    max_bend: f64,
    max_edge: f64,
    min_edge: f64,
    verts: Vec<Vertex>,
    tris: Vec<[u32; 3]>,
    /// The live triangles around each vertex (none around a collapsed one).
    rings: Vec<Vec<u32>>,
    /// Triangles (by corners) whose chordal error is known to be within the tolerance.
    chordal_fine: HashSet<[u32; 3]>,
    /// The pass in which each vertex last moved or changed its ring (see [`Remesher::repeat`]).
    changed: Vec<u32>,
    /// The pass now running.
    pass: u32,
    /// Passes look only at what changed from this pass on (0: everything).
    since: u32,
    /// Known, for the running collapse pass, that no triangle is folded.
    unfolded: bool,
}

/// Remeshes `surface` into a [`QualityMesh`] (see the module documentation).
pub fn quality_mesh(
    surface: &Surface,
    settings: &QualitySettings,
) -> Result<QualityMesh, EmbeddingError> {
    settings.check()?;
    let mut r = Remesher::start(surface, settings)?;
    // The start's triangles wind counter-clockwise in their charts, which is outward.
    // Clean the start's slivers before refining: splitting a sliver makes more of them.
    r.repeat(|r| r.collapse_short());
    r.repeat_at_most(POLISH_PASSES, |r| r.flip(FlipRule::Valence));
    r.smooth(2);
    // After the first round, a round looks only where the round before changed something.
    let mut since = 0;
    for _ in 0..settings.rounds {
        let round = r.pass + 1;
        r.grade_sizes();
        r.repeat_from(since, MAX_PASSES, |r| r.split_long());
        // Collapses and valence flips polish: the next round picks up what a few passes leave.
        r.repeat_from(since, POLISH_PASSES, |r| r.collapse_short());
        r.repeat_from(since, POLISH_PASSES, |r| r.flip(FlipRule::Valence));
        r.smooth(1);
        since = round;
    }
    // Refine what is still turned away or bent, let the shapes settle, then make sure of the
    // tolerance.
    r.repeat(|r| r.split_folded());
    for last in [false, true] {
        r.repeat(|r| r.split_bent());
        r.repeat(|r| r.split_chordal());
        // Splits can leave obtuse triangles; Delaunay flips that keep the tolerance mend them.
        r.repeat(|r| r.flip(FlipRule::Delaunay));
        if !last {
            r.smooth(1);
        }
    }
    r.repeat(|r| r.collapse_tiny());
    r.repeat(|r| r.mend());
    r.finish()
}

impl<'a> Remesher<'a> {
    /// The coarse start mesh on `surface`: the right topology, its slivers still to be
    /// remeshed away.
    fn start(
        surface: &'a Surface,
        settings: &QualitySettings,
    ) -> Result<Remesher<'a>, EmbeddingError> {
        let start = start::start_mesh(surface.atlas(), START_RESOLUTION)?;
        // The surface's own size (its control net can reach far beyond it).
        let positions: Vec<Point3> = start
            .vertices
            .par_iter()
            .map(|&p| surface.position(p))
            .collect();
        let diagonal = crate::fit::diagonal(&positions);
        let mut r = Remesher {
            surface,
            tolerance: settings.tolerance * diagonal,
            bend: settings.bend,
            max_bend: settings.max_bend.to_radians(),
            max_edge: settings.max_edge * diagonal,
            min_edge: 1e-4 * diagonal,
            verts: Vec::with_capacity(start.vertices.len()),
            tris: start.triangles,
            rings: Vec::new(),
            chordal_fine: HashSet::new(),
            changed: Vec::new(),
            pass: 0,
            since: 0,
            unfolded: false,
        };
        let found: Vec<Option<Vertex>> = start.vertices.par_iter().map(|&p| r.vertex(p)).collect();
        for (v, &p) in found.into_iter().zip(&start.vertices) {
            r.verts.push(v.ok_or_else(|| pinched(p))?);
        }
        r.build_rings();
        Ok(r)
    }
}

fn pinched(p: ChartPoint) -> EmbeddingError {
    EmbeddingError::Parameterization(format!(
        "the surface has no tangent plane at chart {} ({:.4}, {:.4})",
        p.chart.0, p.coords.re, p.coords.im
    ))
}

/// How one triangle lies, better to worse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum FoldState {
    Outward,
    /// Counter-clockwise in its chart but facing away from the surface's normals.
    FacingAway,
    /// Clockwise in its chart, or held by no chart.
    Turned,
}

/// Triangles that are turned over, or only lie badly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Folds {
    /// Clockwise in their chart: the mesh is folded over there. Never made.
    turned: usize,
    /// Counter-clockwise, but facing away from the surface's normals by more than 60°: too large or
    /// too thin for the curvature (a coarse start has such slivers). Never made more of.
    facing_away: usize,
}

impl Folds {
    fn none(&self) -> bool {
        self.turned == 0 && self.facing_away == 0
    }

    /// Whether an operation that leaves `self` where there was `before` may go ahead.
    fn no_worse_than(&self, before: Folds) -> bool {
        self.turned == 0 && self.facing_away <= before.facing_away
    }
}

/// What a collapse is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Purpose {
    /// An edge shorter than its target length; refused where it would stretch another.
    Length,
    /// A sliver: where the smallest angle around grows ([`Remesher::mends`]).
    Mend,
    /// A cap: where the largest angle around falls below [`CAP_ANGLE`].
    Uncap,
}

/// Which flips a pass makes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum FlipRule {
    /// Towards valence 6.
    Valence,
    /// Where the two angles facing the edge sum to more than π (and the chordal error stays).
    Delaunay,
    /// Where the pair's smallest angle grows and no angle reaches [`CAP_ANGLE`] that had not
    /// (and the chordal error stays).
    Mend,
    /// Where the pair's largest angle shrinks and the smallest stays above half of what it was
    /// or 5° (and the chordal error stays): a cap's long edge, where the quad across it is too
    /// thin for the smallest angle to grow. A large angle is the worse defect (Babuška and Aziz's
    /// maximum angle condition: interpolated gradients stay bounded as long as it holds).
    Uncap,
}

impl Remesher<'_> {
    // ------------------------------------------------------------------ surface points

    /// The surface at `p`, moved to its deepest chart; `None` where the surface has no normal or
    /// `p` lies outside its chart.
    fn vertex(&self, p: ChartPoint) -> Option<Vertex> {
        let atlas = self.surface.atlas();
        let domain = atlas.chart(p.chart).ok()?.domain();
        if !(p.coords.re.is_finite() && p.coords.im.is_finite() && domain.margin(p.coords) > 0.0) {
            return None;
        }
        // One location serves both the evaluation (in p's chart) and the choice of home chart.
        let located = atlas.locate_with_transitions(p);
        let margin = |q: &ChartPoint| atlas.charts()[q.chart.index()].domain().margin(q.coords);
        let &(point, psi) = located
            .iter()
            .max_by(|a, b| margin(&a.0).total_cmp(&margin(&b.0)))?;
        let jet = self.surface.eval_located(p, &located);
        // The derivatives in the home chart: ψ⁻¹ has complex derivative 1/ψ'(w) = a + ib, so
        // ∂/∂u' = a ∂/∂u + b ∂/∂v and ∂/∂v' = −b ∂/∂u + a ∂/∂v (Cauchy–Riemann). Curvatures
        // do not depend on the chart.
        let [_, _, c, d] = psi.matrix();
        let q = c * p.coords + d;
        let g = q * q;
        let du = jet.du * g.re + jet.dv * g.im;
        let dv = jet.dv * g.re - jet.du * g.im;
        let cross = du.cross(&dv);
        let area = cross.norm();
        if area.is_nan() || area <= 1e-12 * self.max_edge * self.max_edge {
            return None;
        }
        let (k1, k2) = jet.principal_curvatures();
        let kappa = k1.abs().max(k2.abs());
        Some(Vertex {
            point,
            reps: located.iter().map(|r| r.0).collect(),
            pos: jet.pos,
            du,
            dv,
            normal: cross / area,
            size: self.size_for(kappa),
        })
    }

    /// The target edge length where the largest principal curvature is `kappa`.
    fn size_for(&self, kappa: f64) -> f64 {
        let mut h = self.max_edge;
        if kappa > 0.0 && kappa.is_finite() {
            h = h.min((3.0 * self.tolerance / kappa).sqrt());
            h = h.min(self.bend / kappa);
        }
        h.max(self.min_edge)
    }

    /// Coordinates of the given vertices all in one chart: the deepest chart (by the smallest
    /// margin) among the vertices' home charts that holds them all.
    fn common_chart<const N: usize>(&self, ids: [u32; N]) -> Option<(ChartId, [Complex64; N])> {
        let atlas = self.surface.atlas();
        let mut best: Option<(f64, ChartId, [Complex64; N])> = None;
        for &i in &ids {
            let chart = self.verts[i as usize].point.chart;
            let domain = atlas.charts()[chart.index()].domain();
            let mut coords = [Complex64::ZERO; N];
            let mut margin = f64::INFINITY;
            let mut all = true;
            for (k, &j) in ids.iter().enumerate() {
                let reps = &self.verts[j as usize].reps;
                match reps.iter().find(|r| r.chart == chart).map(|r| r.coords) {
                    Some(w) => {
                        coords[k] = w;
                        margin = margin.min(domain.margin(w));
                    }
                    None => {
                        all = false;
                        break;
                    }
                }
            }
            if all && best.as_ref().is_none_or(|b| margin > b.0) {
                best = Some((margin, chart, coords));
            }
        }
        best.map(|(_, c, w)| (c, w))
    }

    /// Coordinates of the given vertices in the first of their home charts that holds them all:
    /// cheaper than [`Self::common_chart`] where any chart will do (orientation tests: the
    /// transitions preserve it).
    fn shared_chart<const N: usize>(&self, ids: [u32; N]) -> Option<[Complex64; N]> {
        let home = self.verts[ids[0] as usize].point.chart;
        if ids
            .iter()
            .all(|&i| self.verts[i as usize].point.chart == home)
        {
            return Some(ids.map(|i| self.verts[i as usize].point.coords));
        }
        ids.iter().find_map(|&i| {
            let chart = self.verts[i as usize].point.chart;
            let mut coords = [Complex64::ZERO; N];
            for (k, &j) in ids.iter().enumerate() {
                let reps = &self.verts[j as usize].reps;
                coords[k] = reps.iter().find(|r| r.chart == chart)?.coords;
            }
            Some(coords)
        })
    }

    /// The surface point at the mean chart coordinates of `ids`.
    fn centre<const N: usize>(&self, ids: [u32; N]) -> Option<Vertex> {
        let (chart, coords) = self.common_chart(ids)?;
        let mean = coords.iter().sum::<Complex64>() / N as f64;
        self.vertex(ChartPoint::new(chart, mean))
    }

    /// Distance between the flat triangle's centre and the surface at its corners' mean chart
    /// coordinates (infinite where no chart holds all three corners).
    fn chordal_error(&self, t: [u32; 3]) -> f64 {
        let Some((chart, coords)) = self.common_chart(t) else {
            return f64::INFINITY;
        };
        // Chart domains are convex, so the mean lies in the chart.
        let mean = coords.iter().sum::<Complex64>() / 3.0;
        let exact = self.surface.position(ChartPoint::new(chart, mean));
        (exact - self.centroid(t)).norm()
    }

    fn centroid(&self, t: [u32; 3]) -> Point3 {
        let [a, b, c] = t.map(|i| self.verts[i as usize].pos.coords);
        Point3::from((a + b + c) / 3.0)
    }

    fn pos(&self, i: u32) -> Point3 {
        self.verts[i as usize].pos
    }

    /// The edge's length over the mean target length of its ends.
    fn relative_length(&self, a: u32, b: u32) -> f64 {
        let (va, vb) = (&self.verts[a as usize], &self.verts[b as usize]);
        (va.pos - vb.pos).norm() / (0.5 * (va.size + vb.size))
    }

    /// Whether triangle (a, b, c) with these positions faces the way the surface does at its
    /// corners (its normal within about 60° of each corner's).
    fn faces_outward(&self, t: [u32; 3], pos: [Point3; 3]) -> bool {
        let n = (pos[1] - pos[0]).cross(&(pos[2] - pos[0]));
        let len = n.norm();
        if len.is_nan() || len <= 0.0 {
            return false;
        }
        t.iter()
            .all(|&i| n.dot(&self.verts[i as usize].normal) > 0.5 * len)
    }

    /// How triangle `t` lies.
    fn fold_state(&self, t: [u32; 3]) -> FoldState {
        if !self.counter_clockwise(t) {
            FoldState::Turned
        } else if !self.faces_outward(t, t.map(|i| self.pos(i))) {
            FoldState::FacingAway
        } else {
            FoldState::Outward
        }
    }

    /// How these triangles sit: how many wind clockwise in the chart holding them (or are held by
    /// none), and how many face away from the surface's normals at their corners.
    fn folds(&self, tris: impl Iterator<Item = [u32; 3]>) -> Folds {
        let mut f = Folds::default();
        for t in tris {
            match self.fold_state(t) {
                FoldState::Turned => f.turned += 1,
                FoldState::FacingAway => f.facing_away += 1,
                FoldState::Outward => {}
            }
        }
        f
    }

    /// Whether the triangle winds counter-clockwise in a chart holding all three corners, as the
    /// start mesh's do: the surface is oriented, so a turned-over triangle winds the other way.
    fn counter_clockwise(&self, t: [u32; 3]) -> bool {
        match self.shared_chart(t) {
            Some([a, b, c]) => {
                let (u, v) = (b - a, c - a);
                u.re * v.im - u.im * v.re > 0.0
            }
            None => false,
        }
    }

    /// Makes every target length at most its neighbour's plus [`GRADATION`] times their distance.
    fn grade_sizes(&mut self) {
        // Outside a pass: every edge once, in triangle order.
        let edges = self.edges();
        // Sweeps one way and back: a small size spreads along a chain of edges in either order.
        for sweep in 0..4 {
            let mut changed = false;
            for k in 0..edges.len() {
                let (a, b) = edges[if sweep % 2 == 0 {
                    k
                } else {
                    edges.len() - 1 - k
                }];
                let (a, b) = (a as usize, b as usize);
                let d = (self.verts[a].pos - self.verts[b].pos).norm();
                let (sa, sb) = (self.verts[a].size, self.verts[b].size);
                if sa > sb + GRADATION * d {
                    self.verts[a].size = sb + GRADATION * d;
                    self.touch(a as u32);
                    changed = true;
                } else if sb > sa + GRADATION * d {
                    self.verts[b].size = sa + GRADATION * d;
                    self.touch(b as u32);
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
    }

    // ------------------------------------------------------------------ connectivity

    /// Builds the rings from the triangles (the operations then keep them up to date).
    fn build_rings(&mut self) {
        self.rings = vec![Vec::new(); self.verts.len()];
        self.changed = vec![0; self.verts.len()];
        for (t, tri) in self.tris.iter().enumerate() {
            if tri[0] != DEAD {
                for &v in tri {
                    self.rings[v as usize].push(t as u32);
                }
            }
        }
    }

    /// Replaces `from` by `to` in `v`'s ring.
    fn ring_replace(&mut self, v: u32, from: u32, to: u32) {
        if let Some(slot) = self.rings[v as usize].iter_mut().find(|t| **t == from) {
            *slot = to;
        }
    }

    fn ring_remove(&mut self, v: u32, t: u32) {
        self.rings[v as usize].retain(|&x| x != t);
    }

    /// Runs passes of `pass` (which returns how many operations it made) until one makes none,
    /// at most [`MAX_PASSES`].
    fn repeat(&mut self, pass: impl FnMut(&mut Self) -> usize) {
        self.repeat_at_most(MAX_PASSES, pass);
    }

    /// Runs passes of `pass` until one makes no change, at most `passes`. The first pass looks at
    /// the whole mesh; each later one only at the triangles around vertices the pass before
    /// changed (every test an operation makes depends on its edge's two triangles and their
    /// corners' rings, so elsewhere the answer would be the same as before). Late passes change
    /// a few dozen edges of tens of thousands.
    fn repeat_at_most(&mut self, passes: usize, pass: impl FnMut(&mut Self) -> usize) {
        self.repeat_from(0, passes, pass);
    }

    /// [`Remesher::repeat_at_most`] whose first pass looks only at what changed from pass
    /// `since` on.
    fn repeat_from(&mut self, since: u32, passes: usize, mut pass: impl FnMut(&mut Self) -> usize) {
        self.since = since;
        for _ in 0..passes {
            self.pass += 1;
            let started = self.pass;
            let made = pass(self);
            self.since = started;
            if made == 0 {
                break;
            }
        }
        self.since = 0;
    }

    /// Marks `v` as changed in this pass.
    fn touch(&mut self, v: u32) {
        self.changed[v as usize] = self.pass;
    }

    /// The live triangles the running pass looks at: all, or those with a corner that changed
    /// since [`Remesher::since`].
    fn live_triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.tris.iter().copied().filter(|t| {
            t[0] != DEAD
                && (self.since == 0 || t.iter().any(|&v| self.changed[v as usize] >= self.since))
        })
    }

    /// The edges (a < b) of the triangles the running pass looks at, each once, in triangle
    /// order: the same input gives the same mesh. A closed manifold mesh holds a→b in one
    /// triangle and b→a in another; the one holding it with a < b lists it, unless that one is
    /// not looked at, in which case the other does.
    fn edges(&self) -> Vec<(u32, u32)> {
        let changed = |v: u32| self.since == 0 || self.changed[v as usize] >= self.since;
        let mut edges = Vec::with_capacity(self.tris.len() * 3 / 2);
        for tri in self.live_triangles() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a < b {
                    edges.push((a, b));
                } else if !changed(a) && !changed(b) {
                    // This triangle is looked at for its third corner: the edge's other triangle
                    // is looked at only if its own third corner changed.
                    let other = self.triangle_with(b, a);
                    if other.is_some_and(|t| !changed(third(self.tris[t as usize], b, a))) {
                        edges.push((b, a));
                    }
                }
            }
        }
        edges
    }

    /// The live triangles around `v`.
    fn ring(&self, v: u32) -> &[u32] {
        &self.rings[v as usize]
    }

    /// The triangle around `a` (by its ring) holding the directed edge a→b.
    fn triangle_with(&self, a: u32, b: u32) -> Option<u32> {
        self.ring(a).iter().copied().find(|&t| {
            let tri = self.tris[t as usize];
            (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
        })
    }

    /// The triangles on each side of edge a→b and their third corners: (t₁ = (a, b, c), c) and
    /// (t₂ = (b, a, d), d); `None` if the edge no longer exists.
    fn edge_wings(&self, a: u32, b: u32) -> Option<(u32, u32, u32, u32)> {
        let t1 = self.triangle_with(a, b)?;
        let t2 = self.triangle_with(b, a)?;
        Some((
            t1,
            third(self.tris[t1 as usize], a, b),
            t2,
            third(self.tris[t2 as usize], b, a),
        ))
    }

    /// How many vertices are neighbours of both `a` and `b`. Each neighbour of `a` lies in two of
    /// its triangles (the mesh is a closed manifold), so it is met twice.
    fn shared_neighbours(&self, a: u32, b: u32) -> usize {
        let adjacent_to_b = |v: u32| {
            self.ring(b)
                .iter()
                .any(|&t| self.tris[t as usize].contains(&v))
        };
        let meetings = self
            .ring(a)
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&v| v != a && v != b && adjacent_to_b(v))
            .count();
        meetings / 2
    }

    fn valence(&self, v: u32) -> usize {
        self.ring(v).len()
    }

    // ------------------------------------------------------------------ operations

    /// Splits, longest first, every edge longer than 4/3 of its target length at its midpoint on
    /// the surface.
    fn split_long(&mut self) -> usize {
        let mut long: Vec<(f64, u32, u32)> = self
            .edges()
            .into_par_iter()
            .map(|(a, b)| (self.relative_length(a, b), a, b))
            .filter(|e| e.0 > 4.0 / 3.0)
            .collect();
        long.par_sort_by(|x, y| y.0.total_cmp(&x.0));
        self.split_edges(long.into_iter().map(|(_, a, b)| (a, b)).collect(), true)
    }

    /// Splits every edge across which the triangles' normals turn by more than the settings'
    /// `max_bend`.
    fn split_bent(&mut self) -> usize {
        let limit = self.max_bend.cos();
        let normal = |t: u32| {
            let p = self.tris[t as usize].map(|i| self.pos(i));
            (p[1] - p[0]).cross(&(p[2] - p[0])).normalize()
        };
        let mut bent: Vec<[u32; 3]> = self
            .edges()
            .into_par_iter()
            .filter_map(|(a, b)| {
                // A folded triangle's normal says nothing of the surface's bend.
                let (t1, _, t2, _) = self.edge_wings(a, b)?;
                let pair = [t1, t2].map(|t| self.tris[t as usize]);
                (normal(t1).dot(&normal(t2)) < limit && self.folds(pair.into_iter()).none())
                    .then_some(pair)
            })
            .flatten()
            .collect();
        // Bisecting each side's longest edge (Rivara) refines without thinning the triangles;
        // splitting the bent edge itself where it is short makes slivers that bend as much.
        bent.sort_unstable();
        bent.dedup();
        self.split_longest_edges(bent)
    }

    /// Flips an edge of every triangle with an angle under 20°, or else collapses its shortest
    /// edge, where that makes the smallest angle around grow (a cap, with an angle of 150° or more,
    /// has its other two under 15°); a cap no such flip mends is flipped where its largest angle
    /// shrinks, or else split across its long side.
    fn mend(&mut self) -> usize {
        let limit = 20f64.to_radians();
        let bad: Vec<[u32; 3]> = self
            .live_triangles()
            .filter(|&t| self.smallest_angle(t) < limit)
            .collect();
        let mut count = 0;
        for t in bad {
            // Longest edge first: a cap's long edge is the one to flip.
            let mut sides = [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])];
            sides.sort_by(|x, y| {
                let len = |(a, b): (u32, u32)| (self.pos(a) - self.pos(b)).norm();
                len(*y).total_cmp(&len(*x))
            });
            // An earlier flip may have changed this triangle; `try_flip` finds what is there now.
            if sides
                .into_iter()
                .any(|(a, b)| self.try_flip(a, b, FlipRule::Mend))
            {
                count += 1;
                continue;
            }
            // A cap that no flip mends: trade it for a pair with a smaller largest angle, or else,
            // where it is one, halve its long side at the surface: two near-right triangles.
            let (a, b) = sides[0];
            let largest = self.largest_angle(&[t]);
            if largest >= CAP_ANGLE - UNCAP_MARGIN && self.try_flip(a, b, FlipRule::Uncap) {
                count += 1;
                continue;
            }
            if largest >= CAP_ANGLE && self.uncap(sides) {
                count += 1;
                continue;
            }
            // A needle's shortest edge, or a cap's, collapsed.
            let (a, b) = sides[2];
            if self.collapse(a, b, Purpose::Mend) || self.collapse(b, a, Purpose::Mend) {
                count += 1;
            }
        }
        count
    }

    /// Moves `v` as smoothing would where that makes the largest angle around it smaller and
    /// folds nothing (a cap's obtuse corner, pulled off its long side).
    fn relocate(&mut self, v: u32) -> bool {
        let Some(moved) = self.relaxed(v, true) else {
            return false;
        };
        let around =
            |r: &Self| -> Vec<[u32; 3]> { r.ring(v).iter().map(|&t| r.tris[t as usize]).collect() };
        let ring = around(self);
        let (old_largest, old_folds) =
            (self.largest_angle(&ring), self.folds(ring.iter().copied()));
        let saved = std::mem::replace(&mut self.verts[v as usize], moved);
        let better = self.largest_angle(&ring) < old_largest - 1e-9
            && self.folds(ring.iter().copied()).no_worse_than(old_folds)
            && ring
                .iter()
                .all(|&t| self.chordal_error(t) <= self.tolerance);
        if better {
            self.touch(v);
        } else {
            self.verts[v as usize] = saved;
        }
        better
    }

    /// Removes a cap (sides longest first) that no flip mends: its obtuse corner collapsed onto
    /// an end of its long side, or else the long side split at the surface into near-right
    /// triangles.
    fn uncap(&mut self, sides: [(u32, u32); 3]) -> bool {
        let (a, b) = sides[0];
        let apex = third([sides[1].0, sides[1].1, sides[2].0], a, b);
        if self.relocate(apex)
            || self.collapse(apex, a, Purpose::Uncap)
            || self.collapse(apex, b, Purpose::Uncap)
        {
            return true;
        }
        // Below the smallest edge too: the halves are checked to be no caps, so this ends.
        (self.pos(a) - self.pos(b)).norm() > 0.01 * self.min_edge
            && self.triangle_with(a, b).is_some()
            && self
                .centre([a, b])
                .is_some_and(|mid| self.halves_uncap(a, b, &mid) && self.split(a, b, mid, false))
    }

    /// Whether splitting edge a→b at `mid` leaves no angle of [`CAP_ANGLE`] or more in the four
    /// triangles it makes (at a curvature spike the halves of a cap can be caps again, and
    /// splitting them on would never end).
    fn halves_uncap(&self, a: u32, b: u32, mid: &Vertex) -> bool {
        let Some((_, c, _, d)) = self.edge_wings(a, b) else {
            return false;
        };
        let m = mid.pos;
        let [pa, pb, pc, pd] = [a, b, c, d].map(|i| self.pos(i));
        [[pa, m, pc], [m, pb, pc], [pb, m, pd], [m, pa, pd]]
            .iter()
            .all(|p| {
                (0..3).all(|k| (p[(k + 1) % 3] - p[k]).angle(&(p[(k + 2) % 3] - p[k])) < CAP_ANGLE)
            })
    }

    /// Whether triangles `new` may replace `old`: for a sliver ([`Purpose::Mend`]) their smallest
    /// angle is larger and no angle reaches [`CAP_ANGLE`] that had not; for a cap
    /// ([`Purpose::Uncap`]) their largest angle is smaller and under it, the smallest above half of
    /// what it was or 5°. Either way no triangle tilts from its corners' normals more than the old
    /// ones did (or half the largest bend), and each is within the chordal tolerance.
    fn mends(&self, old: &[[u32; 3]], new: &[[u32; 3]], purpose: Purpose) -> bool {
        let tilt = |ts: &[[u32; 3]]| {
            ts.iter()
                .map(|&t| {
                    let p = t.map(|i| self.pos(i));
                    let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
                    t.iter()
                        .map(|&i| n.angle(&self.verts[i as usize].normal))
                        .fold(0.0, f64::max)
                })
                .fold(0.0, f64::max)
        };
        let shapes = match purpose {
            Purpose::Uncap => {
                self.largest_angle(new) < self.largest_angle(old).min(CAP_ANGLE)
                    && self.least_angle(new) >= (0.5 * self.least_angle(old)).min(UNCAP_FLOOR)
            }
            _ => {
                self.least_angle(new) > self.least_angle(old) + 1e-9
                    && self.largest_angle(new) < CAP_ANGLE.max(self.largest_angle(old))
            }
        };
        shapes
            && tilt(new) <= tilt(old).max(0.5 * self.max_bend)
            && new.iter().all(|&t| self.chordal_error(t) <= self.tolerance)
    }

    /// The triangle's three angles (radians).
    fn angles(&self, t: [u32; 3]) -> [f64; 3] {
        let p = t.map(|i| self.pos(i));
        [0, 1, 2].map(|k| (p[(k + 1) % 3] - p[k]).angle(&(p[(k + 2) % 3] - p[k])))
    }

    /// The triangle's smallest angle (radians).
    fn smallest_angle(&self, t: [u32; 3]) -> f64 {
        self.angles(t).into_iter().fold(f64::INFINITY, f64::min)
    }

    /// The smallest angle of these triangles.
    fn least_angle(&self, ts: &[[u32; 3]]) -> f64 {
        ts.iter()
            .map(|&t| self.smallest_angle(t))
            .fold(f64::INFINITY, f64::min)
    }

    /// The largest angle of these triangles.
    fn largest_angle(&self, ts: &[[u32; 3]]) -> f64 {
        ts.iter().flat_map(|&t| self.angles(t)).fold(0.0, f64::max)
    }

    /// Splits the longest edge of every triangle whose chordal error exceeds the tolerance.
    fn split_chordal(&mut self) -> usize {
        let unknown: Vec<[u32; 3]> = self
            .live_triangles()
            .filter(|t| !self.chordal_fine.contains(t))
            .collect();
        // One surface evaluation per triangle: the pass's work, shared among the cores.
        let fine: Vec<bool> = unknown
            .par_iter()
            .map(|&t| self.chordal_error(t) <= self.tolerance)
            .collect();
        let mut bad = Vec::new();
        for (t, fine) in unknown.into_iter().zip(fine) {
            if fine {
                self.chordal_fine.insert(t);
            } else {
                bad.push(t);
            }
        }
        self.split_longest_edges(bad)
    }

    /// Splits the longest edge of every triangle that faces away from the surface though it winds
    /// the right way in its chart: too large for the curvature there.
    fn split_folded(&mut self) -> usize {
        let bad: Vec<[u32; 3]> = self
            .live_triangles()
            .filter(|&t| self.folds(std::iter::once(t)).facing_away > 0)
            .collect();
        self.split_longest_edges(bad)
    }

    fn split_longest_edges(&mut self, tris: Vec<[u32; 3]>) -> usize {
        let edges: Vec<(u32, u32)> = tris
            .iter()
            .map(|t| {
                let k = (0..3)
                    .max_by(|&i, &j| {
                        let li = (self.pos(t[i]) - self.pos(t[(i + 1) % 3])).norm();
                        let lj = (self.pos(t[j]) - self.pos(t[(j + 1) % 3])).norm();
                        li.total_cmp(&lj)
                    })
                    .unwrap_or(0);
                (t[k], t[(k + 1) % 3])
            })
            .filter(|&(a, b)| (self.pos(a) - self.pos(b)).norm() > self.min_edge)
            .collect();
        self.split_edges(edges, false)
    }

    /// Splits each edge that still exists when its turn comes (see [`Remesher::split`]); the
    /// midpoints, the pass's surface evaluations, are found first on all cores (a split moves no
    /// vertex, so they stay right).
    fn split_edges(&mut self, edges: Vec<(u32, u32)>, sizing: bool) -> usize {
        let mids: Vec<Option<Vertex>> = edges
            .par_iter()
            .map(|&(a, b)| self.centre([a, b]))
            .collect();
        let mut count = 0;
        for ((a, b), mid) in edges.into_iter().zip(mids) {
            if mid.is_some_and(|mid| self.split(a, b, mid, sizing)) {
                count += 1;
            }
        }
        count
    }

    /// Splits edge a–b at the surface point midway in chart coordinates.
    /// `sizing`: a split for the target length, refused where a child would face away from the
    /// surface more than its parents did. Otherwise a split that refines a triangle that is too
    /// coarse or faces away, where only the orientation in the chart is kept.
    fn split(&mut self, a: u32, b: u32, mid: Vertex, sizing: bool) -> bool {
        let Some((t1, c, t2, d)) = self.edge_wings(a, b) else {
            return false;
        };
        let m = self.verts.len() as u32;
        // Halving a triangle in its chart keeps it counter-clockwise, but where the surface bends
        // sharply between a and b a child can face away from it.
        self.verts.push(mid);
        let children = [[a, m, c], [m, b, c], [b, m, d], [m, a, d]];
        let old = self.folds([t1, t2].map(|t| self.tris[t as usize]).into_iter());
        let new = self.folds(children.into_iter());
        if new.turned > 0 || (sizing && !new.no_worse_than(old)) {
            self.verts.pop();
            return false;
        }
        self.rings.push(Vec::new());
        let (t3, t4) = (self.tris.len() as u32, self.tris.len() as u32 + 1);
        self.tris[t1 as usize] = [a, m, c];
        self.tris[t2 as usize] = [b, m, d];
        self.tris.push([m, b, c]);
        self.tris.push([m, a, d]);
        // a leaves t₂ for t₄, b leaves t₁ for t₃; c gains t₃, d gains t₄.
        self.ring_replace(a, t2, t4);
        self.ring_replace(b, t1, t3);
        self.rings[c as usize].push(t3);
        self.rings[d as usize].push(t4);
        self.rings[m as usize] = vec![t1, t3, t2, t4];
        self.changed.push(0);
        for v in [a, b, c, d, m] {
            self.touch(v);
        }
        true
    }

    /// Collapses, shortest first, every edge shorter than 4/5 of its target length where that
    /// keeps the mesh a manifold with outward triangles and no edge longer than 4/3.
    fn collapse_short(&mut self) -> usize {
        let mut short: Vec<(f64, u32, u32)> = self
            .edges()
            .into_par_iter()
            .map(|(a, b)| (self.relative_length(a, b), a, b))
            .filter(|e| e.0 < 4.0 / 5.0)
            .collect();
        short.par_sort_by(|x, y| x.0.total_cmp(&y.0));
        // No collapse makes a fold where there was none, so a mesh without one stays so through
        // the pass, and a collapse need not look for folds to excuse a long edge.
        self.unfolded = self
            .tris
            .par_iter()
            .filter(|t| t[0] != DEAD)
            .all(|&t| self.folds(std::iter::once(t)).none());
        if self.unfolded {
            // Most short edges would stretch another: those are found on all cores first.
            short = short
                .into_par_iter()
                .filter(|&(_, a, b)| !self.stretches(b, a) || !self.stretches(a, b))
                .collect();
        }
        let count = self.collapse_either_way(short.into_iter().map(|(_, a, b)| (a, b)));
        self.unfolded = false;
        count
    }

    /// Collapses edges shorter than the smallest target length, which bisecting bent edges at a
    /// curvature spike can leave (their triangles there are caps and slivers too small for the
    /// chordal error to matter).
    fn collapse_tiny(&mut self) -> usize {
        let tiny: Vec<(u32, u32)> = self
            .edges()
            .into_par_iter()
            .filter(|&(a, b)| (self.pos(a) - self.pos(b)).norm() < self.min_edge)
            .collect();
        self.collapse_either_way(tiny.into_iter())
    }

    /// Collapses each edge that still exists when its turn comes, b onto a or else a onto b, for
    /// its length; how many.
    fn collapse_either_way(&mut self, edges: impl Iterator<Item = (u32, u32)>) -> usize {
        edges
            .filter(|&(a, b)| {
                self.collapse(b, a, Purpose::Length) || self.collapse(a, b, Purpose::Length)
            })
            .count()
    }

    /// Whether moving `gone` onto `kept` would leave an edge from `kept` to one of `gone`'s
    /// neighbours longer than a split would (4/3 of the smaller target length).
    fn stretches(&self, gone: u32, kept: u32) -> bool {
        let kept_vertex = &self.verts[kept as usize];
        self.ring(gone).iter().any(|&t| {
            self.tris[t as usize].iter().any(|&i| {
                let limit = self.verts[i as usize].size.min(kept_vertex.size);
                i != gone && i != kept && (self.pos(i) - kept_vertex.pos).norm() > 4.0 / 3.0 * limit
            })
        })
    }

    /// Moves `gone` onto `kept` and removes the two triangles of their edge, for `purpose`.
    fn collapse(&mut self, gone: u32, kept: u32, purpose: Purpose) -> bool {
        let Some((t1, c, t2, d)) = self.edge_wings(kept, gone) else {
            return false;
        };
        if self.valence(c) <= 3
            || self.valence(d) <= 3
            || self.valence(gone) + self.valence(kept) - 4 > 10
        {
            return false;
        }
        let ring = self.ring(gone);
        let changed = ring
            .iter()
            .filter(|&&t| t != t1 && t != t2)
            .map(|&t| self.tris[t as usize].map(|i| if i == gone { kept } else { i }));
        let old_folds = || self.folds(ring.iter().map(|&t| self.tris[t as usize]));
        // Where nothing was folded, no edge may come out longer than a split would leave. Most
        // refusals are these: the cheap test goes first.
        if purpose == Purpose::Length
            && self.stretches(gone, kept)
            && (self.unfolded || old_folds().none())
        {
            return false;
        }
        // The link condition: the ends share exactly the two wing vertices.
        if self.shared_neighbours(gone, kept) != 2 {
            return false;
        }
        let old_folds = old_folds();
        if !self.folds(changed.clone()).no_worse_than(old_folds) {
            return false;
        }
        if purpose != Purpose::Length {
            let old: Vec<[u32; 3]> = ring.iter().map(|&t| self.tris[t as usize]).collect();
            let new: Vec<[u32; 3]> = changed.collect();
            if !self.mends(&old, &new, purpose) {
                return false;
            }
        }
        // The wings die; gone's other triangles pass to kept (by the link condition none held
        // kept before).
        for t in std::mem::take(&mut self.rings[gone as usize]) {
            if t == t1 || t == t2 {
                self.tris[t as usize] = [DEAD; 3];
            } else {
                for i in self.tris[t as usize].iter_mut() {
                    if *i == gone {
                        *i = kept;
                    }
                }
                self.rings[kept as usize].push(t);
            }
        }
        for (v, t) in [(kept, t1), (kept, t2), (c, t1), (d, t2)] {
            self.ring_remove(v, t);
        }
        // kept's new triangles are the ones whose shape changed.
        for i in 0..self.rings[kept as usize].len() {
            let t = self.rings[kept as usize][i];
            for v in self.tris[t as usize] {
                self.touch(v);
            }
        }
        true
    }

    /// Flips edges by `rule` where the two new triangles face outward and keep the surface's bend.
    fn flip(&mut self, rule: FlipRule) -> usize {
        // Which edges the rule wants flipped, found on all cores; each is tested again when its
        // turn comes, as the flips before it may have changed its wings (and one they made
        // wanted is the next pass's).
        let wanted: Vec<(u32, u32)> = self
            .edges()
            .into_par_iter()
            .filter(|&(a, b)| self.flip_wanted(a, b, rule).is_some())
            .collect();
        wanted
            .into_iter()
            .filter(|&(a, b)| self.try_flip(a, b, rule))
            .count()
    }

    /// Whether `rule` asks for edge a→b to be flipped, as the mesh is (the flip may still be
    /// refused: see [`Remesher::try_flip`]); the wings if so.
    fn flip_wanted(&self, a: u32, b: u32, rule: FlipRule) -> Option<(u32, u32, u32, u32)> {
        let (t1, c, t2, d) = self.edge_wings(a, b)?;
        if self.triangle_with(c, d).is_some() || self.valence(a) <= 3 || self.valence(b) <= 3 {
            return None;
        }
        let wanted = match rule {
            FlipRule::Valence => {
                let dev = |v: u32, delta: i64| {
                    let x = self.valence(v) as i64 + delta - 6;
                    x * x
                };
                let before = dev(a, 0) + dev(b, 0) + dev(c, 0) + dev(d, 0);
                let after = dev(a, -1) + dev(b, -1) + dev(c, 1) + dev(d, 1);
                after < before
            }
            FlipRule::Delaunay => {
                // α + β > π, for α, β in (0, π): cot α + cot β < 0 (no arccosines).
                let cot = |o: u32, p: u32, q: u32| {
                    let (u, v) = (self.pos(p) - self.pos(o), self.pos(q) - self.pos(o));
                    u.dot(&v) / u.cross(&v).norm()
                };
                cot(c, a, b) + cot(d, b, a) < -1e-9
            }
            FlipRule::Mend => {
                let (old, new) = ([[a, b, c], [b, a, d]], [[a, d, c], [d, b, c]]);
                self.least_angle(&new) > self.least_angle(&old) + 1e-9
                    && self.largest_angle(&new) < CAP_ANGLE.max(self.largest_angle(&old))
            }
            FlipRule::Uncap => {
                let (old, new) = ([[a, b, c], [b, a, d]], [[a, d, c], [d, b, c]]);
                self.largest_angle(&new) < self.largest_angle(&old) - 1e-9
                    && self.least_angle(&new) >= (0.5 * self.least_angle(&old)).min(UNCAP_FLOOR)
            }
        };
        wanted.then_some((t1, c, t2, d))
    }

    fn try_flip(&mut self, a: u32, b: u32, rule: FlipRule) -> bool {
        let Some((t1, c, t2, d)) = self.flip_wanted(a, b, rule) else {
            return false;
        };
        let (n1, n2) = ([a, d, c], [d, b, c]);
        let old_folds = self.folds([[a, b, c], [b, a, d]].into_iter());
        if !self.folds([n1, n2].into_iter()).no_worse_than(old_folds) {
            return false;
        }
        // The new pair must not bend more than the old one (a flip across a ridge makes a crease).
        let normal = |t: [u32; 3]| {
            let p = t.map(|i| self.pos(i));
            (p[1] - p[0]).cross(&(p[2] - p[0])).normalize()
        };
        let old = normal([a, b, c]).dot(&normal([b, a, d]));
        if old_folds.none() && normal(n1).dot(&normal(n2)) < old.min(0.98) {
            return false;
        }
        if rule != FlipRule::Valence
            && (self.chordal_error(n1) > self.tolerance || self.chordal_error(n2) > self.tolerance)
        {
            return false;
        }
        self.tris[t1 as usize] = n1;
        self.tris[t2 as usize] = n2;
        // t₁ = (a, d, c) and t₂ = (d, b, c): a leaves t₂, b leaves t₁, c joins t₂, d joins t₁.
        self.ring_remove(a, t2);
        self.ring_remove(b, t1);
        self.rings[c as usize].push(t2);
        self.rings[d as usize].push(t1);
        for v in [a, b, c, d] {
            self.touch(v);
        }
        true
    }

    /// Sweeps moving each vertex part way towards the area-weighted centre of its triangles,
    /// within its tangent plane, where no triangle turns over or comes to face away. Each sweep
    /// finds every vertex's new place from the old places (Jacobi) and makes all the moves at
    /// once; then, until none is left, every triangle that came out worse than it was puts its
    /// moved corners back. All on all cores but the moves themselves.
    fn smooth(&mut self, sweeps: usize) {
        // Moved corners make the chordal errors known so far stale.
        self.chordal_fine.clear();
        for _ in 0..sweeps {
            let targets: Vec<(u32, Vertex)> = (0..self.verts.len() as u32)
                .into_par_iter()
                .filter_map(|v| Some((v, self.relaxed(v, false)?)))
                .collect();
            let mut moved = vec![false; self.verts.len()];
            for &(v, _) in &targets {
                moved[v as usize] = true;
            }
            // The triangles a move can make worse: those with a moved corner.
            let watched: Vec<u32> = (0..self.tris.len() as u32)
                .into_par_iter()
                .filter(|&t| {
                    let tri = self.tris[t as usize];
                    tri[0] != DEAD && tri.iter().any(|&i| moved[i as usize])
                })
                .collect();
            let before: Vec<FoldState> = watched
                .par_iter()
                .map(|&t| self.fold_state(self.tris[t as usize]))
                .collect();
            let mut saved: Vec<Option<Vertex>> = vec![None; self.verts.len()];
            for (v, target) in targets {
                saved[v as usize] = Some(std::mem::replace(&mut self.verts[v as usize], target));
            }
            loop {
                let worse: Vec<u32> = watched
                    .par_iter()
                    .zip(&before)
                    .filter(|&(&t, &was)| self.fold_state(self.tris[t as usize]) > was)
                    .map(|(&t, _)| t)
                    .collect();
                let mut put_back = 0;
                for t in worse {
                    for i in self.tris[t as usize] {
                        if let Some(old) = saved[i as usize].take() {
                            self.verts[i as usize] = old;
                            put_back += 1;
                        }
                    }
                }
                if put_back == 0 {
                    break;
                }
            }
            for (v, old) in saved.into_iter().enumerate() {
                if let Some(old) = old {
                    let new = &self.verts[v];
                    let step = (new.pos - old.pos).norm();
                    if step > MOVE_NOTICED * new.size || new.size != old.size {
                        self.touch(v as u32);
                    }
                }
            }
        }
    }

    /// Where smoothing would move `v` (`None`: nowhere, or `v` is gone). `small`: also a step
    /// under [`MOVE_SKIPPED`] of the target length.
    fn relaxed(&self, v: u32, small: bool) -> Option<Vertex> {
        if self.ring(v).is_empty() {
            return None;
        }
        let vert = &self.verts[v as usize];
        let (mut sum, mut weight) = (Vector3::zeros(), 0.0);
        for &t in self.ring(v) {
            let tri = self.tris[t as usize];
            let p = tri.map(|i| self.pos(i));
            let area = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            sum += self.centroid(tri).coords * area;
            weight += area;
        }
        if weight.is_nan() || weight <= 0.0 {
            return None;
        }
        let step = (sum / weight - vert.pos.coords) * 0.6;
        let step = step - vert.normal * step.dot(&vert.normal);
        // A vertex nearly where it belongs stays: its new place would cost a surface evaluation.
        if !small && step.norm() < MOVE_SKIPPED * vert.size {
            return None;
        }
        // δw minimising |J δw − step|: the normal equations of the 3×2 Jacobian.
        let (e, f, g) = (
            vert.du.dot(&vert.du),
            vert.du.dot(&vert.dv),
            vert.dv.dot(&vert.dv),
        );
        let det = e * g - f * f;
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let (ru, rv) = (vert.du.dot(&step), vert.dv.dot(&step));
        let dw = Complex64::new((g * ru - f * rv) / det, (e * rv - f * ru) / det);
        self.vertex(ChartPoint::new(vert.point.chart, vert.point.coords + dw))
    }

    // ------------------------------------------------------------------ output

    /// Drops dead triangles and unused vertices, and finds each triangle's home chart.
    fn finish(self) -> Result<QualityMesh, EmbeddingError> {
        let mut remap = vec![DEAD; self.verts.len()];
        let mut mesh = QualityMesh::default();
        for t in self.tris.iter().filter(|t| t[0] != DEAD) {
            for &i in t {
                if remap[i as usize] == DEAD {
                    remap[i as usize] = mesh.vertices.len() as u32;
                    mesh.vertices.push(self.verts[i as usize].point);
                    mesh.positions.push(self.verts[i as usize].pos);
                }
            }
            let (chart, coords) = self.common_chart(*t).ok_or_else(|| {
                let c = self.centroid(*t);
                EmbeddingError::Parameterization(format!(
                    "no chart holds all three corners of a triangle near ({:.3}, {:.3}, {:.3})",
                    c.x, c.y, c.z
                ))
            })?;
            mesh.triangles.push(t.map(|i| remap[i as usize]));
            mesh.triangle_charts.push(chart);
            mesh.triangle_coords.push(coords);
        }
        Ok(mesh)
    }
}

/// The corner of `t` that is neither `a` nor `b`.
fn third(t: [u32; 3], a: u32, b: u32) -> u32 {
    t.into_iter().find(|&i| i != a && i != b).unwrap_or(DEAD)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every edge of the triangles with a corner changed since a pass, each once, as sorting
    /// both orientations of every such triangle's edges finds them.
    #[test]
    fn a_later_pass_sees_each_edge_of_what_changed_once() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../assets/models/genus-2.json"
        ))
        .unwrap();
        let model: crate::Model = serde_json::from_str(&text).unwrap();
        let surface = Surface::from_model(&model).unwrap();
        let mut r = Remesher::start(&surface, &QualitySettings::default()).unwrap();
        r.repeat_at_most(2, |r| r.split_long());
        r.repeat_at_most(2, |r| r.collapse_short());
        let mut checked = 0;
        for since in 1..=r.pass {
            r.since = since;
            let mut expected: Vec<(u32, u32)> = r
                .live_triangles()
                .flat_map(|t| {
                    (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])))
                })
                .collect();
            expected.sort_unstable();
            expected.dedup();
            let mut found = r.edges();
            let listed = found.len();
            found.sort_unstable();
            found.dedup();
            assert_eq!(
                found.len(),
                listed,
                "since pass {since}: an edge listed twice"
            );
            assert_eq!(found, expected, "since pass {since}");
            checked += listed;
        }
        assert!(
            checked > 1000,
            "the passes changed too little to test: {checked}"
        );
    }

    #[test]
    fn third_corner() {
        assert_eq!(third([4, 7, 9], 7, 4), 9);
        assert_eq!(third([4, 7, 9], 9, 7), 4);
    }

    #[test]
    fn tolerance_range_is_checked() {
        for t in [0.0, -1.0, f64::NAN, 0.5] {
            let s = QualitySettings::with_tolerance(t);
            assert!(s.check().is_err(), "{t}");
        }
        assert!(QualitySettings::default().check().is_ok());
    }
}
