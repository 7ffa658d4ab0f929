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
    /// The knot spacing (the domain is [−½, ½]).
    pub fn spacing(&self) -> f64 {
        self.h
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
    /// function first + j).
    ///
    /// The knots are uniform, so on every span the live functions are the same p + 1 polynomials of
    /// the local parameter t ∈ [0, 1) (Cox–de Boor's recurrence on unit knots), and the
    /// derivatives are differences of the lower degrees' values, scaled by h⁻¹ per order.
    pub fn eval(&self, x: f64, derivs: usize) -> (usize, [[f64; MAX_DEGREE + 1]; 4]) {
        let p = self.degree;
        let derivs = derivs.min(p).min(3);
        let (span, t) = self.span(x);
        // One copy per degree: the loops unroll and the bounds checks go.
        let table = match p {
            1 => span_table::<1>(t, derivs, self.h),
            2 => span_table::<2>(t, derivs, self.h),
            3 => span_table::<3>(t, derivs, self.h),
            4 => span_table::<4>(t, derivs, self.h),
            5 => span_table::<5>(t, derivs, self.h),
            6 => span_table::<6>(t, derivs, self.h),
            _ => span_table::<MAX_DEGREE>(t, derivs, self.h),
        };
        (span - p, table)
    }

    /// [`UniformBasis::eval`]'s values alone (its `table[0]`, the same numbers), without the
    /// derivatives' table: for the tensor stencil, which needs only positions.
    pub fn values(&self, x: f64) -> (usize, [f64; MAX_DEGREE + 1]) {
        let p = self.degree;
        let (span, t) = self.span(x);
        (span - p, unit_values(p, t))
    }

    /// The knot span of x (clamped to the domain), t_span ≤ x < t_{span+1} with span ∈ [p,
    /// count − 1], and x's local parameter t ∈ [0, 1] in it.
    fn span(&self, x: f64) -> (usize, f64) {
        // (x + ½)/h ≥ 0 once clamped, so the cast's truncation is the floor (without a call to
        // libm's floor, which the default target makes it; the same number).
        let x = x.clamp(-0.5, 0.5);
        let span = (((x + 0.5) / self.h) as usize + self.degree).min(self.count - 1);
        (span, (x - self.knot(span as isize)) / self.h)
    }
}

/// The top row of [`unit_triangle`] (degree p), without the rows below.
fn unit_values(p: usize, t: f64) -> [f64; MAX_DEGREE + 1] {
    match p {
        0 => unit_values_of::<0>(t),
        1 => unit_values_of::<1>(t),
        2 => unit_values_of::<2>(t),
        3 => {
            let [a, b, c, d] = cubic(t)[0];
            [a, b, c, d, 0.0, 0.0, 0.0, 0.0]
        }
        4 => unit_values_of::<4>(t),
        5 => unit_values_of::<5>(t),
        6 => unit_values_of::<6>(t),
        _ => unit_values_of::<MAX_DEGREE>(t),
    }
}

/// The top row of [`unit_triangle_of`]: Cox–de Boor's recurrence in place, each degree's row
/// overwriting the one below from the right, with the same arithmetic (so the same numbers).
fn unit_values_of<const P: usize>(t: f64) -> [f64; MAX_DEGREE + 1] {
    let mut n = [0.0; MAX_DEGREE + 1];
    n[0] = 1.0;
    for k in 1..=P {
        let inv = 1.0 / k as f64;
        for j in (0..=k).rev() {
            let below = if j > 0 { n[j - 1] } else { 0.0 };
            n[j] = ((t + (k - j) as f64) * below + (j as f64 + 1.0 - t) * n[j]) * inv;
        }
    }
    n
}

/// Zeros before each row of [`unit_triangle`], so that differences of up to third order need no
/// bounds tests.
const PAD: usize = 3;

/// One degree's values on a span, behind [`PAD`] zeros and followed by zeros.
type Level = [f64; MAX_DEGREE + 1 + PAD];

