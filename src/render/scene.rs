//! The CPU side of a picture: the surface tessellated and evaluated, coloured by style, the camera,
//! and the curve segments. Shared by offscreen rendering and the editor.

use charts::Atlas;
use embedding::{Sample, Surface, Wants, evaluate};
use glam::Vec3;

use super::gpu::{Segment, SurfaceVertex};
use super::{CurvatureKind, Curve, RenderError, Style};

/// A surface ready to upload: unindexed triangle corners, and its bounding sphere.
pub struct SceneGeometry {
    pub vertices: Vec<SurfaceVertex>,
    pub segments: Vec<Segment>,
    pub centre: Vec3,
    pub radius: f32,
    /// For the curvature style: the value range the colours span (symmetric about 0).
    pub legend: Option<(CurvatureKind, f64)>,
}

/// The shaded style's colour.
pub const SURFACE_COLOUR: [f32; 3] = [0.55, 0.68, 0.9];

/// A fixed palette indexed by chart id. The renderer's charts style uses [`crate::render::palette`] (one
/// colour per chart kind and edge pair, as in the figures); this stays for callers that only know ids.
pub const CHART_PALETTE: [[f32; 3]; 8] = [
    [0.89, 0.35, 0.32],
    [0.35, 0.72, 0.38],
    [0.30, 0.50, 0.90],
    [0.95, 0.78, 0.25],
    [0.70, 0.40, 0.85],
    [0.25, 0.78, 0.80],
    [0.95, 0.55, 0.20],
    [0.62, 0.62, 0.62],
];

/// The surface tessellated at t_e = t_r = `t`, coloured by `style`.
pub fn model_geometry(
    surface: &Surface,
    t: u32,
    style: Style,
    curves: &[Curve],
) -> Result<SceneGeometry, RenderError> {
    // What export refuses, a picture refuses too (rather than a blank PNG and exit 0).
    if surface.is_degenerate() {
        return Err(RenderError::Degenerate);
    }
    let atlas = surface.atlas();
    let tess = atlas.tessellate(t, t)?;
    let wants = Wants {
        curvature: matches!(style, Style::Curvature(_)),
        blends: matches!(style, Style::Charts),
    };
    let n = tess.vertices.len();
    let (mut corners, mut values) = (Vec::with_capacity(n), Vec::new());
    // No threshold: a pinched point gets a non-finite normal, as the GPU would compute it.
    evaluate(surface, &tess.vertices, wants, 0.0, &mut |s: &Sample| {
        let normal = s.du.cross(&s.dv).normalize();
        let colour = match style {
            Style::Charts => blend_colour(atlas, &s.blends),
            _ => SURFACE_COLOUR,
        };
        if let (Style::Curvature(kind), Some(k)) = (style, s.curvature) {
            values.push(match kind {
                CurvatureKind::Gaussian => k.gaussian,
                CurvatureKind::Mean => k.mean,
            });
        }
        corners.push((s.position.into(), normal.into(), colour));
    });
    check_drawable(&corners)?;
    let mut legend = None;
    if let Style::Curvature(kind) = style {
        let range = robust_range(&values);
        for (corner, &v) in corners.iter_mut().zip(&values) {
            corner.2 = diverging(v / range);
        }
        legend = Some((kind, range));
    }
    let mut geometry = unindexed(&corners, &tess.triangles);
    geometry.segments = segments(curves);
    geometry.legend = legend;
    Ok(geometry)
}

