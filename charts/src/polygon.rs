//! The fundamental polygon: the regular hyperbolic 4n-gon with angles 2π/4n (genus n ≥ 2), or the unit
//! square (genus 1), with its side pairings and the cycle of corners around the surface's one vertex.
//!
//! Conventions (from the notes on the paper, checked by the tests): ω = 2π/4n; edge e lies on the
//! geodesic whose closest point to the origin is γ·e^{ieω}; corner c lies at α·e^{i(c+½)ω}, between edges
//! c and c + 1. Edges come in fours per handle k: 4k = a_k, 4k+1 = b_k, 4k+2 = a_k⁻¹, 4k+3 = b_k⁻¹, and
//! the pairing of edge chart j = 2k + t carries edge 4k+2+t onto edge 4k+t with reversed orientation.

use num_complex::Complex64;
use serde::Serialize;

use crate::dd::{self, DdComplex, ExactLft, dd, div};

/// Which geometry the universal cover carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Geometry {
    /// Genus 0: the Riemann sphere, no polygon.
    Spherical,
    /// Genus 1: the Euclidean plane tiled by unit squares.
    Euclidean,
    /// Genus ≥ 2: the Poincaré disk tiled by regular 4n-gons.
    Hyperbolic,
}

/// The paper's constants, re-derived from their definitions (closed forms in `Polygon::hyperbolic`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PolygonConstants {
    /// ω = 2π/4n, the angle between neighbouring edge directions (and each corner's interior angle).
    pub omega: f64,
    /// Distance from the origin to the centres of the edge circles (hyperbolic only).
    pub h: Option<f64>,
    /// Radius of the edge circles, r = √(h² − 1) (hyperbolic only).
    pub r: Option<f64>,
    /// Distance from the origin to an edge midpoint.
    pub gamma: f64,
    /// Distance from the origin to a corner.
    pub alpha: f64,
    /// The point where the corners of the tessellation squares of edge charts 0 and 1 meet: on the
    /// bisector of corner 0, on the geodesic leaving edge 0's midpoint at 45° towards corner 0.
    pub beta: Complex64,
    /// The paper's vertex-chart scale δ: with the vertex disk |w| < ½ mapped by S(p_c)T(α)S(δ), its
    /// boundary passes through β. (ntori chooses its own scales; see `scales`.)
    pub paper_delta: f64,
}

/// The fundamental polygon and its side-pairing group generators.
#[derive(Clone, Debug)]
pub struct Polygon {
    geometry: Geometry,
    genus: u32,
    constants: PolygonConstants,
    corners: Vec<Complex64>,
    /// cross[e] maps the polygon onto the tile across edge e (exact).
    cross: Vec<ExactLft>,
    cross_f64: Vec<crate::Lft>,
    /// Per edge chart j = 2k + t: the pairing carrying edge 4k+2+t onto edge 4k+t.
    pairings: Vec<ExactLft>,
    /// Edge-circle centres (hyperbolic) or outward normals (Euclidean), per edge.
    edge_dirs: Vec<Complex64>,
    vertex_cycle: Vec<VertexStep>,
    /// γ and α in DD, for forming frames exactly.
    gamma_exact: dd::Dd,
    alpha_exact: dd::Dd,
}

/// One step of the walk around the surface's single vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct VertexStep {
    /// The polygon corner the walk is at.
    pub corner: usize,
    /// The edge it leaves that corner by (one of `corner`, `corner + 1`).
    pub leave_by: usize,
}

impl Polygon {
    /// The fundamental polygon for genus 1 ..= [`crate::MAX_GENUS`] (genus 0 has none).
    ///
    /// ```
    /// let octagon = charts::Polygon::new(2).unwrap();
    /// assert!((octagon.constants().alpha - 2f64.powf(-0.25)).abs() < 1e-15);
    /// ```
    pub fn new(genus: u32) -> Result<Polygon, crate::ChartsError> {
        match genus {
            1 => Ok(Polygon::square()),
            n if (2..=crate::MAX_GENUS).contains(&n) => Ok(Polygon::hyperbolic(n)),
            _ => Err(crate::ChartsError::UnsupportedGenus {
                genus,
                max: crate::MAX_GENUS,
            }),
        }
    }

