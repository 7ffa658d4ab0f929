//! The surface as the viewport shows it: the tessellation, its stencil, every vertex's exact position
//! and tangents (f64; during a stroke, positions within the stroke's lag budget, under half a pixel
//! where the view allows, and tangents as of the stroke's start, until its end), the vertices as
//! the GPU reads them (f32, indexed), which of them changed since the last upload, the picking
//! hierarchy, and the surface's brush samples.
//!
//! Vertices are shared between triangles (an index buffer), so an edit rewrites each moved vertex
//! once; the GPU pulls them by index (see `gpu.rs`), so the wireframe still gets per-corner
//! barycentric coordinates.

use std::ops::Range;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use charts::{ChartId, ChartPoint};
use embedding::brush::{BrushSamples, SurfaceSamples};
use embedding::remesh::{QualitySettings, quality_mesh};
use embedding::stencil::TensorStencil;
use embedding::{
    ColumnIndex, ControlId, EmbeddingError, Point3, Sample, Stencil, Surface, Vector3, Wants,
    bounding_box, evaluate_rows,
};

use num_complex::Complex64;

use super::camera::Ray;
use super::pick::{Bvh, Hit};
use super::state::EditorError;
use crate::io::export::Meshing;
use crate::render::scene::{SURFACE_COLOUR, blend_colour, diverging, robust_range};
use crate::render::{CurvatureKind, Style};

/// One vertex as the GPU's storage buffer holds it (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ViewVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// RGBA, 8 bits each, red in the low byte.
    pub colour: u32,
    /// 0, or 1 + the index of the drag row that moves this vertex during a drag.
    pub flags: u32,
}

/// Packs a colour in [0, 1]³ into RGBA8.
pub fn pack_colour(c: [f32; 3]) -> u32 {
    let [r, g, b] = c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u32);
    r | (g << 8) | (b << 16) | (255 << 24)
}

/// Which vertices the GPU copy lacks: everything, or some ranges of vertex indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dirty {
    pub all: bool,
    pub ranges: Vec<Range<u32>>,
}

/// Runs closer than this (in vertices) are uploaded as one: a few bytes more beat another copy.
const GAP: u32 = 256;

impl Dirty {
    /// Adds vertex indices given in increasing order.
    pub fn add_sorted(&mut self, rows: &[u32]) {
        if self.all {
            return;
        }
        for &r in rows {
            match self.ranges.last_mut() {
                Some(last) if r >= last.start && r <= last.end.saturating_add(GAP) => {
                    last.end = last.end.max(r + 1);
                }
                _ => self.ranges.push(r..r + 1),
            }
        }
        if self.ranges.len() > 4096 {
            self.normalize();
        }
    }

    /// Sorts and merges the ranges.
    pub fn normalize(&mut self) {
        self.ranges.sort_by_key(|r| r.start);
        let mut merged: Vec<Range<u32>> = Vec::with_capacity(self.ranges.len());
        for r in self.ranges.drain(..) {
            match merged.last_mut() {
                Some(last) if r.start <= last.end.saturating_add(GAP) => {
                    last.end = last.end.max(r.end)
                }
                _ => merged.push(r),
            }
        }
        self.ranges = merged;
    }

    pub fn is_empty(&self) -> bool {
        !self.all && self.ranges.is_empty()
    }
}

/// The vertices that moved since the picking boxes were last refitted: a bit each.
#[derive(Clone, Debug, Default)]
struct Unfitted {
    bits: Vec<u64>,
    /// At least the number of bits set (a vertex that moves twice counts twice).
    count: usize,
    /// No vertex moved further than this since the boxes were fitted: after dabs only, whose
    /// vertices move a little at a time ([`LiveMesh::controls_moved`]). A ray is cast against
    /// the boxes grown by it.
    slack: f64,
    /// Whether vertices moved by an unknown amount (an exact evaluation: an undo, a stroke's
    /// end): the boxes must be refitted before the next ray.
    tighten: bool,
}

impl Unfitted {
    /// Vertices moved by at most `moved` (infinite: unknown).
    fn add(&mut self, rows: &[u32], vertex_count: usize, moved: f64) {
        self.bits.resize(vertex_count.div_ceil(64), 0);
        for &r in rows {
            self.bits[r as usize / 64] |= 1 << (r % 64);
        }
        self.count += rows.len();
        if moved.is_finite() {
            self.slack += moved;
        } else {
            self.tighten = true;
        }
    }

