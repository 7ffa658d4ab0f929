//! Stencils: for a fixed set of surface points (a tessellation's vertices), the sparse weights with
//! positions = W · control points, and the same for the first derivatives that normals need.
//!
//! [`Stencil`] holds every weight, with its derivatives, in f64: the editor's column updates and
//! normals use it. [`TensorStencil`] holds the same weights factored chart by chart, in far fewer
//! bytes: positions, and optionally what the first derivatives need; full re-embedding streams it.
//!
//! Stored as compressed rows with the weights in separate arrays (structure of arrays), because the
//! re-embedding loop streams them: a position touches 4 + 8 bytes per weight. A column index (which
//! rows each control point touches) makes a change to a few control points a sparse update.

mod tensor;

pub use tensor::{
    ControlFrame, Followed, NEGLIGIBLE_BLEND, StencilKernel, TensorStencil, tangent_words,
};

use charts::ChartPoint;

use crate::surface::{ControlGrids, Layout, Point3, Vector3};

/// Sparse weights, one row per surface point.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stencil {
    offsets: Vec<usize>,
    controls: Vec<u32>,
    pos: Vec<f64>,
    du: Vec<f64>,
    dv: Vec<f64>,
}

/// For each control point, the (row, entry) pairs of the stencil that use it.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnIndex {
    offsets: Vec<usize>,
    rows: Vec<u32>,
    /// Where in the stencil's weight arrays each pair's weight is (u32: half the bytes of the
    /// largest array an edit streams; 2³² weights would be a stencil of 10¹¹ bytes).
    entries: Vec<u32>,
}

impl Stencil {
    /// The stencil of `points` (each a point of its own chart), on one thread.
    ///
    /// Row by row: the point is located in every chart that holds it, the blends are normalised
    /// with their first derivatives in the row's chart, and each chart's (p + 1)² weights are
    /// β̂·N_i(u)N_j(v) with their gradients, the basis' gradient taken through the transition's
    /// derivative ψ'. The same weights as [`Layout::weights`] (to rounding) without the second
    /// derivatives, which no stencil stores: a third of the work.
    pub fn build(layout: &Layout, points: &[ChartPoint]) -> Stencil {
        let mut s = Stencil::sized(layout, points, false);
        let (offsets, mut rows) = s.rows_mut();
        rows.fill(layout, points, offsets);
        s
    }

    /// [`Stencil::build`] on all cores, bit for bit the same stencil: tasks over ranges of
    /// points, each writing its rows in place.
    pub fn build_parallel(layout: &Layout, points: &[ChartPoint]) -> Stencil {
        use rayon::prelude::*;
        let n = points.len();
        let Some(per_task) = rows_per_task(n, ROWS_PER_TASK, BUILD_NS) else {
            return Stencil::build(layout, points);
        };
        let mut s = Stencil::sized(layout, points, true);
        let (offsets, mut rest) = s.rows_mut();
        let mut tasks = Vec::with_capacity(n.div_ceil(per_task));
        for start in (0..n).step_by(per_task) {
            let end = (start + per_task).min(n);
            let tail = rest.split_off(offsets[end] - offsets[start]);
            let rows = std::mem::replace(&mut rest, tail);
            tasks.push((rows, &offsets[start..=end], &points[start..end]));
        }
        tasks
            .into_par_iter()
            .for_each(|(mut rows, offsets, points)| rows.fill(layout, points, offsets));
        s
    }