/// Refuses positions the GPU's f32 cannot hold (beyond ±3.4e38 they become infinite and the picture
/// blank), and a surface so small that f32 rounds it to one point.
fn check_drawable(corners: &[([f64; 3], [f64; 3], [f32; 3])]) -> Result<(), RenderError> {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for (index, (p, _, _)) in corners.iter().enumerate() {
        let q = p.map(|x| x as f32);
        if !q.iter().all(|x| x.is_finite()) {
            let [x, y, z] = *p;
            return Err(RenderError::NotDrawable { index, x, y, z });
        }
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    if !corners.is_empty() && (0..3).all(|k| lo[k] == hi[k]) {
        let extent = corners.iter().map(|c| glam::DVec3::from(c.0)).fold(
            (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY),
            |(l, h), p| (l.min(p), h.max(p)),
        );
        return Err(RenderError::Collapses {
            extent: (extent.1 - extent.0).length(),
        });
    }
    Ok(())
}

/// A plain triangle mesh, flat shaded (face normals) in the surface colour.
pub fn mesh_geometry(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<SceneGeometry, RenderError> {
    if let Some(t) = triangles
        .iter()
        .find(|t| t.iter().any(|&v| v as usize >= positions.len()))
    {
        return Err(RenderError::Mesh(format!(
            "triangle {t:?} refers to a vertex that does not exist"
        )));
    }
    let mut corners = Vec::with_capacity(3 * triangles.len());
    let mut flat = Vec::with_capacity(3 * triangles.len());
    for (k, t) in triangles.iter().enumerate() {
        let [a, b, c] = t.map(|v| Vec3::from(positions[v as usize].map(|x| x as f32)));
        let n = (b - a).cross(c - a).normalize_or_zero();
        for &v in t {
            corners.push((
                positions[v as usize],
                n.as_dvec3().to_array(),
                SURFACE_COLOUR,
            ));
        }
        flat.push([3 * k as u32, 3 * k as u32 + 1, 3 * k as u32 + 2]);
    }
    Ok(unindexed(&corners, &flat))
}

fn unindexed(corners: &[([f64; 3], [f64; 3], [f32; 3])], triangles: &[[u32; 3]]) -> SceneGeometry {
    const BARY: [[f32; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut vertices = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        for (k, &v) in t.iter().enumerate() {
            let (p, n, c) = corners[v as usize];
            vertices.push(SurfaceVertex {
                position: p.map(|x| x as f32),
                normal: n.map(|x| x as f32),
                colour: c,
                bary: BARY[k],
            });
        }
    }
    let (centre, radius) =
        bounding_sphere(corners.iter().map(|c| Vec3::from(c.0.map(|x| x as f32))));
    SceneGeometry {
        vertices,
        segments: Vec::new(),
        centre,
        radius,
        legend: None,
    }
}

/// The centre of the bounding box and the largest distance from it.
fn bounding_sphere(points: impl Iterator<Item = Vec3> + Clone) -> (Vec3, f32) {
    let (lo, hi) = points.clone().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    let centre = (lo + hi) / 2.0;
    let radius = points.map(|p| (p - centre).length()).fold(0.0, f32::max);
    (centre, radius.max(1e-6))
}

fn segments(curves: &[Curve]) -> Vec<Segment> {
    curves
        .iter()
        .flat_map(|c| {
            c.points.windows(2).map(|w| Segment {
                a: w[0].map(|x| x as f32),
                b: w[1].map(|x| x as f32),
                colour: c.colour,
            })
        })
        .collect()
}

/// Σ b̂_c · colour of chart c, in the figures' palette (one colour per chart kind and edge pair).
pub fn blend_colour(atlas: &Atlas, blends: &[(charts::ChartId, f64)]) -> [f32; 3] {
    let mut c = [0.0f32; 3];
    for &(chart, b) in blends {
        let k = crate::render::palette::surface_rgb(atlas.charts()[chart.index()].kind());
        for ch in 0..3 {
            c[ch] += b as f32 * k[ch];
        }
    }
    c
}

/// The 95th percentile of |v|: the colour scale's end, so that a few extreme values do not wash
/// the rest out. Never zero.
pub fn robust_range(values: &[f64]) -> f64 {
    let mut abs: Vec<f64> = values
        .iter()
        .map(|v| v.abs())
        .filter(|v| v.is_finite())
        .collect();
    if abs.is_empty() {
        return 1.0;
    }
    abs.sort_by(f64::total_cmp);
    let q = abs[((abs.len() - 1) as f64 * 0.95) as usize];
    if q > 0.0 { q } else { 1.0 }
}

/// A diverging colour scale on [−1, 1]: blue, white at 0, red (Moreland's cool–warm ends).
pub fn diverging(t: f64) -> [f32; 3] {
    const COOL: [f32; 3] = [0.23, 0.30, 0.75];
    const MID: [f32; 3] = [0.95, 0.95, 0.95];
    const WARM: [f32; 3] = [0.71, 0.02, 0.15];
    let t = t.clamp(-1.0, 1.0) as f32;
    let (from, to, s) = if t < 0.0 {
        (MID, COOL, -t)
    } else {
        (MID, WARM, t)
    };
    [0, 1, 2].map(|i| from[i] + (to[i] - from[i]) * s)
}
