//! The atlas: 2n + 2 charts, each ONE linear fractional map into the model space (the paper's section
//! 4.4), and the transition functions between them, one LFT per connected overlap component.
//!
//! How transitions are found. Every chart image meets a few tiles u(P) of the tiling by copies of the
//! fundamental polygon P (found by a breadth-first walk across tile edges). A point of chart i whose
//! image lies in tile t(P) is the surface point t⁻¹φ_i(w) ∈ P; it lies in chart j wherever u·t⁻¹φ_i(w)
//! ∈ φ_j(D_j) for a tile u of chart j. So the candidate group elements are g = u·t⁻¹, and each g whose
//! overlap D_i ∩ Ψ⁻¹(D_j) is non-empty (an exact test on circles and segments) is one component with
//! transition Ψ = φ_j⁻¹·g·φ_i, formed in double-double and rounded once.

use num_complex::Complex64;
use serde::Serialize;

use crate::dd::{DdComplex, ExactLft, dd};
use crate::overlap::{domains_overlap, preimage_bbox};
use crate::polygon::{Geometry, Polygon};
use crate::scales::ChartScales;
use crate::{ChartId, ChartPoint, ChartsError, Lft, ModelPoint};

/// The highest genus the atlas is built and validated for.
pub const MAX_GENUS: u32 = 64;

/// A chart's parameter domain. Both have size 1: the disk has radius ½, the square half-width ½.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Domain {
    /// The open disk |w| < ½.
    Disk,
    /// The open square (−½, ½)².
    Square,
}

impl Domain {
    /// Distance from w to the domain's boundary in chart units: positive inside, negative outside.
    ///
    /// ```
    /// use charts::Domain;
    /// use num_complex::Complex64;
    /// assert_eq!(Domain::Square.margin(Complex64::new(0.3, -0.1)), 0.2);
    /// assert!(Domain::Disk.margin(Complex64::new(0.6, 0.0)) < 0.0);
    /// ```
    #[inline]
    pub fn margin(&self, w: Complex64) -> f64 {
        match self {
            Domain::Disk => 0.5 - w.norm(),
            Domain::Square => 0.5 - w.re.abs().max(w.im.abs()),
        }
    }

    /// Whether w lies in the open domain.
    #[inline]
    pub fn contains(&self, w: Complex64) -> bool {
        match self {
            // |w| < ½ without the square root's hypot (a libm call), for the evaluation's loops.
            Domain::Disk => w.norm_sqr() < 0.25,
            Domain::Square => self.margin(w) > 0.0,
        }
    }

    /// Radius of the smallest disk about 0 holding the domain.
    pub fn circumradius(&self) -> f64 {
        match self {
            Domain::Disk => 0.5,
            Domain::Square => std::f64::consts::FRAC_1_SQRT_2,
        }
    }
}

/// What a chart covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ChartKind {
    /// The disk in the middle of the polygon.
    Inside,
    /// The disk about the surface's single vertex (all 4n corners).
    Vertex,
    /// The square across the edge pair of handle `handle`: `side` 0 is a_k (edges 4k, 4k+2), 1 is b_k.
    Edge { handle: u32, side: u32 },
    /// Genus 0: one of the two caps of the sphere (north holds ζ = 0, south holds ζ = ∞).
    Cap { north: bool },
}

impl ChartKind {
    /// A short name for tables: "inside", "vertex", "edge a1", "cap N".
    pub fn label(&self) -> String {
        match self {
            ChartKind::Inside => "inside".into(),
            ChartKind::Vertex => "vertex".into(),
            ChartKind::Edge { handle, side } => {
                format!("edge {}{}", if *side == 0 { 'a' } else { 'b' }, handle + 1)
            }
            ChartKind::Cap { north } => if *north { "cap N" } else { "cap S" }.into(),
        }
    }
}

