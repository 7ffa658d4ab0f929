//! `ntori info`: what the chart layer builds for one genus, and a self-check of it.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::process::ExitCode;

use anyhow::Context as _;
use charts::check::{self, Consistency, Coverage};
use charts::{Atlas, ChartId, ChartKind, ChartScales, Geometry, PolygonConstants};
use serde::Serialize;

use super::GenusArg;
use super::report::{Report, emit};

/// Show the chart structure for one genus, and check it.
///
/// Prints the fundamental polygon's constants (for genus n ≥ 2, the regular hyperbolic 4n-gon in
/// the Poincaré disk):
///   ω  the angle 2π/4n between neighbouring edge directions, also each corner's angle;
///   h, r  the centre distance and radius of the circles the edges lie on (r² = h² − 1);
///   γ  the distance from the centre to an edge midpoint; α the distance to a corner;
///   β  where the corners of neighbouring edge charts' tessellation squares meet;
///   δ  the paper's vertex-chart scale (its boundary passes through β).
///
/// Then the 2n + 2 charts (inside, vertex, one edge chart per glued pair a_k, b_k), each mapped
/// into the disk by one linear fractional transformation; the overlaps U_ij between charts, split
/// into connected components, each with its own transition function ψ_ij.
///
/// The self-check spreads points over the surface and reports: the largest error of ψ_ii = id, of
/// ψ_ji ∘ ψ_ij = id (inverse) and of ψ_jk ∘ ψ_ij = ψ_ik (cocycle), in chart-coordinate units; and
/// the coverage margin: over all points, the smallest distance to a chart boundary from the chart
/// holding the point deepest. The blend functions divide by their sum, and the margin keeps that
/// sum away from zero. Exit status 3 if the self-check fails.
///
/// Examples:
///   ntori info                       genus 2, as text
///   ntori info --genus 1 --json      the flat torus, as JSON
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    #[command(flatten)]
    genus: GenusArg,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// How many points the self-check spreads over the surface.
    #[arg(long, default_value_t = 20_000, value_name = "K",
          value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    points: u64,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        genus: GenusArg { genus },
        json,
        points,
    } = args;
    // Logged under the target the command line has always used (`ntori`), not this module's path.
    tracing::info!(target: "ntori", genus, points, "building the atlas");
    let report = report(genus, points as usize)
        .with_context(|| format!("cannot build the charts for genus {genus}"))?;
    emit(&report, json)
}

/// Everything `ntori info` reports (printed as text or JSON).
#[derive(Debug, Serialize)]
pub struct InfoReport {
    pub genus: u32,
    pub geometry: Geometry,
    pub euler_characteristic: i64,
    pub polygon: Option<PolygonReport>,
    pub scales: ChartScales,
    pub charts: Vec<ChartReport>,
    pub overlaps: Vec<OverlapReport>,
    pub self_check: SelfCheck,
}

#[derive(Debug, Serialize)]
pub struct PolygonReport {
    pub sides: usize,
    pub constants: PolygonConstants,
    /// Hyperbolic area by quadrature (genus ≥ 2), and what Gauss–Bonnet says it must be.
    pub area: f64,
    pub expected_area: f64,
    /// Corners in the order met walking around the surface's single vertex.
    pub vertex_cycle: Vec<usize>,
}

#[derive(Debug, Serialize)]
pub struct ChartReport {
    pub id: u32,
    pub label: String,
    #[serde(flatten)]
    pub kind: ChartKind,
    pub domain: charts::Domain,
    /// Tiles of the polygon tiling that the chart's image meets.
    pub tiles: usize,
    /// Charts it overlaps, and in how many connected components in all.
    pub neighbours: usize,
    pub components: usize,
}

/// Overlaps between two kinds of chart: how many ordered pairs overlap and with how many components.
#[derive(Debug, Serialize)]
pub struct OverlapReport {
    pub from: &'static str,
    pub to: &'static str,
    pub pairs: usize,
    /// component count → number of pairs with that many components.
    pub components_per_pair: BTreeMap<usize, usize>,
}

#[derive(Debug, Serialize)]
pub struct SelfCheck {
    pub points: usize,
    pub consistency: Consistency,
    pub coverage: Coverage,
    /// The worst transition error tolerated (chart units).
    pub tolerance: f64,
    pub passed: bool,
}

/// Transition errors above this fail the self-check (chart-coordinate units).
pub const TOLERANCE: f64 = 1e-12;

