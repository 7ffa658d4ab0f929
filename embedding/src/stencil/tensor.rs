//! The positions-only stencil in tensor form, for re-embedding at memory speed.
//!
//! At a surface point the weights are, chart by chart, a normalised blend times a tensor product of
//! B-spline values: w_ij = β_c · N_i(u) · N_j(v) over the (p + 1)² live control points of chart c's
//! grid. So a row needs per chart only the first live control point's index and 2(p + 1) numbers,
//! N_i(u) and β_c · N_j(v), instead of (p + 1)² weights: for cubics 36 bytes per chart instead of the
//! full stencil's 192. Applying it forms the products again: more arithmetic, far fewer bytes, the
//! right trade when re-embedding is bound by memory.
//!
//! Built [with tangents](TensorStencil::build_with_tangents), a block also holds what the first
//! derivatives in the row's own chart need: N_i'(u), β · N_j'(v), the blend's logarithmic gradient
//! (β_u/β, β_v/β) and the transition's derivative ψ' = a + ib (holomorphic: the charts' transitions
//! are Möbius maps). With A = Σ_j βN_j Σ_i N_i c_ij (β times the chart's patch), B and C the same
//! with N_i' and βN_j' (β times its x and y derivatives), the row sums
//! S = Σ A, S_u = Σ (β_u/β) A + a B + b C, S_v = Σ (β_v/β) A − b B + a C.
//! For cubics that is 88 bytes per chart, against the full stencil's 448 with derivatives.
//!
//! Precision: the factors are stored in f32, and the sums are formed in f32 about the centre of the
//! control points' bounding box, so the error scales with the model's size, not with its distance
//! from the origin. It is measured against the f64 [`Stencil`](super::Stencil) in
//! `embedding/tests/surface.rs` (at most 1e-6 of the bounding-box diagonal).

use std::sync::OnceLock;

use charts::ChartPoint;
use glam::Vec4;
use rayon::prelude::*;

use num_complex::Complex64;

use super::rows_per_task;
use crate::surface::{ControlGrids, Jet, Layout, Point3, Vector3, derivatives};

/// A chart whose normalised blend at a point is below this is left out of the point's row, and the
/// others' blends are renormalised. The position then moves by at most this fraction of the
/// distance between the left-out patch and the blend of the others (a patch disagreement, far below
/// the model's size): under 1e-7 of the diagonal. Built with tangents, a chart is left out only
/// where its blend's gradient is below this too (per unit of chart coordinates).
pub const NEGLIGIBLE_BLEND: f64 = 1e-7;

/// How many blocks ahead the kernels ask for their factors (4 KiB of a cubic's positions): the
/// hardware's stream prefetcher alone left the kernel waiting on memory half the time once the
/// stencil outgrew the caches. At 8·10⁵ rows the AVX-512 kernel made 165–174 M rows/s asking 16
/// blocks ahead, 181 at 32, 188–190 at 64 and 195 at 128 and at 256 (`anchors` bench, 2026-11-30).
const PREFETCH_BLOCKS: usize = 128;

/// How many rows ahead the AVX-512 kernels ask for their output's cache lines. With
/// the stencil's arrays out of the caches (as after any other work on 10⁸ bytes) the positions
/// kernel made 221–228 M rows/s (median of 15 calls) without, 236–238 asking 32 to 128 rows ahead.
const PREFETCH_ROWS: usize = 64;

/// The most rows per parallel task (fewer where that balances the cores better, see
/// [`rows_per_task`]): enough to amortise scheduling, few enough to balance the cores.
const ROWS_PER_TASK: usize = 4096;

/// The most rows per parallel task in [`TensorStencil::follow_controls`]: each task looks its range up in
/// every moved window's list of rows (a binary search), so fewer, larger tasks than elsewhere.
const FOLLOW_ROWS_PER_TASK: usize = 32_768;

/// About how long a row takes on one core (ns), for choosing whether to use more
/// ([`rows_per_task`]): building a row, following a row a moved window reaches (most are only
/// bounded). From `ntori bench` (2026-11-30: `stencil_build` 95 ns and `stencil_build_tangents`
/// 147 ns a row). Re-embedding's depend on the kernel: [`StencilKernel::row_ns`].
const BUILD_NS: usize = 150;
const FOLLOW_NS: usize = 10;

/// Which code sums a cubic stencil's rows. Each gives the same positions to rounding (tested
/// against the f64 stencil); stencils of other orders always take [`StencilKernel::Portable`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StencilKernel {
    /// Plain Rust over glam's four-lane vectors: any CPU, any order.
    Portable,
    /// 256-bit registers and fused multiply-adds (x86-64 with AVX and FMA): two control points
    /// (x, y, z, 0) per register.
    Avx,
    /// 512-bit registers (x86-64 with AVX-512F and VL): a cubic block's whole line, its four control
    /// points, per register, so half the loads and multiply-adds of [`StencilKernel::Avx`].
    Avx512,
}

impl StencilKernel {
    /// Every kernel, slowest first.
    pub const ALL: [StencilKernel; 3] = [
        StencilKernel::Portable,
        StencilKernel::Avx,
        StencilKernel::Avx512,
    ];

    /// Whether this CPU runs it.
    pub fn available(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        let wide = |k: StencilKernel| match k {
            StencilKernel::Portable => true,
            StencilKernel::Avx => {
                is_x86_feature_detected!("avx") && is_x86_feature_detected!("fma")
            }
            StencilKernel::Avx512 => {
                is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
                    && is_x86_feature_detected!("avx")
                    && is_x86_feature_detected!("fma")
            }
        };
        #[cfg(not(target_arch = "x86_64"))]
        let wide = |k: StencilKernel| k == StencilKernel::Portable;
        wide(self)
    }

    /// About how long this kernel takes for a cubic row on one core (ns): a position, and a
    /// position with tangents. For choosing whether to use more cores ([`rows_per_task`]).
    /// Measured in 2026-11 (genus 2, 10⁵ to 8·10⁵ rows in a loop, AMD Zen 5): 3.9–4.1 and
    /// 8.6–8.7 ns with AVX-512, 5.4–5.6 and 10.0–10.6 with AVX, 9.3–9.8 and 22–23 portable.
    fn row_ns(self) -> (usize, usize) {
        match self {
            StencilKernel::Avx512 => (4, 9),
            StencilKernel::Avx => (6, 11),
            StencilKernel::Portable => (10, 23),
        }
    }

    /// The fastest kernel this CPU runs (the widest registers it has).
    pub fn fastest() -> StencilKernel {
        *StencilKernel::ALL
            .iter()
            .rev()
            .find(|k| k.available())
            .unwrap_or(&StencilKernel::Portable)
    }
}

/// Positions = W · control points for a fixed set of surface points, W stored chart by chart in
/// tensor form (see the module's comment).
#[derive(Clone, Debug, Default)]
pub struct TensorStencil {
    /// B-spline order (degree + 1): a chart's block is order × order control points.
    order: usize,
    /// How control points are numbered: a block's lines are its chart's grid apart.
    grids: ControlGrids,
    /// Row r's blocks are `row_starts[r]..row_starts[r + 1]`: a running sum from 0 to the number
    /// of blocks, never decreasing, which the SIMD kernels rely on to slice rows unchecked.
    row_starts: Vec<u32>,
    /// Per block: the index of its first control point (lowest i and j).
    firsts: Vec<u32>,
    /// Per block, 2 · order numbers: N_i(u) for i < order, then β · N_j(v) for j < order.
    factors: Vec<f32>,
    /// Empty, or per block [`tangent_words`]`(order)` numbers: N_i'(u), then β · N_j'(v), then
    /// β_u/β, β_v/β, Re ψ', Im ψ' (see the module's comment).
    tangent_factors: Vec<f32>,
    /// Made at the first [`TensorStencil::follow_controls`]: per window origin, the rows
    /// with a block there.
    rows_by_first: OnceLock<RowsByFirst>,
}

/// The rows with a block at each window origin (a block's first control point), each list
/// increasing: one entry per block, where a column index has one per weight.
#[derive(Clone, Debug, Default)]
struct RowsByFirst {
    /// Origin f's rows are `rows[starts[f]..starts[f + 1]]`.
    starts: Vec<u32>,
    rows: Vec<u32>,
}

