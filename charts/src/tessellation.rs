//! The paper's t_e/t_r tessellation of the surface (section 5.2, figure 7).
//!
//! Coarsest level (genus n ≥ 1): a square [−s, s]² in each edge chart, s chosen so that the corners of
//! neighbouring squares meet at the point β (and its images about the 4n corners); what the squares
//! leave is two "wheels", one about the inside chart's centre and one about the vertex, each bounded by
//! 4n arcs (square sides a = ±s face the inside wheel, b = ±s the vertex wheel). Then t_e divides each
//! square into a t_e × t_e grid and each arc into t_e pieces; t_r divides each wheel's spokes (from
//! genus 14 a whole multiple of t_r does: see [`Tessellation::wheel_rings`]), in steps that
//! shrink toward the rim where the rim's vertices are closer than the even step (from genus 2;
//! see `SpokeGrading`), each ring fades out the rim's star points (see
//! `smoothed_rim_radii`), and each band's quad is split along the diagonal that leaves the smaller
//! largest angle (`band_quad`): the paper's even steps, rings copied from the rim and one
//! diagonal everywhere make slivers at high genus. Genus 0 has no squares: two wheels (the caps)
//! meet along the equator, divided into 4·t_e arcs.
//!
//! Counts, with n the genus, e = t_e and r the wheels' rings, t_r or a whole multiple of it from
//! genus 14 ([`Tessellation::wheel_rings`]: the rims' 4n·t_e vertices need more rings than t_r
//! there) (tested):
//! - genus ≥ 1: V = 2n(e² + 2e − 1) + 2 + 8n·e(r − 1), F = 4n·e² + 8n·e(2r − 1), E = 3F/2;
//! - genus 0:   V = 4e + 2 + 8e(r − 1),                F = 8e(2r − 1),              E = 3F/2;
//!
//! so V − E + F = 2 − 2n. Every vertex is a chart point in its home chart (squares' vertices in their
//! edge chart, ring vertices in their wheel's chart), and is shared, never duplicated, between regions.

use num_complex::Complex64;
use serde::Serialize;

use crate::{Atlas, ChartId, ChartKind, ChartPoint, ChartsError, Domain};

/// The largest t_e or t_r accepted, and the largest triangle count.
pub const MAX_RESOLUTION: u32 = 4096;
pub const MAX_TRIANGLES: u64 = 50_000_000;

/// Which region of the coarsest tessellation a triangle belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Region {
    /// The square of an edge chart.
    Square,
    /// The wheel about the inside chart's centre (or a sphere cap).
    InsideWheel,
    /// The wheel about the surface's vertex.
    VertexWheel,
}

/// A triangle mesh of the surface whose vertices are manifold points.
#[derive(Clone, Debug)]
pub struct Tessellation {
    pub te: u32,
    pub tr: u32,
    /// The steps each wheel's spokes take, the rim's included ([`Tessellation::wheel_rings`]):
    /// t_r, or a whole multiple of it where the wheels' rims are fine for t_r.
    pub rings: u32,
    /// Each vertex in its home chart.
    pub vertices: Vec<ChartPoint>,
    /// Vertex indices, counter-clockwise in the triangle's home chart.
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's home chart (the chart of its region) and region.
    pub triangle_charts: Vec<ChartId>,
    pub triangle_regions: Vec<Region>,
    /// Each triangle's corners in its home chart's coordinates.
    pub triangle_coords: Vec<[Complex64; 3]>,
    /// Per triangle side (side i runs from corner i to corner i + 1): [`EDGE_INNER`], or which arc of
    /// the coarsest level it lies on. At t_e = 1 two different arcs can join the same two vertices
    /// (squares a_k and b_k share three corners), so an edge is its endpoints *and* this label.
    pub triangle_edge_labels: Vec<[u32; 3]>,
}

/// A triangle side inside a region.
pub const EDGE_INNER: u32 = 0;
/// A side on an arc between a square (or the other cap) and the inside wheel.
pub const EDGE_INSIDE_ARC: u32 = 1;
/// A side on an arc between a square and the vertex wheel.
pub const EDGE_VERTEX_ARC: u32 = 2;

