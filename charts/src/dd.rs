//! Double-double ("DD", ~106-bit) arithmetic for forming transition matrices once, exactly enough.
//!
//! Why: the corners of the 4n-gon crowd the unit circle (1 − α ≈ 1.5e-4 at n = 64), so the side-pairing
//! matrices have entries ~1e4 and long products of them amplify f64 rounding by ~1e12. We form every
//! matrix that the atlas stores in DD, normalise it to det = 1, and round it to f64 once.
//!
//! `twofloat` supplies exact `+`, `−`, `×` and `sqrt`; its `/` and its trigonometry are only accurate to
//! ~1e-17 and ~1e-22 (measured), so division gets one Newton correction here and sin/cos come from a
//! Taylor series evaluated in DD.

use num_complex::Complex64;
use twofloat::TwoFloat;

/// A real double-double number.
pub(crate) type Dd = TwoFloat;

pub(crate) fn dd(x: f64) -> Dd {
    TwoFloat::from(x)
}

/// `a / b` to DD accuracy (one Newton step on twofloat's quotient).
pub(crate) fn div(a: Dd, b: Dd) -> Dd {
    let q = a / b;
    let r = a - q * b;
    q + r / b
}

/// π in DD.
pub(crate) fn pi() -> Dd {
    twofloat::consts::PI
}

/// (sin x, cos x) in DD for |x| ≤ π/2, by Taylor series (terms fall below 1e-33 well before 40).
pub(crate) fn sin_cos(x: Dd) -> (Dd, Dd) {
    debug_assert!(x.hi().abs() <= 1.6, "sin_cos expects a reduced argument");
    let x2 = x * x;
    let (mut s, mut s_term) = (x, x);
    let (mut c, mut c_term) = (dd(1.0), dd(1.0));
    for k in 1..40 {
        let k = f64::from(k);
        s_term = -div(s_term * x2, dd((2.0 * k) * (2.0 * k + 1.0)));
        c_term = -div(c_term * x2, dd((2.0 * k - 1.0) * (2.0 * k)));
        s += s_term;
        c += c_term;
        if s_term.hi().abs() < 1e-40 && c_term.hi().abs() < 1e-40 {
            break;
        }
    }
    (s, c)
}

/// e^{iπ·num/den} in DD, exact to ~1e-32 for any integers (the angle is reduced exactly first).
pub(crate) fn unit_pi_fraction(num: i64, den: i64) -> DdComplex {
    assert!(den > 0, "denominator must be positive");
    // Reduce num/den into [0, 2) exactly, then fold into a quarter turn so the series stays short.
    let num = num.rem_euclid(2 * den);
    // Work with angle θ = π·num/den ∈ [0, 2π). Split θ = m·π/2 + φ with φ ∈ [0, π/2).
    let m = (2 * num) / den; // number of whole quarter turns
    let rest_num = 2 * num - m * den; // φ = π/2 · rest_num/den
    let phi = div(pi() * dd(rest_num as f64), dd(2.0 * den as f64));
    let (s, c) = sin_cos(phi);
    let z = DdComplex::new(c, s);
    match m {
        0 => z,
        1 => DdComplex::new(-s, c),
        2 => DdComplex::new(-c, -s),
        _ => DdComplex::new(s, -c),
    }
}

/// A complex number with DD parts. Only the operations the atlas needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DdComplex {
    pub re: Dd,
    pub im: Dd,
}

impl DdComplex {
    pub fn new(re: Dd, im: Dd) -> Self {
        Self { re, im }
    }
    pub fn real(x: Dd) -> Self {
        Self::new(x, dd(0.0))
    }
    pub fn zero() -> Self {
        Self::real(dd(0.0))
    }
    pub fn one() -> Self {
        Self::real(dd(1.0))
    }
    pub fn from_f64(z: Complex64) -> Self {
        Self::new(dd(z.re), dd(z.im))
    }
    pub fn to_f64(self) -> Complex64 {
        Complex64::new(self.re.hi() + self.re.lo(), self.im.hi() + self.im.lo())
    }
    pub fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
    #[cfg(test)]
    pub fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }
    pub fn neg(self) -> Self {
        Self::new(-self.re, -self.im)
    }
    pub fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    pub fn conj(self) -> Self {
        Self::new(self.re, -self.im)
    }
    pub fn norm_sqr(self) -> Dd {
        self.re * self.re + self.im * self.im
    }
    pub fn div(self, o: Self) -> Self {
        let n = o.norm_sqr();
        let p = self.mul(o.conj());
        Self::new(div(p.re, n), div(p.im, n))
    }
}

/// A linear fractional transformation with DD entries, kept at det = 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ExactLft {
    pub a: DdComplex,
    pub b: DdComplex,
    pub c: DdComplex,
    pub d: DdComplex,
}

impl ExactLft {
    pub fn identity() -> Self {
        Self {
            a: DdComplex::one(),
            b: DdComplex::zero(),
            c: DdComplex::zero(),
            d: DdComplex::one(),
        }
    }

