//! Sampling the pieces the figures draw: polygon sides, chart domains and their images, and the
//! group elements that bring a chart's image back into the fundamental polygon.

use charts::{Atlas, Chart, Domain, Lft, Polygon};
use num_complex::Complex64;

/// Points along side e of the hyperbolic polygon, from corner e − 1 to corner e (the geodesic: an
/// arc of the circle about h·e^{ieω} of radius r). `count + 1` points, ends included.
pub fn side_points(poly: &Polygon, e: usize, count: usize) -> Vec<Complex64> {
    let c = poly.constants();
    let (a, b) = poly.edge_corners(e);
    let (za, zb) = (poly.corners()[a], poly.corners()[b]);
    match (c.h, c.r) {
        (Some(h), Some(r)) => {
            let centre = Complex64::from_polar(h, e as f64 * c.omega);
            let (t0, mut t1) = ((za - centre).arg(), (zb - centre).arg());
            // The short way round (the side is less than a half circle).
            while t1 - t0 > std::f64::consts::PI {
                t1 -= std::f64::consts::TAU;
            }
            while t0 - t1 > std::f64::consts::PI {
                t1 += std::f64::consts::TAU;
            }
            (0..=count)
                .map(|i| {
                    centre + Complex64::from_polar(r, t0 + (t1 - t0) * i as f64 / count as f64)
                })
                .collect()
        }
        _ => (0..=count)
            .map(|i| za + (zb - za) * (i as f64 / count as f64))
            .collect(),
    }
}

/// The closed boundary of a chart domain (in chart coordinates), `per_side` points per quarter,
/// counter-clockwise, first point not repeated.
pub fn domain_boundary(domain: Domain, per_side: usize) -> Vec<Complex64> {
    match domain {
        Domain::Disk => (0..4 * per_side)
            .map(|i| {
                Complex64::from_polar(
                    0.5,
                    std::f64::consts::TAU * i as f64 / (4 * per_side) as f64,
                )
            })
            .collect(),
        Domain::Square => {
            let corners = [
                Complex64::new(0.5, -0.5),
                Complex64::new(0.5, 0.5),
                Complex64::new(-0.5, 0.5),
                Complex64::new(-0.5, -0.5),
            ];
            (0..4)
                .flat_map(|s| {
                    let (a, b) = (corners[s], corners[(s + 1) % 4]);
                    (0..per_side).map(move |i| a + (b - a) * (i as f64 / per_side as f64))
                })
                .collect()
        }
    }
}

/// Points along the segment a → b, `count + 1` of them.
pub fn segment(a: Complex64, b: Complex64, count: usize) -> Vec<Complex64> {
    (0..=count)
        .map(|i| a + (b - a) * (i as f64 / count as f64))
        .collect()
}

/// The grid lines drawn in a chart's domain, in chart coordinates: for the square, lines every 0.1;
/// for the inside disk, the same lines clipped to the disk; for the vertex disk, circles every 0.1 and
/// the 4n spokes at `spokes` angles (the wedge boundaries).
pub fn domain_grid(domain: Domain, spokes: Option<&[f64]>) -> Vec<Vec<Complex64>> {
    let mut lines = Vec::new();
    let ticks: Vec<f64> = (-4..=4).map(|i| f64::from(i) * 0.1).collect();
    match (domain, spokes) {
        (Domain::Square, _) => {
            for &t in &ticks {
                lines.push(segment(Complex64::new(t, -0.5), Complex64::new(t, 0.5), 40));
                lines.push(segment(Complex64::new(-0.5, t), Complex64::new(0.5, t), 40));
            }
        }
        (Domain::Disk, None) => {
            for &t in &ticks {
                let half = (0.25 - t * t).sqrt();
                lines.push(segment(
                    Complex64::new(t, -half),
                    Complex64::new(t, half),
                    40,
                ));
                lines.push(segment(
                    Complex64::new(-half, t),
                    Complex64::new(half, t),
                    40,
                ));
            }
        }
        (Domain::Disk, Some(angles)) => {
            for i in 1..5 {
                let r = 0.1 * f64::from(i);
                lines.push(
                    (0..=96)
                        .map(|k| {
                            Complex64::from_polar(r, std::f64::consts::TAU * f64::from(k) / 96.0)
                        })
                        .collect(),
                );
            }
            for &a in angles {
                lines.push(segment(Complex64::ZERO, Complex64::from_polar(0.5, a), 40));
            }
        }
    }
    lines
}

