//! Exact tests on chart domains under an LFT: does D_i meet ψ⁻¹(D_j)? LFTs map circles to circles, so
//! every boundary involved is a segment, a circle, or a circular arc that is the image of a segment.

use num_complex::Complex64;

use crate::{Domain, Lft};

/// Tangencies and overlaps thinner than this (chart units) count as empty.
const THIN: f64 = 1e-12;

/// Whether the open domains `di` (source) and `dj` (target) overlap under ψ: D_i ∩ ψ⁻¹(D_j) ≠ ∅.
pub(crate) fn domains_overlap(di: Domain, dj: Domain, psi: &Lft) -> bool {
    match (di, dj) {
        (_, Domain::Disk) => match psi.inverse().image_of_disk(Complex64::ZERO, 0.5) {
            Some((c, r)) => disk_meets_domain(di, c, r),
            None => sampled_overlap(di, dj, psi),
        },
        (Domain::Disk, Domain::Square) => match psi.image_of_disk(Complex64::ZERO, 0.5) {
            Some((c, r)) => disk_meets_domain(Domain::Square, c, r),
            None => sampled_overlap(di, dj, psi),
        },
        (Domain::Square, Domain::Square) => squares_overlap(psi),
    }
}

fn disk_meets_domain(d: Domain, c: Complex64, r: f64) -> bool {
    let dist = match d {
        Domain::Disk => (c.norm() - 0.5).max(0.0),
        Domain::Square => {
            let clamped = Complex64::new(c.re.clamp(-0.5, 0.5), c.im.clamp(-0.5, 0.5));
            (c - clamped).norm()
        }
    };
    // Inside the domain the disk's own radius decides; the open sets overlap iff dist < r.
    dist < r - THIN
}

const CORNERS: [Complex64; 4] = [
    Complex64::new(-0.5, -0.5),
    Complex64::new(0.5, -0.5),
    Complex64::new(0.5, 0.5),
    Complex64::new(-0.5, 0.5),
];

/// Corners, side midpoints and the centre of the square.
const PROBES: [Complex64; 9] = [
    Complex64::new(-0.5, -0.5),
    Complex64::new(0.5, -0.5),
    Complex64::new(0.5, 0.5),
    Complex64::new(-0.5, 0.5),
    Complex64::new(0.0, -0.5),
    Complex64::new(0.5, 0.0),
    Complex64::new(0.0, 0.5),
    Complex64::new(-0.5, 0.0),
    Complex64::new(0.0, 0.0),
];

/// The open unit-size squares S_i, ψ⁻¹(S_j) overlap iff a probe point (corner, side midpoint, centre)
/// of one lies inside the other, or a side of S_i crosses the image of a side of S_j. The midpoints
/// catch aligned squares (genus 1) whose boundaries meet only at corners.
fn squares_overlap(psi: &Lft) -> bool {
    let inv = psi.inverse();
    let inside = |w: Complex64| Domain::Square.margin(w) > THIN;
    let probes = PROBES.iter();
    if probes.clone().any(|&p| inside(psi.apply(p)))
        || probes.clone().any(|&p| inside(inv.apply(p)))
    {
        return true;
    }
    (0..4).any(|a| {
        (0..4).any(|b| {
            segment_meets_image(
                CORNERS[a],
                CORNERS[(a + 1) % 4],
                psi,
                CORNERS[b],
                CORNERS[(b + 1) % 4],
            )
        })
    })
}

/// Whether the segment [a0, a1] (source coordinates) crosses the segment [b0, b1] (target
/// coordinates) after mapping by ψ. ψ(a0 + s(a1 − a0)) = (α s + β)/(γ s + δ) is a Möbius function of the
/// real s; it meets the line through b0, b1 where Im((y − b0)·conj(b1 − b0)) = 0, a real quadratic in s.
fn segment_meets_image(
    a0: Complex64,
    a1: Complex64,
    psi: &Lft,
    b0: Complex64,
    b1: Complex64,
) -> bool {
    let [pa, pb, pc, pd] = psi.matrix();
    let d = a1 - a0;
    let (al, be, ga, de) = (pa * d, pa * a0 + pb, pc * d, pc * a0 + pd);
    let u = (b1 - b0).conj();
    // (y − b0) = ((al − b0 ga) s + (be − b0 de)) / (ga s + de)
    let (p, q) = (al - b0 * ga, be - b0 * de);
    // Im[(p s + q) u conj(ga s + de)] = 0
    let k2 = (p * u * ga.conj()).im;
    let k1 = (p * u * de.conj() + q * u * ga.conj()).im;
    let k0 = (q * u * de.conj()).im;
    let len2 = (b1 - b0).norm_sqr();
    real_roots(k2, k1, k0).into_iter().flatten().any(|s| {
        if !(THIN..=1.0 - THIN).contains(&s) {
            return false;
        }
        let y = psi.apply(a0 + d * s);
        let along = ((y - b0) * u).re / len2;
        (THIN..=1.0 - THIN).contains(&along)
    })
}