/// (−1)^(d+s) C(d, s) for d, s ≤ 3: the d-th derivative on unit knots of the function with index j
/// is Σ_s `DIFFERENCES[d][s]` · (the degree p − d value with index j − s), from
/// N'_{j} = N_{j−1} − N_{j} one degree down, applied d times.
const DIFFERENCES: [[f64; 4]; 4] = [
    [1.0, 0.0, 0.0, 0.0],
    [-1.0, 1.0, 0.0, 0.0],
    [1.0, -2.0, 1.0, 0.0],
    [-1.0, 3.0, -3.0, 1.0],
];

/// The d-th derivative on unit knots, from the values one level of degree d lower.
fn difference(lower: &Level, d: usize, j: usize) -> f64 {
    let w = &DIFFERENCES[d];
    let i = PAD + j;
    w[0] * lower[i] + w[1] * lower[i - 1] + w[2] * lower[i - 2] + w[3] * lower[i - 3]
}

/// The four cubic B-splines alive on a span of unit knots at t in it (index j: the one whose
/// support starts at j − 3) and their first, second and third derivatives on unit knots: the
/// default degree and the C² blends' bump. The same arithmetic as [`unit_triangle_of`] and
/// [`difference`] for degree 3, in the same order, less the terms that are exact zeros, so the
/// same numbers to the bit; but without zeroing and walking the general table, which made the
/// basis and the blends a quarter of `ntori new`'s time.
fn cubic(t: f64) -> [[f64; 4]; 4] {
    let one = [1.0 - t, t];
    let two = [
        (1.0 - t) * one[0] * 0.5,
        ((t + 1.0) * one[0] + (2.0 - t) * one[1]) * 0.5,
        t * one[1] * 0.5,
    ];
    let third = 1.0 / 3.0;
    let three = [
        (1.0 - t) * two[0] * third,
        ((t + 2.0) * two[0] + (2.0 - t) * two[1]) * third,
        ((t + 1.0) * two[1] + (3.0 - t) * two[2]) * third,
        t * two[2] * third,
    ];
    [
        three,
        [-two[0], -two[1] + two[0], -two[2] + two[1], two[2]],
        [
            one[0],
            one[1] + -2.0 * one[0],
            -2.0 * one[1] + one[0],
            one[1],
        ],
        [-1.0, 3.0, -3.0, 1.0],
    ]
}

/// [`UniformBasis::eval`]'s table at local parameter t of a span, knot spacing h: the table on
/// unit knots, the d-th derivatives scaled by h⁻ᵈ.
fn span_table<const P: usize>(t: f64, derivs: usize, h: f64) -> [[f64; MAX_DEGREE + 1]; 4] {
    let unit = if P == 3 {
        cubic(t).map(|[a, b, c, d]| [a, b, c, d, 0.0, 0.0, 0.0, 0.0])
    } else {
        recurrence_table::<P>(t)
    };
    let mut out = [[0.0; MAX_DEGREE + 1]; 4];
    let mut scale = 1.0;
    for (row, unit_row) in out.iter_mut().zip(unit).take(derivs + 1) {
        for (v, u) in row.iter_mut().zip(unit_row).take(P + 1) {
            *v = scale * u;
        }
        scale /= h;
    }
    out
}

/// The table on unit knots of [`span_table`] by the recurrence, for any degree: the values and
/// their first to third derivatives (rows past the degree are zero).
fn recurrence_table<const P: usize>(t: f64) -> [[f64; MAX_DEGREE + 1]; 4] {
    let levels = unit_triangle_of::<P>(t);
    let mut out = [[0.0; MAX_DEGREE + 1]; 4];
    for (d, row) in out.iter_mut().enumerate().take(P.min(3) + 1) {
        for (j, v) in row.iter_mut().enumerate().take(P + 1) {
            *v = difference(&levels[P - d], d, j);
        }
    }
    out
}

