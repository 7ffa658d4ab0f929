//! The 3D figures, through the offscreen renderer: figure 2 (right: the loops on the surface),
//! figure 6 (input mesh, fitted surface, two edited surfaces) and the gallery.
//!
//! Models are made afresh (`embedding::fit::initial_model_of` on `default_mesh`'s mesh, what
//! `initial_model` makes at that resolution; nothing is cached on disk) and kept in
//! memory for the run, so the genus-2 fit serves figures 2, 6 and the gallery.

use charts::{ChartPoint, ModelPoint};
use embedding::edit::{Constraint, solve};
use embedding::fit::{
    InitialFit, default_mesh, default_resolution, default_settings, initial_model_of,
};
use embedding::{Point3, Surface, Vector3, bounding_box};

use super::geometry::side_points;
use super::{Figure, FiguresError, GENUS, palette};
use crate::render::{CurvatureKind, Curve, Offscreen, RenderError, RenderOptions, Style, View};

/// Input mesh resolution (points around each hole) of the input-mesh figure; the fits take
/// `ntori new`'s ([`embedding::fit::default_resolution`]).
pub const RESOLUTION: usize = 32;
/// Size of the main pictures, and of the gallery's.
const MAIN: (u32, u32) = (1200, 900);
const GALLERY: (u32, u32) = (800, 600);
/// The gallery's genera: every genus to 6, then 8, 10 and 16, where unfair fits showed first
/// (issue 12), and 32, the highest genus issue 12 asks to be fair (its fit takes about half a
/// minute on two cores).
pub const GALLERY_GENERA: [u32; 11] = [0, 1, 2, 3, 4, 5, 6, 8, 10, 16, 32];
/// The gallery's genera also shown in mean curvature, where a ripple or crease shows first (genus
/// 2 has its own row of styles below).
pub const GALLERY_MEAN_CURVATURE_GENERA: [u32; 5] = [3, 5, 10, 16, 32];

/// The renderer and the models made so far.
pub struct Studio {
    offscreen: Offscreen,
    /// Per genus: the input mesh's resolution and the fit.
    fits: Vec<(u32, usize, InitialFit)>,
}

impl Studio {
    pub fn new(offscreen: Offscreen) -> Studio {
        Studio {
            offscreen,
            fits: Vec::new(),
        }
    }

    /// The initial model of `genus` (made on first use).
    fn fit(&mut self, genus: u32, figure: &str) -> Result<&InitialFit, FiguresError> {
        if let Some(k) = self.fits.iter().position(|(g, _, _)| *g == genus) {
            return Ok(&self.fits[k].2);
        }
        let fail = |source| FiguresError::Embedding {
            figure: figure.to_owned(),
            source,
        };
        let (spline, settings) = default_settings(genus);
        let (resolution, mesh) = default_mesh(genus).map_err(fail)?;
        let fit = initial_model_of(mesh, resolution, spline, settings, &|_| {}).map_err(fail)?;
        self.fits.push((genus, resolution, fit));
        Ok(&self.fits.last().expect("just pushed").2)
    }

    /// How the model of `genus` was fitted, for a caption: the resolution its fit used (without
    /// meshing the plate again to find it), or `ntori new`'s if it is not fitted yet.
    fn fit_parameters(&self, genus: u32) -> String {
        let resolution = self.fits.iter().find(|(g, _, _)| *g == genus).map_or_else(
            || default_resolution(genus).unwrap_or(RESOLUTION),
            |(_, r, _)| *r,
        );
        fit_parameters(genus, resolution)
    }

    fn render(
        &mut self,
        model: &Surface,
        options: &RenderOptions,
        curves: &[Curve],
        figure: &str,
    ) -> Result<Vec<u8>, FiguresError> {
        self.offscreen
            .render_model_png(model, options, curves)
            .map_err(render_error(figure))
    }
}

fn render_error(figure: &str) -> impl FnOnce(RenderError) -> FiguresError + '_ {
    move |source| FiguresError::Render {
        figure: figure.to_owned(),
        source,
    }
}