/// One tile u(P) that a chart's image meets, with the map from that tile's points to chart coordinates.
#[derive(Clone, Debug)]
struct Tile {
    group: ExactLft,
    /// φ⁻¹·u: takes a point of P to this chart's coordinates through this tile.
    from_polygon: Lft,
    /// u⁻¹(chart centre), for the ball pre-filter.
    centre_in_polygon: Complex64,
}

/// A chart: its domain, its one LFT into the model space, and the tiles its image meets.
#[derive(Clone, Debug)]
pub struct Chart {
    id: ChartId,
    kind: ChartKind,
    domain: Domain,
    exact: ExactLft,
    to_model: Lft,
    /// Model-space centre φ(0), and the radius of a ball holding the image: the Euclidean radius of
    /// the image of the domain's circumscribed disk as seen from its centre (Poincaré radius at the
    /// origin for hyperbolic charts, after moving the centre to 0).
    centre: Complex64,
    ball: f64,
    scale: f64,
    tiles: Vec<Tile>,
}

impl Chart {
    /// φ = F ∘ (w ↦ scale·w) with F an isometry of the model space (a rotation and translation, or
    /// for the southern cap the sphere's half-turn ζ ↦ 1/ζ). So distances, angles and areas of a figure
    /// in this chart can be measured on `scale·w` near the origin, where the model is well conditioned.
    pub fn scale(&self) -> f64 {
        self.scale
    }
    pub fn id(&self) -> ChartId {
        self.id
    }
    pub fn kind(&self) -> ChartKind {
        self.kind
    }
    pub fn domain(&self) -> Domain {
        self.domain
    }
    /// φ: chart coordinates → model space (one LFT for the whole chart, section 4.4).
    pub fn to_model(&self) -> &Lft {
        &self.to_model
    }
    /// How many tiles of the polygon tiling the chart's image meets.
    pub fn tile_count(&self) -> usize {
        self.tiles.len()
    }
}

/// One connected component of an overlap U_ij, with its transition function ψ_ij there.
#[derive(Clone, Debug, Serialize)]
pub struct Transition {
    pub from: ChartId,
    pub to: ChartId,
    /// ψ = φ_to⁻¹ · g · φ_from.
    pub lft: Lft,
    /// The group element g relating the two charts' images on this component.
    pub group: Lft,
    /// A box [x0, x1] × [y0, y1] in `from` coordinates holding the component.
    pub bbox: [f64; 4],
}

impl Transition {
    /// ψ(w).
    #[inline]
    pub fn apply(&self, w: Complex64) -> Complex64 {
        self.lft.apply(w)
    }
}

/// A point of the surface: every (chart, coordinates) pair that represents it, sorted by chart.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ManifoldPoint {
    reps: Vec<ChartPoint>,
}

impl ManifoldPoint {
    /// All representations, sorted by chart id (a chart appears at most once: charts are injective).
    pub fn representations(&self) -> &[ChartPoint] {
        &self.reps
    }
    /// The coordinates in `chart`, if the point lies in it.
    pub fn in_chart(&self, chart: ChartId) -> Option<Complex64> {
        self.reps
            .iter()
            .find(|p| p.chart == chart)
            .map(|p| p.coords)
    }
}

/// The chart structure of a closed orientable surface of genus n.
#[derive(Clone, Debug)]
pub struct Atlas {
    genus: u32,
    geometry: Geometry,
    polygon: Option<Polygon>,
    scales: ChartScales,
    charts: Vec<Chart>,
    /// transitions[i * count + j]: the components of U_ij (i == j: just the identity).
    transitions: Vec<Vec<Transition>>,
    locators: Vec<Locator>,
}

impl Atlas {
    /// The atlas for genus `genus` with ntori's default chart scales.
    ///
    /// ```
    /// let atlas = charts::Atlas::new(2).unwrap();
    /// assert_eq!(atlas.charts().len(), 6); // inside, vertex, four edge charts
    /// ```
    pub fn new(genus: u32) -> Result<Atlas, ChartsError> {
        Atlas::with_scales(genus, ChartScales::default_for(genus)?)
    }

