//! Brushes defined on the surface: how far an edit reaches is a radius in model units around the
//! picked point, with a falloff profile, whatever the charts and the fit's distortion there.
//!
//! A grab brush moves each surface point x by Δ · f(|x − c| / R): the falloff f of its distance from
//! the brush's centre c, in model space. That field is not a spline, so the brush moves the control
//! points by the least-squares spline nearest to it: per control point a share β_c of Δ (the field
//! is linear in Δ, so the shares are computed once per press), fitted over the tessellation's
//! vertices that the moving control points reach (at most 24 per moving control point, taken
//! evenly), each weighted by its area, so that dense and sparse parts of the tessellation count
//! alike. The unknowns are few (one per moving control point), so the normal equations are
//! formed and solved by a dense Cholesky factorization. Vertices beyond the radius that those control
//! points reach are in the fit with target 0, which keeps the edit inside the brush. The dragged
//! point and the pins are then made exact by the minimum-norm correction of [`crate::edit`].
//!
//! The fit has two more kinds of rows, as the initial fit does: each chart's own patch is fitted to
//! the field as well, weighted by its blend (else patches disagree in the overlaps and ripple), and
//! the second differences of the shares over each chart's grid are kept small (fairness, so a steep
//! profile such as a dome's rim does not ring). What a spline of the model's grid can show sets a
//! floor on the radius: on the default genus-2 model (grid 16) footprints match the falloff from
//! about 0.2 of the model's size in every chart, and from 0.12 in the edge charts; below that the
//! bump comes out wider and lower, and the correction still takes the dragged point to its target.
//!
//! Because the fit sees only model-space distances and surface samples, the same brush at the
//! same surface point gives the same shares whichever chart the point was picked in, and footprints
//! of the same width in every chart.

use charts::ChartPoint;
use nalgebra::{DMatrix, DVector};

use crate::EmbeddingError;
use crate::spline_surface::ControlId;
use crate::stencil::{ColumnIndex, Stencil};
use crate::surface::{Layout, Point3};

/// Weight of the patch terms against the blended surface's (the initial fit's default).
const PATCH_WEIGHT: f64 = 1.0;

/// Weight of the fairness rows (second differences of the shares; the data rows have mean weight
/// 1). Chosen by looking at a dome brush on the default model: 0.03 left ripples at the rim, 0.1
/// few, 0.3 fewer but a softer footprint (measured in `embedding/tests/edit.rs`).
const FAIRNESS: f64 = 0.1;

/// How a brush's effect fades from its centre (s = 0) to its radius (s = 1); nothing beyond.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Falloff {
    /// (1 − s²)³: flat at the centre and at the rim, a soft round bump.
    #[default]
    Smooth,
    /// √(1 − s²): a hemisphere's profile, a full dome.
    Dome,
    /// (1 − s)²: a pointed tip with a soft rim.
    Sharp,
    /// 1 inside the radius: the whole disc moves together.
    Constant,
}

impl Falloff {
    /// The profile at s = distance / radius (0 for s ≥ 1).
    pub fn at(self, s: f64) -> f64 {
        if !(0.0..1.0).contains(&s) {
            return if s < 0.0 { 1.0 } else { 0.0 };
        }
        match self {
            Falloff::Smooth => (1.0 - s * s).powi(3),
            Falloff::Dome => (1.0 - s * s).sqrt(),
            Falloff::Sharp => (1.0 - s).powi(2),
            Falloff::Constant => 1.0,
        }
    }
}

/// The tessellation a brush is fitted over: the surface's layout, the vertices (as chart points),
/// their stencil and its column index, their current positions and their areas (a third of the
/// triangles' around each).
pub struct BrushSamples<'a> {
    pub layout: &'a Layout<'a>,
    pub points: &'a [ChartPoint],
    pub stencil: &'a Stencil,
    pub columns: &'a ColumnIndex,
    pub positions: &'a [Point3],
    pub areas: &'a [f64],
}

