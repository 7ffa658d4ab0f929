//! The 2D figures: well-formed SVG pages for print (white background, a viewBox equal to the page,
//! legible text), with the labels each figure promises, the same bytes every time, and a caption
//! file that lists them all. Figure 5's shaded regions are checked against point location.

use charts::{Atlas, ChartId, ChartPoint};
use ntori::figures::{self, Figure, palette};
use num_complex::Complex64;

/// The library's tests make only the 2D figures (the PNG ones need a GPU; `cli_figures` covers them).
const NO_RENDERING: figures::Options = figures::Options { render: false };

fn figure<'a>(all: &'a [Figure], file: &str) -> &'a Figure {
    all.iter()
        .find(|f| f.file == file)
        .unwrap_or_else(|| panic!("no figure {file}"))
}

fn text(f: &Figure) -> &str {
    std::str::from_utf8(&f.bytes).expect("SVG is UTF-8")
}

/// Every `<text>` element's content, subscripts and all, as a reader sees it.
fn labels(svg: &str) -> Vec<String> {
    let doc = roxmltree::Document::parse(svg).unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            n.descendants()
                .filter(|d| d.is_text())
                .filter_map(|d| d.text())
                .collect()
        })
        .collect()
}

fn number(s: &str) -> f64 {
    s.trim()
        .parse()
        .unwrap_or_else(|_| panic!("not a number: {s}"))
}

#[test]
fn every_2d_figure_is_a_printable_page() {
    let all = figures::figures_2d().unwrap();
    assert_eq!(all.len(), 6);
    for f in &all {
        assert!(f.file.ends_with(".svg"), "{}", f.file);
        let svg = text(f);
        let doc = roxmltree::Document::parse(svg)
            .unwrap_or_else(|e| panic!("{} is not well-formed XML: {e}", f.file));
        let root = doc.root_element();
        assert!(
            root.has_tag_name(("http://www.w3.org/2000/svg", "svg")),
            "{}",
            f.file
        );
        let (w, h) = (
            number(root.attribute("width").unwrap()),
            number(root.attribute("height").unwrap()),
        );
        // The viewBox is the page in pixels, so font sizes are drawn sizes.
        let view: Vec<f64> = root
            .attribute("viewBox")
            .unwrap_or_else(|| panic!("{} has no viewBox", f.file))
            .split_whitespace()
            .map(number)
            .collect();
        assert_eq!(view, [0.0, 0.0, w, h], "{}", f.file);
        // The first thing drawn is a white rectangle over the whole page.
        let first = root
            .children()
            .filter(|n| n.is_element())
            .find(|n| !n.has_tag_name("title") && !n.has_tag_name("defs"))
            .unwrap();
        assert!(first.has_tag_name("rect"), "{}", f.file);
        assert_eq!(first.attribute("fill"), Some("#ffffff"), "{}", f.file);
        assert_eq!(number(first.attribute("width").unwrap()), w);
        assert_eq!(number(first.attribute("height").unwrap()), h);
        // Legible text, on the page.
        let mut texts = 0;
        for n in doc
            .descendants()
            .filter(|n| n.has_tag_name("text") || n.has_tag_name("tspan"))
        {
            if let Some(size) = n.attribute("font-size") {
                assert!(number(size) >= 11.0, "{}: font-size {size}", f.file);
            }
            if n.has_tag_name("text") {
                texts += 1;
                assert!(
                    n.attribute("font-size").is_some(),
                    "{}: text without a size",
                    f.file
                );
                let (x, y) = (
                    number(n.attribute("x").unwrap()),
                    number(n.attribute("y").unwrap()),
                );
                assert!(
                    x > 0.0 && x < w && y > 0.0 && y < h,
                    "{}: text at ({x}, {y})",
                    f.file
                );
            }
        }
        assert!(texts > 0, "{} has no labels", f.file);
        // Every number written with a fixed, short precision (no 17-digit floats).
        for token in svg.split(|c: char| !(c.is_ascii_digit() || c == '.')) {
            let decimals = token.split('.').nth(1).map_or(0, str::len);
            assert!(decimals <= 6, "{}: {token}", f.file);
        }
    }
}

#[test]
fn figures_carry_their_labels() {
    let all = figures::figures_2d().unwrap();
    let has = |file: &str, wanted: &[&str]| {
        let found = labels(text(figure(&all, file)));
        for w in wanted {
            assert!(
                found.iter().any(|l| l == w),
                "{file} lacks the label {w:?}: {found:?}"
            );
        }
    };
    let edges = ["a1", "b1", "a1⁻¹", "b1⁻¹", "a2", "b2", "a2⁻¹", "b2⁻¹"];
    has("fig1-polygon.svg", &edges);
    has("fig2a-corners.svg", &edges);
    has(
        "fig2a-corners.svg",
        &["0", "1", "2", "3", "4", "5", "6", "7"],
    );
    has(
        "fig3-hyperbolic-polygon.svg",
        &["α", "ω", "β", "h", "r", "γ"],
    );
    has(
        "fig4-charts.svg",
        &[
            "inside chart",
            "edge chart a1",
            "vertex chart",
            "along a1",
            "along a1⁻¹",
        ],
    );
    has(
        "fig5-overlaps.svg",
        &[
            "inside – edge",
            "edge – edge",
            "edge – vertex",
            "inside – vertex",
        ],
    );
    has(
        "fig7-tessellation.svg",
        &[
            "coarsest: te = 1, tr = 1",
            "subdivided: te = 4, tr = 3",
            "vertex chart",
        ],
    );
}