    /// The atlas with explicit chart scales (checked: every chart must be injective on the surface).
    pub fn with_scales(genus: u32, scales: ChartScales) -> Result<Atlas, ChartsError> {
        if genus > MAX_GENUS {
            return Err(ChartsError::UnsupportedGenus {
                genus,
                max: MAX_GENUS,
            });
        }
        scales.validate(genus)?;
        match genus {
            0 => Ok(Atlas::sphere(scales)),
            1 => Atlas::from_polygon(Polygon::square(), scales),
            n => Atlas::from_polygon(Polygon::hyperbolic(n), scales),
        }
    }

    pub fn genus(&self) -> u32 {
        self.genus
    }
    pub fn geometry(&self) -> Geometry {
        self.geometry
    }
    /// The fundamental polygon (none for the sphere).
    pub fn polygon(&self) -> Option<&Polygon> {
        self.polygon.as_ref()
    }
    pub fn scales(&self) -> &ChartScales {
        &self.scales
    }
    pub fn charts(&self) -> &[Chart] {
        &self.charts
    }
    pub fn chart(&self, id: ChartId) -> Result<&Chart, ChartsError> {
        self.charts.get(id.index()).ok_or(ChartsError::NoSuchChart {
            index: id.0,
            count: self.charts.len(),
        })
    }

    /// The connected components of U_ij with their transition functions (i == j: the identity only).
    pub fn transitions(&self, from: ChartId, to: ChartId) -> &[Transition] {
        let n = self.charts.len();
        if from.index() >= n || to.index() >= n {
            return &[];
        }
        &self.transitions[from.index() * n + to.index()]
    }

    /// The surface point with coordinates `p`, in every chart that contains it. Errors if the chart
    /// does not exist, the coordinates are not finite, or they lie outside the chart's open domain.
    ///
    /// ```
    /// use charts::{Atlas, ChartId, ChartPoint};
    /// use num_complex::Complex64;
    /// let atlas = Atlas::new(2).unwrap();
    /// let p = atlas.locate(ChartPoint::new(ChartId(2), Complex64::new(0.0, 0.1))).unwrap();
    /// // A point on the middle line of an edge chart is also in the inside chart.
    /// assert!(p.representations().len() >= 2);
    /// ```
    pub fn locate(&self, p: ChartPoint) -> Result<ManifoldPoint, ChartsError> {
        let chart = self.chart(p.chart)?;
        let w = p.coords;
        if !(w.re.is_finite() && w.im.is_finite()) {
            return Err(ChartsError::NotFinite { re: w.re, im: w.im });
        }
        let margin = chart.domain.margin(w);
        if margin <= 0.0 {
            return Err(ChartsError::OutsideChart {
                chart: p.chart,
                re: w.re,
                im: w.im,
                margin,
            });
        }
        Ok(self.locate_unchecked(p))
    }

    /// `locate` for a point already known to lie in its chart's domain.
    pub fn locate_unchecked(&self, p: ChartPoint) -> ManifoldPoint {
        ManifoldPoint {
            reps: self
                .locate_with_transitions(p)
                .into_iter()
                .map(|(r, _)| r)
                .collect(),
        }
    }

    /// [`Atlas::locate_unchecked`], with the map from `p`'s chart to each representation's chart (the
    /// identity for `p` itself), for the chain rule. Sorted by chart.
    pub fn locate_with_transitions(&self, p: ChartPoint) -> Vec<(ChartPoint, Lft)> {
        let mut reps = Vec::new();
        self.locate_with_transitions_into(p, &mut reps);
        reps
    }

    /// [`Atlas::locate_unchecked`]'s representations, written into `out` (cleared first) without
    /// allocating: for loops over many points that reuse one buffer. Sorted by chart.
    pub fn locate_into(&self, p: ChartPoint, out: &mut Vec<ChartPoint>) {
        out.clear();
        out.extend(self.representations(p).map(|(rep, _)| rep));
        out.sort_unstable_by_key(|r| r.chart);
    }