    /// A stencil for `points` with its row offsets set and its weights zero, to be filled: the
    /// first pass only locates each point (how many charts hold it), so the weights are written
    /// once, in place (an array grown and then joined is written twice, and at 10⁶ points its
    /// first touch costs as much as the arithmetic).
    fn sized(layout: &Layout, points: &[ChartPoint], parallel: bool) -> Stencil {
        use rayon::prelude::*;
        let order = layout.settings().degree + 1;
        let count = |points: &[ChartPoint], out: &mut [usize]| {
            let mut reps = Vec::with_capacity(16);
            for (p, o) in points.iter().zip(out) {
                layout.atlas().locate_into(*p, &mut reps);
                *o = reps.len() * order * order;
            }
        };
        let mut offsets = vec![0; points.len() + 1];
        let split = rows_per_task(points.len(), ROWS_PER_TASK, LOCATE_NS).filter(|_| parallel);
        if let Some(per_task) = split {
            offsets[1..]
                .par_chunks_mut(per_task)
                .zip(points.par_chunks(per_task))
                .for_each(|(out, points)| count(points, out));
        } else {
            count(points, &mut offsets[1..]);
        }
        for r in 0..points.len() {
            offsets[r + 1] += offsets[r];
        }
        let total = offsets[points.len()];
        Stencil {
            offsets,
            controls: vec![0; total],
            pos: vec![0.0; total],
            du: vec![0.0; total],
            dv: vec![0.0; total],
        }
    }

    /// The row offsets, and the weights as one writable range.
    fn rows_mut(&mut self) -> (&[usize], RowsMut<'_>) {
        let rows = RowsMut {
            controls: &mut self.controls,
            pos: &mut self.pos,
            du: &mut self.du,
            dv: &mut self.dv,
        };
        (&self.offsets, rows)
    }

    pub fn rows(&self) -> usize {
        self.offsets.len() - 1
    }
    /// Stored weights (per array).
    pub fn nonzeros(&self) -> usize {
        self.controls.len()
    }

    /// positions = W · control.
    pub fn positions(&self, control: &[Point3], out: &mut [Point3]) {
        for (r, o) in out.iter_mut().enumerate().take(self.rows()) {
            *o = self.position(control, r);
        }
    }

    /// Row r of W · control.
    #[inline]
    pub fn position(&self, control: &[Point3], r: usize) -> Point3 {
        // The weights of a row sum to one: an affine combination, accumulated from the origin.
        let mut acc = Vector3::zeros();
        for k in self.offsets[r]..self.offsets[r + 1] {
            acc += control[self.controls[k] as usize].coords * self.pos[k];
        }
        Point3::from(acc)
    }

    /// Row r of W, W_u and W_v times `control` in one pass: the position and the first derivatives
    /// S_u, S_v (in the row's own chart) of one surface point.
    #[inline]
    pub fn position_and_tangents(&self, control: &[Point3], r: usize) -> (Point3, [Vector3; 2]) {
        let (mut p, mut a, mut b) = (Vector3::zeros(), Vector3::zeros(), Vector3::zeros());
        for k in self.offsets[r]..self.offsets[r + 1] {
            let c = control[self.controls[k] as usize].coords;
            p += c * self.pos[k];
            a += c * self.du[k];
            b += c * self.dv[k];
        }
        (Point3::from(p), [a, b])
    }

