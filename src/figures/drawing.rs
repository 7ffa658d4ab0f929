//! Drawing the charts' geometry as SVG: the fundamental polygon's outline and the tessellation's
//! triangles with their true (circular) sides, coloured by home chart. Used by the figures and by
//! `ntori tessellate --svg`.

use std::fmt::Write as _;

use charts::{Atlas, ChartKind, Lft, Polygon, Region, Tessellation};
use num_complex::Complex64;

/// The fill colour of a triangle: its home chart's tint (see [`crate::render::palette`]).
pub fn fill(kind: ChartKind, region: Region) -> String {
    use crate::render::palette;
    match (region, kind) {
        (Region::InsideWheel, ChartKind::Cap { .. }) => palette::fill(kind),
        (Region::InsideWheel, _) => palette::fill(ChartKind::Inside),
        (Region::VertexWheel, _) => palette::fill(ChartKind::Vertex),
        (Region::Square, ChartKind::Edge { .. }) => palette::fill(kind),
        (Region::Square, _) => "#cccccc".into(),
    }
}

/// An SVG path command from p0 to p1 along the circle through pm (a straight line if nearly flat).
pub fn arc_to(out: &mut String, p0: Complex64, pm: Complex64, p1: Complex64) {
    let cross = ((pm - p0).conj() * (p1 - pm)).im;
    let chord = (p1 - p0).norm();
    if cross.abs() <= 1e-9 * chord * chord {
        let _ = write!(out, " L{:.6} {:.6}", p1.re, p1.im);
        return;
    }
    // Circumcentre of p0, pm, p1.
    let (b, c) = (pm - p0, p1 - p0);
    let d = 2.0 * (b.re * c.im - b.im * c.re);
    let centre = p0
        + Complex64::new(
            (c.im * b.norm_sqr() - b.im * c.norm_sqr()) / d,
            (b.re * c.norm_sqr() - c.re * b.norm_sqr()) / d,
        );
    let radius = (p0 - centre).norm();
    // Large arc when the centre lies on pm's side of the chord; sweep when p0 → pm → p1 turns left.
    let side = |z: Complex64| ((p1 - p0).conj() * (z - p0)).im;
    let large = side(centre) * side(pm) > 0.0;
    let _ = write!(
        out,
        " A{radius:.6} {radius:.6} 0 {} {} {:.6} {:.6}",
        u8::from(large),
        u8::from(cross > 0.0),
        p1.re,
        p1.im
    );
}

/// The fundamental polygon's outline as SVG path data (its sides the circular arcs they are), each
/// point taken through `map` (model coordinates to drawing coordinates; a similarity, so arcs stay arcs).
pub fn polygon_path(poly: &Polygon, map: impl Fn(Complex64) -> Complex64) -> String {
    let mut path = String::new();
    let corners: Vec<Complex64> = poly.corners().iter().map(|&c| map(c)).collect();
    let _ = write!(path, "M{:.6} {:.6}", corners[0].re, corners[0].im);
    for e in 1..=corners.len() {
        let e = e % corners.len();
        let (a, b) = poly.edge_corners(e);
        let mid = Complex64::from_polar(poly.constants().gamma, e as f64 * poly.constants().omega);
        arc_to(&mut path, corners[a], map(mid), corners[b]);
    }
    path.push_str(" Z");
    path
}

/// One copy of a tessellation triangle in the model: its corners and the images of its sides'
/// midpoints (which fix the circular arcs its sides are).
#[derive(Clone, Copy, Debug)]
pub struct DrawnTriangle {
    /// Index into the tessellation's triangles.
    pub triangle: usize,
    pub corners: [Complex64; 3],
    pub mids: [Complex64; 3],
}

impl DrawnTriangle {
    /// SVG path data of the triangle with circular sides, each point taken through `map` (a
    /// similarity from model to drawing coordinates).
    pub fn path(&self, map: impl Fn(Complex64) -> Complex64) -> String {
        let [a, b, c] = self.corners.map(&map);
        let m = self.mids.map(&map);
        let mut d = format!("M{:.6} {:.6}", a.re, a.im);
        arc_to(&mut d, a, m[0], b);
        arc_to(&mut d, b, m[1], c);
        arc_to(&mut d, c, m[2], a);
        d.push_str(" Z");
        d
    }
}

/// Every triangle of `t` as drawn in the model: moved into the fundamental polygon by the group, plus
/// one more copy for each tile its corners reach (so that, clipped to the polygon, the copies cover
/// exactly the triangle's part of the surface). For the sphere, the two caps side by side, each in
/// its own coordinate ζ or 1/ζ (the south cap shifted right by 2.3).
pub fn drawn_triangles(atlas: &Atlas, t: &Tessellation) -> Vec<DrawnTriangle> {
    let mut out = Vec::with_capacity(t.triangles.len());
    for (k, coords) in t.triangle_coords.iter().enumerate() {
        let chart = &atlas.charts()[t.triangle_charts[k].index()];
        let phi = *chart.to_model();
        let lift = |w: Complex64| match chart.kind() {
            // The south cap is drawn in 1/ζ = λw (finite at its centre, ζ = ∞), shifted right.
            ChartKind::Cap { north: false } => w * chart.scale() + Complex64::new(2.3, 0.0),
            _ => phi.apply(w),
        };
        let corners = coords.map(lift);
        let mids = [0, 1, 2].map(|i| lift(0.5 * (coords[i] + coords[(i + 1) % 3])));
        let copies: Vec<Lft> = match atlas.polygon() {
            None => vec![Lft::IDENTITY],
            Some(poly) => {
                let centroid = lift((coords[0] + coords[1] + coords[2]) / 3.0);
                let (_, g) = poly.reduce_with_map(centroid);
                let mut maps = vec![g];
                for z in corners {
                    let (_, h) = poly.reduce_with_map(g.apply(z));
                    let h = h.compose(&g);
                    if maps.iter().all(|m| m.distance(&h) > 1e-9) {
                        maps.push(h);
                    }
                }
                maps
            }
        };
        for g in copies {
            out.push(DrawnTriangle {
                triangle: k,
                corners: corners.map(|z| g.apply(z)),
                mids: mids.map(|z| g.apply(z)),
            });
        }
    }
    out
}