#[test]
fn edge_pairs_keep_one_colour_across_figures() {
    let all = figures::figures_2d().unwrap();
    for e in 0..8 {
        let colour = palette::stroke(palette::edge_kind(e));
        assert_eq!(
            colour,
            palette::stroke(palette::edge_kind((e + 2) % 4 + e / 4 * 4))
        );
        for file in [
            "fig1-polygon.svg",
            "fig2a-corners.svg",
            "fig3-hyperbolic-polygon.svg",
            "fig4-charts.svg",
        ] {
            assert!(
                text(figure(&all, file)).contains(&colour),
                "{file} lacks {colour}"
            );
        }
    }
    // Four pairs, four different colours, none the inside or vertex chart's.
    let mut colours: Vec<String> = [0, 1, 4, 5]
        .map(|e| palette::stroke(palette::edge_kind(e)))
        .to_vec();
    colours.push(palette::stroke(charts::ChartKind::Inside));
    colours.push(palette::stroke(charts::ChartKind::Vertex));
    let mut unique = colours.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), colours.len());
}

#[test]
fn the_same_figures_come_out_byte_for_byte() {
    let (a, b) = (
        figures::figures_2d().unwrap(),
        figures::figures_2d().unwrap(),
    );
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.file, y.file);
        assert!(x.bytes == y.bytes, "{} differs between two runs", x.file);
    }
}

#[test]
fn the_caption_file_lists_every_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("figs");
    let mut events = 0;
    let summary = figures::generate(&out, &NO_RENDERING, &mut |_| events += 1).unwrap();
    assert!(events > 0);
    let captions = std::fs::read_to_string(out.join("CAPTIONS.md")).unwrap();
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    files.sort();
    assert_eq!(files.len(), summary.written.len());
    for f in files.iter().filter(|f| *f != "CAPTIONS.md") {
        assert!(
            captions.contains(&format!("## {f}")),
            "CAPTIONS.md lacks {f}"
        );
    }
    for f in figures::figures_2d().unwrap() {
        assert!(files.contains(&f.file), "{} not written", f.file);
    }
    assert!(captions.contains("ntori figures --out DIR"));
    // A second run writes the same bytes.
    let before: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    figures::generate(&out, &NO_RENDERING, &mut |_| {}).unwrap();
    for (f, b) in files.iter().zip(before) {
        assert!(
            std::fs::read(out.join(f)).unwrap() == b,
            "{f} changed on a re-run"
        );
    }
}

/// Point-in-polygon by crossings.
fn inside(poly: &[Complex64], z: Complex64) -> bool {
    let mut odd = false;
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        if (a.im > z.im) != (b.im > z.im) {
            let x = a.re + (z.im - a.im) / (b.im - a.im) * (b.re - a.re);
            if x > z.re {
                odd = !odd;
            }
        }
    }
    odd
}

fn distance_to_outline(poly: &[Complex64], z: Complex64) -> f64 {
    (0..poly.len())
        .map(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            let t = (((z - a).conj() * (b - a)).re / (b - a).norm_sqr()).clamp(0.0, 1.0);
            (a + (b - a) * t - z).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn overlap_regions_are_where_point_location_finds_both_charts() {
    let atlas = Atlas::new(figures::GENUS).unwrap();
    let n = atlas.charts().len() as u32;
    let pairs = [(2, 0), (2, 1), (1, 0), (0, 2)]
        .into_iter()
        .chain((3..n).map(|j| (2, j)));
    for (i, j) in pairs {
        let (i, j) = (ChartId(i), ChartId(j));
        let regions = figures::overlap_regions(&atlas, i, j);
        assert_eq!(regions.len(), atlas.transitions(i, j).len());
        let domain = atlas.charts()[i.index()].domain();
        let m = 120;
        let (mut checked, mut shaded) = (0, 0);
        for a in 0..=m {
            for b in 0..=m {
                let w = Complex64::new(
                    f64::from(a) / f64::from(m) - 0.5,
                    f64::from(b) / f64::from(m) - 0.5,
                );
                if domain.margin(w) < 1e-3 {
                    continue;
                }
                // The sampled outlines are polygons through points of the true arcs: skip points
                // within their sagitta of an outline.
                if regions.iter().any(|r| distance_to_outline(r, w) < 2e-3) {
                    continue;
                }
                let located = atlas
                    .locate(ChartPoint::new(i, w))
                    .unwrap()
                    .in_chart(j)
                    .is_some();
                let drawn = regions.iter().any(|r| inside(r, w));
                assert_eq!(located, drawn, "U({i:?}, {j:?}) at {w}");
                checked += 1;
                shaded += usize::from(drawn);
            }
        }
        assert!(checked > 5000);
        assert!(shaded > 0 || regions.is_empty(), "U({i:?}, {j:?})");
    }
}