    /// Row r's weights: each control point it uses with its weight and the weight's u and v
    /// derivatives.
    pub fn row(&self, r: usize) -> impl ExactSizeIterator<Item = (u32, [f64; 3])> + '_ {
        (self.offsets[r]..self.offsets[r + 1])
            .map(move |k| (self.controls[k], [self.pos[k], self.du[k], self.dv[k]]))
    }

    /// Column `control` of W, W_u and W_v: each row that uses the control point, with the weight and
    /// the weight's u and v derivatives.
    pub fn column<'a>(
        &'a self,
        index: &'a ColumnIndex,
        control: usize,
    ) -> impl Iterator<Item = (u32, [f64; 3])> + 'a {
        (index.offsets[control]..index.offsets[control + 1]).map(move |k| {
            let e = index.entries[k] as usize;
            (index.rows[k], [self.pos[e], self.du[e], self.dv[e]])
        })
    }

    /// The rows that control point `control` touches.
    pub fn rows_of<'a>(&self, index: &'a ColumnIndex, control: usize) -> &'a [u32] {
        &index.rows[index.offsets[control]..index.offsets[control + 1]]
    }

    /// The rows that any of `controls` touches, in increasing order: a bit per row set from their
    /// columns and read out in order (the columns of a wide edit list millions of entries; no
    /// sort).
    pub fn rows_of_controls(
        &self,
        index: &ColumnIndex,
        controls: impl IntoIterator<Item = usize>,
    ) -> Vec<u32> {
        let mut marks = vec![0u64; self.rows().div_ceil(64)];
        for c in controls {
            for &r in self.rows_of(index, c) {
                marks[r as usize / 64] |= 1u64 << (r % 64);
            }
        }
        set_bits(&marks)
    }

    /// S_u and S_v (in each point's own chart) = W_u · control, W_v · control.
    pub fn derivatives(&self, control: &[Point3], du: &mut [Vector3], dv: &mut [Vector3]) {
        for r in 0..self.rows() {
            let (mut a, mut b) = (Vector3::zeros(), Vector3::zeros());
            for k in self.offsets[r]..self.offsets[r + 1] {
                let c = control[self.controls[k] as usize].coords;
                a += c * self.du[k];
                b += c * self.dv[k];
            }
            du[r] = a;
            dv[r] = b;
        }
    }

    /// Unit normals S_u × S_v / |S_u × S_v|.
    pub fn normals(&self, control: &[Point3], out: &mut [Vector3]) {
        let mut du = vec![Vector3::zeros(); self.rows()];
        let mut dv = vec![Vector3::zeros(); self.rows()];
        self.derivatives(control, &mut du, &mut dv);
        for (o, (a, b)) in out.iter_mut().zip(du.iter().zip(&dv)) {
            *o = a.cross(b).normalize();
        }
    }

    /// Which rows each of `control_count` control points touches: for each control point, its
    /// (row, entry) pairs in row order. On all cores where the stencil is large (a 10⁶-vertex
    /// editor mesh has 3·10⁷ weights), the same index as on one thread.
    ///
    /// A counting sort: the weights per control point give each its range; then the control points
    /// are split into as many ranges as tasks, each holding about as many weights, and each task
    /// scans every row and writes the pairs of its own control points only. Its output is one
    /// contiguous slice, so the tasks need no shared writes; each reads all the control indices
    /// (4 bytes a weight, streamed), which costs far less than the scattered writes it shares out.
    pub fn column_index(&self, control_count: usize) -> ColumnIndex {
        use rayon::prelude::*;
        let mut offsets = vec![0usize; control_count + 1];
        for &c in &self.controls {
            offsets[c as usize + 1] += 1;
        }
        for i in 0..control_count {
            offsets[i + 1] += offsets[i];
        }
        let weights = self.controls.len();
        u32::try_from(weights).expect("fewer than 2³² stencil weights");
        let mut rows = vec![0u32; weights];
        let mut entries = vec![0u32; weights];
        let tasks = match rows_per_task(weights, usize::MAX, INDEX_NS_PER_WEIGHT) {
            Some(_) => rayon::current_num_threads(),
            None => 1,
        };
        // Control point ranges of about equal weight, and each range's slices of the output.
        let mut bounds = vec![0usize];
        for t in 1..tasks {
            let c = offsets
                .partition_point(|&o| o < t * weights / tasks)
                .min(control_count);
            bounds.push(c.max(*bounds.last().unwrap_or(&0)));
        }
        bounds.push(control_count);
        let mut parts = Vec::with_capacity(tasks);
        let (mut rows_rest, mut entries_rest) = (&mut rows[..], &mut entries[..]);
        for w in bounds.windows(2) {
            let len = offsets[w[1]] - offsets[w[0]];
            let (r, r_rest) = std::mem::take(&mut rows_rest).split_at_mut(len);
            let (e, e_rest) = std::mem::take(&mut entries_rest).split_at_mut(len);
            (rows_rest, entries_rest) = (r_rest, e_rest);
            parts.push((w[0]..w[1], r, e));
        }
        parts.into_par_iter().for_each(|(range, rows, entries)| {
            let base = offsets[range.start];
            let mut fill: Vec<usize> = offsets[range.clone()].iter().map(|o| o - base).collect();
            for r in 0..self.rows() {
                for k in self.offsets[r]..self.offsets[r + 1] {
                    let c = self.controls[k] as usize;
                    if range.contains(&c) {
                        let at = &mut fill[c - range.start];
                        rows[*at] = r as u32;
                        entries[*at] = k as u32;
                        *at += 1;
                    }
                }
            }
        });
        ColumnIndex {
            offsets,
            rows,
            entries,
        }
    }

    /// After control point `control` moved by `delta`: updates only the positions it touches.
    pub fn update(
        &self,
        index: &ColumnIndex,
        control: usize,
        delta: Vector3,
        positions: &mut [Point3],
    ) {
        for k in index.offsets[control]..index.offsets[control + 1] {
            positions[index.rows[k] as usize] += delta * self.pos[index.entries[k] as usize];
        }
    }
}