impl RowsByFirst {
    /// A counting sort of the blocks by first control point, rows visited in order.
    fn new(row_starts: &[u32], firsts: &[u32]) -> RowsByFirst {
        let origins = firsts.iter().max().map_or(0, |&f| f as usize + 1);
        let mut starts = vec![0u32; origins + 1];
        for &f in firsts {
            starts[f as usize + 1] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        let mut next = starts.clone();
        let mut rows = vec![0u32; firsts.len()];
        for (r, span) in row_starts.windows(2).enumerate() {
            for &f in &firsts[span[0] as usize..span[1] as usize] {
                rows[next[f as usize] as usize] = r as u32;
                next[f as usize] += 1;
            }
        }
        RowsByFirst { starts, rows }
    }

    /// A bit per row of `rows` (from its start): set where the row has a block at one of
    /// `origins`.
    fn rows_between(&self, origins: &[u32], rows: std::ops::Range<usize>) -> Vec<u64> {
        let mut hit = vec![0u64; rows.len().div_ceil(64)];
        for &f in origins {
            let f = f as usize;
            let Some(list) = self.starts.get(f..f + 2) else {
                continue;
            };
            let list = &self.rows[list[0] as usize..list[1] as usize];
            let from = list.partition_point(|&r| (r as usize) < rows.start);
            for &r in list[from..]
                .iter()
                .take_while(|&&r| (r as usize) < rows.end)
            {
                let k = r as usize - rows.start;
                hit[k / 64] |= 1 << (k % 64);
            }
        }
        hit
    }
}

/// What [`TensorStencil::follow_controls`] did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Followed {
    /// The rows evaluated anew, increasing.
    pub rows: Vec<u32>,
    /// The largest lag an evaluated row had.
    pub largest_lag: f64,
}

/// f32 numbers per block that the tangents add, for B-spline order `order`.
pub fn tangent_words(order: usize) -> usize {
    2 * order + 4
}

/// One task's rows while building.
#[derive(Default)]
struct Part {
    blocks_per_row: Vec<u32>,
    firsts: Vec<u32>,
    factors: Vec<f32>,
    tangent_factors: Vec<f32>,
}

impl TensorStencil {
    /// The stencil of `points` (each a point of its own chart), built on all cores.
    pub fn build(layout: &Layout, points: &[ChartPoint]) -> TensorStencil {
        Self::build_parts(layout, points, false)
    }

    /// [`TensorStencil::build`] with what the first derivatives need as well, for
    /// [`TensorStencil::positions_and_tangents`].
    pub fn build_with_tangents(layout: &Layout, points: &[ChartPoint]) -> TensorStencil {
        Self::build_parts(layout, points, true)
    }

