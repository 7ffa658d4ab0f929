//! Uniform B-splines: the basis of the spline patches, and the single cardinal B-spline the blend
//! functions are made of.

use crate::EmbeddingError;

/// The largest spline degree supported.
pub const MAX_DEGREE: usize = 7;

/// A uniform B-spline basis of degree p with `count` functions whose sum is 1 on [−½, ½]: knots
/// t_i = −½ + (i − p)·h, h = 1/(count − p), so the domain [t_p, t_count] is exactly [−½, ½] and
/// every polynomial of degree ≤ p is a combination of the basis there.
///
/// ```
/// use embedding::bspline::UniformBasis;
/// let basis = UniformBasis::new(3, 8).unwrap();
/// let (first, values) = basis.eval(0.123, 0);
/// let sum: f64 = values[0][..=3].iter().sum();
/// assert!((sum - 1.0).abs() < 1e-15 && first <= 8 - 4);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformBasis {
    degree: usize,
    count: usize,
    h: f64,
}

impl UniformBasis {
    pub fn new(degree: usize, count: usize) -> Result<UniformBasis, EmbeddingError> {
        if degree == 0 || degree > MAX_DEGREE {
            return Err(EmbeddingError::Degree(degree));
        }
        if count <= degree || count > 4096 {
            return Err(EmbeddingError::GridSize { count, degree });
        }
        Ok(UniformBasis {
            degree,
            count,
            h: 1.0 / (count - degree) as f64,
        })
    }

    pub fn degree(&self) -> usize {
        self.degree
    }
    pub fn count(&self) -> usize {
        self.count
    }

    /// Knot i.
    pub fn knot(&self, i: isize) -> f64 {
        -0.5 + (i - self.degree as isize) as f64 * self.h
    }

    /// The p + 1 basis functions that do not vanish at x (clamped into [−½, ½]) and their derivatives
    /// up to order `derivs` (≤ p): returns (index of the first, `table[d][j]` = d-th derivative of basis
    /// function first + j). The Cox–de Boor triangle and its derivative form (Piegl and Tiller's
    /// algorithm A2.3), on uniform knots.
    pub fn eval(&self, x: f64, derivs: usize) -> (usize, [[f64; MAX_DEGREE + 1]; 4]) {
        let p = self.degree;
        let derivs = derivs.min(p).min(3);
        let x = x.clamp(-0.5, 0.5);
        // Knot span: t_span ≤ x < t_{span+1}, span ∈ [p, count − 1].
        let span = (((x + 0.5) / self.h).floor() as usize + p).min(self.count - 1);
        let knot = |i: usize| self.knot(i as isize);
        // ndu[j][r]: basis values (upper triangle) and knot differences (lower), as in A2.3.
        let mut ndu = [[0.0; MAX_DEGREE + 1]; MAX_DEGREE + 1];
        let (mut left, mut right) = ([0.0; MAX_DEGREE + 1], [0.0; MAX_DEGREE + 1]);
        ndu[0][0] = 1.0;
        for j in 1..=p {
            left[j] = x - knot(span + 1 - j);
            right[j] = knot(span + j) - x;
            let mut saved = 0.0;
            for r in 0..j {
                ndu[j][r] = right[r + 1] + left[j - r];
                let temp = ndu[r][j - 1] / ndu[j][r];
                ndu[r][j] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            ndu[j][j] = saved;
        }
        let mut out = [[0.0; MAX_DEGREE + 1]; 4];
        for j in 0..=p {
            out[0][j] = ndu[j][p];
        }
        let mut a = [[0.0; MAX_DEGREE + 1]; 2];
        for r in 0..=p {
            let (mut s1, mut s2) = (0usize, 1usize);
            a[0][0] = 1.0;
            for k in 1..=derivs {
                let mut d = 0.0;
                let rk = r as isize - k as isize;
                let pk = p - k;
                if r >= k {
                    a[s2][0] = a[s1][0] / ndu[pk + 1][rk as usize];
                    d = a[s2][0] * ndu[rk as usize][pk];
                }
                let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
                let j2 = if (r as isize - 1) <= pk as isize {
                    k - 1
                } else {
                    p - r
                };
                for j in j1..=j2 {
                    let idx = (rk + j as isize) as usize;
                    a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][idx];
                    d += a[s2][j] * ndu[idx][pk];
                }
                if r <= pk {
                    a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
                    d += a[s2][k] * ndu[r][pk];
                }
                out[k][r] = d;
                std::mem::swap(&mut s1, &mut s2);
            }
        }
        let mut factor = p as f64;
        for (k, row) in out.iter_mut().enumerate().take(derivs + 1).skip(1) {
            for v in row.iter_mut().take(p + 1) {
                *v *= factor;
            }
            factor *= (p - k) as f64;
        }
        (span - p, out)
    }
}