/// Sets, in `bits` (a bit per control point), the first control point of every `width` × `width`
/// window of its chart's control grid that holds control point `c` (control points are numbered
/// chart by chart, a grid line after another: `grids`).
pub(crate) fn mark_windows_holding(bits: &mut [u64], c: usize, grids: ControlGrids, width: usize) {
    for first in windows_holding(c, grids, width) {
        bits[first / 64] |= 1 << (first % 64);
    }
}

/// The first control points of the `width` × `width` windows of its chart's control grid that
/// hold control point `c`.
pub(crate) fn windows_holding(
    c: usize,
    grids: ControlGrids,
    width: usize,
) -> impl Iterator<Item = usize> {
    let (chart, column, row) = grids.locate(c);
    let (base, grid) = (grids.offset(chart), grids.grid(chart));
    (0..=row.min(width - 1)).flat_map(move |j| {
        (0..=column.min(width - 1)).map(move |i| base + (row - j) * grid + (column - i))
    })
}

/// The indices of the set bits of `bits`, in increasing order.
pub(crate) fn set_bits(bits: &[u64]) -> Vec<u32> {
    let mut out = Vec::new();
    for (w, &word) in bits.iter().enumerate() {
        let mut b = word;
        while b != 0 {
            out.push((w * 64) as u32 + b.trailing_zeros());
            b &= b - 1;
        }
    }
    out
}

/// The most rows per task when a stencil is built on all cores.
const ROWS_PER_TASK: usize = 2048;

/// About how long building a row takes on one core (ns), and locating its point: a cubic row
/// in two or three charts (`ntori bench`'s `stencil_build_full`: 674 ns on 2026-11-30).
const BUILD_NS: usize = 700;
const LOCATE_NS: usize = 150;

/// Fewer rows than this are not worth a task of their own.
const LEAST_ROWS_PER_TASK: usize = 256;

/// Nanoseconds per weight of indexing a stencil's columns on one thread (a scattered write of a
/// row and an entry): whether [`Stencil::column_index`] is worth the pool.
const INDEX_NS_PER_WEIGHT: usize = 10;

/// Work (in nanoseconds) worth handing to rayon's pool from the calling thread. A call from a
/// thread outside the pool (the editor's, a command's main thread) wakes a worker, which wakes
/// the next, and the caller is woken at the end: three wake-ups of 10–70 µs each on this
/// machine's virtual cores. Below about twice that round trip, two cores finish later than one.
const LEAST_PARALLEL_NS: usize = 250_000;

/// How to split `rows` rows of about `ns_per_row` nanoseconds each over the current rayon pool:
/// `None` where the calling thread should do them alone (one thread, or too little work to pay
/// for the pool's round trip), else the rows per task: at most `most`, and as many tasks as a
/// multiple of the pool's threads, all of one size but the last. Fixed-size tasks leave a short
/// last one, and a core waiting on it: 12 800 rows in tasks of 4096 are three full tasks and a
/// short one, so 2 cores could be at most 1.56× one core; as four tasks of 3200 they can be 2×.
pub(crate) fn rows_per_task(rows: usize, most: usize, ns_per_row: usize) -> Option<usize> {
    let threads = rayon::current_num_threads().max(1);
    if threads == 1 || rows.saturating_mul(ns_per_row) < LEAST_PARALLEL_NS {
        return None;
    }
    let most = most.max(1);
    let tasks = rows.div_ceil(most).div_ceil(threads) * threads;
    Some(
        rows.div_ceil(tasks)
            .clamp(LEAST_ROWS_PER_TASK.min(most), most),
    )
}

