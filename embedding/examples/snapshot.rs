//! A CPU snapshot of a fitted surface, to look at while the GPU renderer is not there yet:
//! `cargo run --release -p embedding --example snapshot -- GENUS OUT.png [AZIMUTH ELEVATION] [mesh]`.
//! Tessellates at t = 24, evaluates positions and normals through the stencil, and rasterises with a
//! z-buffer and two-sided Lambert shading; `mesh` draws the input mesh instead.
use charts::Atlas;
use embedding::fit::{FitSettings, initial_model};
use embedding::{Layout, Point3, SplineSettings, Stencil, Vector3};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let genus: u32 = args[1].parse().unwrap();
    let out = &args[2];
    let az: f64 = args
        .get(3)
        .map_or(30.0f64, |s| s.parse().unwrap())
        .to_radians();
    let el: f64 = args
        .get(4)
        .map_or(35.0f64, |s| s.parse().unwrap())
        .to_radians();
    let show_mesh = args.get(5).is_some_and(|s| s == "mesh");
    let show_charts = args.get(5).is_some_and(|s| s == "charts");
    let env = |k: &str, d: f64| std::env::var(k).map_or(d, |s| s.parse().unwrap());
    let settings = SplineSettings {
        grid: env("GRID", 12.0) as usize,
        ..SplineSettings::default()
    };
    let fit_settings = FitSettings {
        smoothness: env("LAMBDA", 1e-4),
        patch_weight: env("PATCH", 1.0),
        stretch_rounds: env("STRETCH", FitSettings::default().stretch_rounds as f64) as usize,
        ..FitSettings::default()
    };
    let fit = initial_model(genus, env("RES", 32.0) as usize, settings, fit_settings).unwrap();
    eprintln!(
        "max residual {:.3}%",
        100.0 * fit.max_residual / fit.mesh_diagonal
    );
    let mut colours: Vec<[f64; 3]> = Vec::new();
    let (pos, nor, tris) = if show_mesh {
        let n = vec![Vector3::zeros(); fit.mesh.positions.len()];
        (fit.mesh.positions.clone(), n, fit.mesh.triangles.clone())
    } else {
        let atlas = Atlas::new(genus).unwrap();
        let layout = Layout::new(&atlas, settings).unwrap();
        let t = atlas.tessellate(24, 24).unwrap();
        let stencil = Stencil::build(&layout, &t.vertices);
        let control = fit.surface.control_points().to_vec();
        let mut pos = vec![Point3::origin(); t.vertices.len()];
        let mut nor = vec![Vector3::zeros(); t.vertices.len()];
        stencil.positions(&control, &mut pos);
        stencil.normals(&control, &mut nor);
        if show_charts {
            let palette = [
                [0.9, 0.3, 0.3],
                [0.3, 0.8, 0.3],
                [0.3, 0.4, 0.95],
                [0.95, 0.8, 0.2],
                [0.8, 0.3, 0.9],
                [0.2, 0.85, 0.85],
                [0.95, 0.55, 0.2],
                [0.6, 0.6, 0.6],
            ];
            colours = t
                .vertices
                .iter()
                .map(|p| {
                    let mut c = [0.0; 3];
                    for (chart, b) in layout.blends(*p) {
                        let k = palette[chart.index() % palette.len()];
                        for ch in 0..3 {
                            c[ch] += b * k[ch];
                        }
                    }
                    c
                })
                .collect();
        }
        (pos, nor, t.triangles)
    };
    let (w, h) = (900usize, 700usize);
    // View: rotate about z by the azimuth, then tilt by the elevation; look down −y'.
    // Positions and normals alike, as vectors (a rotation).
    let view = |p: &Vector3| {
        let (x, y) = (
            p.x * az.cos() - p.y * az.sin(),
            p.x * az.sin() + p.y * az.cos(),
        );
        let (y2, z2) = (y * el.cos() - p.z * el.sin(), y * el.sin() + p.z * el.cos());
        Vector3::new(x, z2, y2) // screen x, screen y (up), depth (towards the viewer is smaller)
    };
    let v: Vec<Vector3> = pos.iter().map(|p| view(&p.coords)).collect();
    let (mut lo, mut hi) = (Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN));
    for p in &v {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let scale = 0.9 * (w as f64 / (hi.x - lo.x)).min(h as f64 / (hi.y - lo.y));
    let centre = (lo + hi) / 2.0;
    let px = |p: &Vector3| {
        (
            w as f64 / 2.0 + (p.x - centre.x) * scale,
            h as f64 / 2.0 - (p.y - centre.y) * scale,
        )
    };
    let mut depth = vec![f64::MAX; w * h];
    let mut rgb = vec![255u8; w * h * 3];
    let light = Vector3::new(-0.4, 0.8, -0.6).normalize(); // in view space
    for t in &tris {
        let [a, b, c] = t.map(|i| v[i as usize]);
        let (pa, pb, pc) = (px(&a), px(&b), px(&c));
        let face = {
            let [x, y, z] = t.map(|i| pos[i as usize]);
            (y - x).cross(&(z - x)).normalize()
        };
        let area = (pb.0 - pa.0) * (pc.1 - pa.1) - (pb.1 - pa.1) * (pc.0 - pa.0);
        if area.abs() < 1e-12 {
            continue;
        }
        let x0 = pa.0.min(pb.0).min(pc.0).floor().max(0.0) as usize;
        let x1 = (pa.0.max(pb.0).max(pc.0).ceil() as usize).min(w - 1);
        let y0 = pa.1.min(pb.1).min(pc.1).floor().max(0.0) as usize;
        let y1 = (pa.1.max(pb.1).max(pc.1).ceil() as usize).min(h - 1);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (qx, qy) = (x as f64 + 0.5, y as f64 + 0.5);
                let l0 = ((pb.0 - qx) * (pc.1 - qy) - (pb.1 - qy) * (pc.0 - qx)) / area;
                let l1 = ((pc.0 - qx) * (pa.1 - qy) - (pc.1 - qy) * (pa.0 - qx)) / area;
                let l2 = 1.0 - l0 - l1;
                if l0 < 0.0 || l1 < 0.0 || l2 < 0.0 {
                    continue;
                }
                let d = l0 * a.z + l1 * b.z + l2 * c.z;
                let k = y * w + x;
                if d >= depth[k] {
                    continue;
                }
                depth[k] = d;
                let n = if show_mesh {
                    face
                } else {
                    let [na, nb, nc] = t.map(|i| nor[i as usize]);
                    (na * l0 + nb * l1 + nc * l2).normalize()
                };
                let nv = view(&n);
                let lambert = nv.dot(&light).abs();
                let shade = 0.18 + 0.82 * lambert;
                let col = if colours.is_empty() {
                    [0.55, 0.68, 0.9]
                } else {
                    let [ca, cb, cc] = t.map(|i| colours[i as usize]);
                    [0, 1, 2].map(|ch| ca[ch] * l0 + cb[ch] * l1 + cc[ch] * l2)
                };
                for ch in 0..3 {
                    rgb[3 * k + ch] = (255.0 * (col[ch] * shade).min(1.0)) as u8;
                }
            }
        }
    }
    let file = std::fs::File::create(out).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header().unwrap().write_image_data(&rgb).unwrap();
}