impl Tessellation {
    /// How many steps each wheel's spokes take, the rim's included: k·t_r, with k the least whole
    /// number ≥ 1 that makes the spokes' last step, where the rim's 4n·t_e vertices lie evenly
    /// round a circle and the last band is square (2π·k·t_r/(4n·t_e) of the even step), at least
    /// 0.12 of the even step, and k at most 3. So k = 1 up to genus 13 at t_e = t_r, 2 at genus 14
    /// to 26, and 3 from genus 27. At t_r = 1 the wheels stay fans (there are no bands to keep
    /// square; the remesher's start keeps only the wheels' rims).
    ///
    /// Why: the rim carries 4n·t_e vertices and the spokes t_r steps, so from genus 16 the bands
    /// near the rim were too thin for their length however the steps were graded, and the largest
    /// bend between neighbouring triangles on `ntori new`'s plates fell by only 0.62 (genus 16),
    /// 0.64 (24) and 0.70 (32) when t_e = t_r doubled from 32 to 64, where a smooth surface's
    /// halves. Measured with the `crease_report` example, t = 32 → 64, on those plates:
    ///
    /// | genus | k | largest bend | ratio | triangles ≥ 170° at 32 | triangles at 32 |
    /// |---|---|---|---|---|---|
    /// | 16 | 1 → 2 | 56.4° → 35.0° ⟶ 29.2° → 16.9° | 0.62 ⟶ 0.58 | 34 ⟶ 0 | 324k ⟶ 586k |
    /// | 24 | 1 → 2 | 76.4° → 49.2° ⟶ 34.1° → 19.5° | 0.64 ⟶ 0.57 | 535 ⟶ 140 | 485k ⟶ 879k |
    /// | 32 | 1 → 3 | 95.6° → 66.6° ⟶ 29.7° → 16.2° | 0.70 ⟶ 0.55 | 1 369 ⟶ 97 | 647k ⟶ 1.70M |
    ///
    /// (genus 32 at k = 2: 39.6° → 23.8°, 0.60; genus 10 keeps k = 1: 43.5° → 25.4°, 0.58).
    /// Doubling t_r alone at genus 16 (t_e = 32) had halved the bend, and doubling t_e alone had
    /// raised it: the rings were what the wheels lacked. Why at most 3: the wheels' triangles grow
    /// as k·n·t_e·t_r, so with k growing as n they would grow as n²: genus 64 at t = 32 would have
    /// 5.5 million triangles at k = 5, past `ntori render`'s and `ntori tessellate`'s limits,
    /// where k = 3 makes 3.4 million (k = 1: 1.3 million). The crease test asks for genus 32 at
    /// most, which k = 3 meets.
    pub fn wheel_rings(genus: u32, te: u32, tr: u32) -> u64 {
        if tr <= 1 {
            return u64::from(tr);
        }
        let rim = 4.0 * f64::from(genus.max(1)) * f64::from(te);
        let k = (LEAST_NOMINAL_LAST_STEP * rim / (std::f64::consts::TAU * f64::from(tr))).ceil();
        (k.clamp(1.0, MAX_RING_FACTOR) as u64) * u64::from(tr)
    }

    /// The vertex count the module's formula predicts (t_e, t_r ≥ 1), saturating at `u64::MAX`:
    /// callers compare it with their limits before any work, whatever numbers a user typed.
    pub fn expected_vertices(genus: u32, te: u32, tr: u32) -> u64 {
        let (n, e) = (u128::from(genus), u128::from(te));
        let r = u128::from(Self::wheel_rings(genus, te, tr));
        let count = if genus == 0 {
            4 * e + 2 + 8 * e * r.saturating_sub(1)
        } else {
            2 * n * (e * e + 2 * e).saturating_sub(1) + 2 + 8 * n * e * r.saturating_sub(1)
        };
        u64::try_from(count).unwrap_or(u64::MAX)
    }

    /// The triangle count the module's formula predicts (t_e, t_r ≥ 1), saturating at `u64::MAX`.
    pub fn expected_triangles(genus: u32, te: u32, tr: u32) -> u64 {
        let (n, e) = (u128::from(genus), u128::from(te));
        let r = u128::from(Self::wheel_rings(genus, te, tr));
        let count = if genus == 0 {
            8 * e * (2 * r).saturating_sub(1)
        } else {
            4 * n * e * e + 8 * n * e * (2 * r).saturating_sub(1)
        };
        u64::try_from(count).unwrap_or(u64::MAX)
    }
}

/// Accumulates vertices and triangles.
struct Builder<'a> {
    atlas: &'a Atlas,
    t: Tessellation,
}