/// Builds the atlas for `genus` and checks it on `points` points spread over the surface.
pub fn report(genus: u32, points: usize) -> Result<InfoReport, charts::ChartsError> {
    let atlas = Atlas::new(genus)?;
    let samples = check::spread_points(&atlas, points);
    let coverage = check::coverage(&atlas, &samples);
    let consistency = check::consistency(&atlas, &samples);
    let passed = consistency.worst() <= TOLERANCE && coverage.min_margin > 0.0;
    Ok(InfoReport {
        genus,
        geometry: atlas.geometry(),
        euler_characteristic: 2 - 2 * i64::from(genus),
        polygon: atlas.polygon().map(|p| PolygonReport {
            sides: p.sides(),
            constants: *p.constants(),
            area: p.area_by_quadrature(),
            expected_area: match p.geometry() {
                Geometry::Hyperbolic => 4.0 * std::f64::consts::PI * (f64::from(genus) - 1.0),
                _ => 1.0,
            },
            vertex_cycle: p.vertex_cycle().iter().map(|s| s.corner).collect(),
        }),
        scales: *atlas.scales(),
        charts: chart_reports(&atlas),
        overlaps: overlap_reports(&atlas),
        self_check: SelfCheck {
            points: samples.len(),
            consistency,
            coverage,
            tolerance: TOLERANCE,
            passed,
        },
    })
}

fn kind_class(kind: ChartKind) -> &'static str {
    match kind {
        ChartKind::Inside => "inside",
        ChartKind::Vertex => "vertex",
        ChartKind::Edge { .. } => "edge",
        ChartKind::Cap { .. } => "cap",
    }
}

fn others(atlas: &Atlas, id: ChartId) -> impl Iterator<Item = (ChartId, usize)> + '_ {
    atlas
        .charts()
        .iter()
        .map(|c| c.id())
        .filter(move |&j| j != id)
        .map(move |j| (j, atlas.transitions(id, j).len()))
        .filter(|&(_, k)| k > 0)
}

fn chart_reports(atlas: &Atlas) -> Vec<ChartReport> {
    atlas
        .charts()
        .iter()
        .map(|c| ChartReport {
            id: c.id().0,
            label: c.kind().label(),
            kind: c.kind(),
            domain: c.domain(),
            tiles: c.tile_count(),
            neighbours: others(atlas, c.id()).count(),
            components: others(atlas, c.id()).map(|(_, k)| k).sum(),
        })
        .collect()
}

fn overlap_reports(atlas: &Atlas) -> Vec<OverlapReport> {
    let mut by_kind: BTreeMap<(&'static str, &'static str), BTreeMap<usize, usize>> =
        BTreeMap::new();
    for c in atlas.charts() {
        for (j, k) in others(atlas, c.id()) {
            let key = (
                kind_class(c.kind()),
                kind_class(atlas.charts()[j.index()].kind()),
            );
            *by_kind.entry(key).or_default().entry(k).or_default() += 1;
        }
    }
    by_kind
        .into_iter()
        .map(|((from, to), hist)| OverlapReport {
            from,
            to,
            pairs: hist.values().sum(),
            components_per_pair: hist,
        })
        .collect()
}

impl Report for InfoReport {
    fn passed(&self) -> bool {
        self.self_check.passed
    }

    fn to_text(&self) -> String {
        let mut s = String::new();
        let geometry = match self.geometry {
            Geometry::Spherical => "spherical: the Riemann sphere, two caps glued by an inversion",
            Geometry::Euclidean => {
                "Euclidean: the unit square, opposite sides glued by translations"
            }
            Geometry::Hyperbolic => "hyperbolic: a regular 4n-gon in the Poincaré disk",
        };
        let _ = writeln!(
            s,
            "genus {} ({geometry}); Euler characteristic {}",
            self.genus, self.euler_characteristic
        );
        if let Some(p) = &self.polygon {
            self.polygon_text(&mut s, p);
        }
        let _ = writeln!(
            s,
            "\nCharts ({}; disks have radius ½, squares half-width ½):",
            self.charts.len()
        );
        let _ = writeln!(
            s,
            "  {:>3}  {:<8} {:<7} {:>5} {:>11} {:>11}",
            "id", "chart", "domain", "tiles", "neighbours", "components"
        );
        for c in &self.charts {
            let domain = match c.domain {
                charts::Domain::Disk => "disk",
                charts::Domain::Square => "square",
            };
            let _ = writeln!(
                s,
                "  {:>3}  {:<8} {:<7} {:>5} {:>11} {:>11}",
                c.id, c.label, domain, c.tiles, c.neighbours, c.components
            );
        }
        let _ = writeln!(s, "  scales: {}", scales_text(&self.scales));
        let _ = writeln!(
            s,
            "\nOverlaps U_ij (ordered pairs i ≠ j), split into connected components:"
        );
        for o in &self.overlaps {
            let hist: Vec<String> = o
                .components_per_pair
                .iter()
                .map(|(k, n)| format!("{n} with {k}"))
                .collect();
            let _ = writeln!(
                s,
                "  {:>6} → {:<6} {:>5} {}: {}",
                o.from,
                o.to,
                o.pairs,
                if o.pairs == 1 { "pair" } else { "pairs" },
                hist.join(", ")
            );
        }
        self.check_text(&mut s);
        s
    }
}

