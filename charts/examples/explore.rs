use charts::{Atlas, ChartId, check};
fn main() {
    for g in [0u32, 1, 2, 3, 5, 8, 16, 32, 64] {
        let t0 = std::time::Instant::now();
        let atlas = match Atlas::new(g) {
            Ok(a) => a,
            Err(e) => {
                println!("genus {g}: {e}");
                continue;
            }
        };
        let built = t0.elapsed();
        if let Some(p) = atlas.polygon() {
            let c = p.constants();
            if g <= 3 {
                println!("{:?}", c);
                println!(
                    "cycle {:?}",
                    p.vertex_cycle()
                        .iter()
                        .map(|s| s.corner)
                        .collect::<Vec<_>>()
                );
            }
        }
        let tiles: Vec<usize> = atlas
            .charts()
            .iter()
            .take(3)
            .map(|c| c.tile_count())
            .collect();
        let n = atlas.charts().len();
        let mut comps = 0;
        let mut maxc = 0;
        for i in 0..n {
            for j in 0..n {
                if i != j {
                    let k = atlas
                        .transitions(ChartId(i as u32), ChartId(j as u32))
                        .len();
                    comps += k;
                    maxc = maxc.max(k);
                }
            }
        }
        let pts = check::spread_points(&atlas, 20000);
        let cov = check::coverage(&atlas, &pts);
        let cons = check::consistency(&atlas, &pts[..5000]);
        println!(
            "genus {g}: built {:?} tiles(in,v,e0) {:?} comps {comps} max/pair {maxc} cov {:.4} at {:.4} maxcharts {} cons {:.2e} inv {:.2e} coc {:.2e} missing {} area {:?}",
            built,
            tiles,
            cov.min_margin,
            cov.worst_point,
            cov.max_charts,
            cons.worst(),
            cons.inverse_error,
            cons.cocycle_error,
            cons.missing,
            atlas.polygon().map(|p| p.area_by_quadrature()
                / (4.0 * std::f64::consts::PI * (g as f64 - 1.0))
                - 1.0)
        );
    }
}