impl Builder<'_> {
    fn vertex(&mut self, p: ChartPoint) -> u32 {
        self.t.vertices.push(p);
        (self.t.vertices.len() - 1) as u32
    }

    fn triangle(
        &mut self,
        chart: ChartId,
        region: Region,
        ids: [u32; 3],
        coords: [Complex64; 3],
        labels: [u32; 3],
    ) {
        self.t.triangles.push(ids);
        self.t.triangle_edge_labels.push(labels);
        self.t.triangle_charts.push(chart);
        self.t.triangle_regions.push(region);
        self.t.triangle_coords.push(coords);
    }

    /// Coordinates of a vertex in `chart`, or an error naming the region that does not fit.
    fn coords_in(&self, id: u32, chart: ChartId, what: &str) -> Result<Complex64, ChartsError> {
        let p = self.t.vertices[id as usize];
        if p.chart == chart {
            return Ok(p.coords);
        }
        self.atlas
            .locate_unchecked(p)
            .in_chart(chart)
            .ok_or_else(|| {
                ChartsError::InvalidTessellation(format!(
                    "the {what} does not fit inside {}: chart sizes too small for this layout",
                    self.atlas.charts()[chart.index()].kind().label()
                ))
            })
    }

    /// A wheel about the centre of `chart`: boundary vertices (any order), sorted by angle in the
    /// wheel's chart, joined to the centre by spokes divided into t_r pieces.
    fn wheel(
        &mut self,
        chart: ChartId,
        region: Region,
        boundary: &[u32],
        what: &str,
    ) -> Result<(), ChartsError> {
        let arc = if region == Region::VertexWheel {
            EDGE_VERTEX_ARC
        } else {
            EDGE_INSIDE_ARC
        };
        let mut ring: Vec<(u32, Complex64)> = boundary
            .iter()
            .map(|&id| Ok((id, self.coords_in(id, chart, what)?)))
            .collect::<Result<_, ChartsError>>()?;
        ring.sort_by(|a, b| a.1.arg().total_cmp(&b.1.arg()));
        let tr = self.t.rings;
        let spoke = SpokeGrading::for_wheel(&ring, tr);
        let smoothed = smoothed_rim_radii(&ring, self.t.te.div_ceil(4) as usize);
        let centre = self.vertex(ChartPoint::new(chart, Complex64::ZERO));
        let mut inner: Vec<(u32, Complex64)> = Vec::new();
        for r in 1..=tr {
            let outer: Vec<(u32, Complex64)> = if r == tr {
                ring.clone()
            } else {
                let s = f64::from(r) / f64::from(tr);
                let (f, kept) = (spoke.fraction(s), s.powi(RIM_POINTS_KEPT_POWER));
                ring.iter()
                    .zip(&smoothed)
                    .map(|(&(_, w), &smooth)| {
                        let radius = w.norm();
                        let z = w / radius * (f * (kept * radius + (1.0 - kept) * smooth));
                        (self.vertex(ChartPoint::new(chart, z)), z)
                    })
                    .collect()
            };
            let m = outer.len();
            // The outermost ring's sides lie on the wheel's boundary arcs.
            let rim = if r == tr { arc } else { EDGE_INNER };
            for k in 0..m {
                let (a, b) = (outer[k], outer[(k + 1) % m]);
                if r == 1 {
                    let ids = [centre, a.0, b.0];
                    self.triangle(
                        chart,
                        region,
                        ids,
                        [Complex64::ZERO, a.1, b.1],
                        [EDGE_INNER, rim, EDGE_INNER],
                    );
                } else {
                    let (c, d) = (inner[k], inner[(k + 1) % m]);
                    for (corners, labels) in band_quad([c, a, b, d], rim) {
                        self.triangle(
                            chart,
                            region,
                            corners.map(|v| v.0),
                            corners.map(|v| v.1),
                            labels,
                        );
                    }
                }
            }
            inner = outer;
        }
        Ok(())
    }
}

/// A vertex and its coordinates in the wheel's chart.
type Corner = (u32, Complex64);

/// A triangle's corners and its side labels.
type Half = ([Corner; 3], [u32; 3]);

