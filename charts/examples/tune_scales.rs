//! Chooses ntori's default chart sizes for genus 2..=64: for each genus, a compass search over
//! (inside radius / γ, edge scale σ, vertex radius / (the paper's δ/2)) that maximises the coverage
//! margin measured on `POINTS` points spread over the polygon (`charts::check::spread_points`).
//! Prints the table for `scales.rs` (its last column is the margin on 10^5 points, re-measured).
//! Run: `cargo run --release -p charts --example tune_scales [FROM TO]`, or `… tune_scales measure
//! [FROM TO]` to measure the current defaults on 10^5 and 10^6 points.

use charts::{Atlas, ChartScales, check};

const POINTS: usize = 12_000;

fn margin(
    genus: u32,
    f: [f64; 3],
    gamma: f64,
    half_delta: f64,
    points: &mut Option<Vec<charts::ModelPoint>>,
) -> f64 {
    let scales = ChartScales::Polygon {
        inside: f[0] * gamma,
        edge: f[1],
        vertex: f[2] * half_delta,
    };
    let Ok(atlas) = Atlas::with_scales(genus, scales) else {
        return f64::NEG_INFINITY;
    };
    let pts = points.get_or_insert_with(|| check::spread_points(&atlas, POINTS));
    let m = check::coverage(&atlas, pts).min_margin;
    if m.is_finite() { m } else { -1.0 }
}

/// `tune_scales measure [FROM TO]`: the default scales' margins on 10^5 and 10^6 points.
fn measure(from: u32, to: u32) {
    for genus in from..=to {
        let atlas = Atlas::new(genus).expect("default atlas");
        let m = |k| check::coverage(&atlas, &check::spread_points(&atlas, k)).min_margin;
        println!("{genus} {:.5} {:.5}", m(100_000), m(1_000_000));
    }
}

fn main() {
    let measuring = std::env::args().nth(1).is_some_and(|a| a == "measure");
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let (from, to) = (
        args.first().copied().unwrap_or(2),
        args.get(1).copied().unwrap_or(64),
    );
    if measuring {
        return measure(from, to);
    }
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
                    if k == 0 && f[0] >= 0.9999 {
                        continue;
                    }
                    let m = margin(genus, f, gamma, half_delta, &mut points);
                    if m > best_m {
                        best = f;
                        best_m = m;
                        improved = true;
                    }
                }
            }
            if !improved {
                for s in &mut step {
                    *s *= 0.5;
                }
            }
        }
        let scales = ChartScales::Polygon {
            inside: best[0] * gamma,
            edge: best[1],
            vertex: best[2] * half_delta,
        };
        let atlas = Atlas::with_scales(genus, scales).expect("tuned scales are valid");
        let remeasured = check::coverage(&atlas, &check::spread_points(&atlas, 100_000)).min_margin;
        eprintln!("genus {genus}: margin {best_m:.5} on {POINTS} points, {remeasured:.5} on 10^5");
        println!(
            "    ({genus}, {:.6}, {:.6}, {:.6}, {:.5}),",
            best[0] * gamma,
            best[1],
            best[2] * half_delta,
            remeasured
        );
    }
}
