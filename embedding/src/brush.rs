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
//! Because the fit sees only model-space distances and surface samples, the same brush at the
//! same surface point gives the same shares whichever chart the point was picked in, and footprints
//! of the same width in every chart.

use faer::Mat;
use faer::sparse::Triplet;

use crate::EmbeddingError;
use crate::spline_surface::ControlId;
use crate::stencil::{ColumnIndex, Stencil};
use crate::surface::Point3;

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

/// The tessellation a brush is fitted over: the stencil of its vertices, their column index, their
/// current positions and their areas (a third of the triangles' around each).
pub struct BrushSamples<'a> {
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
    let mut rhs = Mat::<f64>::zeros(rows.len() + controls.len(), 1);
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
    // A row ε·e_c per control point keeps the system full rank where the samples do not tell
    // two control points apart; it moves the shares by about ε² of their size.
    const EPSILON: f64 = 1e-6;
    let n = rows.len();
    triplets.extend((0..controls.len()).map(|j| Triplet::new(n + j, j, EPSILON)));
    let beta = crate::fit::least_squares(n + controls.len(), controls.len(), &triplets, &rhs)
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
