//! `ntori tessellate`: build the t_e/t_r tessellation, check it, and draw it.

use std::fmt::Write as _;

use charts::check::consistency_at;
use charts::{Atlas, ChartKind, Geometry, Lft, Polygon, Region, Tessellation};
use num_complex::Complex64;
use serde::Serialize;

use crate::mesh::{HalfEdgeMesh, Topology};

/// What `ntori tessellate` reports (text or JSON).
#[derive(Debug, Serialize)]
pub struct TessellationReport {
    pub genus: u32,
    pub te: u32,
    pub tr: u32,
    pub vertices: usize,
    pub edges: usize,
    pub faces: usize,
    pub euler_characteristic: i64,
    pub topology: Topology,
    /// What the documented formulas predict.
    pub expected_vertices: u64,
    pub expected_faces: u64,
    /// Triangles with (near-)zero or negative area in their home chart.
    pub degenerate_triangles: usize,
    /// Largest disagreement of a vertex's coordinates between the charts holding it (chart units).
    pub max_vertex_error: f64,
    /// Sum of the triangles' areas with geodesic sides, and what the surface's area must be.
    pub area: f64,
    pub expected_area: f64,
    pub passed: bool,
}

/// Tessellates and checks. Errors only for impossible parameters.
pub fn report(
    atlas: &Atlas,
    t: &Tessellation,
) -> Result<TessellationReport, crate::mesh::MeshError> {
    let genus = atlas.genus();
    let faces = t
        .triangles
        .iter()
        .zip(&t.triangle_edge_labels)
        .map(|(f, l)| (&f[..], Some(&l[..])));
    let topology = HalfEdgeMesh::from_labelled_polygons(t.vertices.len(), faces)?.topology();
    let degenerate_triangles = t
        .triangle_coords
        .iter()
        .filter(|[a, b, c]| {
            let doubled = ((b - a).conj() * (c - a)).im;
            let longest = (b - a)
                .norm_sqr()
                .max((c - b).norm_sqr())
                .max((a - c).norm_sqr());
            doubled <= 1e-10 * longest
        })
        .count();
    let max_vertex_error = t
        .vertices
        .iter()
        .map(|&v| consistency_at(atlas, v).worst())
        .fold(0.0, f64::max);
    let area: f64 = t.geodesic_areas(atlas).iter().sum();
    let expected_area = match atlas.geometry() {
        Geometry::Hyperbolic => 4.0 * std::f64::consts::PI * (f64::from(genus) - 1.0),
        Geometry::Euclidean => 1.0,
        Geometry::Spherical => 4.0 * std::f64::consts::PI,
    };
    let (expected_vertices, expected_faces) = (
        Tessellation::expected_vertices(genus, t.te, t.tr),
        Tessellation::expected_triangles(genus, t.te, t.tr),
    );
    let passed = topology.closed
        && topology.manifold
        && topology.orientable
        && topology.misoriented_edges == 0
        && topology.components == 1
        && topology.genus == Some(genus)
        && expected_vertices == t.vertices.len() as u64
        && expected_faces == t.triangles.len() as u64
        && degenerate_triangles == 0
        && max_vertex_error <= 1e-12
        && ((area - expected_area) / expected_area).abs() < 1e-9;
    Ok(TessellationReport {
        genus,
        te: t.te,
        tr: t.tr,
        vertices: topology.vertices,
        edges: topology.edges,
        faces: topology.faces,
        euler_characteristic: topology.euler_characteristic,
        topology,
        expected_vertices,
        expected_faces,
        degenerate_triangles,
        max_vertex_error,
        area,
        expected_area,
        passed,
    })
}

