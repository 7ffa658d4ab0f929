//! The CPU side of a picture: the surface tessellated and evaluated, coloured by style, the camera,
//! and the curve segments. Shared by offscreen rendering and the editor.

use charts::Atlas;
use embedding::{Layout, Model, Point3, Stencil};
use glam::{Mat4, Vec3};

use super::gpu::{FrameUniforms, Segment, SurfaceVertex};
use super::{CurvatureKind, Curve, RenderError, Style, View};

/// Where the camera looks from: the bounding sphere of what is drawn and a [`View`] around it.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub centre: Vec3,
    pub radius: f32,
    pub view: View,
    pub aspect: f32,
}

/// The vertical field of view.
const FOV_DEG: f32 = 34.0;

impl Camera {
    /// Unit vector from the centre towards the eye (z is up).
    pub fn direction(&self) -> Vec3 {
        let (az, el) = (
            (self.view.azimuth_deg as f32).to_radians(),
            (self.view.elevation_deg as f32).to_radians(),
        );
        Vec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }

    pub fn eye(&self) -> Vec3 {
        self.centre + self.direction() * self.radius * self.view.distance as f32
    }

    pub fn view_proj(&self) -> Mat4 {
        let eye = self.eye();
        // Looking straight down or up, z cannot be "up": use y then.
        let up = if self.direction().z.abs() > 0.999 {
            Vec3::Y
        } else {
            Vec3::Z
        };
        let distance = (eye - self.centre).length();
        let near = (distance - 1.5 * self.radius).max(1e-3 * distance);
        let far = distance + 1.5 * self.radius;
        Mat4::perspective_rh(FOV_DEG.to_radians(), self.aspect, near, far)
            * Mat4::look_at_rh(eye, self.centre, up)
    }

    /// The key light: above and to the left of the camera, towards the light.
    pub fn light(&self) -> Vec3 {
        let back = self.direction();
        let right = Vec3::Z.cross(back).try_normalize().unwrap_or(Vec3::X);
        let up = back.cross(right);
        (back + 0.8 * up - 0.5 * right).normalize()
    }

    pub fn uniforms(&self, style: Style, size: (u32, u32)) -> FrameUniforms {
        let wire = matches!(style, Style::Wireframe);
        FrameUniforms {
            view_proj: self.view_proj().to_cols_array_2d(),
            eye: self.eye().extend(1.0).to_array(),
            light: self.light().extend(0.0).to_array(),
            params: [f32::from(u8::from(wire)), 1.2, 0.22, 0.25],
            // Curves stay readable when printed: about 1/180 of the picture's height, at least 3 px.
            viewport: [
                size.0 as f32,
                size.1 as f32,
                (size.1 as f32 / 180.0).max(3.0),
                2e-4,
            ],
        }
    }
}

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

/// A fixed palette indexed by chart id. The renderer's charts style uses [`crate::palette`] (one
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

/// The model tessellated at t_e = t_r = `t`, coloured by `style`.
pub fn model_geometry(
    model: &Model,
    t: u32,
    style: Style,
    curves: &[Curve],
) -> Result<SceneGeometry, RenderError> {
    let atlas = Atlas::new(model.genus)?;
    let layout = Layout::new(&atlas, model.settings)?;
    model.validate(&layout)?;
    let tess = atlas.tessellate(t, t)?;
    let control = model.points();
    let stencil = Stencil::build(&layout, &tess.vertices);
    let mut positions = vec![Point3::zeros(); tess.vertices.len()];
    let mut normals = positions.clone();
    stencil.positions(&control, &mut positions);
    stencil.normals(&control, &mut normals);
    let (colours, legend) = match style {
        Style::Shaded | Style::Wireframe => (vec![SURFACE_COLOUR; positions.len()], None),
        Style::Charts => (
            tess.vertices
                .iter()
                .map(|p| blend_colour(&atlas, &layout.blends(*p)))
                .collect(),
            None,
        ),
        Style::Curvature(kind) => {
            let values: Vec<f64> = tess
                .vertices
                .iter()
                .map(|p| {
                    let s = layout.eval(&control, *p);
                    match kind {
                        CurvatureKind::Gaussian => s.gaussian_curvature(),
                        CurvatureKind::Mean => s.mean_curvature(),
                    }
                })
                .collect();
            let range = robust_range(&values);
            let colours = values.iter().map(|&v| diverging(v / range)).collect();
            (colours, Some((kind, range)))
        }
    };
    let corners: Vec<([f64; 3], [f64; 3], [f32; 3])> = (0..positions.len())
        .map(|i| {
            let (p, n) = (positions[i], normals[i]);
            ([p.x, p.y, p.z], [n.x, n.y, n.z], colours[i])
        })
        .collect();
    let mut geometry = unindexed(&corners, &tess.triangles);
    geometry.segments = segments(curves);
    geometry.legend = legend;
    Ok(geometry)
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
fn blend_colour(atlas: &Atlas, blends: &[(charts::ChartId, f64)]) -> [f32; 3] {
    let mut c = [0.0f32; 3];
    for &(chart, b) in blends {
        let k = crate::palette::surface_rgb(atlas.charts()[chart.index()].kind());
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
