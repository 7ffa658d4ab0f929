//! Where a model's largest principal curvature sits and what makes it: the blend weights there, and
//! each chart's own patch (position, |E_u × E_v| and the angle between E_u and E_v, by differences
//! in that chart's coordinates). `cargo run --release -p embedding --example spot_report MODEL.json`
//! (the peak over the Gauss–Bonnet check's quadrature points; NTORI_VERTICES=1: over a t = 32
//! tessellation's vertices)
use charts::ChartPoint;
use embedding::Surface;
use embedding::quality::{max_principal_curvature, sample_points};
use num_complex::Complex64;

fn main() {
    let path = std::env::args().nth(1).expect("a model file");
    let text = std::fs::read_to_string(&path).expect("readable");
    let model: embedding::model::Model = serde_json::from_str(&text).expect("a model");
    let surface = Surface::from_model(&model).expect("a surface");
    // The peak over the Gauss–Bonnet quadrature's points (dense), or over a t = 32 tessellation's
    // vertices with NTORI_VERTICES set.
    let k = if std::env::var("NTORI_VERTICES").is_ok() {
        let points = sample_points(&surface, 32).expect("a tessellation");
        max_principal_curvature(&surface, &points)
    } else {
        let layout = surface.layout();
        let sums = embedding::integrals::surface_integrals(
            &layout,
            surface.control_points(),
            embedding::integrals::cells_per_knot(layout.settings()),
        );
        sums.curvature_peak()
    };
    let at = k.at.expect("a point");
    let layout = surface.layout();
    let control = surface.control_points();
    let jet = layout.eval(control, at);
    println!(
        "max |κ| {:.2} at chart {:?} {:.4}: position {:.4?}, area element {:.3e}, normal {:.3?}",
        k.max_abs,
        at.chart,
        at.coords,
        jet.pos,
        jet.area_element(),
        jet.normal()
    );
    if std::env::var("NTORI_LINE").is_ok() {
        // The curvature along the peak chart's u and v lines through the peak.
        for (name, dir) in [
            ("u", Complex64::new(1.0, 0.0)),
            ("v", Complex64::new(0.0, 1.0)),
        ] {
            let mut line = String::new();
            for k in -12..=12 {
                let q = ChartPoint::new(at.chart, at.coords + dir * (k as f64 * 0.004));
                let j = layout.eval(control, q);
                let (k1, k2) = j.principal_curvatures();
                line += &format!(" {:.1}", k1.abs().max(k2.abs()));
            }
            println!("  |κ| along {name} (step 0.004, |E| {:.2}):{line}", {
                let j = layout.eval(control, at);
                if name == "u" {
                    j.du.norm()
                } else {
                    j.dv.norm()
                }
            });
        }
    }
    let blends = layout.blends(at);
    let own = |p: ChartPoint| {
        let mut basis = Vec::new();
        layout.patch_weights(p, &mut basis);
        basis
            .iter()
            .fold(embedding::Vector3::zeros(), |s, &(c, v)| {
                s + control[c as usize].coords * v
            })
    };
    for (rep, _) in surface.atlas().locate_with_transitions(at) {
        let b = blends
            .iter()
            .find(|b| b.0 == rep.chart)
            .map_or(0.0, |b| b.1);
        let h = 1e-5;
        let e = own(rep);
        let shift = |d: Complex64| own(ChartPoint::new(rep.chart, rep.coords + d));
        let eu = (shift(Complex64::new(h, 0.0)) - shift(Complex64::new(-h, 0.0))) / (2.0 * h);
        let ev = (shift(Complex64::new(0.0, h)) - shift(Complex64::new(0.0, -h))) / (2.0 * h);
        let angle = (eu.dot(&ev) / (eu.norm() * ev.norm())).acos().to_degrees();
        // The patch's own principal curvatures, from second differences in its coordinates.
        let k = 1e-4;
        let at_k = |du: f64, dv: f64| shift(Complex64::new(du * k, dv * k));
        let euu = (at_k(1.0, 0.0) - e * 2.0 + at_k(-1.0, 0.0)) / (k * k);
        let evv = (at_k(0.0, 1.0) - e * 2.0 + at_k(0.0, -1.0)) / (k * k);
        let euv =
            (at_k(1.0, 1.0) - at_k(1.0, -1.0) - at_k(-1.0, 1.0) + at_k(-1.0, -1.0)) / (4.0 * k * k);
        let (k1, k2) = embedding::SurfaceJet {
            pos: embedding::Point3::from(e),
            du: eu,
            dv: ev,
            duu: euu,
            duv: euv,
            dvv: evv,
        }
        .principal_curvatures();
        println!(
            "  chart {:?} at {:.4}: blend {b:.4}, patch {:.4?} (off the surface by {:.2e}), |E_u| {:.3e}, |E_v| {:.3e}, angle(E_u, E_v) {angle:.2}°, own κ {:.3} {:.3}",
            rep.chart,
            rep.coords,
            e,
            (e - jet.pos.coords).norm(),
            eu.norm(),
            ev.norm(),
            k1,
            k2
        );
    }
}
