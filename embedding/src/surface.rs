//! The surface S(p) = Σ_c b_c E_c / Σ_c b_c and its derivatives, normal and curvature.
//!
//! Everything here comes from one routine, [`Layout::weights`]: for a surface point seen from one of
//! its charts, the jet (value, first and second derivatives in that chart's coordinates) of every
//! control point's weight. The surface is Σ weight · control point, so direct evaluation and the
//! stencils are the same numbers.

use charts::{Atlas, ChartId, ChartPoint, Domain, Lft};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::EmbeddingError;
use crate::bspline::{UniformBasis, cardinal, cardinal_value};

/// A position in R³: a point of the surface, a control point. Distinct from chart and model points,
/// and from [`Vector3`]: positions subtract to vectors, and only vectors add, scale and cross.
pub type Point3 = nalgebra::Point3<f64>;

/// A vector in R³: a derivative of the surface, a normal, a displacement.
pub type Vector3 = nalgebra::Vector3<f64>;

/// The least and greatest corners of the axis-aligned box around `points` ((+∞, −∞) when there
/// are none).
pub fn bounding_box(points: &[Point3]) -> (Point3, Point3) {
    points.iter().fold(
        (
            Point3::from([f64::INFINITY; 3]),
            Point3::from([f64::NEG_INFINITY; 3]),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    )
}

/// The spline and blend parameters of a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SplineSettings {
    /// Degree of the spline patches (3: cubic).
    pub degree: usize,
    /// Continuity order k of the blend functions (they vanish with derivatives up to k at the
    /// chart boundary; the surface is C^k where the patches are).
    pub continuity: usize,
    /// Control points per side of each chart's grid.
    pub grid: usize,
    /// Control points per side of the disk charts' grids (the inside and vertex charts; the caps
    /// of the sphere), where they differ from `grid`. Those two charts carry far more of a
    /// high-genus surface than an edge chart, and their outer parts are coarse: a grid cell
    /// there spans many times what it does in an edge chart (see `fit::default_disk_grid`).
    /// Absent in files before version 3, which then mean `grid`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disk_grid: Option<usize>,
}

impl SplineSettings {
    /// Control points per side of the disk charts' grids.
    pub fn disk_grid(&self) -> usize {
        self.disk_grid.unwrap_or(self.grid)
    }

    /// The grids in words: "48×48 control grid per chart", or "48×48 control grid per edge
    /// chart, 96×96 per disk chart".
    pub fn grid_text(&self) -> String {
        let g = self.grid;
        match self.disk_grid {
            Some(d) if d != g => {
                format!("{g}×{g} control grid per edge chart, {d}×{d} per disk chart")
            }
            _ => format!("{g}×{g} control grid per chart"),
        }
    }
}

impl Default for SplineSettings {
    /// Cubic patches, C² blends and a 32 × 32 grid per chart. The grid is what keeps the fit fair
    /// (`embedding/examples/shape_report.rs`, `ntori new`'s shape line): at 16 the plates' flat
    /// faces rippled (the normal 2° to 3° off ±z at the 90th percentile, genus 2 and 3), genus
    /// 10's inside chart, which carries a large share of the surface, was too coarse to follow it
    /// (a spot of |κ| ≈ 140), and genus 16 missed Gauss–Bonnet by 4.5% and the residual check; at
    /// 32 the ripple is 0.5° to 1.2° (genus 2 to 10), the spot is gone, and genus 16 passes
    /// (Gauss–Bonnet within 9.4e-6, patch disagreement 0.016% of the diagonal).
    fn default() -> Self {
        SplineSettings {
            degree: 3,
            continuity: 2,
            grid: 32,
            disk_grid: None,
        }
    }
}

/// A value with its first and second derivatives in some chart's coordinates (u, v).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Jet {
    pub val: f64,
    pub du: f64,
    pub dv: f64,
    pub duu: f64,
    pub duv: f64,
    pub dvv: f64,
}

impl Jet {
    /// f(u)·g(v) from the values and first two derivatives of f and g.
    fn tensor(f: [f64; 3], g: [f64; 3]) -> Jet {
        Jet {
            val: f[0] * g[0],
            du: f[1] * g[0],
            dv: f[0] * g[1],
            duu: f[2] * g[0],
            duv: f[1] * g[1],
            dvv: f[0] * g[2],
        }
    }

