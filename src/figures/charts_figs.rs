//! Figures 4 and 5: the three kinds of chart, in their own coordinates and in the polygon, and the
//! overlap regions between them.

use charts::{Atlas, Chart, ChartId, ChartKind, Domain};
use num_complex::Complex64;

use super::geometry::{
    corner_positions, domain_boundary, domain_grid, nearest, tile_maps, vertex_wedge_corners,
};
use super::palette;
use super::polygons::draw_sides;
use super::svg::{Doc, Font, Frame, HEADING_FONT, Label, edge_label, polyline_data};

/// A chart's name as a label: "inside chart", "edge chart a₁", "vertex chart".
fn chart_name(kind: ChartKind) -> Label {
    match kind {
        ChartKind::Edge { handle, side } => Label::plain(if side == 0 {
            "edge chart a"
        } else {
            "edge chart b"
        })
        .sub(&(handle + 1).to_string()),
        ChartKind::Vertex => Label::plain("vertex chart"),
        ChartKind::Inside => Label::plain("inside chart"),
        ChartKind::Cap { north } => Label::plain(if north { "north cap" } else { "south cap" }),
    }
}

/// A chart's short name: "inside", "a₁", "vertex".
fn short_name(kind: ChartKind) -> Label {
    match kind {
        ChartKind::Edge { handle, side } => {
            Label::plain(if side == 0 { "a" } else { "b" }).sub(&(handle + 1).to_string())
        }
        ChartKind::Vertex => Label::plain("vertex"),
        ChartKind::Inside => Label::plain("inside"),
        ChartKind::Cap { north } => Label::plain(if north { "N" } else { "S" }),
    }
}

/// The vertex chart's wedge boundaries (chart directions (m + ½)ω).
fn vertex_spokes(atlas: &Atlas) -> Vec<f64> {
    let poly = atlas.polygon().expect("a polygon atlas");
    let omega = poly.constants().omega;
    (0..poly.sides())
        .map(|m| (m as f64 + 0.5) * omega)
        .collect()
}

/// The chart's domain with its grid, in chart coordinates.
fn draw_domain(doc: &mut Doc, atlas: &Atlas, chart: &Chart, frame: Frame) {
    let kind = chart.kind();
    let boundary: Vec<Complex64> = domain_boundary(chart.domain(), 64)
        .into_iter()
        .map(|w| frame.px(w))
        .collect();
    doc.path(
        &polyline_data(&boundary, true),
        &format!("fill=\"{}\" stroke=\"none\"", palette::fill(kind)),
    );
    let spokes = (kind == ChartKind::Vertex).then(|| vertex_spokes(atlas));
    let grid_style = format!(
        "fill=\"none\" stroke=\"{}\" stroke-width=\"0.9\" stroke-opacity=\"0.75\"",
        palette::stroke(kind)
    );
    for line in domain_grid(chart.domain(), spokes.as_deref()) {
        let pts: Vec<Complex64> = line.into_iter().map(|w| frame.px(w)).collect();
        doc.polyline(&pts, &grid_style);
    }
    doc.path(
        &polyline_data(&boundary, true),
        &format!(
            "fill=\"none\" stroke=\"{}\" stroke-width=\"2.5\"",
            palette::stroke(kind)
        ),
    );
    doc.circle(frame.px(Complex64::ZERO), 3.5, "fill=\"#000000\"");
}

/// The polygon in the Poincaré disk, with `outline_id` made a clip path of it; returns the outline.
fn draw_disk_and_polygon(doc: &mut Doc, atlas: &Atlas, frame: Frame, outline_id: &str) -> String {
    let poly = atlas.polygon().expect("a polygon atlas");
    doc.circle(
        frame.px(Complex64::ZERO),
        frame.scale,
        "fill=\"none\" stroke=\"#888888\" stroke-width=\"1.2\"",
    );
    let outline = super::drawing::polygon_path(poly, |z| frame.px(z));
    doc.clip(outline_id, &outline);
    doc.path(&outline, "fill=\"#f4f4f4\" stroke=\"none\"");
    outline
}