    /// [`Atlas::locate_with_transitions`], written into `out` (cleared first) without allocating.
    pub fn locate_with_transitions_into(&self, p: ChartPoint, out: &mut Vec<(ChartPoint, Lft)>) {
        out.clear();
        out.extend(self.representations(p));
        out.sort_unstable_by_key(|r| r.0.chart);
    }

    /// `p` itself (with the identity), then every other chart's point for it with the transition
    /// that takes `p`'s chart there; unsorted.
    fn representations(&self, p: ChartPoint) -> impl Iterator<Item = (ChartPoint, Lft)> + '_ {
        let i = p.chart.index();
        let n = self.charts.len();
        let others = self.locators[i]
            .candidates(p.coords)
            .iter()
            .filter_map(move |&(j, k)| {
                let t = &self.transitions[i * n + j as usize][k as usize];
                let w = t.apply(p.coords);
                self.charts[j as usize]
                    .domain
                    .contains(w)
                    .then(|| (ChartPoint::new(t.to, w), t.lft))
            });
        std::iter::once((p, Lft::IDENTITY)).chain(others)
    }

    /// The surface point of a model-space point (any point of the disk, plane, or finite sphere
    /// coordinate): reduced into the polygon, then mapped into every chart through that chart's tiles.
    pub fn locate_model(&self, z: ModelPoint) -> ManifoldPoint {
        let z = match &self.polygon {
            Some(poly) => poly.reduce(z.0),
            None => z.0,
        };
        let mut reps = Vec::new();
        for chart in &self.charts {
            for tile in &chart.tiles {
                let w = tile.from_polygon.apply(z);
                if chart.domain.contains(w) {
                    reps.push(ChartPoint::new(chart.id, w));
                }
            }
        }
        ManifoldPoint { reps }
    }

    /// The model-space point of chart coordinates (one lift; the group gives the others).
    pub fn to_model(&self, p: ChartPoint) -> Result<ModelPoint, ChartsError> {
        Ok(ModelPoint(self.chart(p.chart)?.to_model.apply(p.coords)))
    }

    /// How deep the point lies in its best chart: the largest distance to a chart boundary over its
    /// representations, in chart units. The blend functions divide by their sum; this keeps it > 0.
    pub fn margin(&self, p: &ManifoldPoint) -> f64 {
        p.reps
            .iter()
            .map(|r| self.charts[r.chart.index()].domain.margin(r.coords))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    // ---------------------------------------------------------------- construction

    fn sphere(scales: ChartScales) -> Atlas {
        let ChartScales::Sphere { cap } = scales else {
            unreachable!("validated: sphere scales for genus 0")
        };
        // North: ζ = λw. South: ζ = 1/(λw), i.e. [[0, 1], [λ, 0]] rescaled to det = 1.
        let lambda = dd(2.0 * cap);
        let north = ExactLft::scaling(lambda);
        let root = lambda.sqrt();
        let south = ExactLft {
            a: DdComplex::zero(),
            b: DdComplex::new(dd(0.0), -crate::dd::div(dd(1.0), root)),
            c: DdComplex::new(dd(0.0), -root),
            d: DdComplex::zero(),
        };
        let charts: Vec<Chart> = [(north, true), (south, false)]
            .into_iter()
            .enumerate()
            .map(|(i, (exact, is_north))| Chart {
                id: ChartId(i as u32),
                kind: ChartKind::Cap { north: is_north },
                domain: Domain::Disk,
                exact,
                to_model: exact.to_lft(),
                centre: exact.to_lft().apply(Complex64::ZERO),
                ball: 0.5,
                scale: 2.0 * cap,
                tiles: vec![Tile {
                    group: ExactLft::identity(),
                    from_polygon: exact.inverse().to_lft(),
                    centre_in_polygon: Complex64::ZERO,
                }],
            })
            .collect();
        let whole = [-0.5, 0.5, -0.5, 0.5];
        let mut transitions = Vec::new();
        for i in 0..2 {
            for j in 0..2 {
                transitions.push(if i == j {
                    vec![identity_transition(ChartId(i as u32))]
                } else {
                    let psi = charts[j].exact.inverse().then_after(&charts[i].exact);
                    vec![Transition {
                        from: ChartId(i as u32),
                        to: ChartId(j as u32),
                        lft: psi.to_lft(),
                        group: Lft::IDENTITY,
                        bbox: whole,
                    }]
                });
            }
        }
        let mut atlas = Atlas {
            genus: 0,
            geometry: Geometry::Spherical,
            polygon: None,
            scales,
            charts,
            transitions,
            locators: Vec::new(),
        };
        atlas.build_locators();
        atlas
    }

    fn from_polygon(poly: Polygon, scales: ChartScales) -> Result<Atlas, ChartsError> {
        let ChartScales::Polygon {
            inside,
            edge,
            vertex,
        } = scales
        else {
            unreachable!("validated: polygon scales for genus ≥ 1")
        };
        let n = poly.genus();
        let mut charts = Vec::with_capacity(2 * n as usize + 2);
        // Each chart is an isometric frame after a scaling of its domain.
        let mut push = |kind, domain: Domain, frame: ExactLft, scale: f64| {
            let exact = frame.then_after(&ExactLft::scaling(dd(scale)));
            let to_model = exact.to_lft();
            charts.push(Chart {
                id: ChartId(charts.len() as u32),
                kind,
                domain,
                exact,
                to_model,
                centre: to_model.apply(Complex64::ZERO),
                ball: scale * domain.circumradius(),
                scale,
                tiles: Vec::new(),
            });
        };
        // Domain radius ½ ↦ image radius `inside` / `vertex`: scale by twice the radius.
        push(
            ChartKind::Inside,
            Domain::Disk,
            ExactLft::identity(),
            2.0 * inside,
        );
        push(
            ChartKind::Vertex,
            Domain::Disk,
            poly.corner_frame_exact(0),
            2.0 * vertex,
        );
        for j in 0..2 * n {
            let (handle, side) = (j / 2, j % 2);
            let frame = poly.edge_frame_exact((4 * handle + side) as usize);
            push(
                ChartKind::Edge { handle, side },
                Domain::Square,
                frame,
                edge,
            );
        }
        for chart in &mut charts {
            chart.tiles = find_tiles(&poly, chart);
        }
        let transitions = find_transitions(&poly, &charts)?;
        let mut atlas = Atlas {
            genus: n,
            geometry: poly.geometry(),
            polygon: Some(poly),
            scales,
            charts,
            transitions,
            locators: Vec::new(),
        };
        atlas.build_locators();
        Ok(atlas)
    }

    fn build_locators(&mut self) {
        let n = self.charts.len();
        self.locators = (0..n)
            .map(|i| {
                let comps = (0..n).filter(|&j| j != i).flat_map(|j| {
                    self.transitions[i * n + j]
                        .iter()
                        .enumerate()
                        .map(move |(k, t)| ((j as u32, k as u32), t.bbox))
                });
                Locator::new(comps)
            })
            .collect();
    }
}