/// The B-splines of every degree k ≤ p on unit knots that are alive on the span [0, 1), at t in
/// it: `levels[k][PAD + j]`, j = 0..=k, is the one whose support starts at j − k. Cox–de Boor's
/// recurrence with unit knot spacing.
fn unit_triangle(p: usize, t: f64) -> [Level; MAX_DEGREE + 1] {
    match p {
        0 => unit_triangle_of::<0>(t),
        1 => unit_triangle_of::<1>(t),
        2 => unit_triangle_of::<2>(t),
        3 => unit_triangle_of::<3>(t),
        4 => unit_triangle_of::<4>(t),
        5 => unit_triangle_of::<5>(t),
        6 => unit_triangle_of::<6>(t),
        _ => unit_triangle_of::<MAX_DEGREE>(t),
    }
}

fn unit_triangle_of<const P: usize>(t: f64) -> [Level; MAX_DEGREE + 1] {
    let mut levels = [[0.0; MAX_DEGREE + 1 + PAD]; MAX_DEGREE + 1];
    levels[0][PAD] = 1.0;
    for k in 1..=P {
        let inv = 1.0 / k as f64;
        for j in 0..=k {
            // N^k_j = ((t + k − j) N^{k−1}_{j−1} + (j + 1 − t) N^{k−1}_j) / k; the row below is
            // zero at j − 1 = −1 (the padding) and at j = k.
            let (below, here) = (levels[k - 1][PAD + j - 1], levels[k - 1][PAD + j]);
            levels[k][PAD + j] = ((t + (k - j) as f64) * below + (j as f64 + 1.0 - t) * here) * inv;
        }
    }
    levels
}

/// [`cardinal`]'s value alone.
pub fn cardinal_value(d: usize, x: f64) -> f64 {
    let y = x * (d + 1) as f64;
    // Outside [0, d + 1) the bump is zero; inside, the cast's truncation is the floor.
    if !(0.0..(d + 1) as f64).contains(&y) {
        return 0.0;
    }
    let m = y as usize;
    unit_values(d, y - m as f64)[d - m]
}