/// The group elements g (in a fixed order) for which g·φ(D) meets the fundamental polygon: drawn under
/// each of them and clipped to the polygon, a chart's image shows as the surface sees it.
pub fn tile_maps(poly: &Polygon, chart: &Chart) -> Vec<Lft> {
    let phi = chart.to_model();
    let mut samples: Vec<Complex64> = Vec::new();
    let n = 48;
    for i in 0..=n {
        for j in 0..=n {
            let w = Complex64::new(
                -0.5 + f64::from(i) / f64::from(n),
                -0.5 + f64::from(j) / f64::from(n),
            ) * 0.999;
            if chart.domain().margin(w) > -1e-9 {
                samples.push(w);
            }
        }
    }
    samples.extend(
        domain_boundary(chart.domain(), 64)
            .into_iter()
            .map(|w| w * 0.999),
    );
    let mut maps: Vec<Lft> = Vec::new();
    for w in samples {
        let (_, g) = poly.reduce_with_map(phi.apply(w));
        if maps.iter().all(|m| m.distance(&g) > 1e-7) {
            maps.push(g);
        }
    }
    maps
}

/// The wedge of the vertex chart each of its 4n sectors lands in: for sector m (centred on the chart
/// direction m·ω), the polygon corner its image reaches.
pub fn vertex_wedge_corners(atlas: &Atlas, poly: &Polygon) -> Vec<usize> {
    let chart = &atlas.charts()[1];
    let omega = poly.constants().omega;
    (0..poly.sides())
        .map(|m| {
            let w = Complex64::from_polar(0.3, m as f64 * omega);
            let z = poly.reduce(chart.to_model().apply(w));
            nearest(poly.corners(), z)
        })
        .collect()
}

/// Index of the point nearest z.
pub fn nearest(points: &[Complex64], z: Complex64) -> usize {
    (0..points.len())
        .min_by(|&a, &b| (points[a] - z).norm().total_cmp(&(points[b] - z).norm()))
        .unwrap_or(0)
}

/// Each corner's position in the walk around the surface's vertex (`Polygon::vertex_cycle`).
pub fn corner_positions(poly: &Polygon) -> Vec<usize> {
    let mut pos = vec![0; poly.sides()];
    for (i, step) in poly.vertex_cycle().iter().enumerate() {
        pos[step.corner] = i;
    }
    pos
}

/// For each polygon edge, whether its direction arrow runs counter-clockwise (corner e − 1 to corner
/// e). The a_k and b_k edges do by convention; each partner's direction is read off the side pairing
/// (which carries the partner onto the edge, arrow onto arrow), not assumed.
pub fn arrows_counter_clockwise(poly: &Polygon) -> Vec<bool> {
    (0..poly.sides())
        .map(|e| {
            let t = e % 4;
            if t < 2 {
                return true;
            }
            let j = 2 * (e / 4) + t % 2;
            let g = poly.pairing(j);
            let target = poly.partner(e);
            let start = nearest(
                poly.corners(),
                g.apply(poly.corners()[poly.edge_corners(e).0]),
            );
            start == poly.edge_corners(target).0
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_edges_run_clockwise() {
        let poly = Polygon::new(2).unwrap();
        assert_eq!(
            arrows_counter_clockwise(&poly),
            [true, true, false, false, true, true, false, false]
        );
    }

    #[test]
    fn sides_run_from_corner_to_corner_on_the_edge_circle() {
        let poly = Polygon::new(3).unwrap();
        for e in 0..poly.sides() {
            let pts = side_points(&poly, e, 10);
            let (a, b) = poly.edge_corners(e);
            assert!((pts[0] - poly.corners()[a]).norm() < 1e-12);
            assert!((pts[10] - poly.corners()[b]).norm() < 1e-12);
            assert!(pts.iter().all(|&z| poly.outside_edge(z, e).abs() < 1e-12));
        }
    }
}