/// Real roots of k2 s² + k1 s + k0 (stable form; handles the degenerate linear case).
fn real_roots(k2: f64, k1: f64, k0: f64) -> [Option<f64>; 2] {
    let scale = k2.abs().max(k1.abs()).max(k0.abs());
    if scale == 0.0 {
        return [None, None];
    }
    if k2.abs() <= 1e-14 * scale {
        return [(k1.abs() > 1e-14 * scale).then(|| -k0 / k1), None];
    }
    let disc = k1 * k1 - 4.0 * k2 * k0;
    if disc < 0.0 {
        return [None, None];
    }
    let q = -0.5 * (k1 + k1.signum() * disc.sqrt());
    if q == 0.0 {
        return [Some(0.0), None];
    }
    [Some(q / k2), Some(k0 / q)]
}

/// Fallback when a disk's image is unbounded (never for the polygon atlases): a fine grid.
fn sampled_overlap(di: Domain, dj: Domain, psi: &Lft) -> bool {
    let m = 400;
    (0..m).any(|y| {
        (0..m).any(|x| {
            let w = Complex64::new(
                (x as f64 + 0.5) / m as f64 - 0.5,
                (y as f64 + 0.5) / m as f64 - 0.5,
            );
            di.contains(w) && dj.contains(psi.apply(w))
        })
    })
}

/// A box in source coordinates holding D_i ∩ ψ⁻¹(D_j): the source domain's box cut by the box of the
/// preimage of D_j's circumscribed disk (a bounded disk unless the pole intervenes).
pub(crate) fn preimage_bbox(dj: Domain, psi: &Lft) -> [f64; 4] {
    match psi
        .inverse()
        .image_of_disk(Complex64::ZERO, dj.circumradius())
    {
        Some((c, r)) => [
            (c.re - r).max(-0.5),
            (c.re + r).min(0.5),
            (c.im - r).max(-0.5),
            (c.im + r).min(0.5),
        ],
        None => [-0.5, 0.5, -0.5, 0.5],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shift(t: Complex64) -> Lft {
        Lft::new(Complex64::ONE, -t, Complex64::ZERO, Complex64::ONE).unwrap()
    }

    #[test]
    fn translated_squares_overlap_only_when_they_should() {
        // ψ(w) = w − t: the target square sits at t in source coordinates.
        assert!(domains_overlap(
            Domain::Square,
            Domain::Square,
            &shift(Complex64::new(0.9, 0.0))
        ));
        assert!(!domains_overlap(
            Domain::Square,
            Domain::Square,
            &shift(Complex64::new(1.1, 0.0))
        ));
        // Rotated by 45° and shifted: corners poke in although no corner of the source is inside.
        let rot = Lft::rotate_scale(Complex64::from_polar(1.0, std::f64::consts::FRAC_PI_4));
        let psi_near = rot.compose(&shift(Complex64::new(1.15, 0.0)));
        let psi_far = rot.compose(&shift(Complex64::new(1.25, 0.0)));
        assert!(domains_overlap(Domain::Square, Domain::Square, &psi_near));
        assert!(!domains_overlap(Domain::Square, Domain::Square, &psi_far));
    }

    #[test]
    fn disks_and_squares() {
        assert!(domains_overlap(
            Domain::Disk,
            Domain::Square,
            &shift(Complex64::new(0.95, 0.0))
        ));
        // The square about (0.7, 0.7) comes within 0.28 of the disk's centre; about (0.9, 0.9), 0.57.
        assert!(domains_overlap(
            Domain::Disk,
            Domain::Square,
            &shift(Complex64::new(0.7, 0.7))
        ));
        assert!(!domains_overlap(
            Domain::Disk,
            Domain::Square,
            &shift(Complex64::new(0.9, 0.9))
        ));
        assert!(domains_overlap(
            Domain::Square,
            Domain::Disk,
            &shift(Complex64::new(0.6, 0.6))
        ));
        assert!(!domains_overlap(
            Domain::Disk,
            Domain::Disk,
            &shift(Complex64::new(1.01, 0.0))
        ));
    }

    #[test]
    fn curved_images_cross_straight_sides() {
        // A strong hyperbolic translation bends the image square's sides; compare with brute force.
        for k in 0..35 {
            let t = 0.3 + 0.02 * k as f64;
            let psi = Lft::translate(t).compose(&Lft::rotate_scale(Complex64::new(0.9, 0.3)));
            let exact = domains_overlap(Domain::Square, Domain::Square, &psi);
            let sampled = sampled_overlap(Domain::Square, Domain::Square, &psi);
            assert_eq!(exact, sampled, "t = {t}");
        }
    }
}
