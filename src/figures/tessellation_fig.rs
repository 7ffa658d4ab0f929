//! Figure 7: the t_e/t_r tessellation at the coarsest level, subdivided, and inside each chart type.

use charts::{Atlas, ChartId, ChartsError, Tessellation};
use num_complex::Complex64;

use super::drawing::{drawn_triangles, fill, polygon_path};
use super::geometry::domain_boundary;
use super::svg::{Doc, Font, Frame, HEADING_FONT, Label, polyline_data, xy};
use super::{COARSE, SUBDIVIDED};

/// The tessellation in the polygon, clipped to it, triangles coloured by home chart.
fn in_polygon(doc: &mut Doc, atlas: &Atlas, t: &Tessellation, frame: Frame, id: &str, line: f64) {
    let poly = atlas.polygon().expect("a polygon atlas");
    doc.circle(
        frame.px(Complex64::ZERO),
        frame.scale,
        "fill=\"none\" stroke=\"#888888\" stroke-width=\"1.2\"",
    );
    let outline = polygon_path(poly, |z| frame.px(z));
    doc.clip(id, &outline);
    doc.group(&format!(
        "clip-path=\"url(#{id})\" stroke=\"#333333\" stroke-width=\"{line:.1}\" stroke-linejoin=\"round\""
    ));
    for drawn in drawn_triangles(atlas, t) {
        let k = drawn.triangle;
        let kind = atlas.charts()[t.triangle_charts[k].index()].kind();
        doc.path(
            &drawn.path(|z| frame.px(z)),
            &format!("fill=\"{}\"", fill(kind, t.triangle_regions[k])),
        );
    }
    doc.end();
    doc.path(
        &outline,
        "fill=\"none\" stroke=\"#000000\" stroke-width=\"2.2\"",
    );
}

/// The triangles whose home chart is `chart`, in its coordinates (straight sides there).
fn in_chart(doc: &mut Doc, atlas: &Atlas, t: &Tessellation, chart: ChartId, frame: Frame) {
    let c = &atlas.charts()[chart.index()];
    let domain: Vec<Complex64> = domain_boundary(c.domain(), 64)
        .into_iter()
        .map(|w| frame.px(w))
        .collect();
    doc.group("stroke=\"#333333\" stroke-width=\"0.9\" stroke-linejoin=\"round\"");
    for (k, coords) in t.triangle_coords.iter().enumerate() {
        if t.triangle_charts[k] != chart {
            continue;
        }
        let [a, b, c2] = coords.map(|w| frame.px(w));
        doc.path(
            &format!("M{} L{} L{} Z", xy(a), xy(b), xy(c2)),
            &format!("fill=\"{}\"", fill(c.kind(), t.triangle_regions[k])),
        );
    }
    doc.end();
    doc.path(
        &polyline_data(&domain, true),
        "fill=\"none\" stroke=\"#000000\" stroke-width=\"1.5\" stroke-dasharray=\"6 4\"",
    );
}

pub fn figure7(atlas: &Atlas) -> Result<String, ChartsError> {
    let coarse = atlas.tessellate(COARSE.0, COARSE.1)?;
    let fine = atlas.tessellate(SUBDIVIDED.0, SUBDIVIDED.1)?;
    let mut doc = Doc::new(1000, 900);
    let heading = |doc: &mut Doc, x: f64, what: &str, (te, tr): (u32, u32)| {
        let label = Label::plain(what)
            .then(": t")
            .sub("e")
            .then(&format!(" = {te}, t"))
            .sub("r")
            .then(&format!(" = {tr}"));
        doc.text_centred(
            Complex64::new(x, 28.0),
            HEADING_FONT + 1.0,
            Font::SansBold,
            "#000000",
            &label,
        );
    };
    heading(&mut doc, 250.0, "coarsest", COARSE);
    heading(&mut doc, 750.0, "subdivided", SUBDIVIDED);
    in_polygon(
        &mut doc,
        atlas,
        &coarse,
        Frame::new((250.0, 270.0), 225.0),
        "fig7-coarse",
        1.6,
    );
    in_polygon(
        &mut doc,
        atlas,
        &fine,
        Frame::new((750.0, 270.0), 225.0),
        "fig7-fine",
        0.8,
    );
    let names = ["inside chart", "edge chart a1", "vertex chart"];
    for (c, (id, name)) in [ChartId(0), ChartId(2), ChartId(1)]
        .into_iter()
        .zip(names)
        .enumerate()
    {
        let x = 1000.0 / 3.0 * (c as f64 + 0.5);
        let label = if c == 1 {
            Label::plain("edge chart a").sub("1")
        } else {
            Label::plain(name)
        };
        doc.text_centred(
            Complex64::new(x, 548.0),
            HEADING_FONT + 1.0,
            Font::SansBold,
            "#000000",
            &label,
        );
        in_chart(&mut doc, atlas, &fine, id, Frame::new((x, 720.0), 290.0));
    }
    Ok(doc.finish("Figure 7: the tessellation, coarsest, subdivided, and in each chart type"))
}
