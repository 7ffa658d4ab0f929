//! Direct manipulation (the paper's section 5.1, after Fowler and Bartels): the smallest change to the
//! control points that moves chosen surface points to chosen positions.
//!
//! Each constraint i says S(p_i) = t_i. The surface is linear in the control points, S(p_i) = r_i · P
//! with r_i the point's stencil row, so the change ΔP of least norm with R·ΔP = d (d_i = t_i − S(p_i))
//! is ΔP = Rᵀλ where (R Rᵀ) λ = d: a system as small as the number of constraints, one right-hand side
//! per coordinate. Pinning a point is a constraint with t_i = S(p_i). The system is solved through its
//! SVD, so repeated or contradictory constraints give the least-squares compromise, not a failure.

use charts::ChartPoint;
use nalgebra::{DMatrix, DVector};

use crate::EmbeddingError;
use crate::spline_surface::ControlId;
use crate::stencil::{ColumnIndex, Stencil};
use crate::surface::{Layout, Point3, Vector3, Weight};

/// Move the surface point `point` to `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Constraint {
    pub point: ChartPoint,
    pub target: Point3,
}

/// The change to make: control point `controls[k]` moves by `deltas[k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Edit {
    pub controls: Vec<ControlId>,
    pub deltas: Vec<Vector3>,
    /// The largest |S(p_i) − t_i| left after the edit (0 up to rounding unless constraints conflict).
    pub residual: f64,
}

impl Edit {
    /// Adds the change to the control points.
    pub fn apply(&self, control: &mut [Point3]) {
        for (&c, d) in self.controls.iter().zip(&self.deltas) {
            control[c.index()] += d;
        }
    }
}

/// The least-norm change to `control` meeting `constraints` (see the module documentation).
pub fn solve(
    layout: &Layout,
    control: &[Point3],
    constraints: &[Constraint],
) -> Result<Edit, EmbeddingError> {
    let atlas = layout.atlas();
    let mut rows: Vec<Vec<Weight>> = Vec::with_capacity(constraints.len());
    for (i, c) in constraints.iter().enumerate() {
        if !(c.target.x.is_finite() && c.target.y.is_finite() && c.target.z.is_finite()) {
            return Err(EmbeddingError::BadTarget(i));
        }
        atlas.locate(c.point)?;
        let mut row = Vec::with_capacity(64);
        layout.weights(c.point, &mut row);
        rows.push(row);
    }
    // The control points any constraint touches, and R restricted to them.
    let mut controls: Vec<u32> = rows.iter().flatten().map(|w| w.control).collect();
    controls.sort_unstable();
    controls.dedup();
    let column = |c: u32| controls.binary_search(&c).unwrap_or(0);
    let (m, k) = (constraints.len(), controls.len());
    let mut r = DMatrix::<f64>::zeros(m, k);
    let mut d = DMatrix::<f64>::zeros(m, 3);
    for (i, row) in rows.iter().enumerate() {
        let mut current = Vector3::zeros();
        for w in row {
            r[(i, column(w.control))] += w.jet.val;
            current += control[w.control as usize].coords * w.jet.val;
        }
        let gap = constraints[i].target - Point3::from(current);
        for a in 0..3 {
            d[(i, a)] = gap[a];
        }
    }
    let gram = &r * r.transpose();
    let svd = gram.svd(true, true);
    let lambda = svd
        .solve(&d, 1e-12 * svd.singular_values.max().max(f64::MIN_POSITIVE))
        .map_err(|_| EmbeddingError::Unsolvable)?;
    let delta = r.transpose() * lambda;
    let moved = &r * &delta;
    let residual = (0..m)
        .map(|i| DVector::from_iterator(3, (0..3).map(|a| moved[(i, a)] - d[(i, a)])).norm())
        .fold(0.0, f64::max);
    Ok(Edit {
        deltas: (0..k)
            .map(|j| Vector3::new(delta[(j, 0)], delta[(j, 1)], delta[(j, 2)]))
            .collect(),
        controls: controls.into_iter().map(ControlId).collect(),
        residual,
    })
}

/// Reusable buffers for [`refresh`].
#[derive(Clone, Debug, Default)]
pub struct RefreshScratch {
    marked: Vec<u64>,
    rows: Vec<u32>,
}

impl RefreshScratch {
    /// How many rows the last refresh recomputed.
    pub fn refreshed(&self) -> usize {
        self.rows.len()
    }
}

/// Brings `positions` (= stencil · old control points) up to date after `edit` was applied to
/// `control`: each affected row is recomputed once, however many moved control points it uses. When
/// the moved control points touch most rows anyway (a coarse grid), streaming through all rows is
/// cheaper than gathering them, so it does that.
pub fn refresh(
    stencil: &Stencil,
    index: &ColumnIndex,
    edit: &Edit,
    control: &[Point3],
    positions: &mut [Point3],
    scratch: &mut RefreshScratch,
) {
    let rows = stencil.rows();
    let touched: usize = edit
        .controls
        .iter()
        .map(|&c| stencil.rows_of(index, c.index()).len())
        .sum();
    scratch.rows.clear();
    if touched > rows {
        stencil.positions(control, positions);
        scratch.rows.extend(0..rows as u32);
        return;
    }
    scratch.marked.resize(rows.div_ceil(64), 0);
    for &c in &edit.controls {
        for &r in stencil.rows_of(index, c.index()) {
            let (word, bit) = (r as usize / 64, 1u64 << (r % 64));
            if scratch.marked[word] & bit == 0 {
                scratch.marked[word] |= bit;
                scratch.rows.push(r);
            }
        }
    }
    for &r in &scratch.rows {
        positions[r as usize] = stencil.position(control, r as usize);
        scratch.marked[r as usize / 64] = 0;
    }
}
