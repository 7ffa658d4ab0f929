//! Linear fractional transformations z ↦ (a z + b)/(c z + d) in f64.

use num_complex::Complex64;
use serde::Serialize;

use crate::dd::{ExactLft, dd};

/// A linear fractional transformation (Möbius map), stored as a 2×2 complex matrix with det = 1.
///
/// M and −M give the same map; `Lft` keeps whichever the construction produced. Build one from the
/// paper's two primitives, [`Lft::rotate_scale`] (S(p)) and [`Lft::translate`] (T(p)), and compose
/// them. Matrices the atlas stores are formed in double-double first and rounded once (see `dd`).
///
/// ```
/// use charts::Lft;
/// use num_complex::Complex64;
/// // The paper's half-turn about the edge midpoint γ: T(γ)·S(−1)·T(γ)⁻¹ fixes γ.
/// let gamma = (2f64.sqrt() - 1.0).sqrt();
/// let t = Lft::translate(gamma);
/// let half_turn = t.compose(&Lft::rotate_scale(Complex64::new(-1.0, 0.0))).compose(&t.inverse());
/// let z = Complex64::new(gamma, 0.0);
/// assert!((half_turn.apply(z) - z).norm() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lft {
    pub(crate) m: [Complex64; 4],
}

impl Lft {
    /// The identity map.
    pub const IDENTITY: Lft = Lft {
        m: [
            Complex64::new(1.0, 0.0),
            Complex64::new(0.0, 0.0),
            Complex64::new(0.0, 0.0),
            Complex64::new(1.0, 0.0),
        ],
    };

    /// The map with matrix [[a, b], [c, d]], rescaled to det = 1. `None` if the matrix is singular or
    /// not finite.
    pub fn new(a: Complex64, b: Complex64, c: Complex64, d: Complex64) -> Option<Lft> {
        let det = a * d - b * c;
        if !det.is_finite() || det.norm() <= f64::MIN_POSITIVE {
            return None;
        }
        let k = det.sqrt().inv();
        Some(Lft {
            m: [a * k, b * k, c * k, d * k],
        })
    }

    /// Trusts the caller that det = 1 already (to rounding).
    pub(crate) fn from_normalized(m: [Complex64; 4]) -> Lft {
        Lft { m }
    }

    /// The paper's S(p) = [[p, 0], [0, 1]]: rotate by arg p and scale by |p| (p ≠ 0).
    ///
    /// # Panics
    /// If p is zero or not finite (see [`Lft::new`] for a fallible constructor).
    pub fn rotate_scale(p: Complex64) -> Lft {
        Lft::new(p, Complex64::ZERO, Complex64::ZERO, Complex64::ONE)
            .expect("S(p) needs a finite, non-zero p")
    }

    /// The paper's T(p) = [[1, p], [p, 1]] for real −1 < p < 1: the hyperbolic translation along the real
    /// axis that takes 0 to p.
    ///
    /// # Panics
    /// If |p| ≥ 1 or p is not finite.
    pub fn translate(p: f64) -> Lft {
        assert!(
            p.is_finite() && p.abs() < 1.0,
            "T(p) needs |p| < 1, got {p}"
        );
        ExactLft::hyperbolic_translation(dd(p)).to_lft()
    }

    /// The matrix entries [a, b, c, d].
    pub fn matrix(&self) -> [Complex64; 4] {
        self.m
    }