    fn build_parts(layout: &Layout, points: &[ChartPoint], tangents: bool) -> TensorStencil {
        let settings = layout.settings();
        let parts: Vec<Part> = match rows_per_task(points.len(), ROWS_PER_TASK, BUILD_NS) {
            None => vec![Part::build(layout, points, tangents)],
            Some(per_task) => points
                .par_chunks(per_task)
                .map(|chunk| Part::build(layout, chunk, tangents))
                .collect(),
        };
        let blocks: usize = parts.iter().map(|p| p.firsts.len()).sum();
        let mut s = TensorStencil {
            order: settings.degree + 1,
            grids: layout.grids(),
            row_starts: Vec::with_capacity(points.len() + 1),
            firsts: Vec::with_capacity(blocks),
            factors: Vec::with_capacity(blocks * 2 * (settings.degree + 1)),
            tangent_factors: Vec::with_capacity(if tangents {
                blocks * tangent_words(settings.degree + 1)
            } else {
                0
            }),
            rows_by_first: OnceLock::new(),
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
            s.tangent_factors.extend(part.tangent_factors);
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

    /// Bytes [`TensorStencil::positions_and_tangents`] streams per row: the positions' bytes, the
    /// tangent factors, and the two f64 tangents written.
    pub fn bytes_per_row_with_tangents(&self) -> f64 {
        let extra = 4.0 * tangent_words(self.order) as f64;
        self.bytes_per_row() + extra * self.blocks() as f64 / self.rows().max(1) as f64 + 48.0
    }

    /// Built with tangents ([`TensorStencil::build_with_tangents`]).
    pub fn has_tangents(&self) -> bool {
        self.blocks() == 0 || !self.tangent_factors.is_empty()
    }

    /// Per block (when built with tangents), [`tangent_words`]`(order)` numbers: N_i'(u), then
    /// β · N_j'(v), then β_u/β, β_v/β, Re ψ', Im ψ'.
    pub fn tangent_factors(&self) -> &[f32] {
        &self.tangent_factors
    }

    /// B-spline order (degree + 1): a block is order × order control points.
    pub fn order(&self) -> usize {
        self.order
    }

    /// How the control points are numbered: a block starting at control point c has its lines
    /// [`ControlGrids::stride`]`(c)` apart.
    pub fn grids(&self) -> ControlGrids {
        self.grids
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
        let kernel = frame.ready(StencilKernel::fastest(), self.rows());
        self.rows_by(kernel, &frame, 0, &mut out[..self.rows()]);
    }

    /// [`TensorStencil::positions`] on all cores (the same numbers: each row is summed the same way).
    pub fn positions_parallel(&self, control: &[Point3], out: &mut [Point3]) {
        let frame = ControlFrame::new(control);
        let out = &mut out[..self.rows()];
        let kernel = frame.ready(StencilKernel::fastest(), out.len());
        match rows_per_task(out.len(), ROWS_PER_TASK, kernel.row_ns().0) {
            None => self.rows_by(kernel, &frame, 0, out),
            Some(per_task) => out
                .par_chunks_mut(per_task)
                .enumerate()
                .for_each(|(k, chunk)| self.rows_by(kernel, &frame, k * per_task, chunk)),
        }
    }

    /// positions = W · control, and the first derivatives S_u, S_v in each row's own chart (as
    /// [`Stencil::position_and_tangents`](super::Stencil::position_and_tangents) gives them), on
    /// the calling thread.
    ///
    /// # Panics
    /// If the stencil was built without tangents.
    pub fn positions_and_tangents(
        &self,
        control: &[Point3],
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        let frame = ControlFrame::new(control);
        let rows = self.rows();
        let kernel = frame.ready(StencilKernel::fastest(), rows);
        self.frames_by(
            kernel,
            &frame,
            0,
            &mut positions[..rows],
            &mut tangents[..rows],
        );
    }

    /// [`TensorStencil::positions_and_tangents`] by `kernel`, for tests and benches that compare
    /// the kernels.
    ///
    /// # Panics
    /// If the stencil was built without tangents, or this CPU does not run `kernel`.
    pub fn positions_and_tangents_by(
        &self,
        kernel: StencilKernel,
        control: &[Point3],
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        assert!(kernel.available(), "{kernel:?} runs on this CPU");
        let frame = ControlFrame::new(control);
        let rows = self.rows();
        frame.ready(kernel, rows);
        self.frames_by(
            kernel,
            &frame,
            0,
            &mut positions[..rows],
            &mut tangents[..rows],
        );
    }

    /// [`TensorStencil::positions_and_tangents`] on all cores (the same numbers).
    pub fn positions_and_tangents_parallel(
        &self,
        control: &[Point3],
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        let frame = ControlFrame::new(control);
        let rows = self.rows();
        let (positions, tangents) = (&mut positions[..rows], &mut tangents[..rows]);
        let kernel = frame.ready(StencilKernel::fastest(), rows);
        match rows_per_task(rows, ROWS_PER_TASK, kernel.row_ns().1) {
            None => self.frames_by(kernel, &frame, 0, positions, tangents),
            Some(per_task) => positions
                .par_chunks_mut(per_task)
                .zip(tangents.par_chunks_mut(per_task))
                .enumerate()
                .for_each(|(k, (p, t))| self.frames_by(kernel, &frame, k * per_task, p, t)),
        }
    }

    /// [`TensorStencil::frames_into`] by `kernel`, which this CPU must run.
    fn frames_by(
        &self,
        kernel: StencilKernel,
        frame: &ControlFrame,
        first_row: usize,
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        #[cfg(not(target_arch = "x86_64"))]
        let _ = kernel;
        debug_assert!(kernel.available());
        assert!(self.has_tangents(), "a tensor stencil built with tangents");
        #[cfg(target_arch = "x86_64")]
        if self.order == 4 {
            match kernel {
                // SAFETY: the CPU runs `kernel` (the callers' choice: `StencilKernel::fastest`, or
                // asserted available).
                StencilKernel::Avx512 => {
                    let f = match (self.grids.disk == self.grids.square, frame.has_quads()) {
                        (true, true) => simd::cubic_jets_wide::<true, true>,
                        (true, false) => simd::cubic_jets_wide::<true, false>,
                        (false, true) => simd::cubic_jets_wide::<false, true>,
                        (false, false) => simd::cubic_jets_wide::<false, false>,
                    };
                    return unsafe { f(self, frame, first_row, positions, tangents) };
                }
                // SAFETY: as above.
                StencilKernel::Avx => {
                    return unsafe {
                        simd::cubic_jets(self, frame, first_row, positions, tangents)
                    };
                }
                StencilKernel::Portable => {}
            }
        }
        self.portable_frames_into(frame, first_row, positions, tangents);
    }

    /// [`TensorStencil::frames_into`] by the portable kernel.
    fn portable_frames_into(
        &self,
        frame: &ControlFrame,
        first_row: usize,
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        match self.order {
            2 => self.tangent_kernel::<2>(frame, first_row, positions, tangents),
            3 => self.tangent_kernel::<3>(frame, first_row, positions, tangents),
            4 => self.tangent_kernel::<4>(frame, first_row, positions, tangents),
            5 => self.tangent_kernel::<5>(frame, first_row, positions, tangents),
            6 => self.tangent_kernel::<6>(frame, first_row, positions, tangents),
            7 => self.tangent_kernel::<7>(frame, first_row, positions, tangents),
            _ => self.tangent_kernel::<8>(frame, first_row, positions, tangents),
        }
    }

    /// The position and tangents of the rows `rows` alone (any order; `out[k]` is row `rows[k]`'s),
    /// on all cores: for an edit that moved a few control points, the rows they reach.
    ///
    /// # Panics
    /// If the stencil was built without tangents.
    pub fn rows_positions_and_tangents(
        &self,
        control: &[Point3],
        rows: &[u32],
        out: &mut [(Point3, [Vector3; 2])],
    ) {
        assert!(self.has_tangents(), "a tensor stencil built with tangents");
        let frame = ControlFrame::new(control);
        let frame = &frame;
        let kernel = frame.ready(StencilKernel::fastest(), rows.len());
        let jets = |rows: &[u32], out: &mut [(Point3, [Vector3; 2])]| {
            for (o, &r) in out.iter_mut().zip(rows) {
                *o = self.row_jet_of_order(kernel, frame, r as usize);
            }
        };
        match rows_per_task(rows.len(), ROWS_PER_TASK, kernel.row_ns().1) {
            None => jets(rows, out),
            Some(per_task) => rows
                .par_chunks(per_task)
                .zip(out.par_chunks_mut(per_task))
                .for_each(|(rows, out)| jets(rows, out)),
        }
    }

    /// After control points moved (`moved`: each with its displacement since the last call),
    /// brings the rows that use them within `threshold` of the surface: every such row's `lag`
    /// (a bound on how far its last written point is from where the control points now put it)
    /// grows by a bound on how far the row's point moved; where it reaches `threshold`, the row
    /// is evaluated anew (position and tangents, handed to `write` with the row's entries of
    /// `first` and `second`) and its lag set to 0. On all cores; returns the rows evaluated, in
    /// increasing order. A `threshold` of 0 evaluates every row that uses a moved point.
    ///
    /// The bound: a row's weights w_c are positive, so its point moves by at most Σ_c w_c |Δ_c|,
    /// formed from the position factors alone, in scalars. Most rows a dab reaches lie at its
    /// fringe and move very little; those are only bounded, not evaluated.
    ///
    /// Finding the rows: a block uses the order × order window of its chart's grid from its first
    /// control point, so the rows are those listed under the windows that hold a moved point (an
    /// index of the blocks by first control point, made at the first call: 4 bytes a block).
    /// Rows where the moved points' charts were left out as negligible ([`NEGLIGIBLE_BLEND`]) are
    /// not among them: they move by less than that fraction of the points' motion.
    ///
    /// # Panics
    /// If the stencil was built without tangents, or `lag`, `first` or `second` is shorter than
    /// the stencil.
    #[allow(clippy::too_many_arguments)]
    pub fn follow_controls<A: Send, B: Send>(
        &self,
        control: &[Point3],
        moved: &[(u32, Vector3)],
        threshold: f64,
        lag: &mut [f32],
        first: &mut [A],
        second: &mut [B],
        write: impl Fn(&mut A, &mut B, Point3, [Vector3; 2]) + Sync,
    ) -> Followed {
        assert!(self.has_tangents(), "a tensor stencil built with tangents");
        let rows = self.rows();
        let (lag, first, second) = (&mut lag[..rows], &mut first[..rows], &mut second[..rows]);
        // How far each control point moved, and the windows that hold one that did.
        let mut motion = vec![0f32; control.len()];
        let mut windows = vec![0u64; control.len().div_ceil(64).max(1)];
        for &(c, d) in moved {
            motion[c as usize] = d.norm() as f32;
            super::mark_windows_holding(&mut windows, c as usize, self.grids, self.order);
        }
        let index = self
            .rows_by_first
            .get_or_init(|| RowsByFirst::new(&self.row_starts, &self.firsts));
        let origins = super::set_bits(&windows);
        let frame = ControlFrame::new(control);
        // How many rows it follows is known only at the end; an edit's are usually far fewer
        // than the control points, so no aligned copy of them.
        let kernel = StencilKernel::fastest();
        let threshold = threshold as f32;
        let order = self.order;
        // Some(the row's lag) where the row was evaluated.
        let follow = |r: usize, lag: &mut f32, a: &mut A, b: &mut B| -> Option<f32> {
            *lag += match order {
                2 => self.motion_bound::<2>(&motion, &windows, r),
                3 => self.motion_bound::<3>(&motion, &windows, r),
                4 => self.motion_bound::<4>(&motion, &windows, r),
                5 => self.motion_bound::<5>(&motion, &windows, r),
                6 => self.motion_bound::<6>(&motion, &windows, r),
                7 => self.motion_bound::<7>(&motion, &windows, r),
                _ => self.motion_bound::<8>(&motion, &windows, r),
            };
            if *lag < threshold {
                return None;
            }
            let (p, t) = self.row_jet_of_order(kernel, &frame, r);
            write(a, b, p, t);
            Some(std::mem::take(lag))
        };
        // Each task takes a range of rows, finds those a moved window reaches there (a bit each)
        // and follows them in order.
        let task = |start: usize, lag: &mut [f32], a: &mut [A], b: &mut [B]| {
            let reached = index.rows_between(&origins, start..start + lag.len());
            let (mut rows, mut largest) = (Vec::new(), 0f32);
            for k in super::set_bits(&reached) {
                let k = k as usize;
                if let Some(l) = follow(start + k, &mut lag[k], &mut a[k], &mut b[k]) {
                    rows.push((start + k) as u32);
                    largest = largest.max(l);
                }
            }
            (rows, largest)
        };
        let parts: Vec<(Vec<u32>, f32)> = match rows_per_task(rows, FOLLOW_ROWS_PER_TASK, FOLLOW_NS)
        {
            None => vec![task(0, lag, first, second)],
            Some(per_task) => lag
                .par_chunks_mut(per_task)
                .zip(first.par_chunks_mut(per_task))
                .zip(second.par_chunks_mut(per_task))
                .enumerate()
                .map(|(t, ((lag, a), b))| task(t * per_task, lag, a, b))
                .collect(),
        };
        Followed {
            largest_lag: f64::from(parts.iter().map(|p| p.1).fold(0.0, f32::max)),
            rows: parts.into_iter().flat_map(|p| p.0).collect(),
        }
    }

    /// Σ_c w_c |Δ_c| over row `r`'s blocks in a window marked in `windows`, `motion` holding
    /// |Δ_c| per control point: at least how far the row's point moved, |Σ_c w_c Δ_c|.
    fn motion_bound<const O: usize>(&self, motion: &[f32], windows: &[u64], r: usize) -> f32 {
        let mut bound = 0.0;
        for k in self.row_starts[r] as usize..self.row_starts[r + 1] as usize {
            let first = self.firsts[k] as usize;
            let grid = self.grids.stride(first);
            if windows[first / 64] & (1 << (first % 64)) == 0 {
                continue;
            }
            let (u, v) = self.factors[2 * O * k..2 * O * (k + 1)].split_at(O);
            for (j, &vj) in v.iter().enumerate() {
                let start = first + j * grid;
                let line: &[f32; O] = motion[start..start + O].try_into().expect("a block line");
                let s: f32 = u.iter().zip(line).map(|(&ui, &m)| ui * m).sum();
                bound += vj * s;
            }
        }
        bound
    }

    /// [`TensorStencil::row_jet`] for this stencil's order.
    fn row_jet_of_order(
        &self,
        kernel: StencilKernel,
        frame: &ControlFrame,
        r: usize,
    ) -> (Point3, [Vector3; 2]) {
        match self.order {
            2 => self.row_jet::<2>(kernel, frame, r),
            3 => self.row_jet::<3>(kernel, frame, r),
            4 => self.row_jet::<4>(kernel, frame, r),
            5 => self.row_jet::<5>(kernel, frame, r),
            6 => self.row_jet::<6>(kernel, frame, r),
            7 => self.row_jet::<7>(kernel, frame, r),
            _ => self.row_jet::<8>(kernel, frame, r),
        }
    }

    /// One row of [`TensorStencil::tangent_kernel`] (by `kernel` for cubics).
    fn row_jet<const O: usize>(
        &self,
        kernel: StencilKernel,
        frame: &ControlFrame,
        r: usize,
    ) -> (Point3, [Vector3; 2]) {
        let mut position = [Point3::origin()];
        let mut tangents = [[Vector3::zeros(); 2]];
        if O == 4 {
            self.frames_by(kernel, frame, r, &mut position, &mut tangents);
        } else {
            self.tangent_kernel::<O>(frame, r, &mut position, &mut tangents);
        }
        (position[0], tangents[0])
    }

    /// Per block the three sums A, B, C of the module's comment along the chart grid's lines, then
    /// the chain rule into the row's chart.
    fn tangent_kernel<const O: usize>(
        &self,
        frame: &ControlFrame,
        first_row: usize,
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        if positions.is_empty() {
            return;
        }
        let words = tangent_words(O);
        let starts = &self.row_starts[first_row..=first_row + positions.len()];
        for ((o, t), span) in positions.iter_mut().zip(tangents).zip(starts.windows(2)) {
            let (mut p, mut su, mut sv) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
            for k in span[0] as usize..span[1] as usize {
                let (u, v) = self.factors[2 * O * k..2 * O * (k + 1)].split_at(O);
                let d = &self.tangent_factors[words * k..words * (k + 1)];
                let (du, rest) = d.split_at(O);
                let (dv, chain) = rest.split_at(O);
                let first = self.firsts[k] as usize;
                let grid = self.grids.stride(first);
                let (mut a, mut b, mut c) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
                for j in 0..O {
                    let start = first + j * grid;
                    let line: &[Vec4; O] = frame.points[start..start + O]
                        .try_into()
                        .expect("a block line");
                    let (mut s, mut s1) = (Vec4::ZERO, Vec4::ZERO);
                    for i in 0..O {
                        s += line[i] * u[i];
                        s1 += line[i] * du[i];
                    }
                    a += s * v[j];
                    b += s1 * v[j];
                    c += s * dv[j];
                }
                let [gu, gv, re, im] = [chain[0], chain[1], chain[2], chain[3]];
                p += a;
                su += a * gu + b * re + c * im;
                sv += a * gv - b * im + c * re;
            }
            let wide = |v: Vec4| Vector3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z));
            *o = frame.centre + wide(p);
            *t = [wide(su), wide(sv)];
        }
    }

