//! Figures 1, 2 (left) and 3: the abstract 4n-gon with its edge pairing, its corners in the order
//! the surface's vertex sees them, and the hyperbolic 4n-gon with the paper's constants.

use charts::{Atlas, Polygon};
use num_complex::Complex64;

use super::geometry::{arrows_counter_clockwise, corner_positions, side_points, tile_maps};
use super::palette;
use super::svg::{Anchor, Doc, Font, Frame, LABEL_FONT, Label, edge_label, polyline_data};

/// What to write on the abstract polygon.
struct Marks {
    /// Edge labels outside (figure 1) or inside (figure 2) the polygon.
    edge_labels_outside: bool,
    /// Corner labels: each corner's position in the walk around the vertex.
    corner_labels: bool,
}

/// The abstract 4n-gon (straight sides; corner c at angle (c + ½)ω, edge e facing angle eω, as in
/// the hyperbolic polygon), each edge in its pair's colour with an arrow along its direction.
fn abstract_polygon(doc: &mut Doc, poly: &Polygon, frame: Frame, marks: &Marks) {
    let s = poly.sides();
    let omega = poly.constants().omega;
    let corner = |c: usize| frame.px(Complex64::from_polar(1.0, (c as f64 + 0.5) * omega));
    let corners: Vec<Complex64> = (0..s).map(corner).collect();
    doc.path(
        &polyline_data(&corners, true),
        "fill=\"#f4f4f4\" stroke=\"none\"",
    );
    let ccw = arrows_counter_clockwise(poly);
    let apothem = (omega / 2.0).cos();
    for (e, &ccw) in ccw.iter().enumerate() {
        let (a, b) = poly.edge_corners(e);
        let colour = palette::stroke(palette::edge_kind(e));
        doc.line(
            corners[a],
            corners[b],
            &format!("stroke=\"{colour}\" stroke-width=\"4\" stroke-linecap=\"round\""),
        );
        let (from, to) = if ccw { (a, b) } else { (b, a) };
        let dir = corners[to] - corners[from];
        let mid = 0.5 * (corners[a] + corners[b]);
        doc.arrowhead(mid + dir * 0.09, dir, 20.0, &colour);
        let out = Complex64::from_polar(1.0, e as f64 * omega);
        let at = if marks.edge_labels_outside {
            frame.px(out * apothem) + Complex64::new(out.re, -out.im) * 30.0
        } else {
            frame.px(out * apothem) - Complex64::new(out.re, -out.im) * 34.0
        };
        doc.text_centred(at, 22.0, Font::Math, &colour, &edge_label(e));
    }
    let positions = corner_positions(poly);
    for (c, &p) in corners.iter().enumerate() {
        doc.circle(p, 5.0, "fill=\"#000000\"");
        if marks.corner_labels {
            let dir = Complex64::from_polar(1.0, (c as f64 + 0.5) * omega);
            let at = p + Complex64::new(dir.re, -dir.im) * 26.0;
            doc.circle(
                at,
                15.0,
                "fill=\"#ffffff\" stroke=\"#000000\" stroke-width=\"1.5\"",
            );
            doc.text_centred(
                at,
                18.0,
                Font::Sans,
                "#000000",
                &Label::plain(&positions[c].to_string()),
            );
        }
    }
}

/// Figure 1: the abstract 4n-gon with its edges labelled a₁ b₁ a₁⁻¹ b₁⁻¹ … and arrows showing how
/// partner edges are glued (arrow onto arrow).
pub fn figure1(poly: &Polygon) -> String {
    let mut doc = Doc::new(620, 620);
    abstract_polygon(
        &mut doc,
        poly,
        Frame::new((310.0, 310.0), 220.0),
        &Marks {
            edge_labels_outside: true,
            corner_labels: false,
        },
    );
    doc.finish(&format!(
        "Figure 1: the abstract {}-gon of genus {} with its edge pairing",
        poly.sides(),
        poly.genus()
    ))
}

/// Figure 2, left: the 4n-gon with each corner numbered by its place in the walk around the
/// surface's single vertex (all corners are that one point).
pub fn figure2_polygon(poly: &Polygon) -> String {
    let mut doc = Doc::new(620, 660);
    abstract_polygon(
        &mut doc,
        poly,
        Frame::new((310.0, 310.0), 220.0),
        &Marks {
            edge_labels_outside: false,
            corner_labels: true,
        },
    );
    doc.text(
        Complex64::new(310.0, 640.0),
        15.0,
        Anchor::Middle,
        Font::Sans,
        "#000000",
        &Label::plain("corner k: the k-th corner met walking around the one vertex"),
    );
    doc.finish(&format!(
        "Figure 2 (left): the {}-gon's corners in the order around the surface's vertex",
        poly.sides()
    ))
}

