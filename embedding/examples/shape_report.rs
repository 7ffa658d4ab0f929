//! Issue 12's shape measures for the default fit at several genera: patch disagreement (as a
//! fraction of the mesh diagonal), the largest principal curvature, and the normal deviation from
//! the input mesh at its vertices. `cargo run --release -p embedding --example shape_report [GENERA…]`
use std::time::Instant;

use embedding::SplineSettings;
use embedding::fit::{FitSettings, initial_model};
use embedding::quality::{
    max_principal_curvature, normal_deviation, patch_disagreement, sample_points,
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
        "genus  fit(s)  disagreement(max, rms; % of diagonal)  max|κ|   normal deviation (median, p90, max; degrees)"
    );
    for genus in genera {
        let start = Instant::now();
        let fit = initial_model(genus, 32, SplineSettings::default(), FitSettings::default())
            .expect("the fit");
        let seconds = start.elapsed().as_secs_f64();
        let s = &fit.surface;
        let points = sample_points(s, 32).expect("a tessellation");
        let d = patch_disagreement(s, &points, 0.1);
        let k = max_principal_curvature(s, &points);
        let n = normal_deviation(
            s,
            &fit.parameterization.points,
            &fit.mesh.positions,
            &fit.mesh.triangles,
        );
        println!(
            "{genus:5}  {seconds:6.1}  {:8.3}% {:8.3}%                        {:7.2}  {:6.2} {:6.2} {:6.2}",
            100.0 * d.max / fit.mesh_diagonal,
            100.0 * d.rms / fit.mesh_diagonal,
            k.max_abs,
            n.median,
            n.p90,
            n.max
        );
    }
}