    fn vertices(&self) -> impl Iterator<Item = u32> + '_ {
        self.bits.iter().enumerate().flat_map(|(w, &word)| {
            let mut bits = word;
            std::iter::from_fn(move || {
                (bits != 0).then(|| {
                    let b = bits.trailing_zeros();
                    bits &= bits - 1;
                    (w * 64) as u32 + b
                })
            })
        })
    }
}

/// The triangles the viewport shows, every vertex a chart point: the quality tessellation or the
/// t_e/t_r one.
#[derive(Clone, Debug, Default)]
pub struct ChartTriangles {
    /// Each vertex in its home chart.
    pub vertices: Vec<ChartPoint>,
    /// Counter-clockwise in the triangle's home chart.
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's home chart: one holding all three corners.
    pub triangle_charts: Vec<ChartId>,
    /// Each triangle's corners in its home chart's coordinates.
    pub triangle_coords: Vec<[Complex64; 3]>,
}

impl ChartTriangles {
    /// Tessellates `surface` as `meshing` says (quads are shown as their halves).
    pub fn new(surface: &Surface, meshing: Meshing) -> Result<ChartTriangles, EditorError> {
        let tolerance = match meshing {
            Meshing::TeTr { te, tr } => {
                let t = surface.atlas().tessellate(te, tr)?;
                return Ok(ChartTriangles {
                    vertices: t.vertices,
                    triangles: t.triangles,
                    triangle_charts: t.triangle_charts,
                    triangle_coords: t.triangle_coords,
                });
            }
            Meshing::Quality { tolerance } | Meshing::Quads { tolerance } => tolerance,
        };
        let q = quality_mesh(surface, &QualitySettings::with_tolerance(tolerance))?;
        Ok(ChartTriangles {
            vertices: q.vertices,
            triangles: q.triangles,
            triangle_charts: q.triangle_charts,
            triangle_coords: q.triangle_coords,
        })
    }
}

/// During a stroke a vertex may lag the surface by this much of a pixel at the nearest depth a
/// vertex can have (see `EditorState::lag_budget`; [`LiveMesh::controls_moved`] keeps the lag):
/// a hair from the edge of what shows.
pub const LAG_PIXELS: f64 = 0.4;

/// The least lag a stroke is allowed, as a fraction of the model's size, where the view allows
/// less (close up, with vertices near the eye; a tenth of a pixel where the model fills a
/// 1000-pixel view) or there is none.
pub const UNSEEN: f64 = 1e-4;

/// The share of the lag allowed that control points' motions may add up to before the vertices hear of
/// them (the rest is the vertices' own lag): see [`LiveMesh::controls_moved`].
const HELD_BACK: f64 = 0.5;

/// During a stroke the picking boxes are refitted once the vertices may have left them by this
/// fraction of the model's size (a bound from the rows' lags); until then a ray is cast against
/// the boxes grown by how far (a ray then meets a few hundred more triangles' boxes at 10⁶
/// vertices).
const SLACK: f64 = 0.01;

/// What a grab's plan made in the background borrows from the live mesh ([`LiveMesh::lend`]).
pub(crate) struct Lent {
    pub stencil: Arc<Stencil>,
    pub columns: Arc<ColumnIndex>,
    pub positions: Arc<Vec<Point3>>,
    pub tangents: Arc<Vec<[Vector3; 2]>>,
    pub samples: SurfaceSamples,
    pub vertices: Vec<ViewVertex>,
}

/// The live surface mesh (see the module documentation).
pub struct LiveMesh {
    pub tessellation: ChartTriangles,
    /// Shared (never changed after the mesh is made) with a grab's plan made in the background.
    stencil: Arc<Stencil>,
    columns: Arc<ColumnIndex>,
    /// Shared with a grab's plan made in the background, which reads them; written through
    /// [`Arc::make_mut`], which copies only while such a plan holds them (never: a drag's events
    /// do not write them, and its end waits for the plan).
    positions: Arc<Vec<Point3>>,
    tangents: Arc<Vec<[Vector3; 2]>>,
    /// Empty while lent to a grab's plan made in the background ([`LiveMesh::lend`]).
    vertices: Vec<ViewVertex>,
    lent: bool,
    indices: Vec<u32>,
    dirty: Dirty,
    /// A new vertex or index count: the GPU buffers must be made anew.
    pub(crate) rebuilt: bool,
    bvh: Bvh,
    /// The vertices that moved since the picking boxes were last refitted.
    unfitted: Unfitted,
    style: Style,
    /// The curvature style's colour range (kept during edits so colours stay comparable).
    curvature_range: Option<f64>,
    /// The surface points brushes are fitted over (not these vertices: see
    /// [`embedding::brush::SurfaceSamples`]), as of the last [`LiveMesh::refresh_brush_weights`]
    /// and the dabs since.
    /// Made at the first brush's start (a model that is never brushed needs none).
    samples: Option<SurfaceSamples>,
    size: f64,
    /// Per control point, its motion during a stroke since it was last passed on to the vertices
    /// (see [`LiveMesh::controls_moved`]).
    pending: Vec<Vector3>,
    /// Per vertex, a bound on how far it lags the surface during a stroke (its point's motions
    /// since it was last evaluated, summed): see [`LiveMesh::controls_moved`]. Empty until the
    /// first dab.
    lag: Vec<f32>,
    /// The f32 tensor stencil with tangents, made at the first stroke brush's dab: dabs move
    /// their vertices through it (several times faster than the f64 stencil), and the stroke's
    /// end makes them exact again.
    tensor: Option<TensorStencil>,
}

