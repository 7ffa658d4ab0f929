//! Prints, per genus, the mesh, the parameterization and the fit: a quick look while tuning.
use embedding::SplineSettings;
use embedding::fit::{FitSettings, cut, initial_model};
use embedding::holed::HoledMesh;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let res: usize = args.get(1).map_or(32, |s| s.parse().unwrap());
    let grid: usize = args.get(2).map_or(8, |s| s.parse().unwrap());
    let lambda: f64 = args.get(3).map_or(1e-4, |s| s.parse().unwrap());
    let sweeps: usize = args.get(4).map_or(200, |s| s.parse().unwrap());
    for genus in 0..=8 {
        let t = Instant::now();
        let mesh = HoledMesh::new(genus, res).unwrap();
        let t_mesh = t.elapsed();
        let v = mesh.positions.len() as i64;
        let f = mesh.triangles.len() as i64;
        let chi = v - f / 2;
        if genus > 0 {
            let disk = cut(&mesh).unwrap();
            let _ = disk;
        }
        let settings = SplineSettings {
            grid,
            ..Default::default()
        };
        let t = Instant::now();
        let fit = initial_model(
            genus,
            res,
            settings,
            FitSettings {
                smoothness: lambda,
                sweeps,
                ..Default::default()
            },
        )
        .unwrap();
        let folded = fit.parameterization.folded;
        let flips = fit.parameterization.disk.as_ref().map_or(0, |d| {
            d.triangles
                .iter()
                .filter(|t| {
                    let [a, b, c] = t.map(|v| fit.parameterization.flat[v as usize]);
                    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 0.0
                })
                .count()
        });
        // Where is the worst vertex?
        let atlas = charts::Atlas::new(genus).unwrap();
        let layout = embedding::Layout::new(&atlas, settings).unwrap();
        let control = fit.surface.control_points().to_vec();
        let mut errs: Vec<(f64, usize)> = fit
            .parameterization
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                (
                    (layout.eval(&control, *p).pos - fit.mesh.positions[i]).norm(),
                    i,
                )
            })
            .collect();
        errs.sort_by(|a, b| b.0.total_cmp(&a.0));
        for &(e, i) in errs.iter().take(3) {
            let p = fit.parameterization.points[i];
            let x = fit.mesh.positions[i];
            let base = fit.mesh.positions[fit.mesh.base as usize];
            println!(
                "   err {e:.4} at v{i} pos ({:.2},{:.2},{:.2}) dist-to-base {:.3} chart {:?} w {:.4}",
                x.x,
                x.y,
                x.z,
                (x - base).norm(),
                p.chart,
                p.coords
            );
        }
        let gb = embedding::integrals::surface_integrals(
            &layout,
            &control,
            std::env::var("CELLS").map_or(4, |s| s.parse().unwrap()),
        );
        let expect = std::f64::consts::TAU * (2.0 - 2.0 * genus as f64);
        println!(
            "   GB: {:.6} expect {:.6} rel {:.2e} (|K| {:.3}) area {:.3}",
            gb.gaussian_curvature,
            expect,
            (gb.gaussian_curvature - expect).abs() / expect.abs().max(gb.absolute_curvature),
            gb.absolute_curvature,
            gb.area
        );
        println!(
            "genus {genus}: V {v} F {f} chi {chi} mesh {:.0?} | flips {flips} folded {folded} sweeps {} | fit {:.0?} rms {:.4} max {:.4} diag {:.3} ({:.3}% / {:.3}%)",
            t_mesh,
            fit.parameterization.sweeps,
            t.elapsed(),
            fit.rms_residual,
            fit.max_residual,
            fit.mesh_diagonal,
            100.0 * fit.rms_residual / fit.mesh_diagonal,
            100.0 * fit.max_residual / fit.mesh_diagonal
        );
    }
}
