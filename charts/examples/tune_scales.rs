//! Chooses ntori's default chart sizes for genus 2..=64: for each genus, a compass search over
//! (inside radius / γ, edge scale σ, vertex radius / (the paper's δ/2)) that maximises the coverage
//! margin measured on `POINTS` points spread over the polygon (`charts::check::spread_points`).
//! Prints the table for `scales.rs`. Run: `cargo run --release -p charts --example tune_scales [FROM TO]`.

use charts::{check, Atlas, ChartScales};

const POINTS: usize = 12_000;

fn margin(genus: u32, f: [f64; 3], gamma: f64, half_delta: f64, points: &mut Option<Vec<charts::ModelPoint>>) -> f64 {
    let scales = ChartScales::Polygon { inside: f[0] * gamma, edge: f[1], vertex: f[2] * half_delta };
    let Ok(atlas) = Atlas::with_scales(genus, scales) else { return f64::NEG_INFINITY };
    let pts = points.get_or_insert_with(|| check::spread_points(&atlas, POINTS));
    let m = check::coverage(&atlas, pts).min_margin;
    if m.is_finite() { m } else { -1.0 }
}

fn main() {
    let args: Vec<u32> = std::env::args().skip(1).filter_map(|a| a.parse().ok()).collect();
    let (from, to) = (args.first().copied().unwrap_or(2), args.get(1).copied().unwrap_or(64));
    for genus in from..=to {
        let atlas = Atlas::new(genus).expect("default atlas");
        let c = *atlas.polygon().expect("polygon").constants();
        let (gamma, half_delta) = (c.gamma, c.paper_delta / 2.0);
        let mut points = None;
        let mut best = [0.95, 0.875, 1.0];
        let mut best_m = margin(genus, best, gamma, half_delta, &mut points);
        let mut step = [0.04, 0.1, 0.2];
        while step[0] > 1e-4 {
            let mut improved = false;
            for k in 0..3 {
                for sign in [1.0, -1.0] {
                    let mut f = best;
                    f[k] += sign * step[k];
                    if k == 0 && f[0] >= 0.9999 { continue; }
                    let m = margin(genus, f, gamma, half_delta, &mut points);
                    if m > best_m { best = f; best_m = m; improved = true; }
                }
            }
            if !improved { for s in &mut step { *s *= 0.5; } }
        }
        println!("    ({genus}, {:.6}, {:.6}, {:.6}), // margin {:.5}", best[0] * gamma, best[1], best[2] * half_delta, best_m);
    }
}