/// A range of a stencil's weights being written (each array the same range).
struct RowsMut<'a> {
    controls: &'a mut [u32],
    pos: &'a mut [f64],
    du: &'a mut [f64],
    dv: &'a mut [f64],
}

impl<'a> RowsMut<'a> {
    /// Leaves the first `n` weights here and returns the rest.
    fn split_off(&mut self, n: usize) -> RowsMut<'a> {
        let (c, c_rest) = std::mem::take(&mut self.controls).split_at_mut(n);
        let (p, p_rest) = std::mem::take(&mut self.pos).split_at_mut(n);
        let (u, u_rest) = std::mem::take(&mut self.du).split_at_mut(n);
        let (v, v_rest) = std::mem::take(&mut self.dv).split_at_mut(n);
        *self = RowsMut {
            controls: c,
            pos: p,
            du: u,
            dv: v,
        };
        RowsMut {
            controls: c_rest,
            pos: p_rest,
            du: u_rest,
            dv: v_rest,
        }
    }

    /// Writes the rows of `points`; `offsets` are theirs (one more than the points: where each
    /// row starts and the last ends), from the stencil's start.
    fn fill(&mut self, layout: &Layout, points: &[ChartPoint], offsets: &[usize]) {
        let mut transitions = Vec::with_capacity(16);
        let mut blends = Vec::with_capacity(16);
        let base = offsets[0];
        let mut at = 0;
        for (r, &p) in points.iter().enumerate() {
            layout
                .atlas()
                .locate_with_transitions_into(p, &mut transitions);
            tensor::blend_jets(layout, p, &transitions, &mut blends);
            tensor::normalise_blends(&mut blends);
            // Charts come sorted and the layout is chart-major, so the row's controls increase.
            for b in &blends {
                at = self.write_chart(layout, b, at);
            }
            assert_eq!(base + at, offsets[r + 1], "a point located twice alike");
            debug_assert!(
                self.controls[offsets[r] - base..at]
                    .windows(2)
                    .all(|w| w[0] < w[1]),
                "a row's control points increase"
            );
        }
    }

    /// One chart's (p + 1)² weights of a row, from weight `at` on; returns where the next
    /// begins. With q the normalised blend (gradient q_u, q_v in the row's chart) and ψ' = a + ib,
    /// the weight q·x_i·y_j has
    ///   ∂_u = y_j (q_u x_i + q a x_i') + (q b y_j') x_i,
    ///   ∂_v = y_j (q_v x_i − q b x_i') + (q a y_j') x_i,
    /// the chain rule through a conformal map taking (f_x, f_y) to (a f_x + b f_y, −b f_x + a f_y).
    fn write_chart(&mut self, layout: &Layout, b: &tensor::Blend, mut at: usize) -> usize {
        let order = layout.settings().degree + 1;
        let basis = layout.basis(b.rep.chart);
        let w = b.rep.coords;
        let (fu, nu) = basis.eval(w.re, 1);
        let (fv, nv) = basis.eval(w.im, 1);
        let (q, qu, qv) = (b.jet.val, b.jet.du, b.jet.dv);
        let (a, c) = (b.psi.re, b.psi.im);
        let along_u: [[f64; 3]; crate::bspline::MAX_DEGREE + 1] = std::array::from_fn(|i| {
            let (x, dx) = (nu[0][i], nu[1][i]);
            [x, qu * x + q * a * dx, qv * x - q * c * dx]
        });
        for (j, (&y, &dy)) in nv[0][..order].iter().zip(&nv[1][..order]).enumerate() {
            let (qy, cu, cv) = (q * y, q * c * dy, q * a * dy);
            let first = layout.control_index(b.rep.chart, fu, fv + j) as u32;
            for (i, [x, gu, gv]) in along_u[..order].iter().enumerate() {
                self.controls[at] = first + i as u32;
                self.pos[at] = qy * x;
                self.du[at] = y * gu + cu * x;
                self.dv[at] = y * gv + cv * x;
                at += 1;
            }
        }
        at
    }
}

