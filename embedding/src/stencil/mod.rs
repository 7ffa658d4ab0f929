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

pub use tensor::{ControlFrame, Followed, NEGLIGIBLE_BLEND, TensorStencil, tangent_words};

use charts::ChartPoint;

use crate::surface::{Layout, Point3, Vector3, Weight};

/// Sparse weights, one row per surface point.
#[derive(Clone, Debug, Default)]
pub struct Stencil {
    offsets: Vec<usize>,
    controls: Vec<u32>,
    pos: Vec<f64>,
    du: Vec<f64>,
    dv: Vec<f64>,
}

/// For each control point, the (row, entry) pairs of the stencil that use it.
#[derive(Clone, Debug)]
pub struct ColumnIndex {
    offsets: Vec<usize>,
    rows: Vec<u32>,
    entries: Vec<usize>,
}

impl Stencil {
    /// The stencil of `points` (each a point of its own chart).
    pub fn build(layout: &Layout, points: &[ChartPoint]) -> Stencil {
        let mut s = Stencil {
            offsets: Vec::with_capacity(points.len() + 1),
            ..Stencil::default()
        };
        s.offsets.push(0);
        let mut row: Vec<Weight> = Vec::with_capacity(128);
        for &p in points {
            row.clear();
            layout.weights(p, &mut row);
            // Merge repeated control points (none today: charts are injective), keep rows sorted.
            row.sort_unstable_by_key(|w| w.control);
            for w in &row {
                s.controls.push(w.control);
                s.pos.push(w.jet.val);
                s.du.push(w.jet.du);
                s.dv.push(w.jet.dv);
            }
            s.offsets.push(s.controls.len());
        }
        s
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
            let e = index.entries[k];
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

    /// Which rows each of `control_count` control points touches.
    pub fn column_index(&self, control_count: usize) -> ColumnIndex {
        let mut counts = vec![0usize; control_count + 1];
        for &c in &self.controls {
            counts[c as usize + 1] += 1;
        }
        for i in 0..control_count {
            counts[i + 1] += counts[i];
        }
        let mut fill = counts.clone();
        let mut rows = vec![0u32; self.controls.len()];
        let mut entries = vec![0usize; self.controls.len()];
        for r in 0..self.rows() {
            for k in self.offsets[r]..self.offsets[r + 1] {
                let c = self.controls[k] as usize;
                rows[fill[c]] = r as u32;
                entries[fill[c]] = k;
                fill[c] += 1;
            }
        }
        ColumnIndex {
            offsets: counts,
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
            positions[index.rows[k] as usize] += delta * self.pos[index.entries[k]];
        }
    }
}

/// Sets, in `bits` (a bit per control point), the first control point of every `width` × `width`
/// window of a chart's `grid` × `grid` control grid that holds control point `c` (control points
/// are numbered chart by chart, a grid line after another).
pub(crate) fn mark_windows_holding(bits: &mut [u64], c: usize, grid: usize, width: usize) {
    for first in windows_holding(c, grid, width) {
        bits[first / 64] |= 1 << (first % 64);
    }
}

/// The first control points of the `width` × `width` windows of a chart's `grid` × `grid` control
/// grid that hold control point `c`.
pub(crate) fn windows_holding(c: usize, grid: usize, width: usize) -> impl Iterator<Item = usize> {
    let per_chart = grid * grid;
    let (base, local) = (c - c % per_chart, c % per_chart);
    let (row, column) = (local / grid, local % grid);
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