impl LiveMesh {
    /// Tessellates as `meshing` says, builds the stencil and evaluates every vertex.
    pub fn new(surface: &Surface, meshing: Meshing, style: Style) -> Result<LiveMesh, EditorError> {
        let tessellation = ChartTriangles::new(surface, meshing)?;
        let stencil = Arc::new(Stencil::build_parallel(
            &surface.layout(),
            &tessellation.vertices,
        ));
        let columns = Arc::new(stencil.column_index(surface.control_points().len()));
        let n = tessellation.vertices.len();
        let indices = tessellation.triangles.iter().flatten().copied().collect();
        let mut mesh = LiveMesh {
            tessellation,
            stencil,
            columns,
            positions: Arc::new(vec![Point3::origin(); n]),
            tangents: Arc::new(vec![[Vector3::zeros(); 2]; n]),
            vertices: vec![ViewVertex::default(); n],
            lent: false,
            indices,
            dirty: Dirty {
                all: true,
                ranges: Vec::new(),
            },
            rebuilt: true,
            bvh: Bvh::default(),
            unfitted: Unfitted::default(),
            style,
            curvature_range: None,
            samples: None,
            size: 0.0,
            pending: Vec::new(),
            lag: Vec::new(),
            tensor: None,
        };
        let all: Vec<u32> = (0..n as u32).collect();
        mesh.evaluate(surface, &all, true);
        mesh.refresh_size();
        mesh.bvh = Bvh::build(&mesh.positions, &mesh.tessellation.triangles);
        mesh.unfitted = Unfitted::default();
        Ok(mesh)
    }

    /// Brings the brush samples up to `surface` (their positions, areas and orientation; new
    /// samples after a change of spline settings) and the model's size up to the vertices: at a
    /// drag's or stroke's start, for edits, undo and refits may have happened since.
    pub fn refresh_brush_weights(&mut self, surface: &Surface) -> Result<(), EditorError> {
        match &mut self.samples {
            Some(samples) if samples.fits(surface) => samples.refresh(surface),
            _ => self.samples = Some(SurfaceSamples::new(surface)?),
        }
        self.refresh_size();
        Ok(())
    }

    fn refresh_size(&mut self) {
        let (lo, hi) = bounding_box(&self.positions);
        self.size = (hi - lo).norm();
    }

    /// After `controls` moved: the brush samples they reach, exactly (the rest of the mesh is the
    /// caller's to update).
    pub fn brush_controls_moved(&mut self, surface: &Surface, controls: &[ControlId]) {
        if let Some(samples) = &mut self.samples {
            samples.controls_moved(surface, controls);
        }
    }