    fn product(a: Jet, b: Jet) -> Jet {
        Jet {
            val: a.val * b.val,
            du: a.du * b.val + a.val * b.du,
            dv: a.dv * b.val + a.val * b.dv,
            duu: a.duu * b.val + 2.0 * a.du * b.du + a.val * b.duu,
            duv: a.duv * b.val + a.du * b.dv + a.dv * b.du + a.val * b.duv,
            dvv: a.dvv * b.val + 2.0 * a.dv * b.dv + a.val * b.dvv,
        }
    }

    /// This jet (in coordinates x + iy) seen through a holomorphic map x + iy = ψ(u + iv) with
    /// ψ' = d1 and ψ'' = d2 at the point: the chain rule for a conformal change of variables.
    pub(crate) fn through(self, d1: Complex64, d2: Complex64) -> Jet {
        let (xu, yu, xv, yv) = (d1.re, d1.im, -d1.im, d1.re);
        let (xuu, yuu, xuv, yuv, xvv, yvv) = (d2.re, d2.im, -d2.im, d2.re, -d2.re, -d2.im);
        let (fx, fy, fxx, fxy, fyy) = (self.du, self.dv, self.duu, self.duv, self.dvv);
        Jet {
            val: self.val,
            du: fx * xu + fy * yu,
            dv: fx * xv + fy * yv,
            duu: fxx * xu * xu + 2.0 * fxy * xu * yu + fyy * yu * yu + fx * xuu + fy * yuu,
            duv: fxx * xu * xv + fxy * (xu * yv + xv * yu) + fyy * yu * yv + fx * xuv + fy * yuv,
            dvv: fxx * xv * xv + 2.0 * fxy * xv * yv + fyy * yv * yv + fx * xvv + fy * yvv,
        }
    }

    /// a / b by the quotient rule.
    fn quotient(a: Jet, b: Jet) -> Jet {
        let q = a.val / b.val;
        let qu = (a.du - q * b.du) / b.val;
        let qv = (a.dv - q * b.dv) / b.val;
        Jet {
            val: q,
            du: qu,
            dv: qv,
            duu: (a.duu - 2.0 * qu * b.du - q * b.duu) / b.val,
            duv: (a.duv - qu * b.dv - qv * b.du - q * b.duv) / b.val,
            dvv: (a.dvv - 2.0 * qv * b.dv - q * b.dvv) / b.val,
        }
    }
}

/// Position and derivatives of the surface in one chart's coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceJet {
    pub pos: Point3,
    pub du: Vector3,
    pub dv: Vector3,
    pub duu: Vector3,
    pub duv: Vector3,
    pub dvv: Vector3,
}

impl SurfaceJet {
    /// The unit normal S_u × S_v / |S_u × S_v| (outward for a positively oriented embedding).
    pub fn normal(&self) -> Vector3 {
        self.du.cross(&self.dv).normalize()
    }
    /// First fundamental form (E, F, G).
    pub fn first_form(&self) -> (f64, f64, f64) {
        (
            self.du.dot(&self.du),
            self.du.dot(&self.dv),
            self.dv.dot(&self.dv),
        )
    }
    /// Second fundamental form (L, M, N) with respect to [`SurfaceJet::normal`].
    pub fn second_form(&self) -> (f64, f64, f64) {
        let n = self.normal();
        (self.duu.dot(&n), self.duv.dot(&n), self.dvv.dot(&n))
    }
    /// Gaussian curvature (LN − M²)/(EG − F²).
    pub fn gaussian_curvature(&self) -> f64 {
        let ((e, f, g), (l, m, n)) = (self.first_form(), self.second_form());
        (l * n - m * m) / (e * g - f * f)
    }
    /// Mean curvature (EN − 2FM + GL)/(2(EG − F²)).
    pub fn mean_curvature(&self) -> f64 {
        let ((e, f, g), (l, m, n)) = (self.first_form(), self.second_form());
        (e * n - 2.0 * f * m + g * l) / (2.0 * (e * g - f * f))
    }
    /// The principal curvatures κ₁ ≥ κ₂ (H ± √(H² − K), with respect to [`SurfaceJet::normal`]).
    pub fn principal_curvatures(&self) -> (f64, f64) {
        crate::evaluate::Curvatures {
            gaussian: self.gaussian_curvature(),
            mean: self.mean_curvature(),
        }
        .principal()
    }
    /// The area element |S_u × S_v|.
    pub fn area_element(&self) -> f64 {
        self.du.cross(&self.dv).norm()
    }
}