    /// The regular hyperbolic 4n-gon with interior angles 2π/4n, for n ≥ 2.
    ///
    /// Closed forms (derived from the paper's h² = (1 + cos ω)/(2 cos ω), r² = h² − 1): with
    /// c = cos(ω/2), s = sin(ω/2): h = c/√cos ω, r = s/√cos ω, γ = h − r = (c − s)/√cos ω and
    /// α = hc − √((hc)² − 1) = √cos ω. They avoid the cancellation in h − r for large n.
    pub(crate) fn hyperbolic(n: u32) -> Polygon {
        assert!(n >= 2);
        let four_n = 4 * i64::from(n);
        // ω/2 = π/(4n).
        let half = dd::unit_pi_fraction(1, four_n);
        let (c, s) = (half.re, half.im);
        let cos_omega = c * c - s * s;
        let root = cos_omega.sqrt();
        let h = div(c, root);
        let r = div(s, root);
        let gamma = div(c - s, root);
        let alpha = root;
        let t_gamma = ExactLft::hyperbolic_translation(gamma);
        let pairing = |k: i64, t: i64| {
            // S(p_l)·T(γ)·S(−1)·T(γ)⁻¹·S(p_r)⁻¹ with p_l = e^{i(4k+t)ω}, p_r = e^{i(4k+2+t)ω}.
            dd::product(&[
                ExactLft::rotation(4 * k + t, 2 * i64::from(n)),
                t_gamma,
                ExactLft::rotation(1, 1),
                t_gamma.inverse(),
                ExactLft::rotation(-(4 * k + 2 + t), 2 * i64::from(n)),
            ])
        };
        let edge_dirs = (0..four_n)
            .map(|e| dd::unit_pi_fraction(e, 2 * i64::from(n)).to_f64() * to_f64(h))
            .collect();
        Self::assemble(
            Geometry::Hyperbolic,
            n,
            alpha,
            gamma,
            (Some(to_f64(h)), Some(to_f64(r))),
            pairing,
            edge_dirs,
        )
    }

    /// The unit square (−½, ½)² with translations by 1 and i: the flat torus, laid out as the n = 1 case
    /// of the same conventions (edge 0 on the right, corner 0 at (½, ½)).
    pub(crate) fn square() -> Polygon {
        let t_half = ExactLft::euclidean_translation(DdComplex::real(dd(0.5)));
        let pairing = |k: i64, t: i64| {
            dd::product(&[
                ExactLft::rotation(4 * k + t, 2),
                t_half,
                ExactLft::rotation(1, 1),
                t_half.inverse(),
                ExactLft::rotation(-(4 * k + 2 + t), 2),
            ])
        };
        let edge_dirs = (0..4)
            .map(|e| dd::unit_pi_fraction(e, 2).to_f64())
            .collect();
        Self::assemble(
            Geometry::Euclidean,
            1,
            div(dd(1.0), dd(2.0)).sqrt(),
            dd(0.5),
            (None, None),
            pairing,
            edge_dirs,
        )
    }

    fn assemble(
        geometry: Geometry,
        n: u32,
        alpha_exact: dd::Dd,
        gamma_exact: dd::Dd,
        (h, r): (Option<f64>, Option<f64>),
        pairing: impl Fn(i64, i64) -> ExactLft,
        edge_dirs: Vec<Complex64>,
    ) -> Polygon {
        let sides = 4 * n as usize;
        let omega = std::f64::consts::TAU / sides as f64;
        let (alpha, gamma) = (to_f64(alpha_exact), to_f64(gamma_exact));
        let corners: Vec<Complex64> = (0..sides)
            .map(|c| dd::unit_pi_fraction(2 * c as i64 + 1, sides as i64).to_f64() * alpha)
            .collect();
        let pairings: Vec<ExactLft> = (0..2 * n as i64).map(|j| pairing(j / 2, j % 2)).collect();
        let cross: Vec<ExactLft> = (0..sides)
            .map(|e| {
                let (k, t) = (e / 4, e % 4);
                if t < 2 {
                    pairings[2 * k + t]
                } else {
                    pairings[2 * k + t - 2].inverse()
                }
            })
            .collect();
        let cross_f64 = cross.iter().map(|m| m.to_lft()).collect();
        let mut polygon = Polygon {
            geometry,
            genus: n,
            constants: PolygonConstants {
                omega,
                h,
                r,
                gamma,
                alpha,
                beta: Complex64::ZERO,
                paper_delta: 0.0,
            },
            corners,
            cross,
            cross_f64,
            pairings,
            edge_dirs,
            vertex_cycle: Vec::new(),
            gamma_exact,
            alpha_exact,
        };
        polygon.vertex_cycle = polygon.walk_vertex();
        polygon.constants.beta = polygon.find_beta();
        polygon.constants.paper_delta = 2.0
            * polygon
                .to_corner_frame(0)
                .inverse()
                .apply(polygon.constants.beta)
                .norm();
        polygon
    }