/// A wheel band's quad, its corners counter-clockwise in the chart: c and d on the inner ring, a
/// and b on the outer (a–b labelled `rim`), as two triangles with their side labels. Split along
/// c–b, or along a–d where that gives the smaller largest angle in the chart and both halves stay
/// counter-clockwise.
///
/// Why: where the rim's star points shear a band's quads (its arcs meet the spokes at about 45°),
/// one diagonal cuts them into triangles of about 135°, far flatter once mapped onto a plate's rim;
/// the other is the quad's shorter. Measured with the `crease_report` example on `ntori new`'s
/// genus-16 plate: triangles of 170° or more in space at t = 32, 64 and 128 went from 317, 95 and
/// 45 to 34, 10 and 0 (the 99.9th percentile of the bend between neighbours 39.3° → 34.4° at 32),
/// and the genus-2 asset's largest bend at t = 32 from 27.0° to 21.6°. Choosing by the angles in
/// space, which needs the surface, did no better.
fn band_quad([c, a, b, d]: [Corner; 4], rim: u32) -> [Half; 2] {
    let along_cb = [
        ([c, a, b], [EDGE_INNER, rim, EDGE_INNER]),
        ([c, b, d], [EDGE_INNER; 3]),
    ];
    let along_ad = [
        ([c, a, d], [EDGE_INNER; 3]),
        ([a, b, d], [rim, EDGE_INNER, EDGE_INNER]),
    ];
    let largest = |halves: &[Half; 2]| largest_of(halves.map(|h| h.0));
    let counter_clockwise = along_ad
        .iter()
        .all(|(t, _)| doubled_area(t.map(|v| v.1)) > 0.0);
    if counter_clockwise && largest(&along_ad) < largest(&along_cb) - SPLIT_TIE {
        along_ad
    } else {
        along_cb
    }
}

/// How much smaller (radians) the a–d split's largest angle must be for [`band_quad`] to take it.
/// Where the rings are circles (the sphere's caps) every band's quad is an isosceles trapezoid
/// whose two splits tie; rounding would pick between them at random, and the two caps would no
/// longer mirror each other (the editor's symmetric edits on the sphere rely on that).
const SPLIT_TIE: f64 = 1e-9;

/// Twice the signed area of a chart triangle (positive counter-clockwise).
fn doubled_area([a, b, c]: [Complex64; 3]) -> f64 {
    ((b - a).conj() * (c - a)).im
}

/// The largest angle (radians) of any of a quad's two halves, in the chart.
fn largest_of(halves: [[Corner; 3]; 2]) -> f64 {
    halves
        .iter()
        .map(|t| largest_angle(t.map(|v| v.1)))
        .fold(0.0, f64::max)
}

/// A chart triangle's largest angle, in radians.
fn largest_angle(z: [Complex64; 3]) -> f64 {
    (0..3)
        .map(|j| {
            let (u, v) = (z[(j + 1) % 3] - z[j], z[(j + 2) % 3] - z[j]);
            (u.conj() * v).arg().abs()
        })
        .fold(0.0, f64::max)
}

/// How much of the rim's points an inner ring keeps: s^p at s = r / t_r of the way out (see
/// [`smoothed_rim_radii`]). Measured with the `crease_report` example on the default plates:
/// p = 3, 6 and 8 leave 380, 135 and 130 triangles of 170° or more at genus 16 (t = 32; none at
/// 64) and 808, 552 and 446 at genus 24, and the largest bend halves alike at every genus; a
/// larger p thickens the band next to the rim where the points stand highest.
const RIM_POINTS_KEPT_POWER: i32 = 6;

/// The least last step, as a fraction of the even step, that the nominal grading of a wheel's
/// spokes may have before the wheel gets more rings than t_r ([`Tessellation::wheel_rings`]): at
/// t_e = t_r it is 2π/4n, 0.157 at genus 10, whose largest bend halved (0.58), and 0.098 at genus
/// 16, whose did not (0.62).
const LEAST_NOMINAL_LAST_STEP: f64 = 0.12;

/// The most rings a wheel gets per t_r ([`Tessellation::wheel_rings`]).
const MAX_RING_FACTOR: f64 = 3.0;