/// How control points are laid out over an atlas: one g × g patch per chart (g the chart's grid:
/// [`SplineSettings::disk_grid`] for a disk chart, `grid` for a square), chart-major, then
/// row-major (index = the chart's offset + j·g + i for basis i in u, j in v). The disk charts
/// come first in every atlas (tested for every genus), so a chart's offset is a sum of two
/// counts.
#[derive(Clone, Debug)]
pub struct Layout<'a> {
    atlas: &'a Atlas,
    bases: Bases,
    settings: SplineSettings,
}

/// How a layout numbers its control points: the square charts' and the disk charts' grids, how
/// many of the atlas's first charts are disks, and how many charts there are. Copy, so stencils
/// can keep it without the atlas.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ControlGrids {
    pub square: usize,
    pub disk: usize,
    pub disks: usize,
    pub charts: usize,
}

impl ControlGrids {
    /// Control points per side of `chart`'s grid.
    pub fn grid(&self, chart: ChartId) -> usize {
        if chart.index() < self.disks {
            self.disk
        } else {
            self.square
        }
    }

    /// The index of `chart`'s first control point (the count of all of them for the chart one
    /// past the last).
    pub fn offset(&self, chart: ChartId) -> usize {
        let c = chart.index();
        let d2 = self.disk * self.disk;
        if c <= self.disks {
            c * d2
        } else {
            self.disks * d2 + (c - self.disks) * self.square * self.square
        }
    }

    /// Every chart's control points.
    pub fn count(&self) -> usize {
        self.offset(ChartId(self.charts as u32))
    }

    /// The chart holding control point `c`, and c's place (i, j) in its grid.
    pub fn locate(&self, c: usize) -> (ChartId, usize, usize) {
        let in_disks = self.disks * self.disk * self.disk;
        let (chart, local, g) = if c < in_disks {
            let per = self.disk * self.disk;
            (c / per, c % per, self.disk)
        } else {
            let per = self.square * self.square;
            let rest = c - in_disks;
            (self.disks + rest / per, rest % per, self.square)
        };
        (ChartId(chart as u32), local % g, local / g)
    }

    /// The grid of the chart holding control point `c`: the stride between the lines of a
    /// block that starts at `c`.
    #[inline]
    pub fn stride(&self, c: usize) -> usize {
        if c < self.disks * self.disk * self.disk {
            self.disk
        } else {
            self.square
        }
    }
}

/// The B-spline bases of a layout's charts: one for the squares, one for the disks (the same
/// where their grids are), and how many of the atlas's first charts are disks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bases {
    square: UniformBasis,
    disk: UniformBasis,
    disks: usize,
}

/// One control point's weight at a surface point: its index and the jet of its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weight {
    pub control: u32,
    pub jet: Jet,
}

impl<'a> Layout<'a> {
    pub fn new(atlas: &'a Atlas, settings: SplineSettings) -> Result<Layout<'a>, EmbeddingError> {
        if !(1..=4).contains(&settings.continuity) {
            return Err(EmbeddingError::Continuity(settings.continuity));
        }
        let disks = atlas
            .charts()
            .iter()
            .take_while(|c| c.domain() == Domain::Disk)
            .count();
        debug_assert!(
            atlas.charts()[disks..]
                .iter()
                .all(|c| c.domain() == Domain::Square),
            "an atlas lists its disk charts first"
        );
        Ok(Layout {
            atlas,
            bases: Bases {
                square: UniformBasis::new(settings.degree, settings.grid)?,
                disk: UniformBasis::new(settings.degree, settings.disk_grid())?,
                disks,
            },
            settings,
        })
    }

    /// A layout from settings [`Layout::new`] has accepted before (their bases are `bases`).
    pub(crate) fn from_checked(
        atlas: &'a Atlas,
        bases: Bases,
        settings: SplineSettings,
    ) -> Layout<'a> {
        Layout {
            atlas,
            bases,
            settings,
        }
    }

    pub(crate) fn bases(&self) -> Bases {
        self.bases
    }

    /// The B-spline basis of `chart`'s patch.
    pub fn basis(&self, chart: ChartId) -> &UniformBasis {
        if chart.index() < self.bases.disks {
            &self.bases.disk
        } else {
            &self.bases.square
        }
    }

    /// Control points per side of `chart`'s grid.
    pub fn grid(&self, chart: ChartId) -> usize {
        self.basis(chart).count()
    }

