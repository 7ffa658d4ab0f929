//! The flat faces of `ntori new`'s plates measured on the surface itself, not at the input mesh's
//! vertices: |H| and the normal's angle from ±z at the vertices of a fine tessellation (t = 64)
//! that lie over the plate's flat faces (deeper than the rims' bands, by the plan's layout,
//! `holed::PlateLayout`), weighted by the tessellation's area element. Two models fitted to
//! different input meshes are so compared on the same footing. Also |H| by depth into the flat
//! faces (a ripple beside the rims shows in the first bins).
//! `cargo run --release -p embedding --example flat_report MODEL.json…`
use embedding::Surface;
use embedding::holed::PlateLayout;
use embedding::quality::sample_points;

/// Bins of depth into the flat faces, this wide (model units); the last takes the rest.
const DEPTH_BIN: f64 = 0.1;
const DEPTH_BINS: usize = 5;

/// The weighted `q`-quantile of (value, weight) pairs.
fn quantile(mut v: Vec<(f64, f64)>, q: f64) -> f64 {
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = v.iter().map(|x| x.1).sum();
    let mut acc = 0.0;
    for (x, w) in &v {
        acc += w;
        if acc >= q * total {
            return *x;
        }
    }
    v.last().map_or(0.0, |x| x.0)
}

fn main() {
    for path in std::env::args().skip(1) {
        let text = std::fs::read_to_string(&path).expect("readable");
        let model: embedding::model::Model = serde_json::from_str(&text).expect("a model");
        let surface = Surface::from_model(&model).expect("a surface");
        let genus = surface.genus();
        assert!(genus >= 2, "{path}: a plate has genus 2 or more");
        let plate = PlateLayout::new(genus);
        let layout = surface.layout();
        let control = surface.control_points();
        let (mut h, mut angle) = (Vec::new(), Vec::new());
        let mut by_depth: Vec<Vec<(f64, f64)>> = vec![Vec::new(); DEPTH_BINS];
        for p in sample_points(&surface, 64).expect("a tessellation") {
            let jet = layout.eval(control, p);
            let depth = plate.flat_depth(jet.pos.x, jet.pos.y);
            if depth <= 0.0 {
                continue;
            }
            let area = jet.du.cross(&jet.dv).norm();
            let mean = jet.mean_curvature().abs();
            h.push((mean, area));
            by_depth[((depth / DEPTH_BIN) as usize).min(DEPTH_BINS - 1)].push((mean, area));
            angle.push((jet.normal().z.abs().min(1.0).acos().to_degrees(), area));
        }
        println!(
            "{path}: genus {genus}, {} points on the flat faces: |H| median {:.4}, 90% {:.4} \
             (× half-thickness {:.4}), 99% {:.4}; normals off ±z 90% {:.3}°, 99% {:.3}°",
            h.len(),
            quantile(h.clone(), 0.5),
            quantile(h.clone(), 0.9),
            plate.thickness * quantile(h.clone(), 0.9),
            quantile(h, 0.99),
            quantile(angle.clone(), 0.9),
            quantile(angle, 0.99),
        );
        for (k, bin) in by_depth.into_iter().enumerate() {
            let from = DEPTH_BIN * k as f64;
            let to = if k + 1 == DEPTH_BINS {
                "on".to_string()
            } else {
                format!("{:.1}", from + DEPTH_BIN)
            };
            println!(
                "  {from:.1} to {to} deep: {} points, |H| 90% {:.4}",
                bin.len(),
                quantile(bin, 0.9)
            );
        }
    }
}