fn identity_transition(id: ChartId) -> Transition {
    Transition {
        from: id,
        to: id,
        lft: Lft::IDENTITY,
        group: Lft::IDENTITY,
        bbox: [-0.5, 0.5, -0.5, 0.5],
    }
}

/// Whether the ball about `centre` (radius `ball`, see `Chart::ball`) meets the ball about `other`.
fn balls_meet(geometry: Geometry, a: Complex64, ra: f64, b: Complex64, rb: f64) -> bool {
    const SLACK: f64 = 1e-9;
    match geometry {
        Geometry::Hyperbolic => {
            // Pseudo-hyperbolic distance |a − b|/|1 − āb| = tanh(d/2); compare d/2 with the radii's.
            let delta = (a - b).norm() / (Complex64::ONE - a.conj() * b).norm();
            delta.min(1.0 - 1e-16).atanh() < ra.atanh() + rb.atanh() + SLACK
        }
        _ => (a - b).norm() < ra + rb + SLACK,
    }
}

/// The Euclidean disk that a chart's ball occupies when its centre sits at `centre`.
fn ball_as_disk(geometry: Geometry, centre: Complex64, radius: f64) -> (Complex64, f64) {
    match geometry {
        Geometry::Hyperbolic => {
            // Hyperbolic ball of Poincaré radius ρ (at the origin), moved to c: centre c(1 − ρ²)/(1 − ρ²|c|²),
            // radius ρ(1 − |c|²)/(1 − ρ²|c|²).
            let (r2, c2) = (radius * radius, centre.norm_sqr());
            let den = 1.0 - r2 * c2;
            (centre * ((1.0 - r2) / den), radius * (1.0 - c2) / den)
        }
        _ => (centre, radius),
    }
}