fn embedding_error(figure: &str) -> impl FnOnce(embedding::EmbeddingError) -> FiguresError + '_ {
    move |source| FiguresError::Embedding {
        figure: figure.to_owned(),
        source,
    }
}

fn options(size: (u32, u32), view: View, style: Style) -> RenderOptions {
    RenderOptions {
        width: size.0,
        height: size.1,
        view,
        style,
        ..RenderOptions::default()
    }
}

fn describe(o: &RenderOptions) -> String {
    format!(
        "{}×{} pixels, view azimuth {}°, elevation {}°, distance {} bounding radii, style {:?}, \
         t_e = t_r = {}",
        o.width,
        o.height,
        o.view.azimuth_deg,
        o.view.elevation_deg,
        o.view.distance,
        o.style,
        o.tessellation
    )
}

fn fit_parameters(genus: u32, resolution: usize) -> String {
    let (s, f) = default_settings(genus);
    format!(
        "`embedding::fit::initial_model({genus}, {resolution}, …)` with `ntori new`'s defaults \
         (degree {}, C^{} blends, {}, smoothness {}{})",
        s.degree,
        s.continuity,
        s.grid_text(),
        f.smoothness,
        if f.surface_smoothness {
            " in the surface's arc length"
        } else {
            ""
        }
    )
}

/// The view of the genus-2 plate: from above and in front, both holes in sight.
const PLATE_VIEW: View = View {
    azimuth_deg: -70.0,
    elevation_deg: 50.0,
    distance: 3.6,
};

/// The loops a_k, b_k on the surface: each polygon side e = 4k + t (t = 0, 1) sampled as a geodesic
/// of the disk, located on the surface (in the chart that holds it deepest) and evaluated.
pub fn loops(surface: &Surface) -> Result<Vec<Curve>, embedding::EmbeddingError> {
    let atlas = surface.atlas();
    let Some(poly) = atlas.polygon() else {
        return Ok(Vec::new());
    };
    let mut curves = Vec::new();
    for e in (0..poly.sides()).filter(|e| e % 4 < 2) {
        let points = side_points(poly, e, 400)
            .into_iter()
            .filter_map(|z| {
                let p = atlas.locate_model(ModelPoint(z));
                let best = p.representations().iter().max_by(|a, b| {
                    let margin =
                        |q: &ChartPoint| atlas.charts()[q.chart.index()].domain().margin(q.coords);
                    margin(a).total_cmp(&margin(b))
                })?;
                let s = surface.eval(*best).pos;
                Some([s.x, s.y, s.z])
            })
            .collect();
        curves.push(Curve {
            points,
            colour: palette::stroke_rgb(palette::edge_kind(e)),
        });
    }
    Ok(curves)
}

/// An edit of the genus-2 surface: mesh vertices and how far each moves, and vertices that stay.
struct Scripted {
    name: &'static str,
    moved: Vec<(usize, Vector3)>,
    pinned: Vec<usize>,
}

/// "Pull the outer rim out", as a user would drag it: five points along the rim around the +x
/// direction move outwards, by up to 7% of the plate's width (less away from the middle); five
/// points on the far side are pinned.
fn pull_rim(fit: &InitialFit) -> Scripted {
    let p = &fit.mesh.positions;
    let (lo, hi) = bounding_box(p);
    let centre = Point3::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.0);
    let reach = hi.x - centre.x;
    let at = |r: f64, degrees: f64, z: f64| {
        let a = degrees.to_radians();
        centre + Vector3::new(r * a.cos(), r * a.sin(), z)
    };
    let amount = 0.07 * (hi.x - lo.x);
    let mut moved = Vec::new();
    let mut push = |q: Point3, degrees: f64| {
        let a = degrees.to_radians();
        let weight = (degrees / 40.0 * std::f64::consts::FRAC_PI_2).cos();
        moved.push((
            nearest_vertex(p, q),
            Vector3::new(a.cos(), a.sin(), 0.0) * (amount * weight),
        ));
    };
    for degrees in [-30.0, -15.0, 0.0, 15.0, 30.0] {
        push(at(reach, degrees, 0.0), degrees);
    }
    let pinned = [150.0, 165.0, 180.0, 195.0, 210.0]
        .iter()
        .map(|&d| nearest_vertex(p, at(reach, d, 0.0)))
        .collect();
    Scripted {
        name: "pull the outer rim out",
        moved,
        pinned,
    }
}