/// A grab brush of `radius` (model units) centred at `centre` with profile `falloff`: each control
/// point that moves, with its share β of the displacement (sorted by control point). Empty when no
/// vertex lies within the radius.
pub fn grab_shares(
    samples: &BrushSamples,
    centre: Point3,
    radius: f64,
    falloff: Falloff,
) -> Result<Vec<(ControlId, f64)>, EmbeddingError> {
    let BrushSamples {
        layout,
        points,
        stencil,
        columns,
        positions,
        areas,
    } = *samples;
    let target = |r: usize| falloff.at((positions[r] - centre).norm() / radius);
    // The control points that reach the brush's disc, then every vertex they reach.
    let mut controls: Vec<u32> = (0..positions.len())
        .filter(|&r| (positions[r] - centre).norm() < radius)
        .flat_map(|r| stencil.row(r).map(|(c, _)| c))
        .collect();
    controls.sort_unstable();
    controls.dedup();
    if controls.is_empty() {
        return Ok(Vec::new());
    }
    // A bit per vertex rather than a sort: the columns of a wide brush list millions of entries.
    let mut marks = vec![0u64; positions.len().div_ceil(64)];
    for &c in &controls {
        for &r in stencil.rows_of(columns, c as usize) {
            marks[r as usize / 64] |= 1 << (r % 64);
        }
    }
    let rows: Vec<u32> = marks
        .iter()
        .enumerate()
        .flat_map(|(w, &bits)| {
            (0..64u32)
                .filter(move |b| bits & (1u64 << b) != 0)
                .map(move |b| (w * 64) as u32 + b)
        })
        .collect();
    // A fine tessellation has far more vertices than the spline has freedom: every k-th of them
    // (at most SAMPLES_PER_CONTROL per moving control point) fits the same field, each standing
    // for k vertices' area, and the press stays quick at 10⁶ vertices.
    let stride = rows
        .len()
        .div_ceil(SAMPLES_PER_CONTROL * controls.len())
        .max(1);
    let column = |c: u32| controls.binary_search(&c).ok();
    let mut system = Normal::new(controls.len());
    let mut reps = Vec::new();
    let mut patch = Vec::new();
    let mut entries = Vec::new();
    for &r in rows.iter().step_by(stride) {
        let (r, area) = (r as usize, areas[r as usize]);
        let goal = target(r);
        // The blended surface's row.
        entries.clear();
        entries.extend(stencil.row(r).filter_map(|(c, w)| Some((column(c)?, w[0]))));
        system.add(&entries, goal, area);
        // Each chart's own patch too, weighted by its blend (as the initial fit does): the blend
        // alone leaves the patches free to disagree in the overlaps, and they would ripple.
        let blends = layout.blends(points[r]);
        layout.atlas().locate_into(points[r], &mut reps);
        for (rep, (_, blend)) in reps.iter().zip(&blends) {
            patch.clear();
            layout.patch_weights(*rep, &mut patch);
            entries.clear();
            entries.extend(patch.iter().filter_map(|&(c, w)| Some((column(c)?, w))));
            system.add(&entries, goal, area * PATCH_WEIGHT * blend);
        }
    }
    // The data rows (blended and patch, about two per vertex reached) as if each had weight 1 on
    // average, against fairness rows of weight FAIRNESS²: the second differences of the shares
    // over each chart's control grid, with the control points outside the set held at 0, so steep
    // profiles (a dome's rim) do not ring.
    system.scale(2.0 * rows.len() as f64 / system.weight.max(f64::MIN_POSITIVE));
    for row in crate::fit::smoothness_rows(layout) {
        entries.clear();
        entries.extend(
            row.iter()
                .filter_map(|&(c, w)| Some((column(c as u32)?, w))),
        );
        if !entries.is_empty() {
            system.add(&entries, 0.0, FAIRNESS * FAIRNESS);
        }
    }
    let beta = system.solve().ok_or(EmbeddingError::Unsolvable)?;
    Ok(controls
        .iter()
        .enumerate()
        .map(|(j, &c)| (ControlId(c), beta[j]))
        .filter(|&(_, b)| b != 0.0)
        .collect())
}

/// Samples per moving control point at most (the rest of a fine tessellation is skipped evenly).
const SAMPLES_PER_CONTROL: usize = 24;

/// The normal equations (Σ w aᵢaᵢᵀ) β = Σ w aᵢ tᵢ of a weighted least-squares problem whose rows
/// are sparse: small (one unknown per moving control point) and dense.
struct Normal {
    matrix: DMatrix<f64>,
    rhs: DVector<f64>,
    /// Σ w of the rows added since the last [`Normal::scale`].
    weight: f64,
}

impl Normal {
    fn new(n: usize) -> Normal {
        Normal {
            matrix: DMatrix::zeros(n, n),
            rhs: DVector::zeros(n),
            weight: 0.0,
        }
    }

    /// Adds the row Σ aⱼ βⱼ = target with weight w.
    fn add(&mut self, row: &[(usize, f64)], target: f64, w: f64) {
        for &(i, a) in row {
            self.rhs[i] += w * a * target;
            for &(j, b) in row {
                self.matrix[(i, j)] += w * a * b;
            }
        }
        self.weight += w;
    }

    fn scale(&mut self, s: f64) {
        self.matrix *= s;
        self.rhs *= s;
        self.weight = 0.0;
    }

    /// β, with ε² on the diagonal so that control points the samples cannot tell apart still
    /// get a unique (small) share.
    fn solve(mut self) -> Option<Vec<f64>> {
        const EPSILON: f64 = 1e-6;
        let n = self.rhs.len();
        for i in 0..n {
            self.matrix[(i, i)] += EPSILON * EPSILON;
        }
        let beta = self.matrix.cholesky()?.solve(&self.rhs);
        beta.iter()
            .all(|b| b.is_finite())
            .then(|| beta.iter().copied().collect())
    }
}