    /// (a z + b)/(c z + d). The pole −d/c maps to infinity (an infinite or NaN result).
    #[inline]
    pub fn apply(&self, z: Complex64) -> Complex64 {
        let [a, b, c, d] = self.m;
        (a * z + b) / (c * z + d)
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn compose(&self, other: &Lft) -> Lft {
        let [a, b, c, d] = self.m;
        let [e, f, g, h] = other.m;
        Lft {
            m: [a * e + b * g, a * f + b * h, c * e + d * g, c * f + d * h],
        }
    }

    /// The inverse map [[d, −b], [−c, a]] (det = 1 makes this exact).
    pub fn inverse(&self) -> Lft {
        let [a, b, c, d] = self.m;
        Lft { m: [d, -b, -c, a] }
    }

    /// The complex derivative 1/(c z + d)² (det = 1).
    #[inline]
    pub fn derivative(&self, z: Complex64) -> Complex64 {
        let [_, _, c, d] = self.m;
        let q = c * z + d;
        (q * q).inv()
    }

    /// The determinant (1 up to rounding).
    pub fn det(&self) -> Complex64 {
        let [a, b, c, d] = self.m;
        a * d - b * c
    }

    /// The largest entry-wise distance to `other`, allowing for the sign ambiguity M ~ −M.
    pub fn distance(&self, other: &Lft) -> f64 {
        let diff = |s: f64| {
            self.m
                .iter()
                .zip(other.m.iter())
                .map(|(x, y)| (x - y * s).norm())
                .fold(0.0, f64::max)
        };
        diff(1.0).min(diff(-1.0))
    }

    /// The image of the circle |z − centre| = radius: (centre, radius), or `None` if the circle passes
    /// through (or encloses, for the disk's interior) the pole, so that the image is not a bounded disk.
    pub fn image_of_disk(&self, centre: Complex64, radius: f64) -> Option<(Complex64, f64)> {
        let [a, _, c, d] = self.m;
        if c.norm() <= 1e-300 {
            // Affine: z ↦ (a z + b)/d.
            return Some((self.apply(centre), radius * (a / d).norm()));
        }
        let pole = -d / c;
        let off = pole - centre;
        if off.norm() <= radius * (1.0 + 1e-12) {
            return None;
        }
        // The point symmetric to the pole with respect to the circle maps to the image's centre.
        let mirror = centre + radius * radius / off.conj();
        let image_centre = self.apply(mirror);
        let on_circle = centre + off * (radius / off.norm());
        Some((image_centre, (self.apply(on_circle) - image_centre).norm()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_derivative() {
        let m = Lft::new(
            Complex64::new(1.0, 2.0),
            Complex64::new(0.5, 0.0),
            Complex64::new(0.0, 0.3),
            Complex64::new(2.0, -1.0),
        )
        .unwrap();
        assert!((m.det() - 1.0).norm() < 1e-15);
        let z = Complex64::new(0.3, 0.4);
        assert!((m.inverse().apply(m.apply(z)) - z).norm() < 1e-14);
        let h = 1e-6;
        let fd = (m.apply(z + h) - m.apply(z - h)) / (2.0 * h);
        assert!((fd - m.derivative(z)).norm() < 1e-8);
    }

    #[test]
    fn image_of_disk_is_the_image_circle() {
        let m = Lft::translate(0.6).compose(&Lft::rotate_scale(Complex64::new(0.2, 0.1)));
        let (c, r) = m.image_of_disk(Complex64::new(0.1, 0.05), 0.3).unwrap();
        for k in 0..16 {
            let t = k as f64 * std::f64::consts::TAU / 16.0;
            let p = m.apply(Complex64::new(0.1, 0.05) + Complex64::from_polar(0.3, t));
            assert!(((p - c).norm() - r).abs() < 1e-14);
        }
        assert!(
            Lft::new(
                Complex64::ZERO,
                Complex64::ONE,
                Complex64::ONE,
                Complex64::ZERO
            )
            .unwrap()
            .image_of_disk(Complex64::ZERO, 0.5)
            .is_none()
        );
    }

    #[test]
    fn singular_matrices_are_refused() {
        assert!(
            Lft::new(
                Complex64::ONE,
                Complex64::ONE,
                Complex64::ONE,
                Complex64::ONE
            )
            .is_none()
        );
        assert!(
            Lft::new(
                Complex64::new(f64::NAN, 0.0),
                Complex64::ZERO,
                Complex64::ZERO,
                Complex64::ONE
            )
            .is_none()
        );
    }
}