    pub fn geometry(&self) -> Geometry {
        self.geometry
    }
    pub fn genus(&self) -> u32 {
        self.genus
    }
    /// 4n.
    pub fn sides(&self) -> usize {
        self.corners.len()
    }
    pub fn constants(&self) -> &PolygonConstants {
        &self.constants
    }
    /// Corner c at α·e^{i(c+½)ω}.
    pub fn corners(&self) -> &[Complex64] {
        &self.corners
    }
    /// The edge paired with edge e (4k+t ↔ 4k+2+t).
    pub fn partner(&self, e: usize) -> usize {
        let (k, t) = (e / 4, e % 4);
        4 * k + (t + 2) % 4
    }
    /// The two corners bounding edge e, in counter-clockwise order.
    pub fn edge_corners(&self, e: usize) -> (usize, usize) {
        let s = self.sides();
        ((e + s - 1) % s, e)
    }
    /// The group element mapping the polygon onto the tile across edge e, in f64.
    pub fn cross(&self, e: usize) -> &crate::Lft {
        &self.cross_f64[e]
    }
    pub(crate) fn cross_exact(&self, e: usize) -> &ExactLft {
        &self.cross[e]
    }
    /// The side pairing of edge chart j = 2k + t (maps edge 4k+2+t onto edge 4k+t), in f64.
    pub fn pairing(&self, j: usize) -> crate::Lft {
        self.pairings[j].to_lft()
    }
    /// The 4n steps around the single surface vertex, starting at corner 0 and leaving by edge 1.
    pub fn vertex_cycle(&self) -> &[VertexStep] {
        &self.vertex_cycle
    }

    /// The product, over the walk around the vertex, of the maps onto the tiles crossed into:
    /// `cross[e₀]·cross[e₁]·…·cross[e₄ₙ₋₁]`. It is the defining relation of the group, so it must be the
    /// identity. Formed in double-double and rounded once; `naive` forms it in f64 instead (which
    /// loses ~12 digits at n = 64, the reason the atlas uses DD).
    pub fn vertex_composite(&self, naive: bool) -> crate::Lft {
        if naive {
            self.vertex_cycle
                .iter()
                .fold(crate::Lft::IDENTITY, |acc, s| {
                    acc.compose(&self.cross_f64[s.leave_by])
                })
        } else {
            dd::product(self.vertex_cycle.iter().map(|s| &self.cross[s.leave_by])).to_lft()
        }
    }

    /// T(p) in this geometry: the translation along the real axis taking 0 to p.
    pub(crate) fn translation(&self, p: dd::Dd) -> ExactLft {
        match self.geometry {
            Geometry::Hyperbolic => ExactLft::hyperbolic_translation(p),
            _ => ExactLft::euclidean_translation(DdComplex::real(p)),
        }
    }

    /// The frame at edge e: S(e^{ieω})·T(γ), taking 0 to the edge midpoint and the imaginary axis onto
    /// the edge (exact).
    pub(crate) fn edge_frame_exact(&self, e: usize) -> ExactLft {
        ExactLft::rotation(e as i64, 2 * i64::from(self.genus))
            .then_after(&self.translation(self.gamma_exact))
    }

    /// The frame at corner c: S(e^{i(c+½)ω})·T(α), taking 0 to the corner (exact).
    pub(crate) fn corner_frame_exact(&self, c: usize) -> ExactLft {
        ExactLft::rotation(2 * c as i64 + 1, 4 * i64::from(self.genus))
            .then_after(&self.translation(self.alpha_exact))
    }

    fn to_corner_frame(&self, c: usize) -> crate::Lft {
        self.corner_frame_exact(c).to_lft()
    }

    /// Whether z lies in the closed polygon (with a relative slack of `tol`).
    pub fn contains(&self, z: Complex64, tol: f64) -> bool {
        (0..self.sides()).all(|e| self.outside_edge(z, e) <= tol)
    }

    /// Positive when z lies beyond edge e (on the side away from the polygon), negative inside.
    /// Hyperbolic: r − |z − centre|; Euclidean: signed distance past the edge line.
    pub fn outside_edge(&self, z: Complex64, e: usize) -> f64 {
        match self.geometry {
            Geometry::Hyperbolic => {
                self.constants.r.unwrap_or(0.0) - (z - self.edge_dirs[e]).norm()
            }
            _ => (z * self.edge_dirs[e].conj()).re - 0.5,
        }
    }