/// The chart's image in the polygon: the raw image of its domain (one LFT) dashed, and the image
/// brought back into the polygon by the group, filled, with the grid.
fn draw_image(doc: &mut Doc, atlas: &Atlas, chart: &Chart, frame: Frame, clip_id: &str) {
    let poly = atlas.polygon().expect("a polygon atlas");
    let kind = chart.kind();
    let phi = *chart.to_model();
    let boundary = domain_boundary(chart.domain(), 96);
    let spokes = (kind == ChartKind::Vertex).then(|| vertex_spokes(atlas));
    let grid = domain_grid(chart.domain(), spokes.as_deref());
    doc.group(&format!("clip-path=\"url(#{clip_id})\""));
    for g in tile_maps(poly, chart) {
        let map = |w: Complex64| frame.px(g.apply(phi.apply(w)));
        let outline: Vec<Complex64> = boundary.iter().map(|&w| map(w)).collect();
        doc.path(
            &polyline_data(&outline, true),
            &format!(
                "fill=\"{}\" stroke=\"{}\" stroke-width=\"2\"",
                palette::fill(kind),
                palette::stroke(kind)
            ),
        );
        for line in &grid {
            let pts: Vec<Complex64> = line.iter().map(|&w| map(w)).collect();
            doc.polyline(
                &pts,
                &format!(
                    "fill=\"none\" stroke=\"{}\" stroke-width=\"0.7\" stroke-opacity=\"0.75\"",
                    palette::stroke(kind)
                ),
            );
        }
    }
    doc.end();
    let raw: Vec<Complex64> = boundary.iter().map(|&w| frame.px(phi.apply(w))).collect();
    doc.path(
        &polyline_data(&raw, true),
        &format!(
            "fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" stroke-dasharray=\"6 4\"",
            palette::stroke(kind)
        ),
    );
}