/// "Push a hole's rim up", as a user would drag it: eight points around the top rim of the hole
/// furthest towards −x rise by 60% of the plate's half-thickness; four points on the same hole's bottom rim
/// and four around the other holes are pinned.
fn push_hole(fit: &InitialFit) -> Scripted {
    let p = &fit.mesh.positions;
    let (lo, hi) = bounding_box(p);
    let half = 0.5 * (hi.z - lo.z);
    // The holes' centres: the loops a_k run around them, so their centroids lie near.
    let centres: Vec<Point3> = fit
        .mesh
        .loops
        .iter()
        .step_by(2)
        .map(|l| {
            let sum = l
                .iter()
                .fold(Vector3::zeros(), |s, &v| s + p[v as usize].coords);
            let c = sum / l.len() as f64;
            Point3::new(c.x, c.y, 0.0)
        })
        .collect();
    let k = (0..centres.len())
        .min_by(|&a, &b| centres[a].x.total_cmp(&centres[b].x))
        .unwrap_or(0);
    let radius_of = |c: Point3| {
        p.iter()
            .map(|q| (q.x - c.x).hypot(q.y - c.y))
            .fold(f64::INFINITY, f64::min)
    };
    let ring = |c: Point3, z: f64, count: usize| -> Vec<usize> {
        let r = radius_of(c) + 1.5 * half;
        (0..count)
            .map(|j| {
                let a = std::f64::consts::TAU * j as f64 / count as f64;
                nearest_vertex(p, c + Vector3::new(r * a.cos(), r * a.sin(), z))
            })
            .collect()
    };
    let moved = ring(centres[k], half, 8)
        .into_iter()
        .map(|i| (i, Vector3::new(0.0, 0.0, 0.6 * half)))
        .collect();
    let mut pinned = ring(centres[k], -half, 4);
    for (j, &c) in centres.iter().enumerate() {
        if j != k {
            pinned.extend(ring(c, half, 4));
        }
    }
    Scripted {
        name: "push a hole's rim up",
        moved,
        pinned,
    }
}

/// The mesh vertex nearest q.
fn nearest_vertex(p: &[Point3], q: Point3) -> usize {
    (0..p.len())
        .min_by(|&a, &b| (p[a] - q).norm().total_cmp(&(p[b] - q).norm()))
        .unwrap_or(0)
}

/// The edited model: the least-norm change moving the scripted points by their offsets (from where
/// the surface has them now) while the pinned points stay.
fn edited(
    fit: &InitialFit,
    script: &Scripted,
) -> Result<(Surface, String), embedding::EmbeddingError> {
    let layout = fit.surface.layout();
    let mut control = fit.surface.control_points().to_vec();
    let at = |i: usize| fit.parameterization.points[i];
    let mut constraints: Vec<Constraint> = script
        .moved
        .iter()
        .map(|&(i, offset)| Constraint {
            point: at(i),
            target: layout.eval(&control, at(i)).pos + offset,
        })
        .collect();
    constraints.extend(script.pinned.iter().map(|&i| Constraint {
        point: at(i),
        target: layout.eval(&control, at(i)).pos,
    }));
    let edit = solve(&layout, &control, &constraints)?;
    edit.apply(&mut control);
    let largest = script
        .moved
        .iter()
        .map(|(_, o)| o.norm())
        .fold(0.0, f64::max);
    let list = |items: &mut dyn Iterator<Item = usize>| {
        items.map(|i| i.to_string()).collect::<Vec<_>>().join(", ")
    };
    let text = format!(
        "{} (`embedding::edit::solve`): {} surface points (mesh vertices {}) moved by up to {:.3} \
         model units, {} pinned (mesh vertices {}); {}",
        script.name,
        script.moved.len(),
        list(&mut script.moved.iter().map(|(i, _)| *i)),
        largest,
        script.pinned.len(),
        list(&mut script.pinned.iter().copied()),
        residual_text(edit.residual)
    );
    Ok((fit.surface.with_control_points(control)?, text))
}

