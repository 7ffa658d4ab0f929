//! ∫K dA of a model file at several quadrature densities, against 2π(2 − 2n): tells a quadrature
//! that is too coarse (the integral moves with the density) from a surface that is not immersed.
//! `cargo run -p embedding --example gauss_bonnet MODEL.json`
use charts::Atlas;
use embedding::Layout;
use embedding::integrals::surface_integrals;
use embedding::model::Model;

fn main() {
    let path = std::env::args().nth(1).expect("a model file");
    let model: Model =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("readable")).expect("a model");
    let atlas = Atlas::new(model.genus).expect("an atlas");
    let layout = Layout::new(&atlas, model.settings).expect("a layout");
    let control = model.points();
    let expected = std::f64::consts::TAU * (2.0 - 2.0 * f64::from(model.genus));
    let densities: Vec<usize> = std::env::args()
        .skip(2)
        .map(|a| a.parse().expect("cells per knot"))
        .collect();
    let densities = if densities.is_empty() {
        vec![2, 3, 4, 6, 8]
    } else {
        densities
    };
    for cells in densities {
        let sums = surface_integrals(&layout, &control, cells);
        println!(
            "{cells:3} cells per knot: ∫K dA {:.6} (expected {expected:.6}), ∫|K| dA {:.3}, area {:.4}, largest |κ| {:.3}",
            sums.gaussian_curvature, sums.absolute_curvature, sums.area, sums.largest_curvature
        );
        if let Some(at) = sums.largest_curvature_at {
            let p = layout.position(&control, at);
            let blends: Vec<String> = layout
                .blends(at)
                .iter()
                .map(|(c, b)| format!("{} {b:.3}", c.0))
                .collect();
            println!(
                "    at chart {} {:.4}: [{:.3}, {:.3}, {:.3}], blends {}",
                at.chart.0,
                at.coords,
                p.x,
                p.y,
                p.z,
                blends.join(", ")
            );
        }
    }
}
