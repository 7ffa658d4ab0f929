//! Issue 12's shape measures for the default fit at several genera: patch disagreement (as a
//! fraction of the mesh diagonal), the largest principal curvature, and the normal deviation from
//! the intended shape at the input mesh's vertices.
//! `cargo run --release -p embedding --example shape_report [GENERA…]`
use std::time::Instant;

use embedding::SplineSettings;
use embedding::fit::{
    FitSettings, default_disk_grid, default_grid, default_plate_smoothness, initial_model,
    plate_surface_smoothness,
};
use embedding::quality::{
    max_principal_curvature, normal_deviation_from, patch_disagreement, sample_points,
};

fn main() {
    let genera: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a genus"))
        .collect();
    let genera = if genera.is_empty() {
        vec![0, 1, 2, 3, 5, 8]
    } else {
        genera
    };
    println!(
        "genus  fit(s)  disagreement(max, rms; % of diagonal)  max|κ|   normal deviation from the intended shape (median, p90, max; degrees)"
    );
    for genus in genera {
        let start = Instant::now();
        // NTORI_GRID, NTORI_DISK_GRID, NTORI_PATCH_WEIGHT, NTORI_SMOOTHNESS, NTORI_RESOLUTION and
        // NTORI_SURFACE_SMOOTHNESS (1 or 0)
        // override `ntori new`'s defaults, for tuning.
        let defaults = FitSettings::for_plate(genus, embedding::fit::default_settings(genus).0);
        let setting = |name: &str, default: f64| {
            std::env::var(name).map_or(default, |v| v.parse().expect("a number"))
        };
        let grid = setting("NTORI_GRID", default_grid(genus) as f64) as usize;
        let spline = SplineSettings {
            grid,
            disk_grid: std::env::var("NTORI_DISK_GRID")
                .map_or(default_disk_grid(genus, grid), |v| {
                    Some(v.parse().expect("a grid"))
                }),
            ..SplineSettings::default()
        };
        let settings = FitSettings {
            patch_weight: setting("NTORI_PATCH_WEIGHT", defaults.patch_weight),
            smoothness: setting(
                "NTORI_SMOOTHNESS",
                default_plate_smoothness(genus, spline.grid),
            ),
            stretch_rounds: setting("NTORI_STRETCH_ROUNDS", defaults.stretch_rounds as f64)
                as usize,
            surface_smoothness: setting(
                "NTORI_SURFACE_SMOOTHNESS",
                f64::from(u8::from(plate_surface_smoothness(genus, spline.grid))),
            ) != 0.0,
            ..defaults
        };
        let resolution = setting(
            "NTORI_RESOLUTION",
            embedding::fit::default_resolution(genus).expect("a resolution") as f64,
        ) as usize;
        let fit = initial_model(genus, resolution, spline, settings).expect("the fit");
        let seconds = start.elapsed().as_secs_f64();
        let s = &fit.surface;
        let points = sample_points(s, 32).expect("a tessellation");
        let d = patch_disagreement(s, &points, 0.1);
        let k = max_principal_curvature(s, &points);
        let n = normal_deviation_from(s, &fit.parameterization.points, &fit.mesh.normals);
        let flat = flat_faces(&fit);
        println!(
            "{genus:5}  {seconds:6.1}  {:8.3}% {:8.3}%                        {:7.2}  {:6.2} {:6.2} {:6.2}",
            100.0 * d.max / fit.mesh_diagonal,
            100.0 * d.rms / fit.mesh_diagonal,
            k.max_abs,
            n.median,
            n.p90,
            n.max
        );
        if let Some(at) = k.at {
            let p = s.position(at);
            let jet = s.eval(at);
            println!(
                "       largest |κ| at ({:.3}, {:.3}, {:.3}), radius {:.3}, in chart {:?}; normal z {:.3}",
                p.x,
                p.y,
                p.z,
                p.x.hypot(p.y),
                at.chart,
                jet.normal().z
            );
            let blends = s.layout().blends(at);
            println!("       blends there: {blends:?}");
        }
        if let Some((p90, h_median, h_p90, count)) = flat {
            println!(
                "       flat faces ({count} vertices): normal off ±z by {p90:.2}° (90%), |H|·T {h_median:.4} median, {h_p90:.4} (90%)"
            );
        }
    }
}

/// On the plate's flat faces (`HoledMesh::flat_vertices`) the intended normal is ±z and the mean
/// curvature 0: the 90th percentile of the surface normal's angle from ±z, and of |H|·T (median,
/// 90%; T the half-thickness), weighted by the input's vertex areas
/// (`embedding::quality::flat_faces`, as `ntori new` reports them); with NTORI_CENTROIDS set, at
/// the centres of the flat faces' triangles instead, between the points the fit sees. `None` for
/// the sphere and the torus.
fn flat_faces(fit: &embedding::fit::InitialFit) -> Option<(f64, f64, f64, usize)> {
    let mesh = &fit.mesh;
    let flat = mesh.flat_vertices();
    let areas = embedding::fit::vertex_areas(&mesh.positions, &mesh.triangles);
    let mut is_flat = vec![false; mesh.positions.len()];
    for &i in &flat {
        is_flat[i] = true;
    }
    let (points, (normals, weights)): (Vec<_>, (Vec<_>, Vec<f64>)) =
        if std::env::var("NTORI_CENTROIDS").is_ok() {
            let disk = fit.parameterization.disk.as_ref()?;
            let original = |c: u32| disk.original[c as usize] as usize;
            disk.triangles
                .iter()
                .filter(|t| t.iter().all(|&c| is_flat[original(c)]))
                .map(|t| {
                    let z = t
                        .iter()
                        .map(|&c| fit.parameterization.copies[c as usize])
                        .sum::<num_complex::Complex64>()
                        / 3.0;
                    let area: f64 = t.iter().map(|&c| areas[original(c)]).sum();
                    let point = fit
                        .surface
                        .atlas()
                        .locate_model(charts::ModelPoint(z))
                        .representations()[0];
                    (point, (mesh.normals[original(t[0])], area))
                })
                .unzip()
        } else {
            flat.iter()
                .map(|&i| (fit.parameterization.points[i], (mesh.normals[i], areas[i])))
                .unzip()
        };
    let f = embedding::quality::flat_faces(&fit.surface, &points, &normals, &weights)?;
    Some((
        f.normal_p90,
        f.mean_curvature_median * mesh.thickness,
        f.mean_curvature_p90 * mesh.thickness,
        f.points,
    ))
}
