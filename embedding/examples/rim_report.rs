//! Where a plate model's outer rim leaves its intended profile: the t = 32 tessellation's points
//! in the outer band (and just inside it), each one's distance from the flat face or the
//! rim's cross-section, the largest per bin of angle. `ntori render`'s default pictures of the
//! genus-10 and 16 plates show notches in the outer rim's silhouette; this measured the default
//! genus-10 fit (grid 48) within 0.0033 of the intended rim everywhere (0.02% of the diagonal),
//! and at `--tessellation 64` the notches all but go: they are the t = 32 tessellation's chords
//! where its triangles are large, not the surface.
//! `cargo run --release -p embedding --example rim_report MODEL.json`
use std::f64::consts::PI;

use embedding::Surface;
use embedding::holed::PlateLayout;
use embedding::quality::sample_points;

fn main() {
    let path = std::env::args().nth(1).expect("a model file");
    let model: embedding::model::Model =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("readable")).expect("a model");
    let surface = Surface::from_model(&model).expect("a surface");
    let n = surface.genus();
    let plate = PlateLayout::new(n);
    let (band, thickness, r_outer) = (plate.band, plate.thickness, plate.outer_radius);
    // The rim's profile (across, drop) at t, as holed.rs draws it.
    let angle = |t: f64| plate.rim_angle(t);
    let steps = 4000;
    let mut profile = Vec::with_capacity(steps + 1);
    let (mut x, mut z) = (0.0, 0.0);
    for k in 0..=steps {
        profile.push((x, z));
        let t = (k as f64 + 0.5) / steps as f64;
        x += angle(t).cos() / steps as f64;
        z += angle(t).sin() / steps as f64;
    }
    let full = profile[steps].0;
    let curve: Vec<(f64, f64)> = profile
        .iter()
        .map(|&(x, z)| {
            (
                r_outer - band + band * x / full,
                thickness * (1.0 - z / full),
            )
        })
        .collect();
    let points = sample_points(&surface, 32).expect("a tessellation");
    let bins = 8 * n as usize;
    let mut worst = vec![(0.0f64, 0.0f64); bins];
    for p in &points {
        let s = surface.position(*p);
        let rho = s.x.hypot(s.y);
        if rho < r_outer - band - 0.05 {
            continue;
        }
        let zz = s.z.abs();
        // The flat face before the band, then the profile.
        let flat = if rho < r_outer - band {
            (zz - thickness).abs()
        } else {
            f64::INFINITY
        };
        let d = curve
            .iter()
            .map(|&(r, z)| (r - rho).hypot(z - zz))
            .fold(flat, f64::min);
        let a = s.y.atan2(s.x).rem_euclid(2.0 * PI);
        let bin = ((a / (2.0 * PI) * bins as f64) as usize).min(bins - 1);
        if d > worst[bin].0 {
            worst[bin] = (d, s.z);
        }
    }
    println!(
        "genus {n}: outer radius {r_outer:.3}; holes at angles 2πk/{n}, b-loops cross the rim half way between"
    );
    for (k, (d, z)) in worst.iter().enumerate() {
        let a = (k as f64 + 0.5) / bins as f64 * 360.0;
        let hole = a / (360.0 / f64::from(n));
        println!(
            "{a:7.2}° ({hole:5.2} hole spacings): worst {d:.4} (z {z:+.3}) {}",
            "#".repeat((d * 4000.0) as usize)
        );
    }
}