/// The rim's radius at each rim vertex averaged over `half_window` rim vertices either side, or the
/// vertex's own where that is less (so no inner ring reaches past the rim).
///
/// Why: the rim is a star whose 4n points (the images of β) stick out, and its arcs meet them at
/// about 45° to the spokes. Rings that are scaled copies of the rim copy the points, and every band
/// has a triangle with an angle of about 135° there, far flatter once mapped into space (the
/// genus-3 plate had 112 triangles with an angle ≥ 170° at t_e = t_r = 32). Ring r takes the
/// fraction (r / t_r)^p of the rim's own radius and the rest of this smoothed one, so the points
/// fade inward; a fixed fraction of the way out, so the band next to the rim is still thin (it
/// shrinks with t_r rather than keeping the points' height; a ring that dropped the points at once
/// left an edge as long as they are high, whose bend did not halve when t_r doubled).
fn smoothed_rim_radii(rim: &[(u32, Complex64)], half_window: usize) -> Vec<f64> {
    let m = rim.len();
    let radius = |j: usize| rim[j % m].1.norm();
    let half_window = half_window.min(m.saturating_sub(1) / 2);
    (0..m)
        .map(|j| {
            let mean = (m + j - half_window..=m + j + half_window)
                .map(radius)
                .sum::<f64>()
                / (2 * half_window + 1) as f64;
            mean.min(radius(j))
        })
        .collect()
}

/// Where a wheel's rings lie along its spokes: ring r of t_r at the fraction f(r / t_r) of the way
/// from the centre to the rim, with f(s) = (2 − λ)s + (λ − 1)s², so f(0) = 0, f(1) = 1 and the
/// last step is λ times the even step.
///
/// Why: the rim carries 4n·t_e vertices, so at even steps (λ = 1) the outer band's triangles are
/// about 4n/2π times longer along the spoke than across it (6:1 at genus 10, 10:1 at genus 16),
/// and where the surface is strongly curved across the band such slivers bend sharply and do not
/// halve when t_r doubles. λ is chosen so the last step matches the rim's mean vertex spacing, but
/// never below [`SpokeGrading::MIN_LAST_STEP`] (the innermost step is 2 − λ times the even step, so
/// it stays under twice it) nor below 2/(t_r + 2) (neighbouring steps within a factor 2). At genus
/// 0 and 1 the rim is coarse enough that λ = 1: the paper's even steps.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SpokeGrading {
    last_step: f64,
}

impl SpokeGrading {
    /// The smallest λ: the rim's step at least a tenth of the even step.
    const MIN_LAST_STEP: f64 = 0.1;

    /// The grading for a wheel with these rim vertices (sorted by angle, in the wheel's chart)
    /// and `tr` divisions of each spoke.
    fn for_wheel(rim: &[(u32, Complex64)], tr: u32) -> Self {
        let m = rim.len();
        if m < 2 || tr < 2 {
            return SpokeGrading { last_step: 1.0 };
        }
        let radius = rim.iter().map(|(_, w)| w.norm()).sum::<f64>() / m as f64;
        let spacing = (0..m)
            .map(|k| (rim[(k + 1) % m].1 - rim[k].1).norm())
            .sum::<f64>()
            / m as f64;
        let even_step = radius / f64::from(tr);
        // Near the rim the steps grow by 1 + 2(1 − λ)/(λ t_r) from one ring to the next; a
        // smallest λ of 2/(t_r + 2) keeps that growth within 2 at low t_r.
        let smallest = Self::MIN_LAST_STEP.max(2.0 / f64::from(tr + 2));
        SpokeGrading {
            last_step: (spacing / even_step).clamp(smallest, 1.0),
        }
    }

    /// The fraction of the spoke at `s` = r / t_r.
    fn fraction(&self, s: f64) -> f64 {
        let lambda = self.last_step;
        (2.0 - lambda) * s + (lambda - 1.0) * s * s
    }
}

impl Atlas {
    /// The t_e/t_r tessellation (see the module documentation).
    ///
    /// ```
    /// let atlas = charts::Atlas::new(2).unwrap();
    /// let t = atlas.tessellate(2, 3).unwrap();
    /// let (v, f) = (t.vertices.len() as i64, t.triangles.len() as i64);
    /// assert_eq!(v - 3 * f / 2 + f, -2); // χ = 2 − 2n
    /// ```
    pub fn tessellate(&self, te: u32, tr: u32) -> Result<Tessellation, ChartsError> {
        for (name, v) in [("t_e", te), ("t_r", tr)] {
            if v == 0 || v > MAX_RESOLUTION {
                return Err(ChartsError::InvalidTessellation(format!(
                    "{name} must lie in 1..={MAX_RESOLUTION}, got {v}"
                )));
            }
        }
        let triangles = Tessellation::expected_triangles(self.genus(), te, tr);
        if triangles > MAX_TRIANGLES {
            return Err(ChartsError::InvalidTessellation(format!(
                "t_e = {te}, t_r = {tr} would make {triangles} triangles (limit {MAX_TRIANGLES})"
            )));
        }
        let mut b = Builder {
            atlas: self,
            t: Tessellation {
                te,
                tr,
                // Within MAX_TRIANGLES, as just checked.
                rings: Tessellation::wheel_rings(self.genus(), te, tr) as u32,
                vertices: Vec::new(),
                triangles: Vec::with_capacity(triangles as usize),
                triangle_charts: Vec::new(),
                triangle_regions: Vec::new(),
                triangle_coords: Vec::new(),
                triangle_edge_labels: Vec::new(),
            },
        };
        match self.polygon() {
            Some(poly) => self.tessellate_polygon(poly, &mut b)?,
            None => self.tessellate_sphere(&mut b)?,
        }
        Ok(b.t)
    }