    /// z ↦ e^{iπ·num/den} z, as diag(e^{iθ/2}, e^{−iθ/2}) so that det = 1 holds exactly.
    pub fn rotation(num: i64, den: i64) -> Self {
        let half = unit_pi_fraction(num, 2 * den);
        Self {
            a: half,
            b: DdComplex::zero(),
            c: DdComplex::zero(),
            d: half.conj(),
        }
    }

    /// z ↦ k z for real k > 0, as diag(√k, 1/√k).
    pub fn scaling(k: Dd) -> Self {
        let s = k.sqrt();
        Self {
            a: DdComplex::real(s),
            b: DdComplex::zero(),
            c: DdComplex::zero(),
            d: DdComplex::real(div(dd(1.0), s)),
        }
    }

    /// The paper's T(p) for real 0 ≤ p < 1: z ↦ (z + p)/(p z + 1), the hyperbolic translation along the
    /// real axis taking 0 to p, scaled by 1/√(1 − p²) to det = 1.
    pub fn hyperbolic_translation(p: Dd) -> Self {
        let k = div(dd(1.0), (dd(1.0) - p * p).sqrt());
        Self {
            a: DdComplex::real(k),
            b: DdComplex::real(p * k),
            c: DdComplex::real(p * k),
            d: DdComplex::real(k),
        }
    }

    /// z ↦ z + t (already det = 1).
    pub fn euclidean_translation(t: DdComplex) -> Self {
        Self {
            a: DdComplex::one(),
            b: t,
            c: DdComplex::zero(),
            d: DdComplex::one(),
        }
    }

    /// `self ∘ o` (matrix product self · o).
    pub fn then_after(&self, o: &Self) -> Self {
        Self {
            a: self.a.mul(o.a).add(self.b.mul(o.c)),
            b: self.a.mul(o.b).add(self.b.mul(o.d)),
            c: self.c.mul(o.a).add(self.d.mul(o.c)),
            d: self.c.mul(o.b).add(self.d.mul(o.d)),
        }
    }

    /// The inverse of a det = 1 matrix: [[d, −b], [−c, a]].
    pub fn inverse(&self) -> Self {
        Self {
            a: self.d,
            b: self.b.neg(),
            c: self.c.neg(),
            d: self.a,
        }
    }

    pub fn apply(&self, z: DdComplex) -> DdComplex {
        self.a.mul(z).add(self.b).div(self.c.mul(z).add(self.d))
    }

    #[cfg(test)]
    pub fn det(&self) -> DdComplex {
        self.a.mul(self.d).sub(self.b.mul(self.c))
    }

    /// Round to f64 once.
    pub fn to_lft(self) -> crate::Lft {
        crate::Lft::from_normalized([
            self.a.to_f64(),
            self.b.to_f64(),
            self.c.to_f64(),
            self.d.to_f64(),
        ])
    }
}

/// The product of matrices in DD, left to right: `product([A, B, C]) = A·B·C`.
pub(crate) fn product<'a>(factors: impl IntoIterator<Item = &'a ExactLft>) -> ExactLft {
    factors
        .into_iter()
        .fold(ExactLft::identity(), |acc, f| acc.then_after(f))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(a: Dd, b: Dd) -> f64 {
        (a - b).hi().abs()
    }

    #[test]
    fn division_is_dd_accurate() {
        let a = dd(0.7) + dd(1e-20);
        let b = dd(1.3) + dd(3e-18);
        assert!(err(div(a, b) * b, a) < 1e-31);
    }

    #[test]
    fn trig_matches_closed_forms_to_1e30() {
        // cos(π/4) = √½, sin(π/6) = ½, cos²(π/8) = (2 + √2)/4.
        let z = unit_pi_fraction(1, 4);
        assert!(err(z.re, div(dd(1.0), dd(2.0)).sqrt()) < 1e-31);
        assert!(err(z.im, z.re) < 1e-31);
        assert!(err(unit_pi_fraction(1, 6).im, dd(0.5)) < 1e-31);
        let c = unit_pi_fraction(1, 8).re;
        assert!(err(c * c, div(dd(2.0) + dd(2.0).sqrt(), dd(4.0))) < 1e-31);
        // Every quadrant, and |e^{iθ}| = 1.
        for num in -17..40 {
            let z = unit_pi_fraction(num, 7);
            assert!(err(z.norm_sqr(), dd(1.0)) < 1e-31, "num {num}");
            // The f64 reference itself is off by a few ulps of |θ| ≈ 7.
            let f = Complex64::from_polar(1.0, std::f64::consts::PI * num as f64 / 7.0);
            assert!((z.to_f64() - f).norm() < 1e-14, "num {num}");
        }
    }

    #[test]
    fn exact_lfts_keep_det_one() {
        let m = product(&[
            ExactLft::rotation(3, 16),
            ExactLft::hyperbolic_translation(dd(0.9)),
            ExactLft::scaling(dd(0.3)),
        ]);
        assert!(m.det().sub(DdComplex::one()).to_f64().norm() < 1e-30);
        let z = DdComplex::from_f64(Complex64::new(0.1, -0.2));
        let back = m.inverse().apply(m.apply(z));
        assert!(back.sub(z).to_f64().norm() < 1e-30);
    }
}