/// The cardinal B-spline of degree d on the knots 0, 1/(d+1), …, 1, and its derivatives up to order
/// 3 at x: a bump on (0, 1), C^{d−1}, vanishing with its first d − 1 derivatives at 0 and 1. The blend
/// functions use d = k + 1 for continuity order k.
pub fn cardinal(d: usize, x: f64) -> [f64; 4] {
    let n = (d + 1) as f64;
    let y = x * n; // integer knots 0..=d+1
    let mut out = [0.0; 4];
    if !(0.0..n).contains(&y) {
        return out;
    }
    // On the span [m, m + 1) the bump N_d is the degree-d function starting at 0, index d − m:
    // its value and derivatives on unit knots, then scaled by n per order.
    let m = y as usize;
    let t = y - m as f64;
    let orders = d.min(3) + 1;
    let unit: [f64; 4] = if d == 3 {
        cubic(t).map(|row| row[3 - m])
    } else {
        let levels = unit_triangle(d, t);
        std::array::from_fn(|r| {
            if r < orders {
                difference(&levels[d - r], r, d - m)
            } else {
                0.0
            }
        })
    };
    let mut scale = 1.0;
    for (o, u) in out.iter_mut().zip(unit).take(orders) {
        *o = scale * u;
        scale *= n;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The general algorithm (Piegl and Tiller's A2.3, any knots) on the basis's knots: the
    /// oracle for the uniform recurrence.
    fn piegl_tiller(
        b: &UniformBasis,
        x: f64,
        derivs: usize,
    ) -> (usize, [[f64; MAX_DEGREE + 1]; 4]) {
        let p = b.degree;
        let derivs = derivs.min(p).min(3);
        let x = x.clamp(-0.5, 0.5);
        // Knot span: t_span ≤ x < t_{span+1}, span ∈ [p, count − 1].
        let span = (((x + 0.5) / b.h).floor() as usize + p).min(b.count - 1);
        let knot = |i: usize| b.knot(i as isize);
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

    /// The B-spline of degree q on integer knots 0, 1, …, q + 1, by its recursive definition.
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

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn uniform_recurrence_matches_the_general_algorithm(
            p in 1..=MAX_DEGREE,
            extra in 1usize..40,
            x in -0.6f64..0.6,
        ) {
            let b = UniformBasis::new(p, p + extra).unwrap();
            let (first, fast) = b.eval(x, 3);
            let (first_ref, slow) = piegl_tiller(&b, x, 3);
            prop_assert_eq!(first, first_ref);
            // The values alone are the table's first row, to the bit.
            prop_assert_eq!(b.values(x), (first, fast[0]));
            // Each derivative order scales by h⁻¹.
            let mut scale: f64 = 1.0;
            for d in 0..=p.min(3) {
                for j in 0..=p {
                    prop_assert!(
                        (fast[d][j] - slow[d][j]).abs() <= 1e-12 * scale,
                        "d {} j {}: {} vs {}", d, j, fast[d][j], slow[d][j]
                    );
                }
                scale /= b.h;
            }
        }

        /// Inside the support, outside it, and on its integer knots.
        #[test]
        fn cardinal_matches_its_recursive_definition(
            d in 2usize..=5,
            x in -0.2f64..1.2,
            knot in prop::option::of(-1i32..8),
        ) {
            let n = (d + 1) as f64;
            let x = knot.map_or(x, |k| k as f64 / n);
            let fast = cardinal(d, x);
            prop_assert_eq!(cardinal_value(d, x), fast[0]);
            let mut scale = 1.0;
            for (r, &value) in fast.iter().enumerate().take(d.min(3) + 1) {
                let mut slow = 0.0;
                let mut binom = 1.0;
                for s in 0..=r {
                    let sign = if s % 2 == 0 { 1.0 } else { -1.0 };
                    slow += sign * binom * integer_bspline(d - r, x * n - s as f64);
                    binom = binom * (r - s) as f64 / (s + 1) as f64;
                }
                slow *= scale;
                prop_assert!(
                    (value - slow).abs() <= 1e-12 * scale,
                    "r {}: {} vs {}", r, value, slow
                );
                scale *= n;
            }
        }
    }

    proptest! {
        /// The cubic's closed form is the recurrence's arithmetic: the same bits (a remesher
        /// downstream turned out to be sensitive to the last one), for the basis and the bump.
        #[test]
        fn the_cubic_is_the_recurrence_to_the_bit(t in 0.0f64..1.0, h in 0.001f64..1.0) {
            let fast = span_table::<3>(t, 3, h);
            let unit = recurrence_table::<3>(t);
            let mut scale = 1.0;
            for d in 0..4 {
                for j in 0..4 {
                    let slow = scale * unit[d][j];
                    prop_assert_eq!(fast[d][j].to_bits(), slow.to_bits(), "d {} j {}", d, j);
                }
                scale /= h;
            }
            prop_assert_eq!(unit_values(3, t), unit_values_of::<3>(t));
            for m in 0..4 {
                let x = (m as f64 + t) / 4.0;
                let y = x * 4.0;
                let (span, local) = (y.floor() as usize, y - y.floor());
                if span > 3 {
                    continue; // m + t rounded up to the bump's end
                }
                let levels = unit_triangle_of::<3>(local);
                let mut scale = 1.0;
                for (r, &value) in cardinal(3, x).iter().enumerate() {
                    let slow = scale * difference(&levels[3 - r], r, 3 - span);
                    prop_assert_eq!(value.to_bits(), slow.to_bits(), "m {} r {}", m, r);
                    scale *= 4.0;
                }
            }
        }
    }

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
