//! The offscreen renderer on whatever adapter the machine has (Mesa's lavapipe in CI): pictures are
//! non-trivial, styles differ as they should, and the same input gives the same bytes.

use embedding::Surface;
use ntori::render::{CurvatureKind, Image, Offscreen, RenderError, RenderOptions, Style, View};

fn model() -> Surface {
    crate::common::small_model(2).clone()
}

fn offscreen() -> Offscreen {
    Offscreen::new().expect("a graphics adapter (CI installs mesa-vulkan-drivers)")
}

fn options(style: Style) -> RenderOptions {
    RenderOptions {
        width: 320,
        height: 240,
        style,
        tessellation: 12,
        ..RenderOptions::default()
    }
}

/// Pixels that are not the white background.
fn surface_pixels(image: &Image) -> Vec<[u8; 3]> {
    image
        .rgba
        .chunks(4)
        .filter(|p| p[..3] != [255, 255, 255])
        .map(|p| [p[0], p[1], p[2]])
        .collect()
}

fn luminance(p: [u8; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

#[test]
fn the_default_view_shows_a_shaded_surface_and_is_stable() {
    let model = model();
    let mut gpu = offscreen();
    let image = gpu
        .render_model(&model, &options(Style::Shaded), &[])
        .unwrap();
    assert_eq!((image.width, image.height), (320, 240));
    assert_eq!(image.rgba.len(), 320 * 240 * 4);
    let surface = surface_pixels(&image);
    let covered = surface.len() as f64 / (320.0 * 240.0);
    assert!(
        (0.15..0.85).contains(&covered),
        "the surface covers {covered:.2} of the picture"
    );
    let lum: Vec<f64> = surface.iter().map(|&p| luminance(p)).collect();
    let mean = lum.iter().sum::<f64>() / lum.len() as f64;
    let sd = (lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lum.len() as f64).sqrt();
    assert!(sd > 10.0, "shading hardly varies (sd {sd:.1})");
    // Same input, same bytes; a different view, different bytes.
    let a = gpu
        .render_model_png(&model, &options(Style::Shaded), &[])
        .unwrap();
    let b = gpu
        .render_model_png(&model, &options(Style::Shaded), &[])
        .unwrap();
    assert_eq!(a, b);
    let mut turned = options(Style::Shaded);
    turned.view.azimuth_deg += 90.0;
    assert_ne!(a, gpu.render_model_png(&model, &turned, &[]).unwrap());
    assert_eq!(&a[1..4], b"PNG");
}

#[test]
fn styles_colour_the_surface_as_they_say() {
    let model = model();
    let mut gpu = offscreen();
    let shaded = gpu
        .render_model(&model, &options(Style::Shaded), &[])
        .unwrap();
    let wire = gpu
        .render_model(&model, &options(Style::Wireframe), &[])
        .unwrap();
    // Wireframe darkens the edges: more dark pixels than plain shading.
    let dark = |im: &Image| {
        surface_pixels(im)
            .iter()
            .filter(|&&p| luminance(p) < 60.0)
            .count()
    };
    assert!(
        dark(&wire) > dark(&shaded) + 500,
        "{} vs {}",
        dark(&wire),
        dark(&shaded)
    );
    // Charts: several clearly different hues.
    let charts = gpu
        .render_model(&model, &options(Style::Charts), &[])
        .unwrap();
    let mut hues: Vec<u8> = surface_pixels(&charts)
        .iter()
        .filter(|p| p.iter().max().unwrap() - p.iter().min().unwrap() > 60)
        .map(|p| {
            let i = (0..3).max_by_key(|&i| p[i]).unwrap();
            let j = (0..3).filter(|&j| j != i).max_by_key(|&j| p[j]).unwrap();
            (3 * i + j) as u8
        })
        .collect();
    hues.sort_unstable();
    hues.dedup();
    assert!(hues.len() >= 3, "chart colours: {hues:?}");
    // Curvature: the holes' saddles are blue, the outer rim red, and a legend is drawn.
    let k = gpu
        .render_model(
            &model,
            &options(Style::Curvature(CurvatureKind::Gaussian)),
            &[],
        )
        .unwrap();
    let px = surface_pixels(&k);
    let blue = px
        .iter()
        .filter(|p| i32::from(p[2]) > i32::from(p[0]) + 60)
        .count();
    let red = px
        .iter()
        .filter(|p| i32::from(p[0]) > i32::from(p[2]) + 40)
        .count();
    assert!(blue > 100 && red > 100, "blue {blue}, red {red}");
}

#[test]
fn curves_are_drawn_on_top() {
    let model = model();
    let mut gpu = offscreen();
    let plain = gpu
        .render_model(&model, &options(Style::Shaded), &[])
        .unwrap();
    let ring: Vec<[f64; 3]> = (0..=64)
        .map(|i| {
            let a = std::f64::consts::TAU * f64::from(i) / 64.0;
            [3.0 * a.cos(), 3.0 * a.sin(), 0.6]
        })
        .collect();
    let curve = ntori::render::Curve {
        points: ring,
        colour: [1.0, 0.0, 0.0],
    };
    let with = gpu
        .render_model(&model, &options(Style::Shaded), &[curve])
        .unwrap();
    let red = |im: &Image| {
        im.rgba
            .chunks(4)
            .filter(|p| p[0] > 200 && p[1] < 40)
            .count()
    };
    assert_eq!(red(&plain), 0);
    assert!(red(&with) > 200, "{} red pixels", red(&with));
}

#[test]
fn impossible_requests_are_errors() {
    let model = model();
    let mut gpu = offscreen();
    for (w, h) in [(0, 10), (10, 0), (100_000, 10)] {
        let o = RenderOptions {
            width: w,
            height: h,
            ..options(Style::Shaded)
        };
        assert!(matches!(
            gpu.render_model(&model, &o, &[]),
            Err(RenderError::Size { .. })
        ));
    }
    for view in [
        View {
            elevation_deg: 95.0,
            ..View::default()
        },
        View {
            distance: 0.5,
            ..View::default()
        },
        View {
            azimuth_deg: f64::NAN,
            ..View::default()
        },
    ] {
        let o = RenderOptions {
            view,
            ..options(Style::Shaded)
        };
        assert!(matches!(
            gpu.render_model(&model, &o, &[]),
            Err(RenderError::View(_))
        ));
    }
    // A model that does not match its settings never becomes a surface to render.
    let mut broken = model.to_model();
    broken.control_points.pop();
    assert!(embedding::Surface::from_model(&broken).is_err());
    assert!(
        gpu.render_mesh_png(&[[0.0; 3]], &[[0, 1, 2]], &options(Style::Shaded))
            .is_err()
    );
}

/// The GPU's re-embedding (a compute shader over the tensor stencil) equals the CPU's f64 stencil to
/// 1e-6 of the bounding-box diagonal, on the example models of genus 0–3 moved far from the origin
/// and on surfaces whose disk charts have a finer grid than their edge charts (a block's lines are
/// its own chart's grid apart), at tessellations of many 64-row workgroups (the last one partly
/// full); built with tangents, its first derivatives equal the f64 stencil's to 1e-5 of the
/// largest.
#[test]
fn gpu_reembedding_equals_the_cpu_to_a_millionth_of_the_diagonal() {
    use embedding::{Point3, SplineSettings, Stencil, Surface, TensorStencil, Vector3};
    let (device, queue, _) = ntori::render::open_device(None).expect("a graphics adapter");
    let with_disk_grid = |genus: u32, disk: usize| {
        let atlas = std::sync::Arc::new(charts::Atlas::new(genus).unwrap());
        let settings = SplineSettings {
            grid: 8,
            disk_grid: Some(disk),
            ..SplineSettings::default()
        };
        let count = embedding::Layout::new(&atlas, settings)
            .unwrap()
            .control_count();
        // Smooth enough to have normals, different at every control point.
        let control = (0..count)
            .map(|i| {
                let t = i as f64;
                Point3::new((0.37 * t).sin(), (0.23 * t).cos(), 1e-3 * t)
            })
            .collect();
        Surface::new(atlas, settings, control).unwrap()
    };
    let models = (0..=3)
        .map(|genus| crate::common::small_model(genus).clone())
        .chain([
            with_disk_grid(2, 13),
            with_disk_grid(3, 11),
            with_disk_grid(0, 9),
        ]);
    for model in models {
        let genus = model.genus();
        let shift = Vector3::new(250.0, -1e3, 40.0);
        let control: Vec<Point3> = model.control_points().iter().map(|c| c + shift).collect();
        let layout = model.layout();
        let points = model.atlas().tessellate(9, 7).unwrap().vertices;
        let exact_stencil = Stencil::build(&layout, &points);
        let mut exact = vec![Point3::origin(); points.len()];
        exact_stencil.positions(&control, &mut exact);
        let gpu = ntori::render::reembed::GpuReembed::new(
            &device,
            &TensorStencil::build(&layout, &points),
            control.len(),
        )
        .unwrap();
        assert_eq!(gpu.rows(), points.len());
        let mut out = vec![Point3::origin(); points.len()];
        gpu.positions(&device, &queue, &control, &mut out).unwrap();
        let (lo, hi) = embedding::bounding_box(&exact);
        let diagonal = (hi - lo).norm();
        let worst = out
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-6 * diagonal,
            "genus {genus}: off by {:e} of the diagonal",
            worst / diagonal
        );
        // A second upload of other control points replaces the first.
        let moved: Vec<Point3> = control
            .iter()
            .map(|c| c + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        gpu.positions(&device, &queue, &moved, &mut out).unwrap();
        assert!((out[0] - (exact[0] + Vector3::new(1.0, 2.0, 3.0))).norm() <= 1e-6 * diagonal);
        // Built with tangents: the first derivatives too, to 1e-5 of the largest.
        let with_tangents = ntori::render::reembed::GpuReembed::new(
            &device,
            &TensorStencil::build_with_tangents(&layout, &points),
            control.len(),
        )
        .unwrap();
        assert!(with_tangents.has_tangents() && !gpu.has_tangents());
        let mut tangents = vec![[Vector3::zeros(); 2]; points.len()];
        with_tangents
            .positions_and_tangents(&device, &queue, &control, &mut out, &mut tangents)
            .unwrap();
        let exact_tangents: Vec<[Vector3; 2]> = (0..points.len())
            .map(|r| exact_stencil.position_and_tangents(&control, r).1)
            .collect();
        let scale = exact_tangents
            .iter()
            .flatten()
            .map(|t| t.norm())
            .fold(0.0, f64::max);
        for (r, ((p, t), (e, et))) in out
            .iter()
            .zip(&tangents)
            .zip(exact.iter().zip(&exact_tangents))
            .enumerate()
        {
            assert!((p - e).norm() <= 1e-6 * diagonal, "genus {genus} row {r}");
            for (a, b) in t.iter().zip(et) {
                let off = (a - b).norm() / scale;
                assert!(off <= 1e-5, "genus {genus} row {r}: tangent off by {off:e}");
            }
        }
    }
}

/// `ntori render`'s default tessellation: finer from genus 8 on, where t = 32 is coarse on the outer
/// rim, but never past its triangle budget, so every genus renders by default.
#[test]
fn the_default_tessellation_is_finer_at_high_genus_within_its_budget() {
    use ntori::render::{DEFAULT_MAX_TRIANGLES, MAX_TRIANGLES, default_tessellation};
    for genus in 0..=charts::MAX_GENUS {
        let t = default_tessellation(genus);
        let triangles = charts::Tessellation::expected_triangles(genus, t, t);
        assert!(t == 32 || t == 64, "genus {genus}: {t}");
        assert!(t == 32 || genus >= 8, "genus {genus}: {t}");
        assert!(
            t == 32 || triangles <= DEFAULT_MAX_TRIANGLES,
            "genus {genus}: {triangles}"
        );
        assert!(triangles <= MAX_TRIANGLES, "genus {genus}: {triangles}");
    }
    for genus in [0, 1, 2, 3, 7] {
        assert_eq!(default_tessellation(genus), 32, "genus {genus}");
    }
    for genus in [8, 10, 13] {
        assert_eq!(default_tessellation(genus), 64, "genus {genus}");
    }
    // From genus 14 the wheels take more rings than t_r, and t = 64 is past the budget.
    for genus in [14, 16, 32, 64] {
        assert_eq!(default_tessellation(genus), 32, "genus {genus}");
    }
}
