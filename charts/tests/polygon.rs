//! The fundamental polygon: closed forms, side pairings, the vertex cycle, and its area.

use charts::{Lft, Polygon};
use num_complex::Complex64;
use std::f64::consts::PI;

fn hyperbolic_genera() -> impl Iterator<Item = u32> {
    2..=charts::MAX_GENUS
}

#[test]
fn closed_forms_for_genus_two() {
    let c = *Polygon::new(2).unwrap().constants();
    assert!((c.alpha - 2f64.powf(-0.25)).abs() < 1e-14);
    assert!((c.gamma - (2f64.sqrt() - 1.0).sqrt()).abs() < 1e-14);
    // The notes' values.
    assert!((c.h.unwrap() - 1.098684).abs() < 1e-6);
    assert!((c.r.unwrap() - 0.455090).abs() < 1e-6);
    assert!((c.gamma - 0.643594).abs() < 1e-6);
    let c3 = *Polygon::new(3).unwrap().constants();
    assert!((c3.alpha - 0.930605).abs() < 1e-6 && (c3.gamma - 0.759836).abs() < 1e-6);
    let c4 = *Polygon::new(4).unwrap().constants();
    assert!((c4.alpha - 0.961187).abs() < 1e-6 && (c4.gamma - 0.817422).abs() < 1e-6);
}

#[test]
fn constants_agree_with_the_papers_equations_for_every_genus() {
    for n in hyperbolic_genera() {
        let c = *Polygon::new(n).unwrap().constants();
        let w = c.omega;
        assert!((w - 2.0 * PI / (4.0 * n as f64)).abs() < 1e-15);
        // α = √cos(π/2n).
        assert!(
            (c.alpha - (PI / (2.0 * n as f64)).cos().sqrt()).abs() < 1e-14,
            "n = {n}"
        );
        // Equation (3) for h, (2) for r, (5) for γ, (4) for α.
        let h3 = ((w.cos() + 1.0) / (w.cos() + 1.0 - 2.0 * (w / 2.0).sin().powi(2))).sqrt();
        let (h, r) = (c.h.unwrap(), c.r.unwrap());
        assert!((h - h3).abs() < 1e-14, "n = {n}");
        assert!((r - (h * h - 1.0).sqrt()).abs() < 1e-7, "n = {n}"); // f64 cancellation in h² − 1
        assert!((c.gamma - (h - r)).abs() < 1e-14, "n = {n}");
        let hc = h * (w / 2.0).cos();
        assert!(
            (c.alpha - (hc - (hc * hc - 1.0).sqrt())).abs() < 1e-7,
            "n = {n}"
        );
    }
}

#[test]
fn corners_and_midpoints_lie_on_their_edges() {
    for n in hyperbolic_genera() {
        let p = Polygon::new(n).unwrap();
        let c = *p.constants();
        for e in 0..p.sides() {
            let (c0, c1) = p.edge_corners(e);
            for z in [
                p.corners()[c0],
                p.corners()[c1],
                Complex64::from_polar(c.gamma, e as f64 * c.omega),
            ] {
                assert!(p.outside_edge(z, e).abs() < 1e-14, "n = {n}, e = {e}");
            }
        }
        // β lies on corner 0's bisector.
        assert!((c.beta.arg() - c.omega / 2.0).abs() < 1e-12, "n = {n}");
        assert!(p.contains(c.beta, 0.0));
    }
}

/// The point a fraction s along edge e (on its circle arc, or segment for the square).
fn point_on_edge(p: &Polygon, e: usize, s: f64) -> Complex64 {
    let (c0, c1) = p.edge_corners(e);
    let (a, b) = (p.corners()[c0], p.corners()[c1]);
    match (p.constants().h, p.constants().r) {
        (Some(h), Some(r)) => {
            let centre = Complex64::from_polar(h, e as f64 * p.constants().omega);
            let (t0, t1) = ((a - centre).arg(), (b - centre).arg());
            let dt = (t1 - t0 + PI).rem_euclid(2.0 * PI) - PI;
            centre + Complex64::from_polar(r, t0 + s * dt)
        }
        _ => a * (1.0 - s) + b * s,
    }
}