/// Figure 4: the inside chart, edge chart a₁ and the vertex chart, each in its own coordinates
/// (top) and in the polygon (bottom).
pub fn figure4(atlas: &Atlas) -> String {
    let poly = atlas.polygon().expect("a polygon atlas");
    let (col, width) = (380.0, 1140);
    let mut doc = Doc::new(width, 820);
    let ids = [ChartId(0), ChartId(2), ChartId(1)];
    let positions = corner_positions(poly);
    let wedges = vertex_wedge_corners(atlas, poly);
    let omega = poly.constants().omega;
    for (c, id) in ids.iter().enumerate() {
        let chart = &atlas.charts()[id.index()];
        let x = col * (c as f64 + 0.5);
        doc.text_centred(
            Complex64::new(x, 28.0),
            HEADING_FONT + 2.0,
            Font::SansBold,
            "#000000",
            &chart_name(chart.kind()),
        );
        let top = Frame::new((x, 205.0), 300.0);
        draw_domain(&mut doc, atlas, chart, top);
        match chart.kind() {
            ChartKind::Edge { .. } => {
                // The midline (on the edge) and where each half goes.
                doc.line(
                    top.px(Complex64::new(0.0, -0.5)),
                    top.px(Complex64::new(0.0, 0.5)),
                    "stroke=\"#000000\" stroke-width=\"2.5\"",
                );
                for side in [-0.25, 0.25] {
                    let z = poly.reduce(chart.to_model().apply(Complex64::new(side, 0.0)));
                    let mids: Vec<Complex64> = (0..poly.sides())
                        .map(|e| Complex64::from_polar(poly.constants().gamma, e as f64 * omega))
                        .collect();
                    let e = nearest(&mids, z);
                    doc.text_centred(
                        top.px(Complex64::new(side, -0.575)),
                        17.0,
                        Font::Sans,
                        &palette::stroke(chart.kind()),
                        &Label::plain("along ").append(&edge_label(e)),
                    );
                }
            }
            ChartKind::Vertex => {
                for (m, &corner) in wedges.iter().enumerate() {
                    let at = top.px(Complex64::from_polar(0.4, m as f64 * omega));
                    doc.circle(
                        at,
                        12.0,
                        "fill=\"#ffffff\" stroke=\"#000000\" stroke-width=\"1\"",
                    );
                    doc.text_centred(
                        at,
                        14.0,
                        Font::Sans,
                        "#000000",
                        &Label::plain(&positions[corner].to_string()),
                    );
                }
            }
            _ => {}
        }
        let bottom = Frame::new((x, 632.0), 172.0);
        let clip_id = format!("fig4-polygon-{c}");
        draw_disk_and_polygon(&mut doc, atlas, bottom, &clip_id);
        draw_image(&mut doc, atlas, chart, bottom, &clip_id);
        let poly = atlas.polygon().expect("a polygon atlas");
        draw_sides(&mut doc, poly, bottom, 40, 2.0);
        match chart.kind() {
            ChartKind::Edge { handle, side } => {
                for e in [
                    4 * handle as usize + side as usize,
                    4 * handle as usize + side as usize + 2,
                ] {
                    let at = bottom.px(Complex64::from_polar(0.92, (e as f64 - 0.32) * omega));
                    doc.text_centred(
                        at,
                        17.0,
                        Font::Math,
                        &palette::stroke(palette::edge_kind(e)),
                        &edge_label(e),
                    );
                }
            }
            ChartKind::Vertex => {
                for (k, &corner) in poly.corners().iter().enumerate() {
                    let at = bottom.px(corner * ((poly.constants().alpha + 0.11) / corner.norm()));
                    doc.circle(
                        at,
                        11.0,
                        "fill=\"#ffffff\" stroke=\"#000000\" stroke-width=\"1\"",
                    );
                    doc.text_centred(
                        at,
                        13.0,
                        Font::Sans,
                        "#000000",
                        &Label::plain(&positions[k].to_string()),
                    );
                }
            }
            _ => {}
        }
    }
    doc.text_centred(
        Complex64::new(f64::from(width) / 2.0, 422.0),
        HEADING_FONT,
        Font::Sans,
        "#333333",
        &Label::plain("top: in chart coordinates · bottom: in the polygon (dashed: the chart's image before the group brings it back)"),
    );
    doc.finish("Figure 4: the inside chart, an edge chart and the vertex chart")
}

/// The components of U_ij (the points of chart i that also lie in chart j), each as a closed outline
/// in chart i's coordinates: the preimage of chart j's domain boundary under that component's
/// transition ψ_ij. The region is this outline's inside, within chart i's domain.
pub fn overlap_regions(atlas: &Atlas, i: ChartId, j: ChartId) -> Vec<Vec<Complex64>> {
    let to = atlas.charts()[j.index()].domain();
    let boundary = domain_boundary(to, 128);
    atlas
        .transitions(i, j)
        .iter()
        .map(|t| {
            let back = t.lft.inverse();
            boundary.iter().map(|&w| back.apply(w)).collect()
        })
        .collect()
}