/// Figure 3: the hyperbolic 4n-gon in the Poincaré disk, with ω, h, r, γ, α and β marked, and the
/// tessellation squares of the first two edge charts (whose corners meet at β).
pub fn figure3(atlas: &Atlas, poly: &Polygon) -> String {
    let size = 760.0;
    let mut doc = Doc::new(size as u32, size as u32);
    let frame = Frame::new((size / 2.0, size / 2.0), 228.0);
    let c = *poly.constants();
    let (h, r) = (c.h.unwrap_or(1.0), c.r.unwrap_or(0.0));
    let omega = c.omega;
    // The 4n edge circles, and the unit circle.
    for e in 0..poly.sides() {
        let centre = frame.px(Complex64::from_polar(h, e as f64 * omega));
        doc.circle(
            centre,
            r * frame.scale,
            "fill=\"none\" stroke=\"#b0b0b0\" stroke-width=\"1\" stroke-dasharray=\"5 4\"",
        );
    }
    doc.circle(
        frame.px(Complex64::ZERO),
        frame.scale,
        "fill=\"none\" stroke=\"#333333\" stroke-width=\"1.5\"",
    );
    // The polygon, and the squares of edge charts a₁ and b₁ clipped to it.
    let outline = super::drawing::polygon_path(poly, |z| frame.px(z));
    doc.clip("fig3-polygon", &outline);
    doc.path(&outline, "fill=\"#f4f4f4\" stroke=\"none\"");
    if let Some(half) = atlas.tessellation_square_half() {
        doc.group("clip-path=\"url(#fig3-polygon)\"");
        for chart in &atlas.charts()[2..4] {
            let square: Vec<Complex64> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .map(|&(x, y)| Complex64::new(x, y) * half)
                .collect();
            let boundary: Vec<Complex64> = (0..4)
                .flat_map(|k| {
                    let (a, b) = (square[k], square[(k + 1) % 4]);
                    (0..32).map(move |i| a + (b - a) * (f64::from(i) / 32.0))
                })
                .collect();
            for g in tile_maps(poly, chart) {
                let pts: Vec<Complex64> = boundary
                    .iter()
                    .map(|&w| frame.px(g.apply(chart.to_model().apply(w))))
                    .collect();
                doc.path(
                    &polyline_data(&pts, true),
                    &format!(
                        "fill=\"{}\" stroke=\"{}\" stroke-width=\"1.2\"",
                        palette::fill(chart.kind()),
                        palette::stroke(chart.kind())
                    ),
                );
            }
        }
        doc.end();
    }
    draw_sides(&mut doc, poly, frame, 48, 3.5);
    let ink = "#000000";
    let measure = "stroke=\"#000000\" stroke-width=\"1.6\"";
    let origin = frame.px(Complex64::ZERO);
    // h: to the centre of edge 0's circle; r: from there to where the circle meets the unit circle.
    let centre0 = frame.px(Complex64::new(h, 0.0));
    doc.line(origin, centre0, measure);
    doc.circle(centre0, 4.0, "fill=\"#000000\"");
    doc.text_centred(
        frame.px(Complex64::new(0.3, 0.0)) + Complex64::new(0.0, 18.0),
        LABEL_FONT,
        Font::Math,
        ink,
        &Label::plain("h"),
    );
    let meet = Complex64::from_polar(1.0, -(1.0 / h).acos());
    doc.line(centre0, frame.px(meet), measure);
    let mid_r = frame.px(0.5 * (Complex64::new(h, 0.0) + meet));
    doc.text_centred(
        mid_r + Complex64::new(16.0, 4.0),
        LABEL_FONT,
        Font::Math,
        ink,
        &Label::plain("r"),
    );
    // ω: the angle between the directions of edges 0 and 1; γ: the distance to edge 1's midpoint.
    let gamma_end = Complex64::from_polar(c.gamma, omega);
    doc.line(origin, frame.px(gamma_end), measure);
    doc.circle(frame.px(gamma_end), 3.5, "fill=\"#000000\"");
    let normal = Complex64::from_polar(1.0, omega + std::f64::consts::FRAC_PI_2);
    doc.text_centred(
        frame.px(0.55 * gamma_end + normal * 0.07),
        LABEL_FONT,
        Font::Math,
        ink,
        &Label::plain("γ"),
    );
    let arc: Vec<Complex64> = (0..=24)
        .map(|i| frame.px(Complex64::from_polar(0.2, omega * f64::from(i) / 24.0)))
        .collect();
    doc.polyline(
        &arc,
        "fill=\"none\" stroke=\"#000000\" stroke-width=\"1.4\"",
    );
    doc.text_centred(
        frame.px(Complex64::from_polar(0.28, omega / 2.0)),
        LABEL_FONT,
        Font::Math,
        ink,
        &Label::plain("ω"),
    );
    // α: the distance to a corner (corner 3, on the far side, away from the other marks).
    let corner = poly.corners()[3 % poly.sides()];
    doc.line(origin, frame.px(corner), measure);
    let normal = corner * Complex64::new(0.0, 1.0) / corner.norm();
    doc.text_centred(
        frame.px(0.5 * corner + normal * 0.07),
        LABEL_FONT,
        Font::Math,
        ink,
        &Label::plain("α"),
    );
    // β, where the squares of edge charts a₁ and b₁ meet near corner 0.
    doc.circle(frame.px(c.beta), 5.0, "fill=\"#000000\"");
    doc.text_centred(
        frame.px(c.beta) + Complex64::new(-22.0, 16.0),
        LABEL_FONT,
        Font::Math,
        ink,
        &Label::plain("β"),
    );
    doc.circle(origin, 3.5, "fill=\"#000000\"");
    doc.finish(&format!(
        "Figure 3: the hyperbolic {}-gon of genus {} with ω, h, r, γ, α and β",
        poly.sides(),
        poly.genus()
    ))
}

/// The polygon's sides, each in its pair's colour, as polylines of `samples` points.
pub(super) fn draw_sides(doc: &mut Doc, poly: &Polygon, frame: Frame, samples: usize, width: f64) {
    for e in 0..poly.sides() {
        let pts: Vec<Complex64> = side_points(poly, e, samples)
            .into_iter()
            .map(|z| frame.px(z))
            .collect();
        doc.polyline(
            &pts,
            &format!(
                "fill=\"none\" stroke=\"{}\" stroke-width=\"{width:.1}\" stroke-linecap=\"round\"",
                palette::stroke(palette::edge_kind(e))
            ),
        );
    }
}
