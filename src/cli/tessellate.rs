//! `ntori tessellate`: build the t_e/t_r tessellation, check it, and draw it.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use charts::check::consistency_at;
use charts::{Atlas, Geometry, Tessellation};
use mesh::{HalfEdgeMesh, Topology};
use ntori::figures::drawing::{drawn_triangles, fill, polygon_path};
use serde::Serialize;

use super::GenusArg;
use super::report::{Report, emit};

/// Tessellate the surface (the paper's t_e/t_r scheme) and check the mesh.
///
/// The coarsest level (t_e = t_r = 1) cuts the surface into 2n + 2 regions, one per chart: a square
/// in each edge chart, sized so that neighbouring squares' corners meet at the point β, and two
/// "wheels" (about the inside chart's centre and about the vertex) bounded by the 4n arcs the
/// squares leave. t_e divides each square into a t_e × t_e grid and each arc into t_e pieces; t_r
/// divides the wheels' spokes (from genus 14 twice or three times as finely, so the rims' 4n·t_e
/// vertices do not outnumber the rings: the report says how many rings). Genus 0 uses two wheels,
/// the caps, meeting at the equator.
///
/// Prints V, E, F, the Euler characteristic χ = V − E + F (2 − 2n for genus n), the genus read off
/// the mesh, components, and checks: closed, manifold, orientable, consistently oriented; no
/// degenerate triangle; vertex coordinates agreeing across charts; and the triangles' areas, with
/// geodesic sides, adding up to the surface's area (4π(n − 1) for n ≥ 2). Exit status 3 if a check
/// fails.
///
/// Examples:
///   ntori tessellate --genus 2 --te 4 --tr 3
///   ntori tessellate --genus 3 --te 1 --tr 1 --svg coarsest.svg   (the paper's figure 7)
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    #[command(flatten)]
    genus: GenusArg,
    /// Divisions of each square (and each arc).
    #[arg(
        long,
        default_value_t = 4,
        value_name = "A",
        allow_negative_numbers = true
    )]
    te: u32,
    /// Divisions of each wheel spoke.
    #[arg(
        long,
        default_value_t = 4,
        value_name = "B",
        allow_negative_numbers = true
    )]
    tr: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Also draw the tessellation in the fundamental polygon, charts coloured, to this SVG file.
    #[arg(long, value_name = "FILE")]
    svg: Option<PathBuf>,
    /// Replace the SVG file if it exists.
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        genus: GenusArg { genus },
        te,
        tr,
        json,
        svg: svg_path,
        force,
    } = args;
    check_size(genus, te, tr)?;
    if let Some(path) = &svg_path {
        ntori::io::atomic::check_new_output(path, &[], force)?;
    }
    let atlas =
        Atlas::new(genus).with_context(|| format!("cannot build the charts for genus {genus}"))?;
    let t = atlas
        .tessellate(te, tr)
        .with_context(|| format!("genus {genus} at t_e = {te}, t_r = {tr}"))?;
    let report = report(&atlas, &t)?;
    if let Some(path) = &svg_path {
        ntori::io::atomic::write_output(path, svg(&atlas, &t).as_bytes(), force)?;
        // Logged under the target the command line has always used (`ntori`).
        tracing::info!(target: "ntori", path = %path.display(), "wrote the drawing");
    }
    emit(&report, json)
}

/// What `ntori tessellate` reports (text or JSON).
#[derive(Debug, Serialize)]
pub struct TessellationReport {
    pub genus: u32,
    pub te: u32,
    pub tr: u32,
    /// The steps each wheel's spokes take: t_r, or from genus 14 a multiple of it.
    pub wheel_rings: u32,
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
pub fn report(atlas: &Atlas, t: &Tessellation) -> Result<TessellationReport, mesh::MeshError> {
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
        wheel_rings: t.rings,
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

impl Report for TessellationReport {
    fn passed(&self) -> bool {
        self.passed
    }

    fn to_text(&self) -> String {
        let t = &self.topology;
        let yes = |b: bool| if b { "yes" } else { "NO" };
        let mut s = String::new();
        let rings = if self.wheel_rings == self.tr {
            String::new()
        } else {
            format!(" (the wheels' spokes in {} steps)", self.wheel_rings)
        };
        let _ = writeln!(
            s,
            "genus {}, t_e = {}, t_r = {}{rings}",
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

/// The tessellation drawn in the fundamental polygon (the paper's figure 7), charts coloured: each
/// triangle with its true (circular) sides, moved into the polygon by the group, clipped to it. For the
/// sphere, the two caps side by side, each in its own coordinate ζ or 1/ζ.
/// Peak memory of `ntori tessellate` per triangle, measured: genus 2 at t_e = 200, t_r = 4
/// (342 400 triangles) and at t_e = 50, t_r = 200 (339 200) both peak at 180 MB, about 530 bytes a
/// triangle (the tessellation, its chart points, the report's geodesic areas); rounded up.
const BYTES_PER_TRIANGLE: u64 = 560;
/// The most triangles `ntori tessellate` makes: about 2.2 GB at the rate above.
pub const MAX_TRIANGLES: u64 = 4_000_000;

/// Refuses, before any work, a tessellation whose estimated memory is beyond [`MAX_TRIANGLES`].
fn check_size(genus: u32, te: u32, tr: u32) -> anyhow::Result<()> {
    if te == 0 || tr == 0 {
        // Charts' own error says what is wrong; there is nothing to estimate.
        return Ok(());
    }
    let triangles = Tessellation::expected_triangles(genus, te, tr);
    if triangles > MAX_TRIANGLES {
        let gb = |t: u64| t as f64 * BYTES_PER_TRIANGLE as f64 / 1e9;
        // The count saturates at u64::MAX (t_e near 2³²): say "more than" rather than a wrong number.
        let count = if triangles == u64::MAX {
            format!("more than {triangles}")
        } else {
            triangles.to_string()
        };
        anyhow::bail!(
            "genus {genus} at t_e = {te}, t_r = {tr} makes {count} triangles, about {:.1} GB of \
             memory; at most {MAX_TRIANGLES} triangles (about {:.1} GB) are allowed: lower --te or --tr",
            gb(triangles),
            gb(MAX_TRIANGLES)
        );
    }
    Ok(())
}

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