/// The tiles u(P) that a chart's image meets: breadth-first across tile edges, starting from P, adding
/// the tile across an edge whenever the chart's ball (a superset of its image) meets that edge.
fn find_tiles(poly: &Polygon, chart: &Chart) -> Vec<Tile> {
    let geometry = poly.geometry();
    let phi_inv = chart.exact.inverse();
    let mut tiles: Vec<Tile> = Vec::new();
    let mut queue = std::collections::VecDeque::from([ExactLft::identity()]);
    let mut seen: Vec<Complex64> = Vec::new();
    while let Some(g) = queue.pop_front() {
        let g_f64 = g.to_lft();
        let key = g_f64.apply(Complex64::ZERO);
        if seen.iter().any(|&s| same_point(geometry, s, key)) {
            continue;
        }
        seen.push(key);
        let centre_in_polygon = DdComplex::from_f64(chart.centre);
        let centre_in_polygon = g.inverse().apply(centre_in_polygon).to_f64();
        let (disk_c, disk_r) = ball_as_disk(geometry, centre_in_polygon, chart.ball);
        for e in 0..poly.sides() {
            if edge_meets_disk(poly, e, disk_c, disk_r) {
                queue.push_back(g.then_after(poly.cross_exact(e)));
            }
        }
        tiles.push(Tile {
            group: g,
            from_polygon: phi_inv.then_after(&g).to_lft(),
            centre_in_polygon,
        });
    }
    tiles
}

/// Two model points that are the same tile centre (distinct tiles' centres are far apart).
fn same_point(geometry: Geometry, a: Complex64, b: Complex64) -> bool {
    match geometry {
        Geometry::Hyperbolic => (a - b).norm() < 1e-7 * (Complex64::ONE - a.conj() * b).norm(),
        _ => (a - b).norm() < 1e-7,
    }
}

/// Whether the closed disk (c, r) meets edge e of the polygon (a geodesic arc or a segment), with a
/// small slack: a false "yes" only adds a tile to check.
fn edge_meets_disk(poly: &Polygon, e: usize, c: Complex64, r: f64) -> bool {
    let (c0, c1) = poly.edge_corners(e);
    let (p, q) = (poly.corners()[c0], poly.corners()[c1]);
    let slack = 1e-9 + 1e-6 * r;
    let dist = match poly.geometry() {
        Geometry::Hyperbolic => {
            let consts = poly.constants();
            let (h, radius) = (consts.h.unwrap_or(0.0), consts.r.unwrap_or(0.0));
            let centre = Complex64::from_polar(h, e as f64 * consts.omega);
            // Closest point of the full circle to c; if it falls on the arc (between the corners, on
            // the side facing the origin) use it, otherwise the nearer endpoint.
            let off = c - centre;
            let foot = centre + off * (radius / off.norm().max(1e-300));
            let ang = |z: Complex64| ((z - centre) / (-centre)).arg();
            let (a0, a1, a) = (ang(p), ang(q), ang(foot));
            let on_arc = a >= a0.min(a1) && a <= a0.max(a1);
            let ends = (c - p).norm().min((c - q).norm());
            if on_arc {
                (off.norm() - radius).abs().min(ends)
            } else {
                ends
            }
        }
        _ => {
            let d = q - p;
            let s = (((c - p) * d.conj()).re / d.norm_sqr()).clamp(0.0, 1.0);
            (c - (p + d * s)).norm()
        }
    };
    dist <= r + slack
}