    /// Half-size s of the tessellation squares: β = φ(−s + i s) in edge chart a₁.
    pub fn tessellation_square_half(&self) -> Option<f64> {
        let beta = self.polygon()?.constants().beta;
        Some(self.square_half(beta))
    }

    /// β = φ(−s + i s) in the first edge chart, solved for s.
    fn square_half(&self, beta: Complex64) -> f64 {
        let chart = self.charts().iter().find(|c| c.domain() == Domain::Square);
        let w = chart.map_or(Complex64::ZERO, |c| c.to_model().inverse().apply(beta));
        0.5 * (w.im - w.re)
    }

    fn tessellate_sphere(&self, b: &mut Builder) -> Result<(), ChartsError> {
        let (north, south) = (ChartId(0), ChartId(1));
        let arcs = 4 * b.t.te;
        let to_north = self.charts()[0].to_model().inverse();
        let equator: Vec<u32> = (0..arcs)
            .map(|k| {
                let z = Complex64::from_polar(
                    1.0,
                    std::f64::consts::TAU * f64::from(k) / f64::from(arcs),
                );
                b.vertex(ChartPoint::new(north, to_north.apply(z)))
            })
            .collect();
        b.wheel(north, Region::InsideWheel, &equator, "northern cap")?;
        b.wheel(south, Region::InsideWheel, &equator, "southern cap")
    }

    fn tessellate_polygon(
        &self,
        poly: &crate::Polygon,
        b: &mut Builder,
    ) -> Result<(), ChartsError> {
        let s = self.square_half(poly.constants().beta);
        if !(s > 0.0 && s < 0.5) {
            return Err(ChartsError::InvalidTessellation(format!(
                "the tessellation square (half-size {s}) does not fit in its edge chart"
            )));
        }
        let te = b.t.te as usize;
        let c = *poly.constants();
        let betas: Vec<Complex64> = (0..poly.sides())
            .map(|k| c.beta * Complex64::from_polar(1.0, k as f64 * c.omega))
            .collect();
        let mut corner_ids: Vec<Option<u32>> = vec![None; poly.sides()];
        let (mut inside_ring, mut vertex_ring) = (Vec::new(), Vec::new());
        let squares: Vec<ChartId> = self
            .charts()
            .iter()
            .filter(|ch| matches!(ch.kind(), ChartKind::Edge { .. }))
            .map(|ch| ch.id())
            .collect();
        for &chart in &squares {
            let at = |i: usize, k: usize| {
                Complex64::new(
                    -s + 2.0 * s * i as f64 / te as f64,
                    -s + 2.0 * s * k as f64 / te as f64,
                )
            };
            let mut grid = vec![0u32; (te + 1) * (te + 1)];
            for k in 0..=te {
                for i in 0..=te {
                    let w = at(i, k);
                    let corner = (i == 0 || i == te) && (k == 0 || k == te);
                    let id = if corner {
                        // Which β this corner is: reduce its image into the polygon, take the nearest.
                        let z = poly.reduce(self.charts()[chart.index()].to_model().apply(w));
                        let which = (0..betas.len())
                            .min_by(|&x, &y| {
                                (betas[x] - z).norm().total_cmp(&(betas[y] - z).norm())
                            })
                            .unwrap_or(0);
                        *corner_ids[which]
                            .get_or_insert_with(|| b.vertex(ChartPoint::new(chart, w)))
                    } else {
                        b.vertex(ChartPoint::new(chart, w))
                    };
                    grid[k * (te + 1) + i] = id;
                    // Sides a = ±s face the inside wheel, b = ±s the vertex wheel (corners: both).
                    if i == 0 || i == te {
                        inside_ring.push(id);
                    }
                    if k == 0 || k == te {
                        vertex_ring.push(id);
                    }
                }
            }
            // A grid side lies on an arc when both its ends are on the same side of the square.
            let label = |(i0, k0): (usize, usize), (i1, k1): (usize, usize)| {
                if i0 == i1 && (i0 == 0 || i0 == te) {
                    EDGE_INSIDE_ARC
                } else if k0 == k1 && (k0 == 0 || k0 == te) {
                    EDGE_VERTEX_ARC
                } else {
                    EDGE_INNER
                }
            };
            for k in 0..te {
                for i in 0..te {
                    let g = |(i, k): (usize, usize)| (grid[k * (te + 1) + i], at(i, k));
                    let (q00, q10, q11, q01) = ((i, k), (i + 1, k), (i + 1, k + 1), (i, k + 1));
                    for tri in [[q00, q10, q11], [q00, q11, q01]] {
                        let [a, b2, c] = tri.map(g);
                        let labels = [
                            label(tri[0], tri[1]),
                            label(tri[1], tri[2]),
                            label(tri[2], tri[0]),
                        ];
                        b.triangle(
                            chart,
                            Region::Square,
                            [a.0, b2.0, c.0],
                            [a.1, b2.1, c.1],
                            labels,
                        );
                    }
                }
            }
        }
        for ring in [&mut inside_ring, &mut vertex_ring] {
            ring.sort_unstable();
            ring.dedup();
        }
        let inside = self
            .charts()
            .iter()
            .find(|ch| ch.kind() == ChartKind::Inside)
            .map(|ch| ch.id());
        let vertex = self
            .charts()
            .iter()
            .find(|ch| ch.kind() == ChartKind::Vertex)
            .map(|ch| ch.id());
        let (Some(inside), Some(vertex)) = (inside, vertex) else {
            unreachable!("polygon atlases have an inside and a vertex chart")
        };
        b.wheel(inside, Region::InsideWheel, &inside_ring, "inside wheel")?;
        b.wheel(vertex, Region::VertexWheel, &vertex_ring, "vertex wheel")
    }
}

