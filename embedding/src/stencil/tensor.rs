//! The positions-only stencil in tensor form, for re-embedding at memory speed.
//!
//! At a surface point the weights are, chart by chart, a normalised blend times a tensor product of
//! B-spline values: w_ij = β_c · N_i(u) · N_j(v) over the (p + 1)² live control points of chart c's
//! grid. So a row needs per chart only the first live control point's index and 2(p + 1) numbers,
//! N_i(u) and β_c · N_j(v), instead of (p + 1)² weights: for cubics 36 bytes per chart instead of the
//! full stencil's 192. Applying it forms the products again: more arithmetic, far fewer bytes, the
//! right trade when re-embedding is bound by memory.
//!
//! Precision: the factors are stored in f32, and the sums are formed in f32 about the centre of the
//! control points' bounding box, so the error scales with the model's size, not with its distance
//! from the origin. It is measured against the f64 [`Stencil`](super::Stencil) in
//! `embedding/tests/surface.rs` (at most 1e-6 of the bounding-box diagonal).

use charts::ChartPoint;
use rayon::prelude::*;

use crate::surface::{Layout, Point3, Vector3};

/// A chart whose normalised blend at a point is below this is left out of the point's row, and the
/// others' blends are renormalised. The position then moves by at most this fraction of the
/// distance between the left-out patch and the blend of the others (a patch disagreement, far below
/// the model's size): under 1e-7 of the diagonal.
pub const NEGLIGIBLE_BLEND: f64 = 1e-7;

/// Rows per parallel task: enough to amortise scheduling, few enough to balance the cores.
const ROWS_PER_TASK: usize = 4096;

/// Positions = W · control points for a fixed set of surface points, W stored chart by chart in
/// tensor form (see the module's comment).
#[derive(Clone, Debug, Default)]
pub struct TensorStencil {
    /// B-spline order (degree + 1): a chart's block is order × order control points.
    order: usize,
    /// Control points per side of a chart's grid: the stride between a block's lines.
    grid: usize,
    /// Row r's blocks are `row_starts[r]..row_starts[r + 1]`.
    row_starts: Vec<u32>,
    /// Per block: the index of its first control point (lowest i and j).
    firsts: Vec<u32>,
    /// Per block, 2 · order numbers: N_i(u) for i < order, then β · N_j(v) for j < order.
    factors: Vec<f32>,
}

/// One task's rows while building.
#[derive(Default)]
struct Part {
    blocks_per_row: Vec<u32>,
    firsts: Vec<u32>,
    factors: Vec<f32>,
}

impl TensorStencil {
    /// The stencil of `points` (each a point of its own chart), built on all cores.
    pub fn build(layout: &Layout, points: &[ChartPoint]) -> TensorStencil {
        let settings = layout.settings();
        let parts: Vec<Part> = points
            .par_chunks(ROWS_PER_TASK)
            .map(|chunk| Part::build(layout, chunk))
            .collect();
        let blocks: usize = parts.iter().map(|p| p.firsts.len()).sum();
        let mut s = TensorStencil {
            order: settings.degree + 1,
            grid: settings.grid,
            row_starts: Vec::with_capacity(points.len() + 1),
            firsts: Vec::with_capacity(blocks),
            factors: Vec::with_capacity(blocks * 2 * (settings.degree + 1)),
        };
        let block_index = |n: usize| u32::try_from(n).expect("fewer than 2³² chart blocks");
        s.row_starts.push(0);
        for part in parts {
            for n in part.blocks_per_row {
                let end = *s.row_starts.last().expect("starts with 0") as usize + n as usize;
                s.row_starts.push(block_index(end));
            }
            s.firsts.extend(part.firsts);
            s.factors.extend(part.factors);
        }
        s
    }

    pub fn rows(&self) -> usize {
        self.row_starts.len().saturating_sub(1)
    }

    /// Chart blocks stored (on average 1 to 3 per row: one per chart whose blend counts there).
    pub fn blocks(&self) -> usize {
        self.firsts.len()
    }

    /// Bytes one re-embedding streams per row: its share of the blocks (an index and 2 · order
    /// f32 factors each), its start, and the f64 position written.
    pub fn bytes_per_row(&self) -> f64 {
        let block = 4.0 + 8.0 * self.order as f64;
        block * self.blocks() as f64 / self.rows().max(1) as f64 + 4.0 + 24.0
    }

    /// B-spline order (degree + 1): a block is order × order control points.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Control points per side of a chart's grid (the stride between a block's lines).
    pub fn grid(&self) -> usize {
        self.grid
    }

    /// Row r's blocks are `row_starts()[r]..row_starts()[r + 1]`.
    pub fn row_starts(&self) -> &[u32] {
        &self.row_starts
    }

    /// Per block, the index of its first control point.
    pub fn firsts(&self) -> &[u32] {
        &self.firsts
    }

    /// Per block, 2 · order factors: N_i(u) for i < order, then β · N_j(v) for j < order.
    pub fn factors(&self) -> &[f32] {
        &self.factors
    }