/// The cardinal B-spline of degree d on the knots 0, 1/(d+1), …, 1, and its derivatives up to order
/// 3 at x: a bump on (0, 1), C^{d−1}, vanishing with its first d − 1 derivatives at 0 and 1. The blend
/// functions use d = k + 1 for continuity order k.
pub fn cardinal(d: usize, x: f64) -> [f64; 4] {
    let n = (d + 1) as f64;
    let y = x * n; // integer knots 0..=d+1
    let mut out = [0.0; 4];
    let mut scale = 1.0;
    for (r, o) in out.iter_mut().enumerate() {
        if r <= d {
            // N_d^(r)(y) = Σ_s (−1)^s C(r, s) N_{d−r}(y − s)
            let mut acc = 0.0;
            let mut binom = 1.0;
            for s in 0..=r {
                let sign = if s % 2 == 0 { 1.0 } else { -1.0 };
                acc += sign * binom * integer_bspline(d - r, y - s as f64);
                binom = binom * (r - s) as f64 / (s + 1) as f64;
            }
            *o = acc * scale;
        }
        scale *= n;
    }
    out
}

/// The B-spline of degree q on integer knots 0, 1, …, q + 1 (support [0, q + 1]).
fn integer_bspline(q: usize, y: f64) -> f64 {
    if q == 0 {
        return if (0.0..1.0).contains(&y) { 1.0 } else { 0.0 };
    }
    if y <= 0.0 || y >= (q + 1) as f64 {
        return 0.0;
    }
    let qf = q as f64;
    (y * integer_bspline(q - 1, y) + (qf + 1.0 - y) * integer_bspline(q - 1, y - 1.0)) / qf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_finite_differences() {
        for p in 1..=5 {
            let b = UniformBasis::new(p, p + 6).unwrap();
            for &x in &[-0.41, -0.07, 0.2, 0.33] {
                let (f0, v) = b.eval(x, 3);
                let h = 1e-5;
                let (fp, vp) = b.eval(x + h, 3);
                let (fm, vm) = b.eval(x - h, 3);
                assert!(f0 == fp && f0 == fm, "stay within one span");
                for d in 0..p.min(3) {
                    for j in 0..=p {
                        let fd = (vp[d][j] - vm[d][j]) / (2.0 * h);
                        assert!(
                            (fd - v[d + 1][j]).abs() < 1e-4 * (1.0 + fd.abs()),
                            "p {p} x {x} d {d} j {j}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn cardinal_bumps_vanish_smoothly_at_their_ends() {
        for d in 2..=5 {
            let at0 = cardinal(d, 1e-9);
            for (r, v) in at0.iter().enumerate().take(d) {
                assert!(v.abs() < 1e-6, "d {d} r {r}: {v}");
            }
            // Symmetric about ½, and the derivative matches a difference quotient.
            assert!((cardinal(d, 0.3)[0] - cardinal(d, 0.7)[0]).abs() < 1e-15);
            let h = 1e-6;
            let fd = (cardinal(d, 0.31 + h)[0] - cardinal(d, 0.31 - h)[0]) / (2.0 * h);
            assert!((fd - cardinal(d, 0.31)[1]).abs() < 1e-5);
        }
    }
}