    /// Rows `first_row..first_row + out.len()` by `kernel`, which this CPU must run (the portable
    /// kernel for orders other than cubic).
    fn rows_by(
        &self,
        kernel: StencilKernel,
        frame: &ControlFrame,
        first_row: usize,
        out: &mut [Point3],
    ) {
        #[cfg(not(target_arch = "x86_64"))]
        let _ = kernel;
        debug_assert!(kernel.available());
        #[cfg(target_arch = "x86_64")]
        if self.order == 4 {
            match kernel {
                // SAFETY: the CPU runs `kernel` (the callers' choice: `StencilKernel::fastest`, or
                // asserted available).
                StencilKernel::Avx512 => {
                    let f = match (self.grids.disk == self.grids.square, frame.has_quads()) {
                        (true, true) => simd::cubic_rows_wide::<true, true>,
                        (true, false) => simd::cubic_rows_wide::<true, false>,
                        (false, true) => simd::cubic_rows_wide::<false, true>,
                        (false, false) => simd::cubic_rows_wide::<false, false>,
                    };
                    return unsafe { f(self, frame, first_row, out) };
                }
                // SAFETY: as above.
                StencilKernel::Avx => {
                    return unsafe { simd::cubic_rows(self, frame, first_row, out) };
                }
                StencilKernel::Portable => {}
            }
        }
        self.portable_rows(frame, first_row, out);
    }

    /// [`TensorStencil::positions`] by `kernel`, for tests and benches that compare the kernels.
    ///
    /// # Panics
    /// If this CPU does not run `kernel`.
    pub fn positions_by(&self, kernel: StencilKernel, control: &[Point3], out: &mut [Point3]) {
        assert!(kernel.available(), "{kernel:?} runs on this CPU");
        let frame = ControlFrame::new(control);
        frame.ready(kernel, self.rows());
        self.rows_by(kernel, &frame, 0, &mut out[..self.rows()]);
    }

    /// What [`TensorStencil::positions`] moves, without its arithmetic: each row's start, its
    /// blocks' indices and factors (one factor per block read, which touches each of the blocks'
    /// cache lines) and an f64 position written. For the `anchors` bench: the ceiling memory sets
    /// for this stencil's bytes on one core, against which the kernel's arithmetic is measured.
    #[doc(hidden)]
    pub fn stream_rows(&self, out: &mut [Point3]) {
        let width = 2 * self.order;
        for (o, span) in out.iter_mut().zip(self.row_starts.windows(2)) {
            let mut sum = 0.0f32;
            for k in span[0] as usize..span[1] as usize {
                prefetch(&self.factors, width * (k + PREFETCH_BLOCKS));
                sum += self.factors[width * k] + self.firsts[k] as f32;
            }
            *o = Point3::new(f64::from(sum), 0.0, 0.0);
        }
    }

    fn portable_rows(&self, frame: &ControlFrame, first_row: usize, out: &mut [Point3]) {
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
            let mut acc = Vec4::ZERO;
            for k in span[0] as usize..span[1] as usize {
                prefetch(&self.factors, 2 * O * (k + PREFETCH_BLOCKS));
                let factors = &self.factors[2 * O * k..2 * O * (k + 1)];
                let (u, v) = factors.split_at(O);
                let u: &[f32; O] = u.try_into().expect("order factors");
                let v: &[f32; O] = v.try_into().expect("order factors");
                let first = self.firsts[k] as usize;
                let grid = self.grids.stride(first);
                for (j, &vj) in v.iter().enumerate() {
                    let start = first + j * grid;
                    let line: &[Vec4; O] = frame.points[start..start + O]
                        .try_into()
                        .expect("a block line");
                    let mut s = Vec4::ZERO;
                    for (&ui, &c) in u.iter().zip(line) {
                        s += c * ui;
                    }
                    acc += s * vj;
                }
            }
            let d = Vector3::new(f64::from(acc.x), f64::from(acc.y), f64::from(acc.z));
            *o = frame.centre + d;
        }
    }
}

/// The cubic kernels: with 256-bit registers, two control points (x, y, z, 0) per register and
/// fused multiply-adds, about half the instructions of the portable kernel per block; with 512-bit
/// registers a whole line of a block, four control points, per register, half as many again.
#[cfg(target_arch = "x86_64")]
mod simd {
    use std::arch::x86_64::*;

    use super::{ControlFrame, PREFETCH_BLOCKS, PREFETCH_ROWS, Point3, TensorStencil, Vector3};

    /// Rows `first_row..first_row + out.len()` of a cubic (order 4) stencil.
    #[target_feature(enable = "avx,fma")]
    pub(super) fn cubic_rows(
        stencil: &TensorStencil,
        frame: &ControlFrame,
        first_row: usize,
        out: &mut [Point3],
    ) {
        let lines = Lines::new(stencil, frame);
        let rows = RowBlocks::<false>::new(stencil, first_row, out.len());
        for (o, (factors, firsts, _)) in out.iter_mut().zip(rows) {
            let mut acc = _mm_setzero_ps();
            for (f, &first) in factors.iter().zip(firsts) {
                ahead(f, 8 * PREFETCH_BLOCKS);
                acc = _mm_add_ps(acc, lines.block(f, first as usize));
            }
            *o = frame.centre + widen(acc);
        }
    }

    /// Asks the cache for the float `by` floats past `block`'s first.
    #[inline(always)]
    fn ahead(block: &[f32], by: usize) {
        // SAFETY: a prefetch is only a hint, and never faults, even past the end (the address is
        // only computed, never read).
        unsafe { _mm_prefetch::<_MM_HINT_T0>(block.as_ptr().wrapping_add(by).cast()) };
    }

