//! Issue 14's acceptance measures on meshes that are not plates: a knotted tube (genus 1), a
//! pretzel (genus 3), a cube with tunnels (genus 5), an animal with thin legs (genus 0), and a plate of about 200 000 triangles, each
//! fitted as a user's mesh (`mesh_model`, `ntori fit`'s grid): folds, the two-sided Hausdorff
//! distance between the input and the surface's t = 32 tessellation, the normals against the mesh's
//! own at the 95th percentile, Gauss–Bonnet, the loops' canonical words, and the time.
//!
//! `cargo run --release -p embedding --example acceptance [SCALE] [--large]`: SCALE (default 1)
//! multiplies each mesh's resolution; `--large` adds the 203 056-triangle plate (a minute and a half). GRID,
//! DISK_GRID, SMOOTHNESS, AGREEMENT, EDGE_SAMPLES, ROUNDS and EVEN (rounds of evening out) override `ntori fit`'s settings; DUMP=DIR writes each mesh
//! there as OBJ; ONLY=TEXT fits only the meshes whose names contain TEXT.
#[path = "../tests/shapes/mod.rs"]
mod shapes;

use std::time::Instant;

use embedding::fit::FitSettings;
use embedding::holed::HoledMesh;
use embedding::integrals::{cells_per_knot, surface_integrals};
use embedding::mesh_fit;
use embedding::quality;
use embedding::{Point3, SplineSettings};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scale: f64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(1.0);
    let mut cases: Vec<(&str, shapes::Mesh)> = vec![
        (
            "trefoil tube",
            shapes::trefoil_tube((160.0 * scale) as usize, (16.0 * scale) as usize, 0.45),
        ),
        ("pretzel", shapes::pretzel(0.12 / scale)),
        ("cube with tunnels", shapes::cube_with_tunnels(0.1 / scale)),
        (
            "pretzel, evened out",
            shapes::even_pretzel(0.12 / scale, 10),
        ),
        (
            "cube with tunnels, evened out",
            shapes::even_cube_with_tunnels(0.1 / scale, 10),
        ),
        ("animal", shapes::animal(0.07 / scale)),
    ];
    if args.iter().any(|a| a == "--large") {
        let plate = HoledMesh::new(4, 109).expect("a plate");
        cases.push(("genus-4 plate, large", (plate.positions, plate.triangles)));
    }
    let only = std::env::var("ONLY").ok();
    for (name, (positions, triangles)) in &cases {
        if only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        if let Ok(dir) = std::env::var("DUMP") {
            dump(
                &std::path::Path::new(&dir).join(format!("{}.obj", name.replace([' ', ','], "-"))),
                positions,
                triangles,
            );
        }
        report(name, positions, triangles);
    }
}

/// Writes a mesh as OBJ (DUMP=DIR), to fit or look at with `ntori`.
fn dump(path: &std::path::Path, positions: &[Point3], triangles: &[[u32; 3]]) {
    use std::fmt::Write as _;
    let mut text = String::new();
    for p in positions {
        writeln!(text, "v {} {} {}", p.x, p.y, p.z).expect("a string");
    }
    for t in triangles {
        writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).expect("a string");
    }
    std::fs::write(path, text).expect("a writable DUMP directory");
}

fn report(name: &str, positions: &[Point3], triangles: &[[u32; 3]]) {
    let env = |name: &str| std::env::var(name).ok().and_then(|g| g.parse::<f64>().ok());
    // χ = V − E + F with E = 3F/2 on a closed triangle mesh.
    let euler = positions.len() as i64 - triangles.len() as i64 / 2;
    let genus = u32::try_from((2 - euler) / 2).expect("a closed orientable mesh");
    let (defaults, fit_defaults) = mesh_fit::default_settings(genus, positions.len());
    let grid = env("GRID").map_or(defaults.grid, |g| g as usize);
    let settings = SplineSettings {
        grid,
        disk_grid: env("DISK_GRID").map_or(mesh_fit::mesh_fit_disk_grid(genus, grid), |g| {
            Some(g as usize)
        }),
        ..defaults
    };
    let start = Instant::now();
    let rounds = env("ROUNDS").map_or(fit_defaults.stretch_rounds, |r| r as usize);
    let fit_settings = FitSettings {
        stretch_rounds: rounds,
        even_rounds: env("EVEN").map_or(fit_defaults.even_rounds, |r| r as usize),
        smoothness: env("SMOOTHNESS").unwrap_or(embedding::fit::default_smoothness(grid)),
        raise_smoothness: env("SMOOTHNESS").is_none(),
        agreement: env("AGREEMENT").unwrap_or(fit_defaults.agreement),
        raise_agreement: env("AGREEMENT").is_none(),
        edge_samples: env("EDGE_SAMPLES").unwrap_or(fit_defaults.edge_samples),
        ..fit_defaults
    };
    let user = match mesh_fit::fit_user_mesh(positions, triangles, settings, fit_settings, &|_| {})
    {
        Ok(user) => user,
        Err(e) => {
            println!(
                "{name}: {} vertices, {} triangles: {e}",
                positions.len(),
                triangles.len()
            );
            return;
        }
    };
    if let Some(split) = &user.split {
        println!("  long edges split: {} vertices added", split.added);
    }
    // As `ntori fit` measures: on the mesh the fit went through (the same surface).
    let (positions, triangles) = user.mesh(positions, triangles);
    let fit = user.fit.clone();
    let seconds = start.elapsed().as_secs_f64();
    let diagonal = fit.mesh_diagonal;
    let surface = &fit.surface;
    let distance = quality::hausdorff_to_mesh(surface, 32, positions, triangles).expect("measured");
    let normals =
        quality::normal_deviation(surface, &fit.parameterization.points, positions, triangles);
    let layout = surface.layout();
    let sums = surface_integrals(
        &layout,
        surface.control_points(),
        cells_per_knot(layout.settings()),
    );
    let gauss_bonnet = sums.gauss_bonnet_error(fit.genus);
    if let Some(e) = fit.evening {
        println!("  evened out: {e:?}");
    }
    let tried: Vec<String> = fit
        .smoothness
        .tried
        .iter()
        .map(|t| {
            format!(
                "{} ({:.2}× its tolerance)",
                t.smoothness,
                t.roughness.excess()
            )
        })
        .collect();
    println!("  λ {} (tried: {})", fit.smoothness.used, tried.join(", "));
    if let Some(d) = fit.parameterization.map_distortion {
        println!("  map distortion: {d:?}");
    }
    let longest_word = fit.loops.canonical.iter().map(Vec::len).max().unwrap_or(0);
    println!(
        "{name}: {} vertices, {} triangles, genus {}, fitted in {seconds:.1} s\n  \
         folded {}, residual max {:.3}% of the diagonal, Hausdorff {:.3}% (input to surface \
         {:.3}%, surface to input {:.3}%)\n  normals median {:.2}°, 90% {:.2}°, 95% {:.2}°, max \
         {:.1}°; Gauss–Bonnet {gauss_bonnet:.1e}\n  loops: {} through vertex {}, relation of {} \
         letters, canonical words of up to {longest_word} letters",
        positions.len(),
        triangles.len(),
        fit.genus,
        fit.parameterization.folded,
        100.0 * fit.max_residual / diagonal,
        100.0 * distance.symmetric / diagonal,
        100.0 * distance.b_to_a / diagonal,
        100.0 * distance.a_to_b / diagonal,
        normals.median,
        normals.p90,
        normals.p95,
        normals.max,
        fit.loops.paths.len(),
        fit.loops.base,
        fit.loops.relation.len(),
    );
}