impl Tessellation {
    /// The area of each triangle with geodesic sides through its corners, in the surface's own
    /// geometry (curvature −1, 0 or +1; the flat torus has area 1, the sphere 4π). Negative for a
    /// triangle that is clockwise once lifted. Each triangle is measured on `scale·w` in its chart
    /// (see [`crate::Chart::scale`]), near the origin, where the model is well conditioned.
    pub fn geodesic_areas(&self, atlas: &Atlas) -> Vec<f64> {
        self.triangle_coords
            .iter()
            .zip(&self.triangle_charts)
            .map(|(coords, chart)| {
                let scale = atlas.charts()[chart.index()].scale();
                let p = coords.map(|w| w * scale);
                match atlas.geometry() {
                    crate::Geometry::Hyperbolic => hyperbolic_area(p),
                    crate::Geometry::Euclidean => 0.5 * ((p[1] - p[0]).conj() * (p[2] - p[0])).im,
                    crate::Geometry::Spherical => spherical_area(p),
                }
            })
            .collect()
    }
}

/// Area of the geodesic triangle on three Poincaré-disk points (curvature −1): π minus the angle
/// sum, signed by orientation.
pub fn hyperbolic_area(p: [Complex64; 3]) -> f64 {
    let angle = |a: Complex64, b: Complex64, c: Complex64| {
        // Move a to the origin, where geodesics from it are straight.
        let m = |z: Complex64| (z - a) / (Complex64::ONE - a.conj() * z);
        (m(c) / m(b)).arg()
    };
    let sum = angle(p[0], p[1], p[2]) + angle(p[1], p[2], p[0]) + angle(p[2], p[0], p[1]);
    (std::f64::consts::PI - sum.abs()) * sum.signum()
}