/// For every ordered pair of charts, the group elements g = u·t⁻¹ (t a tile of chart i, u of chart j)
/// whose overlap is non-empty, each giving one component.
fn find_transitions(poly: &Polygon, charts: &[Chart]) -> Result<Vec<Vec<Transition>>, ChartsError> {
    let geometry = poly.geometry();
    let count = charts.len();
    let mut all = Vec::with_capacity(count * count);
    for ci in charts {
        for cj in charts {
            let mut comps: Vec<Transition> = Vec::new();
            if ci.id == cj.id {
                comps.push(identity_transition(ci.id));
            }
            for t in &ci.tiles {
                for u in &cj.tiles {
                    // Pre-filter: the balls about g(c_i) = u(t⁻¹ c_i) and c_j must meet.
                    let moved = u.group.to_lft().apply(t.centre_in_polygon);
                    if !balls_meet(geometry, moved, ci.ball, cj.centre, cj.ball) {
                        continue;
                    }
                    let g = u.group.then_after(&t.group.inverse());
                    let psi = cj.exact.inverse().then_after(&g).then_after(&ci.exact);
                    let lft = psi.to_lft();
                    if comps.iter().any(|c| c.lft.distance(&lft) < 1e-9) {
                        continue;
                    }
                    if !domains_overlap(ci.domain, cj.domain, &lft) {
                        continue;
                    }
                    if ci.id == cj.id {
                        return Err(ChartsError::InvalidScales(format!(
                            "{} overlaps itself on the surface (it is not injective); use smaller scales",
                            ci.kind.label()
                        )));
                    }
                    comps.push(Transition {
                        from: ci.id,
                        to: cj.id,
                        lft,
                        group: g.to_lft(),
                        bbox: preimage_bbox(cj.domain, &lft),
                    });
                }
            }
            all.push(comps);
        }
    }
    Ok(all)
}

/// A uniform grid over a chart's domain listing, per cell, the overlap components whose boxes meet it.
#[derive(Clone, Debug)]
struct Locator {
    cells: Vec<Vec<(u32, u32)>>,
}

const GRID: usize = 16;

impl Locator {
    fn new(components: impl Iterator<Item = ((u32, u32), [f64; 4])>) -> Locator {
        let mut cells = vec![Vec::new(); GRID * GRID];
        // The cast truncates a non-negative number to its floor (no call to libm's floor).
        let cell = |x: f64| (((x + 0.5) * GRID as f64).max(0.0) as usize).min(GRID - 1);
        for (key, [x0, x1, y0, y1]) in components {
            for cy in cell(y0)..=cell(y1) {
                for cx in cell(x0)..=cell(x1) {
                    cells[cy * GRID + cx].push(key);
                }
            }
        }
        Locator { cells }
    }

    #[inline]
    fn candidates(&self, w: Complex64) -> &[(u32, u32)] {
        // The cast truncates a non-negative number to its floor (no call to libm's floor).
        let cell = |x: f64| (((x + 0.5) * GRID as f64).max(0.0) as usize).min(GRID - 1);
        &self.cells[cell(w.im) * GRID + cell(w.re)]
    }
}