impl TessellationReport {
    pub fn to_text(&self) -> String {
        let t = &self.topology;
        let yes = |b: bool| if b { "yes" } else { "NO" };
        let mut s = String::new();
        let _ = writeln!(
            s,
            "genus {}, t_e = {}, t_r = {}",
            self.genus, self.te, self.tr
        );
        let _ = writeln!(
            s,
            "  V = {}  (formula: {})",
            self.vertices, self.expected_vertices
        );
        let _ = writeln!(s, "  E = {}", self.edges);
        let _ = writeln!(
            s,
            "  F = {}  (formula: {})",
            self.faces, self.expected_faces
        );
        let _ = writeln!(
            s,
            "  χ = V − E + F = {}  (2 − 2n = {})",
            self.euler_characteristic,
            2 - 2 * i64::from(self.genus)
        );
        let genus = t.genus.map_or("none".to_string(), |g| g.to_string());
        let _ = writeln!(
            s,
            "  genus from the topology: {genus}; components: {}",
            t.components
        );
        let _ = writeln!(
            s,
            "  closed: {}; manifold: {}; orientable: {}; consistently oriented: {}",
            yes(t.closed),
            yes(t.manifold),
            yes(t.orientable),
            yes(t.misoriented_edges == 0)
        );
        let _ = writeln!(
            s,
            "  degenerate triangles in their home chart: {}",
            self.degenerate_triangles
        );
        let _ = writeln!(
            s,
            "  vertex coordinates agree across charts to {:.2e}",
            self.max_vertex_error
        );
        let _ = writeln!(
            s,
            "  triangle areas (geodesic sides) add to {:.12}; the surface's area is {:.12}",
            self.area, self.expected_area
        );
        let _ = writeln!(s, "  {}", if self.passed { "passed" } else { "FAILED" });
        s
    }
}

/// The fill colour of a triangle: its home chart's tint (see [`crate::palette`]).
pub fn fill(kind: ChartKind, region: Region) -> String {
    use crate::palette;
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

/// The tessellation drawn in the fundamental polygon (the paper's figure 7), charts coloured: each
/// triangle with its true (circular) sides, moved into the polygon by the group, clipped to it. For the
/// sphere, the two caps side by side, each in its own coordinate ζ or 1/ζ.
pub fn svg(atlas: &Atlas, t: &Tessellation) -> String {
    let mut body = String::new();
    let (view, clip) = match (atlas.geometry(), atlas.polygon()) {
        (Geometry::Spherical, _) => ("-1.15 -1.15 4.5 2.3".to_string(), None),
        (_, Some(poly)) => {
            let r = if atlas.geometry() == Geometry::Euclidean {
                0.6
            } else {
                1.05
            };
            let path = polygon_path(poly, |z| z);
            (format!("{} {} {} {}", -r, -r, 2.0 * r, 2.0 * r), Some(path))
        }
        _ => unreachable!("polygon atlases have a polygon"),
    };
    let stroke = (0.8 / (t.triangles.len() as f64).sqrt()).clamp(0.0004, 0.004);
    for drawn in drawn_triangles(atlas, t) {
        let k = drawn.triangle;
        let chart = &atlas.charts()[t.triangle_charts[k].index()];
        let _ = writeln!(
            body,
            "<path d=\"{}\" fill=\"{}\"/>",
            drawn.path(|z| z),
            fill(chart.kind(), t.triangle_regions[k])
        );
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{view}\" width=\"900\" height=\"{}\">",
        if atlas.geometry() == Geometry::Spherical {
            460
        } else {
            900
        }
    );
    let _ = writeln!(
        s,
        "<title>ntori: genus {} tessellation, t_e = {}, t_r = {}</title>",
        atlas.genus(),
        t.te,
        t.tr
    );
    let _ = writeln!(
        s,
        "<rect x=\"-10\" y=\"-10\" width=\"20\" height=\"20\" fill=\"white\"/>"
    );
    let _ = writeln!(s, "<g transform=\"scale(1,-1)\">");
    if let Some(clip) = &clip {
        let _ = writeln!(
            s,
            "<clipPath id=\"polygon\"><path d=\"{clip}\"/></clipPath>"
        );
        if atlas.geometry() == Geometry::Hyperbolic {
            let _ = writeln!(
                s,
                "<circle r=\"1\" fill=\"none\" stroke=\"#999\" stroke-width=\"0.003\"/>"
            );
        }
    }
    let _ = writeln!(
        s,
        "<g{} stroke=\"#333\" stroke-width=\"{stroke:.5}\" stroke-linejoin=\"round\">",
        if clip.is_some() {
            " clip-path=\"url(#polygon)\""
        } else {
            ""
        }
    );
    s.push_str(&body);
    let _ = writeln!(s, "</g>");
    if let Some(clip) = &clip {
        let _ = writeln!(
            s,
            "<path d=\"{clip}\" fill=\"none\" stroke=\"black\" stroke-width=\"0.006\"/>"
        );
    }
    let _ = writeln!(s, "</g>\n</svg>");
    s
}