/// Makes one 3D figure with the studio's renderer and models.
pub type Make3d = Box<dyn FnOnce(&mut Studio) -> Result<Figure, FiguresError>>;

/// A 3D figure to make.
pub struct Job3d {
    pub file: String,
    pub make: Make3d,
}

fn png(file: &str, caption: String, parameters: String, bytes: Vec<u8>) -> Figure {
    Figure {
        file: file.to_owned(),
        caption,
        parameters,
        bytes,
    }
}

/// The 3D figures, in order.
pub fn jobs() -> Vec<Job3d> {
    let mut jobs: Vec<Job3d> = Vec::new();
    jobs.push(Job3d {
        file: "fig2b-loops.png".into(),
        make: Box::new(|studio| {
            let fit = studio.fit(GENUS, "2")?;
            let model = fit.surface.clone();
            let curves = loops(&model).map_err(embedding_error("2"))?;
            let o = options(MAIN, PLATE_VIEW, Style::Shaded);
            let bytes = studio.render(&model, &o, &curves, "2")?;
            Ok(png(
                "fig2b-loops.png",
                "Right half of figure 2: the genus-2 surface with the loops a₁ b₁ a₂ b₂ drawn on it, \
                 each in its edge pair's colour (as in figures 1 and 2, left). The loops are the \
                 polygon's sides: each side is sampled as a geodesic of the Poincaré disk, located on \
                 the surface (`Atlas::locate_model`) and evaluated (`Layout::eval`). They all pass \
                 through the surface's one vertex. Which of a_k and b_k runs around hole k and which \
                 through it is the fit's choice; the paper notes that an embedding may swap them."
                    .into(),
                format!("{}; {}; 400 samples per loop", studio.fit_parameters(GENUS), describe(&o)),
                bytes,
            ))
        }),
    });
    jobs.push(Job3d {
        file: "fig6a-input-mesh.png".into(),
        make: Box::new(|studio| {
            let fit = studio.fit(GENUS, "6")?;
            let positions: Vec<[f64; 3]> = fit.mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
            let triangles = fit.mesh.triangles.clone();
            let o = options(MAIN, PLATE_VIEW, Style::Shaded);
            let bytes = studio
                .offscreen
                .render_mesh_png(&positions, &triangles, &o)
                .map_err(render_error("6"))?;
            Ok(png(
                "fig6a-input-mesh.png",
                format!(
                    "Figure 6, upper left: the n-holed input mesh the fit starts from \
                     (`embedding::holed::HoledMesh::new(2, {RESOLUTION})`: {} vertices, {} triangles), \
                     flat shaded.",
                    positions.len(),
                    triangles.len()
                ),
                describe(&o),
                bytes,
            ))
        }),
    });
    jobs.push(Job3d {
        file: "fig6b-fitted.png".into(),
        make: Box::new(|studio| {
            let fit = studio.fit(GENUS, "6")?;
            let (model, rms, diag) = (fit.surface.clone(), fit.rms_residual, fit.mesh_diagonal);
            let o = options(MAIN, PLATE_VIEW, Style::Shaded);
            let bytes = studio.render(&model, &o, &[], "6")?;
            Ok(png(
                "fig6b-fitted.png",
                format!(
                    "Figure 6, lower left: the smooth surface fitted to that mesh (rms residual \
                     {:.3}% of the mesh's diagonal).",
                    100.0 * rms / diag
                ),
                format!("{}; {}", studio.fit_parameters(GENUS), describe(&o)),
                bytes,
            ))
        }),
    });
    for (file, corner, script) in [
        (
            "fig6c-edit-rim.png",
            "upper right",
            pull_rim as fn(&InitialFit) -> Scripted,
        ),
        ("fig6d-edit-hole.png", "lower right", push_hole),
    ] {
        jobs.push(Job3d {
            file: file.into(),
            make: Box::new(move |studio| {
                let fit = studio.fit(GENUS, "6")?;
                let (model, what) = edited(fit, &script(fit)).map_err(embedding_error("6"))?;
                let o = options(MAIN, PLATE_VIEW, Style::Shaded);
                let bytes = studio.render(&model, &o, &[], "6")?;
                Ok(png(
                    file,
                    format!(
                        "Figure 6, {corner}: the fitted surface after a scripted direct-manipulation \
                         edit, the smallest change of the control points that moves the chosen \
                         surface points to their targets and keeps the pinned ones: {what}."
                    ),
                    format!("{}; {}", studio.fit_parameters(GENUS), describe(&o)),
                    bytes,
                ))
            }),
        });
    }
    let shaded = GALLERY_GENERA.map(|genus| (genus, Style::Shaded, "shaded", ""));
    let mean = GALLERY_MEAN_CURVATURE_GENERA.map(|genus| {
        let style = Style::Curvature(CurvatureKind::Mean);
        (
            genus,
            style,
            "in mean curvature on a diverging scale",
            "-mean",
        )
    });
    for (genus, style, what, suffix) in shaded.into_iter().chain(mean) {
        let file = format!("gallery-genus{genus}{suffix}.png");
        jobs.push(Job3d {
            file: file.clone(),
            make: Box::new(move |studio| {
                let model = studio.fit(genus, "gallery")?.surface.clone();
                let view = if genus >= 2 {
                    PLATE_VIEW
                } else {
                    View::default()
                };
                let o = RenderOptions {
                    tessellation: crate::render::default_tessellation(genus),
                    ..options(GALLERY, view, style)
                };
                let bytes = studio.render(&model, &o, &[], "gallery")?;
                Ok(png(
                    &file,
                    format!("Gallery: the initial model of genus {genus}, {what}."),
                    format!("{}; {}", studio.fit_parameters(genus), describe(&o)),
                    bytes,
                ))
            }),
        });
    }
    for (file, style, what) in [
        (
            "gallery-genus2-charts.png",
            Style::Charts,
            "each point coloured by its blend weights, one colour per chart (the renderer's chart colours)",
        ),
        (
            "gallery-genus2-gaussian.png",
            Style::Curvature(CurvatureKind::Gaussian),
            "Gaussian curvature on a diverging scale, with its legend",
        ),
        (
            "gallery-genus2-mean.png",
            Style::Curvature(CurvatureKind::Mean),
            "mean curvature on a diverging scale, with its legend",
        ),
    ] {
        jobs.push(Job3d {
            file: file.into(),
            make: Box::new(move |studio| {
                let model = studio.fit(GENUS, "gallery")?.surface.clone();
                let o = options(GALLERY, PLATE_VIEW, style);
                let bytes = studio.render(&model, &o, &[], "gallery")?;
                Ok(png(
                    file,
                    format!("Gallery: the genus-2 model, {what}."),
                    format!("{}; {}", studio.fit_parameters(GENUS), describe(&o)),
                    bytes,
                ))
            }),
        });
    }
    jobs
}

/// The edit's residual for a caption. Below 1e-12 it is rounding, whose last digits change with the
/// compiler and its settings; a caption printed them, so a rebuild changed the captions file.
fn residual_text(residual: f64) -> String {
    if residual < 1e-12 {
        "residual below 1e-12 (rounding)".into()
    } else {
        format!("residual {residual:.1e}")
    }
}