#[cfg(test)]
mod tests {
    use super::{LEAST_PARALLEL_NS, LEAST_ROWS_PER_TASK, rows_per_task, windows_holding};
    use crate::surface::ControlGrids;
    use charts::ChartId;

    /// Control points are numbered chart by chart, each chart's grid its own (the disk charts'
    /// first): `locate` inverts the numbering, `stride` is the chart's grid, and the windows
    /// holding a control point are exactly the width × width windows of its chart's grid that
    /// contain it (checked against every window of every chart).
    #[test]
    fn control_grids_number_every_chart_in_turn_and_find_its_windows() {
        for (square, disk, disks, charts) in [
            (5, 5, 2, 6),
            (5, 9, 2, 6),
            (7, 4, 2, 10),
            (6, 11, 2, 2),
            (4, 8, 0, 3),
        ] {
            let grids = ControlGrids {
                square,
                disk,
                disks,
                charts,
            };
            let mut next = 0;
            for chart in (0..charts as u32).map(ChartId) {
                let g = grids.grid(chart);
                assert_eq!(g, if chart.index() < disks { disk } else { square });
                assert_eq!(grids.offset(chart), next);
                for j in 0..g {
                    for i in 0..g {
                        assert_eq!(grids.locate(next), (chart, i, j));
                        assert_eq!(grids.stride(next), g);
                        next += 1;
                    }
                }
            }
            assert_eq!(grids.count(), next);
            let width = 3;
            for c in 0..grids.count() {
                let mut found: Vec<usize> = windows_holding(c, grids, width).collect();
                found.sort_unstable();
                let (chart, ci, cj) = grids.locate(c);
                let (base, g) = (grids.offset(chart), grids.grid(chart));
                let mut expected = Vec::new();
                for j in 0..g {
                    for i in 0..g {
                        if (i..i + width).contains(&ci) && (j..j + width).contains(&cj) {
                            expected.push(base + j * g + i);
                        }
                    }
                }
                assert_eq!(found, expected, "control point {c}");
            }
        }
    }

    /// Split work is in tasks of at most `most` rows, as many as a multiple of the threads and
    /// all but the last of one size, which is never much longer; little work is not split.
    #[test]
    fn work_is_split_evenly_over_the_threads_or_not_at_all() {
        for threads in [1, 2, 3, 16] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                for rows in [0, 1, 100, 1000, 12_800, 51_200, 100_003, 1_000_000] {
                    for (most, ns) in [(2048, 1200), (4096, 15), (4096, 50), (32_768, 10)] {
                        let split = rows_per_task(rows, most, ns);
                        let Some(per_task) = split else {
                            assert!(
                                threads == 1 || rows * ns < LEAST_PARALLEL_NS,
                                "{rows} rows not split"
                            );
                            continue;
                        };
                        assert!(threads > 1 && rows * ns >= LEAST_PARALLEL_NS);
                        assert!((1..=most).contains(&per_task), "{per_task} rows a task");
                        let tasks = rows.div_ceil(per_task);
                        let last = rows - (tasks - 1) * per_task;
                        // Whole rounds over the threads, or tasks of the least size.
                        assert!(tasks % threads == 0 || per_task == LEAST_ROWS_PER_TASK.min(most));
                        assert!(
                            last > per_task / 2 || tasks >= 4 * threads,
                            "{rows}: {per_task} and {last}"
                        );
                    }
                }
            });
        }
    }
}