    /// Brings a model point into the polygon by side pairings: returns the reduced point. Each step
    /// crosses back over the edge the point lies furthest beyond; for a Dirichlet domain centred at the
    /// origin (as here) this strictly decreases the distance to the origin, so it terminates.
    pub fn reduce(&self, z: Complex64) -> Complex64 {
        self.reduce_with_map(z).0
    }

    /// [`Polygon::reduce`], also returning the group element g it applied (g(z) is the reduced point),
    /// so that nearby points can be moved along with z.
    pub fn reduce_with_map(&self, mut z: Complex64) -> (Complex64, crate::Lft) {
        let mut g = crate::Lft::IDENTITY;
        for _ in 0..10_000 {
            let (e, out) = (0..self.sides())
                .map(|e| (e, self.outside_edge(z, e)))
                .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
            if out <= 0.0 {
                break;
            }
            let step = self.cross_f64[e].inverse();
            z = step.apply(z);
            g = step.compose(&g);
        }
        (z, g)
    }

    /// Follows a corner through the pairing of the edge it leaves by: the tile across edge e sees our
    /// vertex as the image of the corner c' = cross[e]⁻¹(corner); we arrive there through partner(e)
    /// and leave by the corner's other edge.
    fn walk_vertex(&self) -> Vec<VertexStep> {
        let s = self.sides();
        let mut steps = Vec::with_capacity(s);
        let (mut corner, mut leave_by) = (0usize, 1usize);
        for _ in 0..s {
            steps.push(VertexStep { corner, leave_by });
            let image = self.cross_f64[leave_by]
                .inverse()
                .apply(self.corners[corner]);
            corner = self.nearest_corner(image);
            let arrived = self.partner(leave_by);
            leave_by = if arrived == corner {
                (corner + 1) % s
            } else {
                corner
            };
        }
        steps
    }

    fn nearest_corner(&self, z: Complex64) -> usize {
        (0..self.sides())
            .min_by(|&a, &b| {
                (self.corners[a] - z)
                    .norm()
                    .total_cmp(&(self.corners[b] - z).norm())
            })
            .unwrap_or(0)
    }

    /// β: on the bisector of corner 0 and on the geodesic leaving edge 0's midpoint at 45° towards
    /// corner 0 (the diagonal a = −b of edge chart 0). Bisection on the angle along that geodesic.
    fn find_beta(&self) -> Complex64 {
        let frame = self.edge_frame_exact(0).to_lft();
        let dir = Complex64::from_polar(1.0, 0.75 * std::f64::consts::PI);
        let target = self.constants.omega / 2.0;
        let (mut lo, mut hi) = (0.0, 0.999_999);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if frame.apply(dir * mid).arg() < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        frame.apply(dir * (0.5 * (lo + hi)))
    }

    /// Hyperbolic area of the polygon by quadrature (curvature −1): in polar coordinates each half
    /// sector contributes ∫ 2R(θ)²/(1 − R(θ)²) dθ, R(θ) the distance to the edge along the ray.
    /// Euclidean: the plain area. Used to check the constants against Gauss–Bonnet.
    pub fn area_by_quadrature(&self) -> f64 {
        match self.geometry {
            Geometry::Hyperbolic => {
                let h = self.constants.h.unwrap_or(0.0);
                let half = self.constants.omega / 2.0;
                let integrand = |phi: f64| {
                    let hc = h * phi.cos();
                    let big_r = hc - (hc * hc - 1.0).sqrt();
                    2.0 * big_r * big_r / (1.0 - big_r * big_r)
                };
                // R(φ) has a square-root near-singularity just past the corner (φ = ω/2), so substitute
                // φ = ω/2 − s², dφ = 2s ds, and integrate the now smooth function of s by Simpson.
                let g = |s: f64| integrand(half - s * s) * 2.0 * s;
                let (m, top) = (20_000, half.sqrt());
                let step = top / m as f64;
                let mut sum = g(0.0) + g(top);
                for i in 1..m {
                    let w = if i % 2 == 1 { 4.0 } else { 2.0 };
                    sum += w * g(i as f64 * step);
                }
                sum * step / 3.0 * 2.0 * self.sides() as f64
            }
            _ => 1.0,
        }
    }
}

fn to_f64(x: dd::Dd) -> f64 {
    x.hi() + x.lo()
}