#[test]
fn side_pairings_reverse_edges_and_map_corners_to_corners() {
    for n in [1, 2, 3, 5, 8, 16, 32, 64] {
        let p = Polygon::new(n).unwrap();
        let c = *p.constants();
        for j in 0..2 * n as usize {
            let (k, t) = (j / 2, j % 2);
            let (src, dst) = (4 * k + 2 + t, 4 * k + t);
            assert_eq!(p.partner(src), dst);
            let g = p.pairing(j);
            let (s0, s1) = p.edge_corners(src);
            let (d0, d1) = p.edge_corners(dst);
            // Reversed orientation: the first corner of the source edge goes to the last of the target.
            let tol = 1e-11;
            assert!(
                (g.apply(p.corners()[s0]) - p.corners()[d1]).norm() < tol,
                "n {n} j {j}"
            );
            assert!(
                (g.apply(p.corners()[s1]) - p.corners()[d0]).norm() < tol,
                "n {n} j {j}"
            );
            let mid = |e: usize| Complex64::from_polar(c.gamma, e as f64 * c.omega);
            assert!((g.apply(mid(src)) - mid(dst)).norm() < 1e-13, "n {n} j {j}");
            // Points along the source edge land on the target edge; the polygon's inside goes outside.
            for s in [0.1, 0.35, 0.8] {
                let z = point_on_edge(&p, src, s);
                assert!(p.outside_edge(z, src).abs() < 1e-13);
                assert!(
                    p.outside_edge(g.apply(z), dst).abs() < 1e-11,
                    "n {n} j {j} s {s}"
                );
            }
            let inside_near_src = mid(src) * 0.98;
            assert!(
                p.outside_edge(g.apply(inside_near_src), dst) > 0.0,
                "n {n} j {j}"
            );
            // Fixes no point of the open disk: |trace| ≥ 2 (hyperbolic or parabolic in SL2).
            let [a, _, _, d] = g.matrix();
            assert!((a + d).norm() > 2.0 - 1e-9, "n {n} j {j}");
        }
    }
}

#[test]
fn the_vertex_cycle_visits_every_corner_once_and_closes() {
    let octagon = Polygon::new(2).unwrap();
    let corners: Vec<usize> = octagon.vertex_cycle().iter().map(|s| s.corner).collect();
    assert_eq!(corners, [0, 3, 6, 5, 4, 7, 2, 1]); // the notes' order
    for n in 1..=charts::MAX_GENUS {
        let p = Polygon::new(n).unwrap();
        let mut seen: Vec<usize> = p.vertex_cycle().iter().map(|s| s.corner).collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..p.sides()).collect::<Vec<_>>(), "n = {n}");
        for s in p.vertex_cycle() {
            assert!(s.leave_by == s.corner || s.leave_by == (s.corner + 1) % p.sides());
        }
        // The composite of the 4n maps is the identity, to 1e-12 even at n = 64 (formed in DD).
        let err = p.vertex_composite(false).distance(&Lft::IDENTITY);
        assert!(err < 1e-12, "n = {n}: composite off by {err:e}");
    }
}

#[test]
fn naive_f64_products_lose_what_double_double_keeps() {
    // Documents why the atlas forms its matrices in DD: the same product in f64 drifts at n = 64.
    let p = Polygon::new(64).unwrap();
    let naive = p.vertex_composite(true).distance(&Lft::IDENTITY);
    let exact = p.vertex_composite(false).distance(&Lft::IDENTITY);
    assert!(
        naive > 1e3 * exact.max(1e-16),
        "naive {naive:e}, exact {exact:e}"
    );
}

#[test]
fn area_is_4pi_times_genus_minus_one() {
    for n in hyperbolic_genera() {
        let area = Polygon::new(n).unwrap().area_by_quadrature();
        let want = 4.0 * PI * (n as f64 - 1.0);
        assert!(
            ((area - want) / want).abs() < 1e-9,
            "n = {n}: {area} vs {want}"
        );
    }
}

#[test]
fn reduction_brings_points_into_the_polygon() {
    for n in [1, 2, 5, 16] {
        let p = Polygon::new(n).unwrap();
        for k in 0..200 {
            let t = k as f64 * 0.731;
            let z = if n == 1 {
                Complex64::new(3.7 * t.sin(), -2.2 * t.cos())
            } else {
                Complex64::from_polar(0.999 * (k as f64 / 200.0).sqrt(), t)
            };
            assert!(p.contains(p.reduce(z), 1e-12), "n = {n}, z = {z}");
        }
    }
}

#[test]
fn unsupported_genus_is_an_error() {
    assert!(Polygon::new(0).is_err());
    assert!(Polygon::new(charts::MAX_GENUS + 1).is_err());
}