/// Figure 5: one panel per kind of pair, each in chart i's coordinates with U_ij shaded in chart j's
/// colour. Also returns a one-line summary of the component counts, for the caption.
pub fn figure5(atlas: &Atlas) -> (String, String) {
    let edge = ChartId(2);
    let (inside, vertex) = (ChartId(0), ChartId(1));
    let others: Vec<ChartId> = (3..atlas.charts().len() as u32).map(ChartId).collect();
    let panels: Vec<(&str, ChartId, Vec<ChartId>)> = vec![
        ("inside – edge", edge, vec![inside]),
        ("edge – edge", edge, others),
        ("edge – vertex", edge, vec![vertex]),
        ("inside – vertex", vertex, vec![inside]),
    ];
    let panels: Vec<_> = panels
        .into_iter()
        .filter(|(_, i, js)| js.iter().any(|&j| !atlas.transitions(*i, j).is_empty()))
        .collect();
    let (cell_w, cell_h) = (460.0, 470.0);
    let columns = 2;
    let rows = panels.len().div_ceil(columns);
    let mut doc = Doc::new(
        (cell_w * columns as f64) as u32,
        (cell_h * rows as f64) as u32,
    );
    let mut summary = Vec::new();
    for (p, (title, i, js)) in panels.iter().enumerate() {
        let (cx, cy) = (
            cell_w * ((p % columns) as f64 + 0.5),
            cell_h * (p / columns) as f64,
        );
        let chart_i = &atlas.charts()[i.index()];
        doc.text_centred(
            Complex64::new(cx, cy + 26.0),
            HEADING_FONT + 2.0,
            Font::SansBold,
            "#000000",
            &Label::plain(title),
        );
        doc.text_centred(
            Complex64::new(cx, cy + 50.0),
            15.0,
            Font::Sans,
            "#333333",
            &Label::plain("in the coordinates of the ").append(&chart_name(chart_i.kind())),
        );
        let frame = Frame::new((cx, cy + 235.0), 320.0);
        let domain: Vec<Complex64> = domain_boundary(chart_i.domain(), 64)
            .into_iter()
            .map(|w| frame.px(w))
            .collect();
        let clip_id = format!("fig5-domain-{p}");
        doc.clip(&clip_id, &polyline_data(&domain, true));
        doc.path(
            &polyline_data(&domain, true),
            "fill=\"#ffffff\" stroke=\"none\"",
        );
        for line in domain_grid(Domain::Square, None) {
            let pts: Vec<Complex64> = line.into_iter().map(|w| frame.px(w)).collect();
            doc.group(&format!("clip-path=\"url(#{clip_id})\""));
            doc.polyline(
                &pts,
                "fill=\"none\" stroke=\"#d8d8d8\" stroke-width=\"0.8\"",
            );
            doc.end();
        }
        let mut legend = Vec::new();
        for &j in js {
            let kind = atlas.charts()[j.index()].kind();
            let regions = overlap_regions(atlas, *i, j);
            doc.group(&format!("clip-path=\"url(#{clip_id})\""));
            for region in &regions {
                let pts: Vec<Complex64> = region.iter().map(|&w| frame.px(w)).collect();
                doc.path(
                    &polyline_data(&pts, true),
                    &format!(
                        "fill=\"{}\" fill-opacity=\"0.9\" stroke=\"{}\" stroke-width=\"1.8\"",
                        palette::fill(kind),
                        palette::stroke(kind)
                    ),
                );
            }
            doc.end();
            legend.push((kind, regions.len()));
            summary.push(format!(
                "{} ∩ {}: {} component{}",
                short_name(chart_i.kind()).text(),
                short_name(kind).text(),
                regions.len(),
                if regions.len() == 1 { "" } else { "s" }
            ));
        }
        doc.path(
            &polyline_data(&domain, true),
            &format!(
                "fill=\"none\" stroke=\"{}\" stroke-width=\"2.5\"",
                palette::stroke(chart_i.kind())
            ),
        );
        // The legend: chart j's colour, name and component count.
        let total = legend.len() as f64;
        for (k, (kind, count)) in legend.iter().enumerate() {
            let x = cx + (k as f64 - (total - 1.0) / 2.0) * 140.0;
            let y = cy + cell_h - 38.0;
            doc.rect(
                x - 62.0,
                y - 11.0,
                20.0,
                20.0,
                &format!(
                    "fill=\"{}\" stroke=\"{}\" stroke-width=\"1.5\"",
                    palette::fill(*kind),
                    palette::stroke(*kind)
                ),
            );
            doc.text(
                Complex64::new(x - 36.0, y + 5.0),
                15.0,
                super::svg::Anchor::Start,
                Font::Sans,
                "#000000",
                &short_name(*kind).then(&format!(": {count}")),
            );
        }
    }
    (
        doc.finish("Figure 5: the overlap regions U_ij for each kind of chart pair"),
        summary.join("; "),
    )
}