/// Signed area of the spherical triangle (unit sphere) on three stereographic coordinates
/// (Van Oosterom–Strackee).
pub fn spherical_area(p: [Complex64; 3]) -> f64 {
    let lift = |z: Complex64| {
        let d = 1.0 + z.norm_sqr();
        [2.0 * z.re / d, 2.0 * z.im / d, (z.norm_sqr() - 1.0) / d]
    };
    let [a, b, c] = p.map(lift);
    let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let triple = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0]);
    // Projecting from the north pole (ζ ↦ (x, y, z) with z = (|ζ|² − 1)/(|ζ|² + 1)) reverses orientation.
    -2.0 * triple.atan2(1.0 + dot(a, b) + dot(b, c) + dot(c, a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn the_polygons_fan_adds_up_to_its_area() {
        for n in [2, 3, 4] {
            let poly = crate::Polygon::new(n).unwrap();
            let c = poly.corners();
            let total: f64 = (0..c.len())
                .map(|k| hyperbolic_area([Complex64::ZERO, c[k], c[(k + 1) % c.len()]]))
                .sum();
            assert!(
                (total - 4.0 * PI * (f64::from(n) - 1.0)).abs() < 1e-12,
                "n = {n}: {total}"
            );
        }
    }

    proptest::proptest! {
        /// A band's quad (inner corners c, d at radius r; outer a, b further out along their
        /// spokes, as the wheels make them) splits into two counter-clockwise triangles that
        /// cover it, the rim label on the a–b side, with a largest angle no greater than the c–b
        /// split's. Keeping c–b always fails the last assertion.
        #[test]
        fn a_band_quad_takes_the_diagonal_with_the_smaller_largest_angle(
            r in 0.05f64..0.9,
            angle in 0.0f64..std::f64::consts::TAU,
            step in 1e-4f64..0.05,
            inner_gain in 0.8f64..1.25,
            outer in 1e-4f64..0.1,
            outer_gain in 0.5f64..2.0,
        ) {
            let (s, e) = (Complex64::from_polar(1.0, angle), Complex64::from_polar(1.0, angle + step));
            let c = (0, s * r);
            let d = (3, e * (r * inner_gain));
            let a = (1, s * (r + outer));
            let b = (2, e * (r * inner_gain + outer * outer_gain));
            let halves = band_quad([c, a, b, d], EDGE_INSIDE_ARC);
            let quad = doubled_area([c.1, a.1, b.1]) + doubled_area([c.1, b.1, d.1]);
            let mut covered = 0.0;
            for (t, labels) in &halves {
                let area = doubled_area(t.map(|v| v.1));
                proptest::prop_assert!(area > 0.0, "{t:?} turns clockwise");
                covered += area;
                for side in 0..3 {
                    let ends = (t[side].0, t[(side + 1) % 3].0);
                    let want = if ends == (1, 2) { EDGE_INSIDE_ARC } else { EDGE_INNER };
                    proptest::prop_assert_eq!(labels[side], want, "side {:?}", ends);
                }
            }
            proptest::prop_assert!((covered - quad).abs() <= 1e-12 * quad.abs().max(1e-300));
            let kept = largest_of(halves.map(|h| h.0));
            proptest::prop_assert!(kept <= largest_of([[c, a, b], [c, b, d]]));
            let other = [[c, a, d], [a, b, d]];
            if other.iter().all(|t| doubled_area(t.map(|v| v.1)) > 0.0) {
                proptest::prop_assert!(kept <= largest_of(other) + SPLIT_TIE);
            }
        }
    }

    /// The sphere's caps split every band's quad alike, along c–b (their quads are isosceles
    /// trapezoids, whose two splits tie), so the tessellation mirrors itself across the equator.
    /// Without [`SPLIT_TIE`] rounding flips some of them.
    #[test]
    fn the_sphere_s_caps_split_every_quad_alike() {
        let atlas = crate::Atlas::new(0).unwrap();
        for t in [4, 8, 16, 32] {
            let tess = atlas.tessellate(t, t).unwrap();
            // Triangles come in pairs (each cap's fan has 4·t_e, an even count, before its
            // bands): a c–b split's halves [c, a, b], [c, b, d] share c and b in these places,
            // as two neighbouring fan triangles share the centre and a spoke.
            for pair in tess.triangles.chunks_exact(2) {
                let [first, second] = [pair[0], pair[1]];
                assert!(
                    first[0] == second[0] && first[2] == second[1],
                    "t {t}: {first:?}, {second:?} are not split along c–b"
                );
            }
        }
    }

    #[test]
    fn an_octant_of_the_sphere_has_area_pi_over_two() {
        // ζ = 0 is the south pole; ζ = 1 and ζ = i are on the equator.
        let a = spherical_area([Complex64::ZERO, Complex64::ONE, Complex64::I]);
        assert!((a - PI / 2.0).abs() < 1e-14, "{a}");
        let flipped = spherical_area([Complex64::ZERO, Complex64::I, Complex64::ONE]);
        assert!((flipped + PI / 2.0).abs() < 1e-14);
    }
}
