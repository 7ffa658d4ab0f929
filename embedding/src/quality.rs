//! Measures of shape: what a designer sees and topology cannot. χ and Gauss–Bonnet hold for any
//! closed surface, ripples and creases included; these look at the geometry itself.
//!
//! - **Patch disagreement**: where two charts both carry real blend weight, the distance between
//!   their two unblended patches E_c at the same surface point. The surface blends the patches, so
//!   patches that disagree draw ripples where the blend weights change.
//! - **Principal curvature**: the largest |κ| over a set of points (a crease or a spike shows up as
//!   an outlier far above what the intended shape has).
//! - **Normal deviation** from a reference mesh: the angle between the surface's normal at each
//!   mesh vertex's surface point and the mesh's own vertex normal (area-weighted face normals).
//!
//! ```
//! use charts::Atlas;
//! use embedding::quality::{patch_disagreement, sample_points};
//! use embedding::{Layout, Model, Point3, SplineSettings, Surface};
//! use std::sync::Arc;
//!
//! let atlas = Arc::new(Atlas::new(2)?);
//! let layout = Layout::new(&atlas, SplineSettings::default())?;
//! // Every patch the same constant: the patches agree everywhere.
//! let control = Model::constant(&layout, Point3::new(1.0, 2.0, 3.0)).points();
//! let surface = Surface::new(atlas.clone(), SplineSettings::default(), control)?;
//! let d = patch_disagreement(&surface, &sample_points(&surface, 4)?, 0.1);
//! assert!(d.max < 1e-12 && d.compared > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use charts::ChartPoint;

use crate::spline_surface::Surface;
use crate::surface::{Point3, Vector3};
use crate::{EmbeddingError, evaluate};

/// Points spread over the whole surface: the vertices of its t × t tessellation.
pub fn sample_points(surface: &Surface, t: u32) -> Result<Vec<ChartPoint>, EmbeddingError> {
    Ok(surface.atlas().tessellate(t, t)?.vertices)
}

/// How far apart overlapping patches are (see the module documentation), in model units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Disagreement {
    /// The largest distance between two patches that both carry blend weight ≥ the threshold.
    pub max: f64,
    /// The root mean square of each compared point's largest distance.
    pub rms: f64,
    /// Where the largest distance was found.
    pub worst: Option<ChartPoint>,
    /// How many points had two or more patches to compare.
    pub compared: usize,
}

/// The patch disagreement over `points`, comparing the patches whose normalised blend weight is at
/// least `min_blend` (0.1 is a good threshold: below it a patch hardly shows).
pub fn patch_disagreement(
    surface: &Surface,
    points: &[ChartPoint],
    min_blend: f64,
) -> Disagreement {
    let layout = surface.layout();
    let atlas = surface.atlas();
    let control = surface.control_points();
    let mut weights = Vec::with_capacity(16);
    let (mut out, mut sum_squares) = (Disagreement::default(), 0.0);
    for &p in points {
        let reps = atlas.locate_with_transitions(p);
        let raw: Vec<f64> = reps
            .iter()
            .map(|(r, _)| {
                layout
                    .raw_blend(atlas.charts()[r.chart.index()].domain(), r.coords)
                    .val
            })
            .collect();
        let total: f64 = raw.iter().sum();
        let patches: Vec<Point3> = reps
            .iter()
            .zip(&raw)
            .filter(|&(_, &b)| b >= min_blend * total)
            .map(|((r, _), _)| {
                weights.clear();
                layout.patch_weights(*r, &mut weights);
                // The B-spline basis sums to one: an affine combination of control points.
                let sum: Vector3 = weights
                    .iter()
                    .map(|&(c, w)| control[c as usize].coords * w)
                    .sum();
                Point3::from(sum)
            })
            .collect();
        if patches.len() < 2 {
            continue;
        }
        let mut largest = 0.0f64;
        for (i, a) in patches.iter().enumerate() {
            for b in &patches[i + 1..] {
                largest = largest.max((a - b).norm());
            }
        }
        out.compared += 1;
        sum_squares += largest * largest;
        if largest > out.max || out.worst.is_none() {
            out.max = largest;
            out.worst = Some(p);
        }
    }
    out.rms = (sum_squares / out.compared.max(1) as f64).sqrt();
    out
}

/// The largest principal curvature in absolute value over `points`, and where it is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurvatureExtreme {
    pub max_abs: f64,
    pub at: Option<ChartPoint>,
}

/// The largest |κ₁|, |κ₂| over `points` (points where the surface is singular, S_u × S_v = 0,
/// count as infinite curvature).
pub fn max_principal_curvature(surface: &Surface, points: &[ChartPoint]) -> CurvatureExtreme {
    let mut out = CurvatureExtreme::default();
    let wants = evaluate::Wants {
        curvature: true,
        blends: false,
    };
    evaluate::evaluate(surface, points, wants, 0.0, &mut |s: &evaluate::Sample| {
        let k = match s.curvature {
            Some(c) if s.normal.is_some() => {
                let (k1, k2) = c.principal();
                k1.abs().max(k2.abs())
            }
            _ => f64::INFINITY,
        };
        let k = if k.is_nan() { f64::INFINITY } else { k };
        if k > out.max_abs || out.at.is_none() {
            out.max_abs = k;
            out.at = Some(s.point);
        }
    });
    out
}

/// Angles in degrees: the median, the 90th percentile and the largest.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AngleSpread {
    pub median: f64,
    pub p90: f64,
    pub max: f64,
}

impl AngleSpread {
    fn of(mut angles: Vec<f64>) -> AngleSpread {
        if angles.is_empty() {
            return AngleSpread::default();
        }
        angles.sort_by(f64::total_cmp);
        let at = |q: f64| angles[((angles.len() - 1) as f64 * q).round() as usize];
        AngleSpread {
            median: at(0.5),
            p90: at(0.9),
            max: angles[angles.len() - 1],
        }
    }
}

/// The angle between the surface's normal at `points[i]` and the vertex normal of the mesh
/// (`positions`, `triangles`, counter-clockwise seen from outside) at vertex i, over every vertex.
/// A vertex whose mesh normal or surface normal is undefined counts as 180°.
pub fn normal_deviation(
    surface: &Surface,
    points: &[ChartPoint],
    positions: &[Point3],
    triangles: &[[u32; 3]],
) -> AngleSpread {
    let mut mesh_normals = vec![Vector3::zeros(); positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        // Twice the area times the unit normal: the area weighting comes for free.
        let n = (b - a).cross(&(c - a));
        for &v in t {
            mesh_normals[v as usize] += n;
        }
    }
    normal_deviation_from(surface, points, &mesh_normals)
}

/// The angle between the surface's normal at `points[i]` and `normals[i]` (any length; e.g. the
/// intended shape's exact normals, which [`crate::holed::HoledMesh`] knows), over every point. A
/// point whose normal is undefined, on either side, counts as 180°.
pub fn normal_deviation_from(
    surface: &Surface,
    points: &[ChartPoint],
    normals: &[Vector3],
) -> AngleSpread {
    let mut angles = vec![180.0; points.len().min(normals.len())];
    evaluate::evaluate(
        surface,
        &points[..angles.len()],
        evaluate::Wants::default(),
        0.0,
        &mut |s: &evaluate::Sample| {
            let (m, n) = (normals[s.index], s.normal);
            if let Some(n) = n
                && m.norm() > 0.0
            {
                angles[s.index] = n.angle(&m).to_degrees();
            }
        },
    );
    AngleSpread::of(angles)
}