    /// How the control points are numbered (without the bases).
    pub fn grids(&self) -> ControlGrids {
        ControlGrids {
            square: self.bases.square.count(),
            disk: self.bases.disk.count(),
            disks: self.bases.disks,
            charts: self.atlas.charts().len(),
        }
    }

    /// The index of `chart`'s first control point; its g² points follow it.
    pub fn chart_offset(&self, chart: ChartId) -> usize {
        self.grids().offset(chart)
    }

    pub fn atlas(&self) -> &'a Atlas {
        self.atlas
    }
    pub fn settings(&self) -> SplineSettings {
        self.settings
    }
    /// Total number of control points.
    pub fn control_count(&self) -> usize {
        self.grids().count()
    }
    pub fn control_index(&self, chart: ChartId, i: usize, j: usize) -> usize {
        self.chart_offset(chart) + j * self.grid(chart) + i
    }

    /// The unnormalised blend b_c and its derivatives at w in chart c's own coordinates.
    pub fn raw_blend(&self, domain: Domain, w: Complex64) -> Jet {
        let d = self.settings.continuity + 1;
        match domain {
            Domain::Square => {
                let (x, y) = (cardinal(d, w.re + 0.5), cardinal(d, w.im + 0.5));
                Jet::tensor([x[0], x[1], x[2]], [y[0], y[1], y[2]])
            }
            Domain::Disk => {
                // |w| < 2 in a disk chart: no overflow for hypot to guard against.
                let r = w.norm_sqr().sqrt();
                let b = cardinal(d, 0.5 + r);
                if r < 1e-9 {
                    // Even about the centre: the gradient vanishes, the Hessian is B''·I.
                    return Jet {
                        val: b[0],
                        duu: b[2],
                        dvv: b[2],
                        ..Jet::default()
                    };
                }
                let (ux, uy) = (w.re / r, w.im / r);
                Jet {
                    val: b[0],
                    du: b[1] * ux,
                    dv: b[1] * uy,
                    duu: b[2] * ux * ux + b[1] * (1.0 - ux * ux) / r,
                    duv: b[2] * ux * uy - b[1] * ux * uy / r,
                    dvv: b[2] * uy * uy + b[1] * (1.0 - uy * uy) / r,
                }
            }
        }
    }

    /// [`Layout::raw_blend`]'s value alone.
    pub fn raw_blend_value(&self, domain: Domain, w: Complex64) -> f64 {
        let d = self.settings.continuity + 1;
        match domain {
            Domain::Square => cardinal_value(d, w.re + 0.5) * cardinal_value(d, w.im + 0.5),
            Domain::Disk => cardinal_value(d, 0.5 + w.norm_sqr().sqrt()),
        }
    }

    /// Every control point's weight at the surface point `p` (a point of `p.chart`), with first and
    /// second derivatives in `p.chart`'s coordinates. Appends to `out` and returns the normalising
    /// sum Σ b_c (its jet), which the coverage margin keeps away from zero.
    pub fn weights(&self, p: ChartPoint, out: &mut Vec<Weight>) -> Jet {
        let p1 = self.settings.degree + 1;
        let start = out.len();
        let mut sum = Jet::default();
        for (rep, psi) in self.atlas.locate_with_transitions(p) {
            let chart = &self.atlas.charts()[rep.chart.index()];
            let w = rep.coords;
            let (d1, d2) = derivatives(&psi, p.coords);
            let raw = self.raw_blend(chart.domain(), w);
            add(&mut sum, raw.through(d1, d2));
            let basis = self.basis(rep.chart);
            let (fu, nu) = basis.eval(w.re, 2);
            let (fv, nv) = basis.eval(w.im, 2);
            // (value, first, second derivative) of each of the p + 1 basis functions alive here.
            let triples = |n: &[[f64; crate::bspline::MAX_DEGREE + 1]; 4]| {
                std::array::from_fn::<[f64; 3], { crate::bspline::MAX_DEGREE + 1 }, _>(|k| {
                    [n[0][k], n[1][k], n[2][k]]
                })
            };
            let (bu, bv) = (triples(&nu), triples(&nv));
            for (j, y) in bv[..p1].iter().enumerate() {
                for (i, x) in bu[..p1].iter().enumerate() {
                    let basis = Jet::tensor(*x, *y);
                    out.push(Weight {
                        control: self.control_index(rep.chart, fu + i, fv + j) as u32,
                        jet: Jet::product(raw, basis).through(d1, d2),
                    });
                }
            }
        }
        for weight in &mut out[start..] {
            weight.jet = Jet::quotient(weight.jet, sum);
        }
        sum
    }

    /// [`Layout::weights`]' values alone, bit for bit (the same products in the same order),
    /// without their derivatives: (control point, weight) appended to `out`. Returns Σ b_c. The
    /// fit's data rows need no more, and forming the second-order jets of every weight was most of
    /// their assembly.
    pub fn weight_values(&self, p: ChartPoint, out: &mut Vec<(u32, f64)>) -> f64 {
        let p1 = self.settings.degree + 1;
        let start = out.len();
        let mut sum = 0.0;
        for (rep, _) in self.atlas.locate_with_transitions(p) {
            let chart = &self.atlas.charts()[rep.chart.index()];
            let w = rep.coords;
            let raw = self.raw_blend_value(chart.domain(), w);
            sum += raw;
            let basis = self.basis(rep.chart);
            let (fu, nu) = basis.values(w.re);
            let (fv, nv) = basis.values(w.im);
            for (j, y) in nv[..p1].iter().enumerate() {
                for (i, x) in nu[..p1].iter().enumerate() {
                    let control = self.control_index(rep.chart, fu + i, fv + j) as u32;
                    out.push((control, raw * (x * y)));
                }
            }
        }
        for weight in &mut out[start..] {
            weight.1 /= sum;
        }
        sum
    }

    /// The unblended patch E_c at a point of chart c: each of its (degree + 1)² live control points
    /// with its basis value (appended to `out`).
    pub fn patch_weights(&self, p: ChartPoint, out: &mut Vec<(u32, f64)>) {
        let p1 = self.settings.degree + 1;
        let basis = self.basis(p.chart);
        let (fu, nu) = basis.eval(p.coords.re, 0);
        let (fv, nv) = basis.eval(p.coords.im, 0);
        for (j, y) in nv[0][..p1].iter().enumerate() {
            for (i, x) in nu[0][..p1].iter().enumerate() {
                out.push((self.control_index(p.chart, fu + i, fv + j) as u32, x * y));
            }
        }
    }

    /// The normalised blend of each chart holding `p` (they sum to 1), in chart order.
    pub fn blends(&self, p: ChartPoint) -> Vec<(ChartId, f64)> {
        self.blends_located(&self.atlas.locate_with_transitions(p))
    }

    /// [`Layout::blends`] where the point is already located: `reps` is what
    /// [`Atlas::locate_with_transitions`] gives for it.
    pub(crate) fn blends_located(&self, reps: &[(ChartPoint, Lft)]) -> Vec<(ChartId, f64)> {
        let raw: Vec<f64> = reps
            .iter()
            .map(|(r, _)| {
                self.raw_blend_value(self.atlas.charts()[r.chart.index()].domain(), r.coords)
            })
            .collect();
        let total: f64 = raw.iter().sum();
        reps.iter()
            .zip(raw)
            .map(|((r, _), b)| (r.chart, b / total))
            .collect()
    }

    /// S at `p` alone: [`Layout::eval`]'s position without the derivatives, for callers that
    /// need many points and no normals (a third of the work).
    pub fn position(&self, control: &[Point3], p: ChartPoint) -> Point3 {
        let p1 = self.settings.degree + 1;
        let (mut sum, mut total) = (Vector3::zeros(), 0.0);
        for (rep, _) in self.atlas.locate_with_transitions(p) {
            let chart = &self.atlas.charts()[rep.chart.index()];
            let w = rep.coords;
            let blend = self.raw_blend_value(chart.domain(), w);
            let basis = self.basis(rep.chart);
            let (fu, nu) = basis.eval(w.re, 0);
            let (fv, nv) = basis.eval(w.im, 0);
            let mut patch = Vector3::zeros();
            for (j, y) in nv[0][..p1].iter().enumerate() {
                for (i, x) in nu[0][..p1].iter().enumerate() {
                    let c = self.control_index(rep.chart, fu + i, fv + j);
                    patch += control[c].coords * (x * y);
                }
            }
            sum += patch * blend;
            total += blend;
        }
        // Σ b_c E_c / Σ b_c: an affine combination, accumulated from the origin.
        Point3::from(sum / total)
    }

    /// S and its first and second derivatives at `p`, in `p.chart`'s coordinates.
    ///
    /// The same sum as [`Layout::weights`] gives, grouped by chart: each patch E_c is summed
    /// with its basis functions' jets first, and the blend, the chain rule and the quotient act on
    /// the patch (three coordinate jets) rather than on each of its (degree + 1)² weights.
    pub fn eval(&self, control: &[Point3], p: ChartPoint) -> SurfaceJet {
        self.eval_located(control, p, &self.atlas.locate_with_transitions(p))
    }

    /// [`Layout::eval`] where `p` is already located: `reps` is what
    /// [`Atlas::locate_with_transitions`] gives for it.
    pub(crate) fn eval_located(
        &self,
        control: &[Point3],
        p: ChartPoint,
        reps: &[(ChartPoint, Lft)],
    ) -> SurfaceJet {
        self.eval_located_with_sum(control, p, reps).0
    }

    /// [`Layout::eval_located`] and the normalising sum Σ b_c of the raw blends there (the same
    /// sum [`Layout::blends_located`] divides by, in the same order, so the same bits): a chart's
    /// normalised blend is then its raw blend over it, without locating or blending again.
    pub(crate) fn eval_located_with_sum(
        &self,
        control: &[Point3],
        p: ChartPoint,
        reps: &[(ChartPoint, Lft)],
    ) -> (SurfaceJet, f64) {
        let p1 = self.settings.degree + 1;
        let mut numerator = [Jet::default(); 3];
        let mut denominator = Jet::default();
        for &(rep, psi) in reps {
            let chart = &self.atlas.charts()[rep.chart.index()];
            let w = rep.coords;
            let (d1, d2) = derivatives(&psi, p.coords);
            let raw = self.raw_blend(chart.domain(), w);
            add(&mut denominator, raw.through(d1, d2));
            let basis = self.basis(rep.chart);
            let (fu, nu) = basis.eval(w.re, 2);
            let (fv, nv) = basis.eval(w.im, 2);
            // E_c and its derivatives in its own chart's coordinates: each row of control
            // points summed along u first (value, ∂u, ∂uu), then the rows along v.
            let zero = Vector3::zeros;
            let (mut val, mut du, mut dv) = (zero(), zero(), zero());
            let (mut duu, mut duv, mut dvv) = (zero(), zero(), zero());
            for j in 0..p1 {
                let (mut row, mut row_u, mut row_uu) = (zero(), zero(), zero());
                for i in 0..p1 {
                    let c = control[self.control_index(rep.chart, fu + i, fv + j)].coords;
                    row += c * nu[0][i];
                    row_u += c * nu[1][i];
                    row_uu += c * nu[2][i];
                }
                val += row * nv[0][j];
                dv += row * nv[1][j];
                dvv += row * nv[2][j];
                du += row_u * nv[0][j];
                duv += row_u * nv[1][j];
                duu += row_uu * nv[0][j];
            }
            let patch: [Jet; 3] = std::array::from_fn(|k| Jet {
                val: val[k],
                du: du[k],
                dv: dv[k],
                duu: duu[k],
                duv: duv[k],
                dvv: dvv[k],
            });
            for (n, e) in numerator.iter_mut().zip(patch) {
                add(n, Jet::product(raw, e).through(d1, d2));
            }
        }
        let [x, y, z] = numerator.map(|n| Jet::quotient(n, denominator));
        let v = |f: fn(&Jet) -> f64| Vector3::new(f(&x), f(&y), f(&z));
        let jet = SurfaceJet {
            pos: Point3::from(v(|j| j.val)),
            du: v(|j| j.du),
            dv: v(|j| j.dv),
            duu: v(|j| j.duu),
            duv: v(|j| j.duv),
            dvv: v(|j| j.dvv),
        };
        (jet, denominator.val)
    }
}

fn add(acc: &mut Jet, j: Jet) {
    acc.val += j.val;
    acc.du += j.du;
    acc.dv += j.dv;
    acc.duu += j.duu;
    acc.duv += j.duv;
    acc.dvv += j.dvv;
}

/// ψ'(w) and ψ''(w) of an LFT with det 1: 1/(cw + d)² and −2c/(cw + d)³.
pub(crate) fn derivatives(psi: &Lft, w: Complex64) -> (Complex64, Complex64) {
    let [_, _, c, d] = psi.matrix();
    let q = c * w + d;
    let inv = q.inv();
    (inv * inv, -2.0 * c * inv * inv * inv)
}
