//! The surface as the viewport shows it: the tessellation, its stencil, every vertex's exact position
//! and tangents (f64), the vertices as the GPU reads them (f32, indexed), which of them changed since
//! the last upload, and the picking hierarchy.
//!
//! Vertices are shared between triangles (an index buffer), so an edit rewrites each moved vertex
//! once; the GPU pulls them by index (see `gpu.rs`), so the wireframe still gets per-corner
//! barycentric coordinates.

use std::ops::Range;

use bytemuck::{Pod, Zeroable};
use charts::Tessellation;
use embedding::{ColumnIndex, Layout, Point3, Stencil};

use super::camera::Ray;
use super::pick::{Bvh, Hit};
use crate::render::scene::{SURFACE_COLOUR, diverging, robust_range};
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

/// The live surface mesh (see the module documentation).
pub struct LiveMesh {
    pub tessellation: Tessellation,
    stencil: Stencil,
    columns: ColumnIndex,
    positions: Vec<Point3>,
    tangents: Vec<[Point3; 2]>,
    vertices: Vec<ViewVertex>,
    indices: Vec<u32>,
    dirty: Dirty,
    /// A new vertex or index count: the GPU buffers must be made anew.
    pub(crate) rebuilt: bool,
    bvh: Bvh,
    bvh_stale: bool,
    style: Style,
    /// The curvature style's colour range (kept during edits so colours stay comparable).
    curvature_range: Option<f64>,
    /// Scratch: a mark per vertex.
    marks: Vec<u64>,
}

impl LiveMesh {
    /// Tessellates, builds the stencil and evaluates every vertex.
    pub fn new(
        layout: &Layout,
        control: &[Point3],
        te: u32,
        tr: u32,
        style: Style,
    ) -> Result<LiveMesh, charts::ChartsError> {
        let tessellation = layout.atlas().tessellate(te, tr)?;
        let stencil = Stencil::build(layout, &tessellation.vertices);
        let columns = stencil.column_index(layout.control_count());
        let n = tessellation.vertices.len();
        let indices = tessellation.triangles.iter().flatten().copied().collect();
        let mut mesh = LiveMesh {
            tessellation,
            stencil,
            columns,
            positions: vec![Point3::zeros(); n],
            tangents: vec![[Point3::zeros(); 2]; n],
            vertices: vec![ViewVertex::default(); n],
            indices,
            dirty: Dirty {
                all: true,
                ranges: Vec::new(),
            },
            rebuilt: true,
            bvh: Bvh::default(),
            bvh_stale: true,
            style,
            curvature_range: None,
            marks: vec![0; n.div_ceil(64)],
        };
        let all: Vec<u32> = (0..n as u32).collect();
        mesh.recompute_rows(control, &all);
        mesh.set_style(layout, control, style);
        mesh.bvh = Bvh::build(&mesh.positions, &mesh.tessellation.triangles);
        mesh.bvh_stale = false;
        Ok(mesh)
    }