    /// Asks the cache for the output `by` rows past `row`'s, to be written: a store must first read
    /// its cache line, and this has it read while the kernel works. (A plain prefetch: the
    /// prefetch-to-write instruction needs a target feature of its own.)
    #[inline(always)]
    fn ahead_of_store<T>(row: &T, by: usize) {
        // SAFETY: a prefetch is only a hint, and never faults, even past the end (the address is
        // only computed, never read).
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(row).wrapping_add(by).cast()) };
    }

    /// The control points as the cubic kernels read them: a block's 4 lines of 4 points each.
    struct Lines {
        points: *const f32,
        /// Control points below this are the disk charts', whose lines are `disk` apart.
        disk_points: usize,
        disk: usize,
        square: usize,
    }

    impl Lines {
        fn new(stencil: &TensorStencil, frame: &ControlFrame) -> Lines {
            let grids = stencil.grids;
            // Every block of a built stencil lies inside the layout's grids, so with this each
            // line's loads stay inside `frame.points`.
            assert!(
                frame.points.len() >= grids.count(),
                "a control point per grid point"
            );
            Lines {
                points: frame.points.as_ptr().cast(),
                disk_points: grids.disks * grids.disk * grids.disk,
                disk: grids.disk,
                square: grids.square,
            }
        }

        /// The 4 lines of the block whose first control point is `first`, each as points 0–1 and
        /// 2–3 of the line, (x, y, z, 0) twice per register. The lines are the chart's grid apart
        /// (`ControlGrids::stride`, its bound hoisted into `disk_points`).
        #[target_feature(enable = "avx")]
        #[inline]
        fn lines(&self, first: usize) -> [(__m256, __m256); 4] {
            let grid = self.stride(first);
            std::array::from_fn(|j| {
                // SAFETY: a block's lines lie inside the grids, which `frame.points` covers
                // (asserted in `new`): 16 contiguous f32 from `first + j·grid`, read as floats
                // 0–7 and 8–15.
                unsafe {
                    let p = self.points.add(4 * (first + j * grid));
                    (_mm256_loadu_ps(p), _mm256_loadu_ps(p.add(8)))
                }
            })
        }

        /// The chart's grid for a block starting at control point `first` (`ControlGrids::stride`,
        /// its bound hoisted into `disk_points`).
        #[inline]
        fn stride(&self, first: usize) -> usize {
            if first < self.disk_points {
                self.disk
            } else {
                self.square
            }
        }

        /// Σ_j β N_j(v) Σ_i N_i(u) c_ij of the cubic block with factors `f` whose first control
        /// point is `first`, as (x, y, z, 0). The sums run along v first: two control points per
        /// register, the lines' points times β N_j(v) accumulate by fused multiply-adds, and
        /// N_i(u) multiplies once at the end.
        #[target_feature(enable = "avx,fma")]
        #[inline]
        fn block(&self, f: &[f32; 8], first: usize) -> __m128 {
            let (mut c01, mut c23) = (_mm256_setzero_ps(), _mm256_setzero_ps());
            for ((p01, p23), &v) in self.lines(first).into_iter().zip(&f[4..]) {
                let v = _mm256_set1_ps(v);
                c01 = _mm256_fmadd_ps(p01, v, c01);
                c23 = _mm256_fmadd_ps(p23, v, c23);
            }
            let (u01, u23) = spread(f[..4].try_into().expect("4 factors"));
            let s = _mm256_fmadd_ps(c23, u23, _mm256_mul_ps(c01, u01));
            _mm_add_ps(_mm256_castps256_ps128(s), _mm256_extractf128_ps::<1>(s))
        }

        /// A cubic block's three sums for a row with tangents (see the module's comment), each
        /// still in two halves: A = Σ_j βN_j Σ_i N_i c_ij, B with N_i', C with βN_j'. Along v
        /// first, as in [`Lines::block`]: the lines' points times βN_j and βN_j' accumulate,
        /// then N_i and N_i' multiply once.
        #[target_feature(enable = "avx,fma")]
        #[inline]
        fn jet_block(&self, f: &[f32; 8], d: &[f32; 12], first: usize) -> [__m256; 3] {
            let zero = _mm256_setzero_ps();
            let (mut v01, mut v23, mut dv01, mut dv23) = (zero, zero, zero, zero);
            for (j, (p01, p23)) in self.lines(first).into_iter().enumerate() {
                let (v, dv) = (_mm256_set1_ps(f[4 + j]), _mm256_set1_ps(d[4 + j]));
                v01 = _mm256_fmadd_ps(p01, v, v01);
                v23 = _mm256_fmadd_ps(p23, v, v23);
                dv01 = _mm256_fmadd_ps(p01, dv, dv01);
                dv23 = _mm256_fmadd_ps(p23, dv, dv23);
            }
            let (u01, u23) = spread(f[..4].try_into().expect("4 factors"));
            let (du01, du23) = spread(d[..4].try_into().expect("4 factors"));
            [
                _mm256_fmadd_ps(v23, u23, _mm256_mul_ps(v01, u01)),
                _mm256_fmadd_ps(v23, du23, _mm256_mul_ps(v01, du01)),
                _mm256_fmadd_ps(dv23, u23, _mm256_mul_ps(dv01, u01)),
            ]
        }
    }

    /// [`cubic_rows`] with 512-bit registers: a block's line, its four control points, in one.
    /// The lanes of control point i hold N_i(u) Σ_j β N_j(v) c_ij and are summed over i once, at
    /// the row's end. `UNIFORM`: the disk and square charts' grids are the same size. `ALIGNED`:
    /// the lines are read from the frame's quads, which must be made.
    #[target_feature(enable = "avx512f,avx512vl,avx,fma")]
    pub(super) fn cubic_rows_wide<const UNIFORM: bool, const ALIGNED: bool>(
        stencil: &TensorStencil,
        frame: &ControlFrame,
        first_row: usize,
        out: &mut [Point3],
    ) {
        let lines = WideLines::<UNIFORM, ALIGNED>::new(stencil, frame);
        let centre = centre_of(frame);
        let rows = RowBlocks::<false>::new(stencil, first_row, out.len());
        for (o, (factors, firsts, _)) in out.iter_mut().zip(rows) {
            ahead_of_store(o, PREFETCH_ROWS);
            let mut acc = _mm512_setzero_ps();
            for (f, &first) in factors.iter().zip(firsts) {
                ahead(f, 8 * PREFETCH_BLOCKS);
                acc = lines.block(f, first as usize, acc);
            }
            store(&mut o.coords, quarters(acc), centre);
        }
    }

    /// [`cubic_jets`] with 512-bit registers, as [`cubic_rows_wide`].
    #[target_feature(enable = "avx512f,avx512vl,avx,fma")]
    pub(super) fn cubic_jets_wide<const UNIFORM: bool, const ALIGNED: bool>(
        stencil: &TensorStencil,
        frame: &ControlFrame,
        first_row: usize,
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        let lines = WideLines::<UNIFORM, ALIGNED>::new(stencil, frame);
        let rows = RowBlocks::<true>::new(stencil, first_row, positions.len());
        let centre = centre_of(frame);
        let zero = _mm256_setzero_pd();
        for ((o, t), (factors, firsts, derivatives)) in positions.iter_mut().zip(tangents).zip(rows)
        {
            ahead_of_store(o, PREFETCH_ROWS);
            ahead_of_store(t, PREFETCH_ROWS);
            let zero_sum = _mm512_setzero_ps();
            let (mut p, mut su, mut sv) = (zero_sum, zero_sum, zero_sum);
            for ((f, &first), d) in factors.iter().zip(firsts).zip(derivatives) {
                ahead(f, 8 * PREFETCH_BLOCKS);
                ahead(d, 12 * PREFETCH_BLOCKS);
                let [a, b, c] = lines.jet_block(f, d, first as usize);
                let (gu, gv) = (_mm512_set1_ps(d[8]), _mm512_set1_ps(d[9]));
                let (re, im) = (_mm512_set1_ps(d[10]), _mm512_set1_ps(d[11]));
                p = _mm512_add_ps(p, a);
                su = _mm512_fmadd_ps(a, gu, su);
                su = _mm512_fmadd_ps(b, re, su);
                su = _mm512_fmadd_ps(c, im, su);
                sv = _mm512_fmadd_ps(a, gv, sv);
                sv = _mm512_fnmadd_ps(b, im, sv);
                sv = _mm512_fmadd_ps(c, re, sv);
            }
            store(&mut o.coords, quarters(p), centre);
            let [tu, tv] = t;
            store(tu, quarters(su), zero);
            store(tv, quarters(sv), zero);
        }
    }

    /// A cubic stencil's blocks, a row at a time as slices, so the kernels' inner loops run over a
    /// row's own blocks with one counter: its factors, first control points and (with `TANGENTS`)
    /// tangent factors. (Taking each row's count from one iterator over all the blocks, zipped
    /// and prefetching, cost the AVX-512 kernel a tenth of its time in length checks per block;
    /// slicing each row with its bounds checked, another tenth.)
    struct RowBlocks<'a, const TANGENTS: bool> {
        starts: std::slice::Windows<'a, u32>,
        factors: &'a [[f32; 8]],
        firsts: &'a [u32],
        derivatives: &'a [[f32; 12]],
    }

    /// A row's blocks: factors, first control points, tangent factors (empty without tangents).
    type Row<'a> = (&'a [[f32; 8]], &'a [u32], &'a [[f32; 12]]);

    impl<'a, const TANGENTS: bool> RowBlocks<'a, TANGENTS> {
        /// The blocks of rows `first_row..first_row + rows` (the stencil must have tangents if
        /// `TANGENTS`).
        fn new(
            stencil: &'a TensorStencil,
            first_row: usize,
            rows: usize,
        ) -> RowBlocks<'a, TANGENTS> {
            let starts = &stencil.row_starts[first_row..=first_row + rows];
            let (factors, _) = stencil.factors.as_chunks::<8>();
            let (derivatives, _) = stencil.tangent_factors.as_chunks::<12>();
            let end = starts[rows] as usize;
            // With the starts ascending, what `next` relies on.
            assert!(end <= factors.len() && end <= stencil.firsts.len());
            assert!(!TANGENTS || end <= derivatives.len(), "tangent factors");
            RowBlocks {
                starts: starts.windows(2),
                factors,
                firsts: &stencil.firsts,
                derivatives,
            }
        }
    }

    impl<'a, const TANGENTS: bool> Iterator for RowBlocks<'a, TANGENTS> {
        type Item = Row<'a>;

        #[inline]
        fn next(&mut self) -> Option<Row<'a>> {
            let span = self.starts.next()?;
            let blocks = span[0] as usize..span[1] as usize;
            debug_assert!(blocks.start <= blocks.end);
            // SAFETY: the spans are the stencil's own row starts, which ascend
            // (`TensorStencil::row_starts`), and `new` checked that the last of these is within
            // the arrays (the tangent factors too where they are sliced).
            unsafe {
                Some((
                    self.factors.get_unchecked(blocks.clone()),
                    self.firsts.get_unchecked(blocks.clone()),
                    if TANGENTS {
                        self.derivatives.get_unchecked(blocks)
                    } else {
                        &[]
                    },
                ))
            }
        }
    }

    /// The control points as the 512-bit kernels read them: a block's line, four control points,
    /// in one register. With `ALIGNED` a line is one aligned [`Quad`](super::Quad) of the frame's
    /// (which must be made), else the same 16 floats read in place from its points. The lines are
    /// the chart's grid apart (with `UNIFORM`, every chart's).
    struct WideLines<const UNIFORM: bool, const ALIGNED: bool> {
        floats: *const f32,
        /// Control points below this are the disk charts', whose lines are `disk` apart.
        disk_points: usize,
        disk: usize,
        square: usize,
    }

    impl<const UNIFORM: bool, const ALIGNED: bool> WideLines<UNIFORM, ALIGNED> {
        fn new(stencil: &TensorStencil, frame: &ControlFrame) -> WideLines<UNIFORM, ALIGNED> {
            let grids = stencil.grids;
            // Every block of a built stencil lies inside the layout's grids, so with this each
            // line's load stays inside the quads (one per control point) or the points (a line's
            // last point is a grid point).
            let (floats, len) = if ALIGNED {
                let quads = frame.quads.get().expect("the frame's quads are made");
                (quads.as_ptr().cast(), quads.len())
            } else {
                (frame.points.as_ptr().cast(), frame.points.len())
            };
            assert!(len >= grids.count(), "a control point per grid point");
            assert!(!UNIFORM || grids.disk == grids.square, "one grid size");
            WideLines {
                floats,
                disk_points: grids.disks * grids.disk * grids.disk,
                disk: grids.disk,
                square: grids.square,
            }
        }

        /// The 4 lines of the block whose first control point is `first`, a line's four points
        /// (x, y, z, 0) per register.
        #[target_feature(enable = "avx512f")]
        #[inline]
        fn lines(&self, first: usize) -> [__m512; 4] {
            let grid = if UNIFORM || first >= self.disk_points {
                self.square
            } else {
                self.disk
            };
            std::array::from_fn(|j| {
                let start = first + j * grid;
                // SAFETY: a block's lines start at grid points, each with its quad, and end at
                // grid points (asserted in `new`); a quad is 64-byte aligned (`Quad`'s alignment).
                unsafe {
                    if ALIGNED {
                        _mm512_load_ps(self.floats.add(16 * start))
                    } else {
                        _mm512_loadu_ps(self.floats.add(4 * start))
                    }
                }
            })
        }

        /// `acc` plus the cubic block with factors `f` whose first control point is `first`,
        /// the lanes of control point i holding N_i(u) Σ_j β N_j(v) c_ij. The lines' products
        /// run in two chains of two, so they do not wait on one another.
        #[target_feature(enable = "avx512f,avx,fma")]
        #[inline]
        fn block(&self, f: &[f32; 8], first: usize, acc: __m512) -> __m512 {
            let [l0, l1, l2, l3] = self.lines(first);
            let v = |j: usize| _mm512_set1_ps(f[4 + j]);
            let even = _mm512_fmadd_ps(l2, v(2), _mm512_mul_ps(l0, v(0)));
            let odd = _mm512_fmadd_ps(l3, v(3), _mm512_mul_ps(l1, v(1)));
            let u = spread_wide(f[..4].try_into().expect("4 factors"));
            _mm512_fmadd_ps(_mm512_add_ps(even, odd), u, acc)
        }

        /// [`Lines::jet_block`]'s three sums with 512-bit registers, control point i's terms in
        /// its lanes, to be summed at the row's end.
        #[target_feature(enable = "avx512f,avx,fma")]
        #[inline]
        fn jet_block(&self, f: &[f32; 8], d: &[f32; 12], first: usize) -> [__m512; 3] {
            let (mut v, mut dv) = (_mm512_setzero_ps(), _mm512_setzero_ps());
            for (j, line) in self.lines(first).into_iter().enumerate() {
                v = _mm512_fmadd_ps(line, _mm512_set1_ps(f[4 + j]), v);
                dv = _mm512_fmadd_ps(line, _mm512_set1_ps(d[4 + j]), dv);
            }
            let u = spread_wide(f[..4].try_into().expect("4 factors"));
            let du = spread_wide(d[..4].try_into().expect("4 factors"));
            [
                _mm512_mul_ps(v, u),
                _mm512_mul_ps(v, du),
                _mm512_mul_ps(dv, u),
            ]
        }
    }

    /// The frame's centre as (x, y, z, 0) in f64.
    #[target_feature(enable = "avx")]
    #[inline]
    fn centre_of(frame: &ControlFrame) -> __m256d {
        let c = frame.centre;
        _mm256_setr_pd(c.x, c.y, c.z, 0.0)
    }

    /// `*out = offset + sum`, sum's (x, y, z) widened to f64: one conversion, one add and one
    /// masked store of three lanes.
    #[target_feature(enable = "avx512f,avx512vl,avx")]
    #[inline]
    fn store(out: &mut Vector3, sum: __m128, offset: __m256d) {
        let v = _mm256_add_pd(_mm256_cvtps_pd(sum), offset);
        // SAFETY: `out` is three contiguous f64 (nalgebra's column-major storage), the lanes the
        // mask writes.
        unsafe { _mm256_mask_storeu_pd(std::ptr::from_mut(out).cast(), 0b0111, v) };
    }

    /// Positions and tangents of rows `first_row..first_row + positions.len()` of a cubic stencil
    /// built with tangents: the portable tangent kernel's sums, two control points per 256-bit
    /// register, along v first as in [`cubic_rows`]. Every step after the first products is
    /// linear with the same factor in both halves, so the halves are added only at the row's end.
    #[target_feature(enable = "avx,fma")]
    pub(super) fn cubic_jets(
        stencil: &TensorStencil,
        frame: &ControlFrame,
        first_row: usize,
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) {
        let lines = Lines::new(stencil, frame);
        let rows = RowBlocks::<true>::new(stencil, first_row, positions.len());
        for ((o, t), (factors, firsts, derivatives)) in positions.iter_mut().zip(tangents).zip(rows)
        {
            let (mut p, mut su, mut sv) = (
                _mm256_setzero_ps(),
                _mm256_setzero_ps(),
                _mm256_setzero_ps(),
            );
            for ((f, &first), d) in factors.iter().zip(firsts).zip(derivatives) {
                ahead(f, 8 * PREFETCH_BLOCKS);
                ahead(d, 12 * PREFETCH_BLOCKS);
                let [a, b, c] = lines.jet_block(f, d, first as usize);
                let (gu, gv) = (_mm256_set1_ps(d[8]), _mm256_set1_ps(d[9]));
                let (re, im) = (_mm256_set1_ps(d[10]), _mm256_set1_ps(d[11]));
                p = _mm256_add_ps(p, a);
                su = _mm256_fmadd_ps(a, gu, su);
                su = _mm256_fmadd_ps(b, re, su);
                su = _mm256_fmadd_ps(c, im, su);
                sv = _mm256_fmadd_ps(a, gv, sv);
                sv = _mm256_fnmadd_ps(b, im, sv);
                sv = _mm256_fmadd_ps(c, re, sv);
            }
            let wide = |v: __m256| {
                widen(_mm_add_ps(
                    _mm256_castps256_ps128(v),
                    _mm256_extractf128_ps::<1>(v),
                ))
            };
            *o = frame.centre + wide(p);
            *t = [wide(su), wide(sv)];
        }
    }

    /// Spreads (u₀, u₁, u₂, u₃) into (u₀ ×4, u₁ ×4, u₂ ×4, u₃ ×4): each control point's factor
    /// across its lanes of a line.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn spread_wide(u: &[f32; 4]) -> __m512 {
        // SAFETY: `u` holds the 4 floats read.
        let u = _mm512_castps128_ps512(unsafe { _mm_loadu_ps(u.as_ptr()) });
        _mm512_permutexvar_ps(
            _mm512_set_epi32(3, 3, 3, 3, 2, 2, 2, 2, 1, 1, 1, 1, 0, 0, 0, 0),
            u,
        )
    }

    /// The sum of a 512-bit register's four lane groups (x, y, z, 0).
    #[target_feature(enable = "avx512f,avx")]
    #[inline]
    fn quarters(v: __m512) -> __m128 {
        let high = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v)));
        let half = _mm256_add_ps(_mm512_castps512_ps256(v), high);
        _mm_add_ps(
            _mm256_castps256_ps128(half),
            _mm256_extractf128_ps::<1>(half),
        )
    }

    /// (x, y, z, 0) as an f64 vector.
    #[target_feature(enable = "avx")]
    #[inline]
    fn widen(v: __m128) -> Vector3 {
        let mut lanes = [0f32; 4];
        // SAFETY: `lanes` holds the 4 floats stored.
        unsafe { _mm_storeu_ps(lanes.as_mut_ptr(), v) };
        let [x, y, z, _] = lanes.map(f64::from);
        Vector3::new(x, y, z)
    }

    /// Spreads (u₀, u₁, u₂, u₃) into (u₀ ×4, u₁ ×4) and (u₂ ×4, u₃ ×4): each control point's
    /// factor in a register that holds two of them.
    #[target_feature(enable = "avx")]
    #[inline]
    fn spread(u: &[f32; 4]) -> (__m256, __m256) {
        // SAFETY: `u` holds the 4 floats read.
        let u = _mm256_broadcast_ps(unsafe { &*u.as_ptr().cast::<__m128>() });
        (
            _mm256_permutevar_ps(u, _mm256_set_epi32(1, 1, 1, 1, 0, 0, 0, 0)),
            _mm256_permutevar_ps(u, _mm256_set_epi32(3, 3, 3, 3, 2, 2, 2, 2)),
        )
    }
}