    /// The surface as a brush samples it (as of the last [`LiveMesh::refresh_brush_weights`] and
    /// the dabs since; made now if there are no samples for `surface` yet).
    pub fn brush_samples<'a>(
        &'a mut self,
        surface: &'a Surface,
    ) -> Result<BrushSamples<'a>, EmbeddingError> {
        let samples = match self.samples.take() {
            Some(samples) if samples.fits(surface) => samples,
            _ => SurfaceSamples::new(surface)?,
        };
        Ok(self.samples.insert(samples).view(surface))
    }

    pub fn stencil(&self) -> &Stencil {
        &self.stencil
    }
    pub fn columns(&self) -> &ColumnIndex {
        &self.columns
    }
    /// Exact positions (stencil × control points) of every vertex (during a stroke: within the
    /// stroke's lag budget, [`LiveMesh::controls_moved`]).
    pub fn positions(&self) -> &[Point3] {
        &self.positions
    }
    pub fn tangents(&self) -> &[[Vector3; 2]] {
        &self.tangents
    }
    pub fn vertices(&self) -> &[ViewVertex] {
        &self.vertices
    }
    pub(crate) fn vertices_mut(&mut self) -> &mut [ViewVertex] {
        assert!(!self.lent, "the vertices are lent to a plan");
        &mut self.vertices
    }
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }
    pub fn triangle_count(&self) -> usize {
        self.tessellation.triangles.len()
    }
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    pub fn style(&self) -> Style {
        self.style
    }

    /// What the GPU copy lacks (and forgets it).
    pub fn take_dirty(&mut self) -> Dirty {
        let mut d = std::mem::take(&mut self.dirty);
        d.normalize();
        d
    }
    /// Hands what the GPU copy lacks to `write(byte offset, bytes)` (the vertex buffer's ranges that
    /// changed), or, after a new tessellation or when `new_buffers`, tells the caller to make the
    /// buffers anew from [`LiveMesh::vertices`] and [`LiveMesh::indices`]. Returns the bytes
    /// written, or `None` for "make new buffers".
    ///
    /// While the vertices are lent to a plan made in the background, nothing is written: what
    /// changed waits for their return.
    pub fn upload(
        &mut self,
        new_buffers: bool,
        mut write: impl FnMut(u64, &[u8]),
    ) -> Option<usize> {
        if self.lent {
            return Some(0);
        }
        let dirty = self.take_dirty();
        if self.rebuilt || new_buffers {
            self.rebuilt = false;
            return None;
        }
        let stride = std::mem::size_of::<ViewVertex>();
        if dirty.all {
            write(0, bytemuck::cast_slice(&self.vertices));
            return Some(self.vertices.len() * stride);
        }
        let mut bytes = 0;
        for range in dirty.ranges {
            let (start, end) = (
                range.start as usize,
                (range.end as usize).min(self.vertices.len()),
            );
            if start < end {
                write(
                    (start * stride) as u64,
                    bytemuck::cast_slice(&self.vertices[start..end]),
                );
                bytes += (end - start) * stride;
            }
        }
        Some(bytes)
    }

    /// Every vertex must be uploaded again.
    pub fn mark_all_dirty(&mut self) {
        self.dirty.all = true;
    }

    pub(crate) fn mark_dirty(&mut self, rows: &[u32]) {
        self.dirty.add_sorted(rows);
    }

    /// The nearest triangle the ray meets (the picking boxes are refitted first if the surface
    /// moved since).
    pub fn cast(&mut self, ray: &Ray) -> Option<Hit> {
        let triangles = &self.tessellation.triangles;
        let unfitted = &self.unfitted;
        if unfitted.tighten || unfitted.slack > SLACK * self.size {
            let moved = std::mem::take(&mut self.unfitted);
            // Past a quarter of the vertices, one pass over every box is the cheaper way.
            if 4 * moved.count > self.positions.len() {
                self.bvh.refit(&self.positions, triangles);
            } else if moved.count > 0 {
                self.bvh
                    .refit_vertices(&self.positions, triangles, moved.vertices());
            }
        }
        let pad = self.unfitted.slack;
        self.bvh.cast(ray, &self.positions, triangles, pad)
    }

    /// The centre of the bounding box and the largest distance from it.
    pub fn bounding_sphere(&self) -> (Point3, f64) {
        let (lo, hi) = bounding_box(&self.positions);
        let centre = lo + (hi - lo) / 2.0;
        let radius = self
            .positions
            .iter()
            .map(|p| (p - centre).norm())
            .fold(0.0, f64::max);
        (centre, radius)
    }

    /// The bounding box's diagonal: the model's size (as of the last
    /// [`LiveMesh::refresh_brush_weights`]: made when the mesh is, and again at each drag's or
    /// stroke's start, not per edit, for it reads every vertex).
    pub fn size(&self) -> f64 {
        self.size
    }

    /// Recolours every vertex for `style`.
    pub fn set_style(&mut self, surface: &Surface, style: Style) {
        assert!(!self.lent, "the vertices are lent to a plan");
        self.style = style;
        self.curvature_range = None;
        let all: Vec<u32> = (0..self.positions.len() as u32).collect();
        self.evaluate(surface, &all, true);
        self.dirty.all = true;
    }

    /// The rows any of `controls` touches, in increasing order.
    pub fn rows_of_controls(&self, controls: &[ControlId]) -> Vec<u32> {
        self.stencil
            .rows_of_controls(&self.columns, controls.iter().map(|c| c.index()))
    }

    /// After a brush's dab moved control points (each with how far): the brush samples they reach
    /// exactly, and the vertices through the f32 tensor stencil (made at the first call; within
    /// `unseen` model units of the surface, below), on all cores; call [`LiveMesh::controls_changed`] with every
    /// control point a stroke moved when it ends, to make the vertices exact. In the shaded and
    /// wireframe styles that is all a vertex shows; in the others the colours follow too (the
    /// exact, full evaluation).
    ///
    /// Most of the control points a dab moves lie at its fringe and move very little, yet reach
    /// half a million vertices at 10⁶. So the vertices follow in two stages, each with a share of
    /// the allowed lag, `unseen`:
    /// - a control point's motion is passed on only once it adds up (as a vector, since it was
    ///   last passed on) to half of it. A row's weights are positive and sum to 1, so the
    ///   motions held back move no vertex further than that;
    /// - each vertex keeps a bound on how far the motions passed on have moved it since it was
    ///   last evaluated, and is evaluated anew only once that reaches the other half
    ///   ([`TensorStencil::follow_controls`]: bounding a motion reads a row's position factors
    ///   alone, and sums scalars).
    ///
    /// So no vertex is ever further than `unseen` from where the control points put it, as long
    /// as `unseen` does not shrink during a stroke (where it must, make the vertices exact first).
    pub fn controls_moved(
        &mut self,
        surface: &Surface,
        moved: &[(ControlId, Vector3)],
        unseen: f64,
    ) {
        let controls: Vec<ControlId> = moved.iter().map(|m| m.0).collect();
        self.brush_controls_moved(surface, &controls);
        if matches!(self.style, Style::Curvature(_) | Style::Charts) {
            self.controls_changed(surface, &controls);
            return;
        }
        self.pending
            .resize(surface.control_points().len(), Vector3::zeros());
        self.lag.resize(self.positions.len(), 0.0);
        let due: Vec<(u32, Vector3)> = moved
            .iter()
            .filter_map(|&(c, d)| {
                let pending = &mut self.pending[c.index()];
                *pending += d;
                (pending.norm() >= HELD_BACK * unseen).then(|| (c.0, std::mem::take(pending)))
            })
            .collect();
        if due.is_empty() {
            return;
        }
        let points = &self.tessellation.vertices;
        let tensor = self
            .tensor
            .get_or_insert_with(|| TensorStencil::build_with_tangents(&surface.layout(), points));
        // The vertex and its f64 position are written; the f64 tangents are left as they were
        // (nothing reads them during a stroke, and its end makes them exact again): bytes a
        // vertex need not move.
        let followed = tensor.follow_controls(
            surface.control_points(),
            &due,
            (1.0 - HELD_BACK) * unseen,
            &mut self.lag,
            Arc::make_mut(&mut self.positions).as_mut_slice(),
            &mut self.vertices,
            |position, vertex, p, [u, v]| {
                let n = u.cross(&v).normalize();
                *position = p;
                vertex.position = [p.x as f32, p.y as f32, p.z as f32];
                vertex.normal = [n.x as f32, n.y as f32, n.z as f32];
                vertex.flags = 0;
            },
        );
        if !followed.rows.is_empty() {
            self.dirty.add_sorted(&followed.rows);
            // How far a written vertex moved: at most its lag, with the motions held back when it
            // was last evaluated and now (each under HELD_BACK of `unseen`).
            let moved = followed.largest_lag + 2.0 * HELD_BACK * unseen;
            self.unfitted
                .add(&followed.rows, self.positions.len(), moved);
        }
    }

    /// After `controls` changed: recomputes exactly the rows they touch (and their colours in the
    /// curvature style), marks them for upload and the picking boxes for refitting.
    pub fn controls_changed(&mut self, surface: &Surface, controls: &[ControlId]) {
        let rows = self.rows_of_controls(controls);
        self.rows_changed(surface, &rows);
        for c in controls {
            if let Some(pending) = self.pending.get_mut(c.index()) {
                *pending = Vector3::zeros();
            }
        }
    }

    /// After the control points under `rows` (increasing) changed: their positions, tangents and,
    /// in the curvature style, colours anew.
    pub fn rows_changed(&mut self, surface: &Surface, rows: &[u32]) {
        let recolour = matches!(self.style, Style::Curvature(_));
        self.evaluate(surface, rows, recolour);
    }

    /// Positions and tangents of `rows` (increasing) through the one evaluation path, their GPU
    /// vertices (and colours, when `recolour`), marked dirty; the picking boxes are stale
    /// afterwards.
    fn evaluate(&mut self, surface: &Surface, rows: &[u32], recolour: bool) {
        let style = self.style;
        let wants = Wants {
            curvature: recolour && matches!(style, Style::Curvature(_)),
            blends: recolour && style == Style::Charts,
        };
        let atlas = surface.atlas();
        assert!(!self.lent, "the vertices are lent to a plan");
        let (positions, tangents, vertices) = (
            Arc::make_mut(&mut self.positions),
            Arc::make_mut(&mut self.tangents),
            &mut self.vertices,
        );
        let mut values = Vec::new();
        let sink = &mut |s: &Sample| {
            let (p, u, v) = (s.position, s.du, s.dv);
            positions[s.index] = p;
            tangents[s.index] = [u, v];
            let n = u.cross(&v).normalize();
            let vertex = &mut vertices[s.index];
            vertex.position = [p.x as f32, p.y as f32, p.z as f32];
            vertex.normal = [n.x as f32, n.y as f32, n.z as f32];
            vertex.flags = 0;
            match (recolour, style, s.curvature) {
                (false, ..) => {}
                (_, Style::Curvature(kind), Some(k)) => values.push(match kind {
                    CurvatureKind::Gaussian => k.gaussian,
                    CurvatureKind::Mean => k.mean,
                }),
                (_, Style::Charts, _) => {
                    vertex.colour = pack_colour(blend_colour(atlas, &s.blends))
                }
                _ => vertex.colour = pack_colour(SURFACE_COLOUR),
            }
        };
        let points = &self.tessellation.vertices;
        evaluate_rows(surface, &self.stencil, points, rows, wants, 0.0, sink);
        if !self.lag.is_empty() {
            for &r in rows {
                self.lag[r as usize] = 0.0;
            }
        }
        if !values.is_empty() {
            let range = *self
                .curvature_range
                .get_or_insert_with(|| robust_range(&values));
            for (&r, v) in rows.iter().zip(values) {
                self.vertices[r as usize].colour = pack_colour(diverging(v / range));
            }
        }
        self.dirty.add_sorted(rows);
        self.unfitted.add(rows, self.positions.len(), f64::INFINITY);
    }

    /// Lends what a grab's next plan is made from to a thread of its own: the stencil, the f64
    /// positions and tangents (shared: nothing writes them during a drag), and the brush samples
    /// and the GPU vertices (moved out: the plan brings its samples up to date and writes its
    /// vertices' flags and the last plan's settled vertices itself). Until
    /// [`LiveMesh::give_back`], nothing is uploaded.
    ///
    /// # Panics
    /// If they are lent already.
    pub(crate) fn lend(&mut self, surface: &Surface) -> Result<Lent, EmbeddingError> {
        assert!(!self.lent, "the vertices are lent to a plan");
        let samples = match self.samples.take() {
            Some(samples) if samples.fits(surface) => samples,
            _ => SurfaceSamples::new(surface)?,
        };
        self.lent = true;
        Ok(Lent {
            stencil: Arc::clone(&self.stencil),
            columns: Arc::clone(&self.columns),
            positions: Arc::clone(&self.positions),
            tangents: Arc::clone(&self.tangents),
            samples,
            vertices: std::mem::take(&mut self.vertices),
        })
    }

    /// Takes back what [`LiveMesh::lend`] lent, with the rows (increasing) whose vertices the
    /// plan wrote, to upload.
    pub(crate) fn give_back(&mut self, lent: Lent, written: &[u32]) {
        assert!(self.lent, "nothing was lent");
        self.samples = Some(lent.samples);
        self.vertices = lent.vertices;
        self.lent = false;
        self.dirty.add_sorted(written);
    }

    /// What a drag's plan reads of the mesh.
    pub(crate) fn plan_rows(&self) -> super::drag::PlanRows<'_> {
        super::drag::PlanRows {
            stencil: &self.stencil,
            columns: &self.columns,
            positions: &self.positions,
            tangents: &self.tangents,
        }
    }

    /// Whether a grab's plan made in the background holds the vertices.
    pub fn is_lent(&self) -> bool {
        self.lent
    }

    /// The curvature style's colour range (95th percentile of |curvature| when the style was set).
    pub fn curvature_range(&self) -> Option<f64> {
        self.curvature_range
    }
}
