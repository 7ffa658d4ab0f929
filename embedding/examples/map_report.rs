//! The plates' maps onto the polygon per genus: time, Newton steps, residual, folds and distortion.
//! `cargo run -p embedding --example map_report [RESOLUTION] [GENERA…]`
use std::time::Instant;

use charts::Atlas;
use embedding::fit::parameterize;
use embedding::holed::HoledMesh;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let resolution: usize = args
        .first()
        .map_or(32, |s| s.parse().expect("a resolution"));
    let genera: Vec<u32> = args
        .iter()
        .skip(1)
        .map(|a| a.parse().expect("a genus"))
        .collect();
    let genera = if genera.is_empty() {
        vec![1, 2, 3, 5, 8, 10, 16]
    } else {
        genera
    };
    println!(
        "genus vertices  mesh(s)  map(s)  newton LUs sweeps residual  folded  angle(mean,max)  area(mean,max)"
    );
    for genus in genera {
        let atlas = Atlas::new(genus).expect("an atlas");
        let t = Instant::now();
        let mesh = HoledMesh::new(genus, resolution).expect("a plate");
        let meshing = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let rounds: usize = std::env::var("ROUNDS").map_or(1, |r| r.parse().expect("rounds"));
        let p = parameterize(&atlas, &mesh, rounds).expect("a map");
        let mapping = t.elapsed().as_secs_f64();
        let geometry = atlas.polygon().expect("genus ≥ 1").geometry();
        let newton = p.newton.expect("a Newton solve");
        let d = p.distortion(&mesh.positions, geometry).expect("a disk");
        println!(
            "{genus:5} {:8} {meshing:8.2} {mapping:7.2} {:6} {:6} {:6} {:8.1e} {:7} {:7.2} {:7.2} {:7.2} {:7.2}",
            mesh.positions.len(),
            newton.steps,
            newton.factorizations,
            p.sweeps,
            newton.residual,
            p.folded,
            d.angle_mean,
            d.angle_max,
            d.area_mean,
            d.area_max
        );
    }
}