/// Asks the cache for `data[at]` (nothing where it is out of range, or off x86-64).
#[inline(always)]
fn prefetch(data: &[f32], at: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(x) = data.get(at) {
        // SAFETY: a prefetch is only a hint; the address is of a live element.
        unsafe {
            std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                std::ptr::from_ref(x).cast(),
            )
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (data, at);
}

impl Part {
    /// Rows for `points`; with `tangents`, the derivatives' factors too.
    fn build(layout: &Layout, points: &[ChartPoint], tangents: bool) -> Part {
        let order = layout.settings().degree + 1;
        let mut part = Part {
            blocks_per_row: Vec::with_capacity(points.len()),
            firsts: Vec::with_capacity(3 * points.len()),
            factors: Vec::with_capacity(6 * order * points.len()),
            tangent_factors: Vec::new(),
        };
        let mut blends = Vec::with_capacity(16);
        let mut reps = Vec::with_capacity(16);
        let mut transitions = Vec::with_capacity(16);
        for &p in points {
            if tangents {
                layout
                    .atlas()
                    .locate_with_transitions_into(p, &mut transitions);
                blend_jets(layout, p, &transitions, &mut blends);
            } else {
                layout.atlas().locate_into(p, &mut reps);
                blend_values(layout, &reps, &mut blends);
            }
            keep_counting_blends(&mut blends);
            for b in &blends {
                part.push_block(layout, b, tangents);
            }
            part.blocks_per_row.push(blends.len() as u32);
        }
        part
    }

    /// One chart's block: its first control point, its factors, and with `tangents` theirs.
    fn push_block(&mut self, layout: &Layout, b: &Blend, tangents: bool) {
        let order = layout.settings().degree + 1;
        let basis = layout.basis(b.rep.chart);
        let w = b.rep.coords;
        let beta = b.jet.val;
        if tangents {
            let (fu, nu) = basis.eval(w.re, 1);
            let (fv, nv) = basis.eval(w.im, 1);
            self.firsts
                .push(layout.control_index(b.rep.chart, fu, fv) as u32);
            self.factors
                .extend(nu[0][..order].iter().map(|&x| x as f32));
            self.factors
                .extend(nv[0][..order].iter().map(|&y| (beta * y) as f32));
            let d = &mut self.tangent_factors;
            d.extend(nu[1][..order].iter().map(|&x| x as f32));
            d.extend(nv[1][..order].iter().map(|&y| (beta * y) as f32));
            let chain = [b.jet.du / beta, b.jet.dv / beta, b.psi.re, b.psi.im];
            d.extend(chain.map(|x| x as f32));
        } else {
            let (fu, nu) = basis.values(w.re);
            let (fv, nv) = basis.values(w.im);
            self.firsts
                .push(layout.control_index(b.rep.chart, fu, fv) as u32);
            self.factors.extend(nu[..order].iter().map(|&x| x as f32));
            self.factors
                .extend(nv[..order].iter().map(|&y| (beta * y) as f32));
        }
    }
}

/// One chart's share of a row while building: the point in that chart, its blend (value and,
/// when tangents are wanted, first derivatives in the row's chart) and the transition's ψ'.
pub(super) struct Blend {
    pub(super) rep: ChartPoint,
    pub(super) jet: Jet,
    pub(super) psi: Complex64,
}

/// The raw blend value of each representation (no derivatives).
fn blend_values(layout: &Layout, reps: &[ChartPoint], out: &mut Vec<Blend>) {
    let charts = layout.atlas().charts();
    out.clear();
    out.extend(reps.iter().map(|&rep| {
        let domain = charts[rep.chart.index()].domain();
        let val = layout.raw_blend_value(domain, rep.coords);
        Blend {
            rep,
            jet: Jet {
                val,
                ..Jet::default()
            },
            psi: Complex64::ONE,
        }
    }));
}

/// The raw blend of each representation with its first derivatives in `p`'s chart, and ψ'.
pub(super) fn blend_jets(
    layout: &Layout,
    p: ChartPoint,
    reps: &[(ChartPoint, charts::Lft)],
    out: &mut Vec<Blend>,
) {
    let charts = layout.atlas().charts();
    out.clear();
    out.extend(reps.iter().map(|&(rep, lft)| {
        let domain = charts[rep.chart.index()].domain();
        let (psi, psi2) = derivatives(&lft, p.coords);
        let jet = layout.raw_blend(domain, rep.coords).through(psi, psi2);
        Blend { rep, jet, psi }
    }));
}

/// Leaves out the charts whose share is below [`NEGLIGIBLE_BLEND`] and normalises the others
/// (value and first derivatives, by the quotient rule) to sum to one.
fn keep_counting_blends(blends: &mut Vec<Blend>) {
    let total: f64 = blends.iter().map(|b| b.jet.val).sum();
    // With tangents the blend's gradient must be negligible too (per unit of the chart's
    // coordinates, about a chart's width): near the edge of a C¹ blend's support β ~ t² while
    // β' ~ 2t, so a share of 1e-7 can still turn the tangents by 1e-5.
    blends.retain(|b| {
        let largest = b.jet.val.max(b.jet.du.abs()).max(b.jet.dv.abs());
        largest >= NEGLIGIBLE_BLEND * total
    });
    normalise_blends(blends);
}

/// Divides each blend by their sum (value and first derivatives, by the quotient rule), so they
/// sum to one; second derivatives are dropped.
pub(super) fn normalise_blends(blends: &mut [Blend]) {
    let (kept, du, dv) = blends.iter().fold((0.0, 0.0, 0.0), |(s, u, v), b| {
        (s + b.jet.val, u + b.jet.du, v + b.jet.dv)
    });
    for b in blends.iter_mut() {
        let q = b.jet.val / kept;
        b.jet = Jet {
            val: q,
            du: (b.jet.du - q * du) / kept,
            dv: (b.jet.dv - q * dv) / kept,
            ..Jet::default()
        };
    }
}

/// The control points as f32 lanes (x, y, z, 0) about the centre of their bounding box: what the
/// tensor stencil is applied to, here or on a GPU.
pub struct ControlFrame {
    pub centre: Point3,
    /// 16-byte SIMD lanes (glam's `Vec4`), so a line of a block is a few aligned vector loads.
    pub points: Vec<Vec4>,
    /// [`ControlFrame::quads`], made when first asked for.
    quads: OnceLock<Vec<Quad>>,
}

/// Four consecutive control points on a 64-byte boundary of their own: a cubic block's line, where
/// the first is a line's start, in one aligned 512-bit load. A cubic block's line read straight from
/// [`ControlFrame::points`] starts on a 16-byte boundary and so straddles two cache lines three
/// times in four, which cost the AVX-512 kernel about a tenth of its time.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct Quad(pub [Vec4; 4]);

// The AVX-512 kernels step through quads as 512-bit registers.
const _: () = assert!(align_of::<Quad>() == 64 && size_of::<Quad>() == 64);

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
                Vec4::new(d.x as f32, d.y as f32, d.z as f32, 0.0)
            })
            .collect();
        ControlFrame {
            centre,
            points,
            quads: OnceLock::new(),
        }
    }

    /// Per control point p, points p to p + 3 (zero past the last): four times the points' memory,
    /// made once per frame, on one thread, in time proportional to the control points (a few µs
    /// at genus 2's 6 144; re-embedding 10⁴ rows takes 36 µs).
    pub(crate) fn quads(&self) -> &[Quad] {
        self.quads.get_or_init(|| {
            let at = |p: usize| self.points.get(p).copied().unwrap_or(Vec4::ZERO);
            (0..self.points.len())
                .map(|p| Quad(std::array::from_fn(|k| at(p + k))))
                .collect()
        })
    }

    /// Whether [`ControlFrame::quads`] are made.
    fn has_quads(&self) -> bool {
        self.quads.get().is_some()
    }

    /// Makes [`ControlFrame::quads`] for a call of `rows` rows by `kernel` where they pay: the
    /// AVX-512 kernels read their lines from the quads where these are made, else from the
    /// points in place, with the same numbers. The copy costs about what re-embedding as many
    /// rows as control points does, so only calls with at least that many rows make it (not an
    /// edit's few rows, for each dab); it is made here, before the rows are split over cores.
    /// Returns `kernel`.
    fn ready(&self, kernel: StencilKernel, rows: usize) -> StencilKernel {
        if kernel == StencilKernel::Avx512 && rows >= self.points.len() {
            self.quads();
        }
        kernel
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::SplineSettings;

    /// A call of fewer rows than control points makes no aligned copy of the points, one of as
    /// many makes it (for AVX-512 only), and the AVX-512 kernels give the same bits reading the
    /// points in place as reading the copy, positions and tangents, equal grids or not.
    #[test]
    fn the_aligned_copy_is_made_for_long_calls_and_changes_no_bit() {
        let control: Vec<Point3> = (0..100).map(|i| Point3::new(i as f64, 1.0, 2.0)).collect();
        let frame = ControlFrame::new(&control);
        for kernel in [StencilKernel::Portable, StencilKernel::Avx] {
            frame.ready(kernel, 1000);
            assert!(!frame.has_quads(), "{kernel:?} needs no copy");
        }
        frame.ready(StencilKernel::Avx512, 99);
        assert!(!frame.has_quads(), "no copy for 99 rows");
        frame.ready(StencilKernel::Avx512, 100);
        assert!(frame.has_quads(), "the copy made for 100 rows");
        if !StencilKernel::Avx512.available() {
            return;
        }
        for (settings, stencil, control) in stencils_on_both_grids(3, 5, 4) {
            let n = stencil.rows();
            let run = |frame: &ControlFrame| {
                let mut out = (vec![Point3::origin(); n], vec![[Vector3::zeros(); 2]; n]);
                let mut alone = vec![Point3::origin(); n];
                stencil.frames_by(StencilKernel::Avx512, frame, 0, &mut out.0, &mut out.1);
                stencil.rows_by(StencilKernel::Avx512, frame, 0, &mut alone);
                (alone, out)
            };
            let (in_place, copied) = (ControlFrame::new(&control), ControlFrame::new(&control));
            copied.quads();
            assert_eq!(run(&in_place), run(&copied), "{settings:?}");
            assert!(!in_place.has_quads(), "read in place");
        }
    }

    /// For the default grids and for disk grids larger than the squares' by an odd number (the
    /// AVX-512 kernels' two stride paths): a genus-`genus` stencil with tangents on the
    /// `te` × `tr` tessellation, and control points that vary smoothly.
    fn stencils_on_both_grids(
        genus: u32,
        te: u32,
        tr: u32,
    ) -> Vec<(SplineSettings, TensorStencil, Vec<Point3>)> {
        let atlas = charts::Atlas::new(genus).unwrap();
        let points = atlas.tessellate(te, tr).unwrap().vertices;
        let unequal = SplineSettings {
            grid: 14,
            disk_grid: Some(23),
            ..SplineSettings::default()
        };
        [SplineSettings::default(), unequal]
            .into_iter()
            .map(|settings| {
                let layout = Layout::new(&atlas, settings).unwrap();
                let control = (0..layout.control_count())
                    .map(|i| {
                        let i = i as f64;
                        Point3::new((i * 0.37).sin(), (i * 0.71).cos(), (i * 0.13).sin())
                    })
                    .collect();
                let stencil = TensorStencil::build_with_tangents(&layout, &points);
                (settings, stencil, control)
            })
            .collect()
    }

    /// A frame's quads are its points p to p + 3 for every p, zero past the last, each on a cache
    /// line of its own; made once.
    #[test]
    fn quads_hold_four_points_from_each() {
        let control: Vec<Point3> = (0..11)
            .map(|i| Point3::new(i as f64, -2.0 * i as f64, 0.5))
            .collect();
        let frame = ControlFrame::new(&control);
        let quads = frame.quads();
        assert_eq!(quads.len(), control.len());
        for (p, quad) in quads.iter().enumerate() {
            assert_eq!(std::ptr::from_ref(quad).addr() % 64, 0, "quad {p} aligned");
            for (k, point) in quad.0.iter().enumerate() {
                let want = frame.points.get(p + k).copied().unwrap_or(Vec4::ZERO);
                assert_eq!(*point, want, "quad {p}, point {k}");
            }
        }
        assert!(std::ptr::eq(quads, frame.quads()), "made once");
    }

    /// A parallel task starts at some row r > 0: every kernel this CPU runs gives rows r.. the
    /// same bits whether they start the call or follow row r − 1 in it, positions and tangents,
    /// and an empty range writes nothing.
    #[test]
    fn every_kernel_starts_at_any_row() {
        for (settings, stencil, control) in stencils_on_both_grids(2, 6, 5) {
            let frame = ControlFrame::new(&control);
            let n = stencil.rows();
            let kernels = StencilKernel::ALL.into_iter().filter(|k| k.available());
            for kernel in kernels {
                let mut whole = vec![Point3::origin(); n];
                stencil.rows_by(kernel, &frame, 0, &mut whole);
                let mut framed = (whole.clone(), vec![[Vector3::zeros(); 2]; n]);
                stencil.frames_by(kernel, &frame, 0, &mut framed.0, &mut framed.1);
                for first in [1, 2, 7, n / 3, n - 1, n] {
                    let at = format!("{kernel:?} from row {first}, {settings:?}");
                    let mut part = vec![Point3::origin(); n - first];
                    stencil.rows_by(kernel, &frame, first, &mut part);
                    assert_eq!(part, whole[first..], "{at}");
                    let mut tangents = vec![[Vector3::zeros(); 2]; n - first];
                    stencil.frames_by(kernel, &frame, first, &mut part, &mut tangents);
                    assert_eq!(part, framed.0[first..], "{at}");
                    assert_eq!(tangents, framed.1[first..], "{at}");
                }
            }
        }
    }
}