impl InfoReport {
    fn polygon_text(&self, s: &mut String, p: &PolygonReport) {
        let c = &p.constants;
        let _ = writeln!(
            s,
            "\nFundamental polygon: {} sides, each corner angle ω",
            p.sides
        );
        let _ = writeln!(s, "  ω = {:.15}  (2π/4n)", c.omega);
        if let (Some(h), Some(r)) = (c.h, c.r) {
            let _ = writeln!(s, "  h = {h:.15}  (distance to the edge circles' centres)");
            let _ = writeln!(s, "  r = {r:.15}  (edge circles' radius, √(h² − 1))");
        }
        let _ = writeln!(s, "  γ = {:.15}  (distance to an edge midpoint)", c.gamma);
        let _ = writeln!(s, "  α = {:.15}  (distance to a corner)", c.alpha);
        let _ = writeln!(
            s,
            "  β = ({:.15}, {:.15})  (where tessellation squares of edge charts 0 and 1 meet)",
            c.beta.re, c.beta.im
        );
        let _ = writeln!(
            s,
            "  δ = {:.15}  (the paper's vertex-chart scale: boundary through β)",
            c.paper_delta
        );
        let _ = writeln!(
            s,
            "  area = {:.12} by quadrature; Gauss–Bonnet wants {:.12}",
            p.area, p.expected_area
        );
        let cycle: Vec<String> = p.vertex_cycle.iter().map(|c| c.to_string()).collect();
        let _ = writeln!(
            s,
            "  corners around the vertex: {} → back to {}",
            cycle.join(" → "),
            p.vertex_cycle[0]
        );
    }

    fn check_text(&self, s: &mut String) {
        let c = &self.self_check;
        let k = &c.consistency;
        let _ = writeln!(
            s,
            "\nSelf-check on {} points spread over the surface:",
            c.points
        );
        let _ = writeln!(
            s,
            "  ψ_ii = id            largest error {:.2e}",
            k.identity_error
        );
        let _ = writeln!(
            s,
            "  ψ_ji ∘ ψ_ij = id     largest error {:.2e}",
            k.inverse_error
        );
        let _ = writeln!(
            s,
            "  ψ_jk ∘ ψ_ij = ψ_ik   largest error {:.2e}",
            k.cocycle_error
        );
        if k.missing > 0 {
            let _ = writeln!(
                s,
                "  representations missed by some chart's view: {}",
                k.missing
            );
        }
        let _ = writeln!(
            s,
            "  coverage margin      {:.5} chart units (worst at {:.6}{:+.6}i; up to {} charts hold a point)",
            c.coverage.min_margin,
            c.coverage.worst_point.re,
            c.coverage.worst_point.im,
            c.coverage.max_charts
        );
        let verdict = if c.passed { "passed" } else { "FAILED" };
        let _ = writeln!(s, "  {verdict} (errors ≤ {:.0e}, margin > 0)", c.tolerance);
    }
}

fn scales_text(scales: &ChartScales) -> String {
    match scales {
        ChartScales::Sphere { cap } => format!("each cap covers |ζ| < {cap:.6} of its own side"),
        ChartScales::Polygon {
            inside,
            edge,
            vertex,
        } => format!(
            "inside image radius {inside:.6}, edge square scale σ = {edge:.6}, vertex image radius {vertex:.6}"
        ),
    }
}
