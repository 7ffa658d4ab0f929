//! Brushes defined on the surface: how far an edit reaches is a radius in model units around the
//! picked point, with a falloff profile, whatever the charts and the fit's distortion there.
//!
//! A grab brush moves each surface point x by Δ · f(|x − c| / R): the falloff f of its distance from
//! the brush's centre c, in model space. That field is not a spline, so the brush moves the control
//! points by the least-squares spline nearest to it: per control point a share β_c of Δ (the field
//! is linear in Δ, so the shares are computed once per press), fitted over the tessellation's
//! vertices that the moving control points reach, each weighted by its area, so that dense and
//! sparse parts of the tessellation count alike. Vertices beyond the radius that those control
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
use faer::Mat;
use faer::sparse::Triplet;

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
    let mut rows: Vec<u32> = controls
        .iter()
        .flat_map(|&c| stencil.rows_of(columns, c as usize).iter().copied())
        .collect();
    rows.sort_unstable();
    rows.dedup();
    let column = |c: u32| controls.binary_search(&c).ok();
    let mean_area = rows.iter().map(|&r| areas[r as usize]).sum::<f64>() / rows.len() as f64;
    let mut triplets = Vec::new();
    let mut patch_targets = Vec::new();
    let mut rhs = Mat::<f64>::zeros(rows.len(), 1);
    for (i, &r) in rows.iter().enumerate() {
        let scale = (areas[r as usize] / mean_area).sqrt();
        for (c, w) in stencil.row(r as usize) {
            // A control point outside the set stays put: its weight only sees the target.
            if let Some(j) = column(c) {
                triplets.push(Triplet::new(i, j, scale * w[0]));
            }
        }
        rhs[(i, 0)] = scale * target(r as usize);
    }
    // Each chart's own patch is fitted too, weighted by its blend (as the initial fit does): the
    // blend alone leaves the patches free to disagree in the overlaps, and they would ripple.
    let mut reps = Vec::new();
    let mut patch = Vec::new();
    let mut extra = 0;
    for &r in &rows {
        let blends = layout.blends(points[r as usize]);
        layout.atlas().locate_into(points[r as usize], &mut reps);
        let scale = (areas[r as usize] / mean_area).sqrt();
        for (rep, (_, blend)) in reps.iter().zip(&blends) {
            patch.clear();
            layout.patch_weights(*rep, &mut patch);
            let weight = scale * (PATCH_WEIGHT * blend).sqrt();
            let row = rows.len() + extra;
            for &(c, w) in &patch {
                if let Some(j) = column(c) {
                    triplets.push(Triplet::new(row, j, weight * w));
                }
            }
            patch_targets.push(weight * target(r as usize));
            extra += 1;
        }
    }
    // Fairness: the second differences of the shares over each chart's control grid, with the
    // control points outside the set held at 0, so steep profiles (a dome's rim) do not ripple.
    for row in crate::fit::smoothness_rows(layout) {
        if !row.iter().any(|&(c, _)| column(c as u32).is_some()) {
            continue;
        }
        let at = rows.len() + extra;
        for &(c, w) in &row {
            if let Some(j) = column(c as u32) {
                triplets.push(Triplet::new(at, j, FAIRNESS * w));
            }
        }
        patch_targets.push(0.0);
        extra += 1;
    }
    // A row ε·e_c per control point keeps the system full rank where the samples do not tell
    // two control points apart; it moves the shares by about ε² of their size.
    const EPSILON: f64 = 1e-6;
    let n = rows.len() + extra;
    triplets.extend((0..controls.len()).map(|j| Triplet::new(n + j, j, EPSILON)));
    let mut full = Mat::<f64>::zeros(n + controls.len(), 1);
    for i in 0..rows.len() {
        full[(i, 0)] = rhs[(i, 0)];
    }
    for (k, t) in patch_targets.iter().enumerate() {
        full[(rows.len() + k, 0)] = *t;
    }
    let beta = crate::fit::least_squares(n + controls.len(), controls.len(), &triplets, &full)
        .ok()
        .flatten()
        .ok_or(EmbeddingError::Unsolvable)?;
    Ok(controls
        .iter()
        .enumerate()
        .map(|(j, &c)| (ControlId(c), beta[(j, 0)]))
        .filter(|&(_, b)| b != 0.0)
        .collect())
}