    pub fn stencil(&self) -> &Stencil {
        &self.stencil
    }
    pub fn columns(&self) -> &ColumnIndex {
        &self.columns
    }
    /// Exact positions (stencil × control points) of every vertex.
    pub fn positions(&self) -> &[Point3] {
        &self.positions
    }
    pub fn tangents(&self) -> &[[Point3; 2]] {
        &self.tangents
    }
    pub fn vertices(&self) -> &[ViewVertex] {
        &self.vertices
    }
    pub(crate) fn vertices_mut(&mut self) -> &mut [ViewVertex] {
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
    pub fn upload(
        &mut self,
        new_buffers: bool,
        mut write: impl FnMut(u64, &[u8]),
    ) -> Option<usize> {
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
        if self.bvh_stale {
            self.bvh
                .refit(&self.positions, &self.tessellation.triangles);
            self.bvh_stale = false;
        }
        self.bvh
            .cast(ray, &self.positions, &self.tessellation.triangles)
    }

    /// The centre of the bounding box and the largest distance from it.
    pub fn bounding_sphere(&self) -> (Point3, f64) {
        let (lo, hi) = bounds(&self.positions);
        let centre = (lo + hi) / 2.0;
        let radius = self
            .positions
            .iter()
            .map(|p| (p - centre).norm())
            .fold(0.0, f64::max);
        (centre, radius)
    }

    /// The bounding box's diagonal: the model's size.
    pub fn size(&self) -> f64 {
        let (lo, hi) = bounds(&self.positions);
        (hi - lo).norm()
    }

    /// Recolours every vertex for `style`.
    pub fn set_style(&mut self, layout: &Layout, control: &[Point3], style: Style) {
        self.style = style;
        self.curvature_range = None;
        let all: Vec<u32> = (0..self.positions.len() as u32).collect();
        self.recolour(layout, control, &all);
        self.dirty.all = true;
    }

    /// The rows any of `controls` touches, in increasing order.
    pub fn rows_of_controls(&mut self, controls: &[u32]) -> Vec<u32> {
        let mut rows = Vec::new();
        for &c in controls {
            for &r in self.stencil.rows_of(&self.columns, c as usize) {
                let (w, bit) = (r as usize / 64, 1u64 << (r % 64));
                if self.marks[w] & bit == 0 {
                    self.marks[w] |= bit;
                    rows.push(r);
                }
            }
        }
        for &r in &rows {
            self.marks[r as usize / 64] = 0;
        }
        rows.sort_unstable();
        rows
    }

    /// After `controls` changed: recomputes exactly the rows they touch (and their colours in the
    /// curvature style), marks them for upload and the picking boxes for refitting.
    pub fn controls_changed(&mut self, layout: &Layout, control: &[Point3], controls: &[u32]) {
        let rows = self.rows_of_controls(controls);
        self.recompute_rows(control, &rows);
        if matches!(self.style, Style::Curvature(_)) {
            self.recolour(layout, control, &rows);
        }
    }

    /// Positions and tangents of `rows` (increasing) from the stencil, their GPU vertices, marked
    /// dirty; the picking boxes are stale afterwards.
    pub fn recompute_rows(&mut self, control: &[Point3], rows: &[u32]) {
        let stencil = &self.stencil;
        let mut jets = vec![[Point3::zeros(); 3]; rows.len()];
        parallel_chunks(rows, &mut jets, |rows, out| {
            for (o, &r) in out.iter_mut().zip(rows) {
                *o = stencil.position_and_tangents(control, r as usize);
            }
        });
        for (&r, [p, u, v]) in rows.iter().zip(jets) {
            let r = r as usize;
            self.positions[r] = p;
            self.tangents[r] = [u, v];
            let n = u.cross(&v).normalize();
            let vertex = &mut self.vertices[r];
            vertex.position = [p.x as f32, p.y as f32, p.z as f32];
            vertex.normal = [n.x as f32, n.y as f32, n.z as f32];
            vertex.flags = 0;
        }
        self.dirty.add_sorted(rows);
        self.bvh_stale = true;
    }

    /// Colours of `rows` (increasing) for the current style.
    pub fn recolour(&mut self, layout: &Layout, control: &[Point3], rows: &[u32]) {
        let points = &self.tessellation.vertices;
        let colours: Vec<u32> = match self.style {
            Style::Shaded | Style::Wireframe => vec![pack_colour(SURFACE_COLOUR); rows.len()],
            Style::Charts => rows
                .iter()
                .map(|&r| {
                    let mut c = [0.0f32; 3];
                    for (chart, b) in layout.blends(points[r as usize]) {
                        let kind = layout.atlas().charts()[chart.index()].kind();
                        let k = crate::palette::surface_rgb(kind);
                        for ch in 0..3 {
                            c[ch] += b as f32 * k[ch];
                        }
                    }
                    pack_colour(c)
                })
                .collect(),
            Style::Curvature(kind) => {
                let mut values = vec![0.0; rows.len()];
                parallel_chunks(rows, &mut values, |rows, out| {
                    for (o, &r) in out.iter_mut().zip(rows) {
                        let s = layout.eval(control, points[r as usize]);
                        *o = match kind {
                            CurvatureKind::Gaussian => s.gaussian_curvature(),
                            CurvatureKind::Mean => s.mean_curvature(),
                        };
                    }
                });
                let range = *self
                    .curvature_range
                    .get_or_insert_with(|| robust_range(&values));
                values
                    .iter()
                    .map(|&v| pack_colour(diverging(v / range)))
                    .collect()
            }
        };
        for (&r, c) in rows.iter().zip(colours) {
            self.vertices[r as usize].colour = c;
        }
        self.dirty.add_sorted(rows);
    }

    /// The curvature style's colour range (95th percentile of |curvature| when the style was set).
    pub fn curvature_range(&self) -> Option<f64> {
        self.curvature_range
    }
}

fn bounds(points: &[Point3]) -> (Point3, Point3) {
    points.iter().fold(
        (
            Point3::repeat(f64::INFINITY),
            Point3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    )
}

/// Runs `work` over matching chunks of `input` and `output` on the available cores (one chunk when
/// there is little to do).
pub fn parallel_chunks<T: Sync, U: Send>(
    input: &[T],
    output: &mut [U],
    work: impl Fn(&[T], &mut [U]) + Sync,
) {
    const MIN_PER_THREAD: usize = 16_384;
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(input.len().div_ceil(MIN_PER_THREAD))
        .max(1);
    if threads == 1 {
        work(input, output);
        return;
    }
    let per = input.len().div_ceil(threads);
    std::thread::scope(|scope| {
        for (i, o) in input.chunks(per).zip(output.chunks_mut(per)) {
            let work = &work;
            scope.spawn(move || work(i, o));
        }
    });
}