    /// positions = W · control, on the calling thread.
    pub fn positions(&self, control: &[Point3], out: &mut [Point3]) {
        let frame = ControlFrame::new(control);
        self.rows_into(&frame, 0, &mut out[..self.rows()]);
    }

    /// [`TensorStencil::positions`] on all cores (the same numbers: each row is summed the same way).
    pub fn positions_parallel(&self, control: &[Point3], out: &mut [Point3]) {
        let frame = ControlFrame::new(control);
        out[..self.rows()]
            .par_chunks_mut(ROWS_PER_TASK)
            .enumerate()
            .for_each(|(k, chunk)| self.rows_into(&frame, k * ROWS_PER_TASK, chunk));
    }

    /// Rows `first_row..first_row + out.len()`, by a copy of the kernel for this order.
    fn rows_into(&self, frame: &ControlFrame, first_row: usize, out: &mut [Point3]) {
        match self.order {
            2 => self.kernel::<2>(frame, first_row, out),
            3 => self.kernel::<3>(frame, first_row, out),
            4 => self.kernel::<4>(frame, first_row, out),
            5 => self.kernel::<5>(frame, first_row, out),
            6 => self.kernel::<6>(frame, first_row, out),
            7 => self.kernel::<7>(frame, first_row, out),
            _ => self.kernel::<8>(frame, first_row, out),
        }
    }

    /// Σ over a row's blocks of Σ_j β N_j(v) Σ_i N_i(u) c_ij: the inner sums run along a line of
    /// the chart's grid (consecutive control points), four lanes (x, y, z, 0) at a time.
    fn kernel<const O: usize>(&self, frame: &ControlFrame, first_row: usize, out: &mut [Point3]) {
        if out.is_empty() {
            return;
        }
        let starts = &self.row_starts[first_row..=first_row + out.len()];
        for (o, span) in out.iter_mut().zip(starts.windows(2)) {
            let mut acc = [0f32; 4];
            for k in span[0] as usize..span[1] as usize {
                let factors = &self.factors[2 * O * k..2 * O * (k + 1)];
                let (u, v) = factors.split_at(O);
                let u: &[f32; O] = u.try_into().expect("order factors");
                let first = self.firsts[k] as usize;
                for (j, &vj) in v.iter().enumerate() {
                    let start = first + j * self.grid;
                    let line: &[[f32; 4]; O] = frame.points[start..start + O]
                        .try_into()
                        .expect("a block line");
                    let mut s = [0f32; 4];
                    for (ui, c) in u.iter().zip(line) {
                        for d in 0..4 {
                            s[d] += ui * c[d];
                        }
                    }
                    for d in 0..4 {
                        acc[d] += vj * s[d];
                    }
                }
            }
            *o = frame.centre
                + Vector3::new(f64::from(acc[0]), f64::from(acc[1]), f64::from(acc[2]));
        }
    }
}

impl Part {
    fn build(layout: &Layout, points: &[ChartPoint]) -> Part {
        let order = layout.settings().degree + 1;
        let basis = layout.basis();
        let charts = layout.atlas().charts();
        let mut part = Part {
            blocks_per_row: Vec::with_capacity(points.len()),
            firsts: Vec::with_capacity(3 * points.len()),
            factors: Vec::with_capacity(6 * order * points.len()),
        };
        let mut blends: Vec<(ChartPoint, f64)> = Vec::with_capacity(16);
        for &p in points {
            blends.clear();
            blends.extend(
                layout
                    .atlas()
                    .locate_with_transitions(p)
                    .into_iter()
                    .map(|(rep, _)| {
                        let domain = charts[rep.chart.index()].domain();
                        (rep, layout.raw_blend_value(domain, rep.coords))
                    }),
            );
            let total: f64 = blends.iter().map(|b| b.1).sum();
            blends.retain(|b| b.1 >= NEGLIGIBLE_BLEND * total);
            let kept: f64 = blends.iter().map(|b| b.1).sum();
            for &(rep, blend) in &blends {
                let beta = blend / kept;
                let (fu, nu) = basis.eval(rep.coords.re, 0);
                let (fv, nv) = basis.eval(rep.coords.im, 0);
                part.firsts
                    .push(layout.control_index(rep.chart, fu, fv) as u32);
                part.factors
                    .extend(nu[0][..order].iter().map(|&x| x as f32));
                part.factors
                    .extend(nv[0][..order].iter().map(|&y| (beta * y) as f32));
            }
            part.blocks_per_row.push(blends.len() as u32);
        }
        part
    }
}

/// The control points as f32 lanes (x, y, z, 0) about the centre of their bounding box: what the
/// tensor stencil is applied to, here or on a GPU.
pub struct ControlFrame {
    pub centre: Point3,
    pub points: Vec<[f32; 4]>,
}

impl ControlFrame {
    pub fn new(control: &[Point3]) -> ControlFrame {
        let centre = match control {
            [] => Point3::origin(),
            _ => {
                let (lo, hi) = crate::bounding_box(control);
                nalgebra::center(&lo, &hi)
            }
        };
        let points = control
            .iter()
            .map(|c| {
                let d = c - centre;
                [d.x as f32, d.y as f32, d.z as f32, 0.0]
            })
            .collect();
        ControlFrame { centre, points }
    }
}
