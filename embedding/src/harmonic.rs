//! The equivariant Tutte map solved by Newton's method: every vertex's lift is the weighted
//! average of its neighbours' lifts seen through the side pairings, in the vertex's own frame.
//!
//! In the Poincaré disk the average is taken after the isometry T_z(q) = (q − z)/(1 − z̄q) that moves
//! the vertex z to the origin, so the condition F_v = Σ_u w_vu T_{z_v}(g_vu(z_u)) / Σ_u w_vu = 0 is
//! nonlinear; on the flat torus T_z(q) = q − z and it is linear (one Newton step solves it). The
//! Jacobian has the mesh's sparsity with 2×2 real blocks (F is holomorphic in the neighbours'
//! lifts, not in z_v: it depends on z̄_v), and is factored by sparse LU; later steps solve it by
//! GMRES with an earlier factorization as the preconditioner (inexact Newton).
//!
//! Why Newton and not sweeps: Gauss–Seidel sweeps converge at a rate that falls with the mesh's size
//! and the genus (genus 16 stopped at its 5000-sweep cap, far from converged, and folded). Newton's
//! iteration converges quadratically near the solution; each step is damped by backtracking on
//! ‖F‖₂ so it never increases the residual, and where no decrease is found a few sweeps move the
//! map first. The result is the same fixed point the sweeps approach.

use faer::prelude::*;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat, Triplet};
use num_complex::Complex64;

use crate::EmbeddingError;
use crate::fit::Lifts;

/// How a solve went.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Convergence {
    /// Newton steps taken.
    pub steps: usize,
    /// Jacobians factored (a step reuses the last one, as GMRES's preconditioner, while GMRES
    /// converges fast with it).
    pub factorizations: usize,
    /// Gauss–Seidel sweeps run: the warm-up before Newton's method, and where a step found no
    /// decrease.
    pub sweeps: usize,
    /// The largest |F_v| at the end (frame units: how far the vertex is from its neighbours'
    /// average, where the vertex sits at the origin).
    pub residual: f64,
    /// Stretch rounds left out because the map, reweighted by them, did not settle
    /// (the map is then the last round that settled).
    pub rounds_dropped: usize,
}

impl Convergence {
    /// This solve followed by `next` (of the same map, after a reweighting).
    pub fn then(self, next: Convergence) -> Convergence {
        Convergence {
            steps: self.steps + next.steps,
            factorizations: self.factorizations + next.factorizations,
            sweeps: self.sweeps + next.sweeps,
            residual: next.residual,
            rounds_dropped: self.rounds_dropped + next.rounds_dropped,
        }
    }
}

/// Newton steps at most per solve; a converging solve takes 2 to 8 (resolution 32, genus 1 to 16).
const MAX_STEPS: usize = 60;
/// Halvings of a step before it counts as failed.
const MAX_HALVINGS: usize = 30;
/// Sweeps run after a failed step.
const RESCUE_SWEEPS: usize = 20;

/// The residual of every vertex in its own frame, less the drift: F_v − c.
fn residuals(lifts: &Lifts, hyperbolic: bool, drift: Complex64) -> Vec<Complex64> {
    (0..lifts.home.len())
        .map(|v| {
            let z = lifts.home[v];
            let (mut sum, mut total) = (Complex64::ZERO, 0.0);
            for &(w, u, g) in &lifts.neighbours[v] {
                sum += to_frame(z, g.apply(lifts.home[u as usize]), hyperbolic) * w;
                total += w;
            }
            sum / total - drift
        })
        .collect()
}

fn to_frame(z: Complex64, q: Complex64, hyperbolic: bool) -> Complex64 {
    if hyperbolic {
        (q - z) / (Complex64::ONE - z.conj() * q)
    } else {
        q - z
    }
}

fn norm2(f: &[Complex64]) -> f64 {
    f.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt()
}

fn max_norm(f: &[Complex64]) -> f64 {
    f.iter().map(|c| c.norm()).fold(0.0, f64::max)
}

/// The real 2×2 block of a map with complex derivatives ∂/∂z = a, ∂/∂z̄ = b, as (row, col) entries:
/// df = a dz + b dz̄ = (a + b) dx + i (a − b) dy.
fn block(a: Complex64, b: Complex64) -> [[f64; 2]; 2] {
    let (s, d) = (a + b, a - b);
    [[s.re, -d.im], [s.im, d.re]]
}

/// The Jacobian of [`residuals`] as triplets over (2v + re/im, 2u + x/y).
///
/// On the flat torus the map is unique only up to translation, and with mean value weights (not
/// symmetric) the equations F_v = 0 have no solution in general: the sweeps' fixed point slides
/// the whole map by the same step c every sweep (F_v = c for all v), and they took that out by
/// holding the base vertex still. Here c is an unknown (column N) and the base vertex is held by
/// an extra row (row N), so the system is square and has that very fixed point as its solution.
fn jacobian(lifts: &Lifts, hyperbolic: bool) -> Vec<Triplet<usize, usize, f64>> {
    let n = lifts.home.len();
    let mut triplets = Vec::new();
    let mut push = |row: usize, col: usize, m: [[f64; 2]; 2]| {
        for (i, line) in m.iter().enumerate() {
            for (j, &x) in line.iter().enumerate() {
                // Zeros too: the pattern must not change between factorizations, which share
                // one symbolic analysis (see `Analysis`).
                triplets.push(Triplet::new(2 * row + i, 2 * col + j, x));
            }
        }
    };
    const IDENTITY: [[f64; 2]; 2] = [[1.0, 0.0], [0.0, 1.0]];
    if !hyperbolic {
        push(n, lifts.base, IDENTITY);
    }
    for v in 0..n {
        let z = lifts.home[v];
        let total: f64 = lifts.neighbours[v].iter().map(|n| n.0).sum();
        let (mut own_a, mut own_b) = (Complex64::ZERO, Complex64::ZERO);
        for &(w, u, g) in &lifts.neighbours[v] {
            let zu = lifts.home[u as usize];
            let q = g.apply(zu);
            let w = w / total;
            let (a, b, dq) = if hyperbolic {
                let d = Complex64::ONE - z.conj() * q;
                let d2 = d * d;
                (
                    -Complex64::ONE / d,
                    (q - z) * q / d2,
                    (1.0 - z.norm_sqr()) / d2 * g.derivative(zu),
                )
            } else {
                (-Complex64::ONE, Complex64::ZERO, Complex64::ONE)
            };
            own_a += a * w;
            own_b += b * w;
            push(v, u as usize, block(dq * w, Complex64::ZERO));
        }
        push(v, v, block(own_a, own_b));
        if !hyperbolic {
            push(v, n, [[-1.0, 0.0], [0.0, -1.0]]);
        }
    }
    triplets
}

/// Moves `lifts` to the fixed point (every vertex within `tolerance` of its neighbours' average,
/// up to the torus's drift), or fails with how far it got.
///
/// A factorization is kept for later steps: with it the Newton step is solved by GMRES,
/// preconditioned by that earlier Jacobian's inverse (see [`krylov_step`]), and it is renewed only
/// where that does not converge in [`KRYLOV_ITERATIONS`] or a step finds no decrease.
pub(crate) fn solve(
    lifts: &mut Lifts,
    hyperbolic: bool,
    tolerance: f64,
    kept: &mut Option<KeptJacobian>,
) -> Result<Convergence, EmbeddingError> {
    let mut drift = Complex64::ZERO;
    let mut f = residuals(lifts, hyperbolic, drift);
    let mut report = Convergence {
        steps: 0,
        factorizations: 0,
        sweeps: 0,
        residual: max_norm(&f),
        rounds_dropped: 0,
    };
    let (mut factor, analysis) = match kept.take() {
        Some(k) if k.analysis.size == system_size(lifts.home.len(), hyperbolic) => {
            (k.lu, k.analysis)
        }
        _ => (None, Analysis::new(pattern(lifts, hyperbolic))?),
    };
    let mut forcing = Forcing::default();
    // The Jacobian at the current map where a GMRES step has assembled it already: a
    // factorization that follows there (GMRES failed, or its step found no decrease and the map
    // went back) takes it instead of assembling it again. Cleared whenever the map moves.
    let mut here: Option<SparseColMat<usize, f64>> = None;
    while report.residual > tolerance {
        let forcing = forcing.next(norm2(&f));
        if report.steps == MAX_STEPS {
            return Err(EmbeddingError::Parameterization(format!(
                "the map did not converge in {MAX_STEPS} Newton steps (largest residual {:.2e})",
                report.residual
            )));
        }
        report.steps += 1;
        let earlier = match factor.take() {
            Some(lu) => {
                let j = here.insert(analysis.jacobian(lifts, hyperbolic)?);
                krylov_step(j, lifts, hyperbolic, &lu, &f, forcing, tolerance)
                    .map(|step| (lu, step))
            }
            None => None,
        };
        let (lu, (step, drift_step), fresh) = match earlier {
            Some((lu, step)) => (lu, step, false),
            None => {
                // Any earlier factorization is dropped by now: two LUs at once would double the
                // map's peak memory.
                report.factorizations += 1;
                let j = match here.take() {
                    Some(j) => j,
                    None => analysis.jacobian(lifts, hyperbolic)?,
                };
                let lu = analysis.factorize(j, lifts.home.len())?;
                let step = newton_step(&lu, lifts.home.len(), hyperbolic, &f)?;
                (lu, step, true)
            }
        };
        let (start, start_drift) = (lifts.home.clone(), drift);
        let before = norm2(&f);
        let mut t = whole_step(&lifts.home, &step, hyperbolic);
        let mut accepted = false;
        for _ in 0..MAX_HALVINGS {
            for ((h, z), d) in lifts.home.iter_mut().zip(&start).zip(&step) {
                *h = advance(*z, d * t, hyperbolic);
            }
            drift = start_drift + drift_step * t;
            let trial = residuals(lifts, hyperbolic, drift);
            if norm2(&trial) < (1.0 - 1e-4 * t) * before {
                f = trial;
                accepted = true;
                break;
            }
            t /= 2.0;
        }
        if accepted {
            factor = Some(lu);
            here = None;
        } else {
            // No decrease along this step: with an earlier Jacobian, factor the current one;
            // with the current one, move the map by a few sweeps first.
            lifts.home = start;
            drift = start_drift;
            if fresh {
                here = None;
                report.sweeps += lifts.relax(hyperbolic, RESCUE_SWEEPS, 0.0);
                f = residuals(lifts, hyperbolic, drift);
            }
        }
        report.residual = max_norm(&f);
    }
    *kept = Some(KeptJacobian {
        lu: factor,
        analysis,
    });
    Ok(report)
}

/// The forcing term η of each Newton step: how far its linear system is solved. Eisenstat and
/// Walker's second choice, safeguarded: loosely while F falls slowly (far from the fixed point,
/// where the linear model is poor anyway), tightly as it falls fast.
struct Forcing {
    eta: f64,
    /// ‖F‖₂ at the step before.
    previous: Option<f64>,
}

impl Default for Forcing {
    fn default() -> Self {
        Forcing {
            eta: FORCING_MAX,
            previous: None,
        }
    }
}

impl Forcing {
    /// η for a step from a map whose ‖F‖₂ is `now`.
    fn next(&mut self, now: f64) -> f64 {
        if let Some(previous) = self.previous {
            let chosen = FORCING_GAMMA * (now / previous).powi(2);
            let kept = FORCING_GAMMA * self.eta * self.eta;
            let eta = if kept > 0.1 { chosen.max(kept) } else { chosen };
            self.eta = eta.clamp(FORCING_MIN, FORCING_MAX);
        }
        self.previous = Some(now);
        self.eta
    }
}

/// The Jacobian's analysis, and its factorization where one was made, kept from one solve for the
/// next (a later round's map, whose weights differ a little): the factorization preconditions
/// GMRES before a fresh one is tried.
pub(crate) struct KeptJacobian {
    lu: Option<Lu<usize, f64>>,
    analysis: Analysis,
}

impl KeptJacobian {
    /// The analysis alone of the Jacobian whose pattern `pattern` holds ([`pattern`]): it depends
    /// on the mesh, not the map, so it can be made while the warm-up sweeps move the map (at
    /// genus 10 it takes 0.35 s of the 0.4 s they take).
    pub(crate) fn analyse(pattern: Pattern) -> Result<KeptJacobian, EmbeddingError> {
        Ok(KeptJacobian {
            lu: None,
            analysis: Analysis::new(pattern)?,
        })
    }
}

/// What the Jacobian's pattern (the mesh's, the same at every map: zeros are kept) fixes: its
/// compressed columns, the order that puts [`jacobian`]'s entries into them (so that each map's
/// matrix is filled, not sorted: sorting 1.3 million triplets took about as long as a GMRES
/// iteration), and the LU's symbolic analysis (COLAMD's fill-reducing ordering, most of all:
/// it had been about a tenth of `ntori new` at resolution 64).
struct Analysis {
    /// The system's size (two rows a vertex, and the torus's drift).
    size: usize,
    shape: SymbolicSparseColMat<usize>,
    order: Argsort<usize>,
    symbolic: SymbolicLu<usize>,
}

impl Analysis {
    fn new(pattern: Pattern) -> Result<Analysis, EmbeddingError> {
        let pairs: Vec<Pair<usize, usize>> = pattern
            .triplets
            .iter()
            .map(|t| Pair::new(t.row, t.col))
            .collect();
        let (shape, order) =
            SymbolicSparseColMat::try_new_from_indices(pattern.size, pattern.size, &pairs)
                .map_err(|e| failed(format!("{e:?}")))?;
        let symbolic = SymbolicLu::try_new(shape.as_ref()).map_err(|e| failed(format!("{e:?}")))?;
        Ok(Analysis {
            size: pattern.size,
            shape,
            order,
            symbolic,
        })
    }

    /// The Jacobian at the map `lifts`.
    fn jacobian(
        &self,
        lifts: &Lifts,
        hyperbolic: bool,
    ) -> Result<SparseColMat<usize, f64>, EmbeddingError> {
        let values: Vec<f64> = jacobian(lifts, hyperbolic).iter().map(|t| t.val).collect();
        SparseColMat::new_from_argsort(self.shape.clone(), &self.order, &values)
            .map_err(|e| failed(format!("{e:?}")))
    }

    /// The sparse LU of `a`, a Jacobian of this pattern ([`Analysis::jacobian`]) of a map of
    /// `vertices` vertices (consumed: the LU is the map's peak of memory).
    fn factorize(
        &self,
        a: SparseColMat<usize, f64>,
        vertices: usize,
    ) -> Result<Lu<usize, f64>, EmbeddingError> {
        let started = std::time::Instant::now();
        let lu = Lu::try_new_with_symbolic(self.symbolic.clone(), a.as_ref())
            .map_err(|e| failed(format!("{e:?}")))?;
        tracing::debug!(
            vertices,
            seconds = started.elapsed().as_secs_f64(),
            "map's Jacobian factored"
        );
        Ok(lu)
    }
}

/// The Jacobian's entries at some map (its pattern is what matters: it is the mesh's), for
/// [`KeptJacobian::analyse`] on another thread.
pub(crate) struct Pattern {
    size: usize,
    triplets: Vec<Triplet<usize, usize, f64>>,
}

/// The Jacobian's pattern at the map `lifts`.
pub(crate) fn pattern(lifts: &Lifts, hyperbolic: bool) -> Pattern {
    Pattern {
        size: system_size(lifts.home.len(), hyperbolic),
        triplets: jacobian(lifts, hyperbolic),
    }
}

/// The Newton system's size for `n` vertices: two real unknowns each, and on the flat torus the
/// drift's two.
fn system_size(n: usize, hyperbolic: bool) -> usize {
    if hyperbolic { 2 * n } else { 2 * n + 2 }
}

/// Vertex z moved by the Newton step d. On the flat torus z + d. In the Poincaré disk the step is
/// taken as a vector at z in z's own frame (T_z has derivative 1/(1 − |z|²) there) and carried back
/// by T_z⁻¹: to first order z + d, the same Newton direction, but along a path on which the
/// residual, itself taken in the vertices' frames, stays close to its linearization, and which
/// never leaves the disk.
///
/// Why: added in a straight line, the steps of the first solve on a 100 000-vertex genus-4 plate
/// raised ‖F‖₂ and were halved to 1/16 and then 1/32 of Newton's step, each shrinking it by half a
/// per cent at the cost of a fresh sparse LU (40 of 3 to 4 s, 166 s for the first round, and still
/// not solved). Carried this way the steps are taken whole: 5 factorizations and 21 s.
fn advance(z: Complex64, d: Complex64, hyperbolic: bool) -> Complex64 {
    if !hyperbolic {
        return z + d;
    }
    let frame = d / (1.0 - z.norm_sqr());
    (frame + z) / (Complex64::ONE + z.conj() * frame)
}

/// The part of the Newton step `step` that the line search starts from: all of it, unless it
/// moves some vertex further than [`MAX_FRAME_STEP`] in its frame; then the whole step is shortened
/// to that (not vertex by vertex, which turns it off Newton's direction: from Floater's map at
/// genus 8 that wandered into a tangled map whose ‖F‖₂ still fell).
fn whole_step(home: &[Complex64], step: &[Complex64], hyperbolic: bool) -> f64 {
    if !hyperbolic {
        return 1.0;
    }
    let longest = home
        .iter()
        .zip(step)
        .map(|(z, d)| d.norm() / (1.0 - z.norm_sqr()))
        .fold(0.0, f64::max);
    if longest > MAX_FRAME_STEP {
        MAX_FRAME_STEP / longest
    } else {
        1.0
    }
}

/// The longest step a vertex takes at once in its own frame (frame units: 1 is the rim), as the
/// sweeps' step cap. From Floater's map 0.25 solved genus 2 to 32; 0.5 failed at genus 16 and 0.9
/// from genus 8.
const MAX_FRAME_STEP: f64 = 0.25;

/// The loosest forcing term η (GMRES stops at ‖J δ + F‖ ≤ η ‖F‖): the first step with an earlier
/// factorization is solved this far.
const FORCING_MAX: f64 = 0.3;
/// The tightest: with less the last steps over-solve (a GMRES iteration per digit) for a
/// residual that the next step's own F sets anyway. Measured on `ntori new`'s map (both rounds),
/// minimum 1e-4 / 1e-3 / 1e-2: genus 10 3.0 / 2.9 / 2.7 s.
const FORCING_MIN: f64 = 1e-2;
/// Eisenstat and Walker's γ: η = γ (‖F_k‖ / ‖F_{k−1}‖)².
const FORCING_GAMMA: f64 = 0.9;

/// GMRES's iterations (each a solve with the earlier factorization and a product with the
/// current Jacobian) before a fresh factorization is cheaper: it costs 20 to 30 solves.
const KRYLOV_ITERATIONS: usize = 12;

fn failed(what: String) -> EmbeddingError {
    EmbeddingError::Parameterization(format!("the map's Newton step failed: {what}"))
}

/// The Newton system's right-hand side −F, two real rows a vertex (and the torus's drift row, 0).
fn negated(f: &[Complex64], size: usize) -> Mat<f64> {
    let mut rhs = Mat::<f64>::zeros(size, 1);
    for (v, c) in f.iter().enumerate() {
        rhs[(2 * v, 0)] = -c.re;
        rhs[(2 * v + 1, 0)] = -c.im;
    }
    rhs
}

/// The solution x of the Newton system as the step (δ, δc), or an error where it is not finite.
fn unpack(
    x: &Mat<f64>,
    n: usize,
    hyperbolic: bool,
) -> Result<(Vec<Complex64>, Complex64), EmbeddingError> {
    let at = |k: usize| Complex64::new(x[(2 * k, 0)], x[(2 * k + 1, 0)]);
    let step: Vec<Complex64> = (0..n).map(at).collect();
    let drift = if hyperbolic { Complex64::ZERO } else { at(n) };
    if step
        .iter()
        .chain([&drift])
        .any(|d| !(d.re.is_finite() && d.im.is_finite()))
    {
        return Err(failed("the Jacobian is singular".into()));
    }
    Ok((step, drift))
}

/// The step (δ, δc) with J (δ, δc) = −F, J factored at the current map.
fn newton_step(
    lu: &Lu<usize, f64>,
    n: usize,
    hyperbolic: bool,
    f: &[Complex64],
) -> Result<(Vec<Complex64>, Complex64), EmbeddingError> {
    unpack(
        &lu.solve(&negated(f, system_size(n, hyperbolic))),
        n,
        hyperbolic,
    )
}

/// The Newton step at the current map (whose Jacobian is `j`) solved by GMRES to the relative residual `forcing` (or to
/// half the map's `tolerance`, whichever is looser), preconditioned by `earlier`: a factored Jacobian of a
/// nearby map (a step before, or the round before). `None` where it does not converge in
/// [`KRYLOV_ITERATIONS`].
///
/// Why: a fresh sparse LU costs 20 to 30 solves with one. Steps taken with the earlier factor
/// alone (chord steps) contract the residual only by ‖I − J_old⁻¹ J‖ each, and where that was
/// over a quarter the old solver factored afresh (genus 10 took three LUs).
/// Preconditioned by the same factor, GMRES gets Newton's step to η in a few iterations: `ntori
/// new`'s map (both rounds) genus 10 2.9 → 2.7 s, genus 32 21.9 → 15.1 s.
fn krylov_step(
    j: &SparseColMat<usize, f64>,
    lifts: &Lifts,
    hyperbolic: bool,
    earlier: &Lu<usize, f64>,
    f: &[Complex64],
    forcing: f64,
    tolerance: f64,
) -> Option<(Vec<Complex64>, Complex64)> {
    let started = std::time::Instant::now();
    let n = lifts.home.len();
    let size = system_size(n, hyperbolic);
    let rhs = negated(f, size);
    let threshold = (forcing * rhs.norm_l2()).max(tolerance / 2.0);
    let solved = gmres(j.as_ref(), earlier, &rhs, threshold, KRYLOV_ITERATIONS);
    tracing::debug!(
        iterations = solved.as_ref().map(|s| s.1),
        forcing,
        seconds = started.elapsed().as_secs_f64(),
        "map's Newton step by GMRES"
    );
    // A step that is not finite is no step: the caller factors the current Jacobian instead (and
    // that one reports a singular Jacobian).
    solved.and_then(|(x, _)| unpack(&x, n, hyperbolic).ok())
}

/// GMRES without restarts, preconditioned on the right by the factored `m`: x with
/// ‖a x − b‖₂ ≤ `threshold` and the iterations it took, or `None` after `iterations`. One solve
/// with `m` and one product with `a` an iteration (faer 0.24 has BiCGSTAB, which takes two of
/// each). Flexible form (the preconditioned directions z_k are kept), so x needs no last solve.
fn gmres(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    m: &Lu<usize, f64>,
    b: &Mat<f64>,
    threshold: f64,
    iterations: usize,
) -> Option<(Mat<f64>, usize)> {
    let beta = b.norm_l2();
    if beta <= threshold {
        return Some((Mat::zeros(b.nrows(), 1), 0));
    }
    let mut basis = vec![b * faer::Scale(1.0 / beta)];
    let mut directions: Vec<Mat<f64>> = Vec::new();
    // The Hessenberg matrix's columns, rotated into an upper triangle as they come (Givens),
    // and the rotated right-hand side β e₁.
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut rotations: Vec<(f64, f64)> = Vec::new();
    let mut g = vec![beta];
    for k in 0..iterations {
        let z = m.solve(&basis[k]);
        let mut w = a * &z;
        directions.push(z);
        let mut h = Vec::with_capacity(k + 2);
        for v in &basis {
            let dot = (v.transpose() * &w)[(0, 0)];
            w -= v * faer::Scale(dot);
            h.push(dot);
        }
        let next = w.norm_l2();
        h.push(next);
        for (i, &(c, s)) in rotations.iter().enumerate() {
            let (x, y) = (h[i], h[i + 1]);
            h[i] = c * x + s * y;
            h[i + 1] = -s * x + c * y;
        }
        let r = h[k].hypot(h[k + 1]);
        if !(r > 0.0 && r.is_finite()) {
            // A breakdown (or a product that is not finite): the caller factors afresh.
            return None;
        }
        let (c, s) = (h[k] / r, h[k + 1] / r);
        h[k] = r;
        h.truncate(k + 1);
        g.push(-s * g[k]);
        g[k] *= c;
        rotations.push((c, s));
        columns.push(h);
        if g[k + 1].abs() <= threshold || next == 0.0 {
            // Back substitution in the triangle, then x = Σ y_k z_k.
            let mut y = vec![0.0; k + 1];
            for i in (0..=k).rev() {
                let tail: f64 = (i + 1..=k).map(|j| columns[j][i] * y[j]).sum();
                y[i] = (g[i] - tail) / columns[i][i];
            }
            let mut x = Mat::<f64>::zeros(b.nrows(), 1);
            for (z, yk) in directions.iter().zip(&y) {
                x += z * faer::Scale(*yk);
            }
            return Some((x, k + 1));
        }
        basis.push(w * faer::Scale(1.0 / next));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::floater_lifts;
    use crate::holed::HoledMesh;
    use charts::{Atlas, Geometry};

    /// The plate of `genus` at `resolution`, its Floater lifts, and whether the model is hyperbolic.
    fn start(genus: u32, resolution: usize) -> (Lifts, bool) {
        let (lifts, hyperbolic, _) = start_with_mesh(genus, resolution);
        (lifts, hyperbolic)
    }

    /// [`start`], and the plate's vertex positions.
    fn start_with_mesh(genus: u32, resolution: usize) -> (Lifts, bool, Vec<crate::Point3>) {
        let atlas = Atlas::new(genus).unwrap();
        let polygon = atlas.polygon().unwrap();
        let mesh = HoledMesh::new(genus, resolution).unwrap();
        let (_, _, lifts) = floater_lifts(polygon, &mesh).unwrap();
        (
            lifts,
            polygon.geometry() == Geometry::Hyperbolic,
            mesh.positions,
        )
    }

    /// The largest distance between two maps' lifts of a vertex, in frame units of the first.
    fn frame_gap(a: &Lifts, b: &Lifts) -> f64 {
        a.home
            .iter()
            .zip(&b.home)
            .map(|(a, b)| (a - b).norm() / (1.0 - a.norm_sqr()))
            .fold(0.0, f64::max)
    }

    /// A stretch round whose map does not settle is dropped with the rounds after it: the map
    /// is the first round's fixed point, settled to the final tolerance, its weights not
    /// reweighted, the same map as with no stretch rounds at all, and the report says how many
    /// rounds went. Any other error still fails the map.
    #[test]
    fn a_stretch_round_that_does_not_settle_leaves_the_round_before() {
        let (original, hyperbolic, positions) = start_with_mesh(3, 8);
        let (mut plain, _) = start(3, 8);
        let none = plain
            .settle_rounds(&positions, hyperbolic, 0, &|_| {})
            .unwrap();
        assert_eq!(none.rounds_dropped, 0);
        for failing in [2, 3] {
            let (mut lifts, _) = start(3, 8);
            let mut calls = 0;
            let solved = lifts
                .settle_rounds_by(
                    &positions,
                    hyperbolic,
                    2,
                    &|_| {},
                    &mut |l, tolerance, kept| {
                        calls += 1;
                        if calls == failing {
                            return Err(EmbeddingError::Parameterization("did not settle".into()));
                        }
                        l.settle(hyperbolic, tolerance, kept)
                    },
                )
                .unwrap();
            assert_eq!(solved.rounds_dropped, 4 - failing, "round {failing} failed");
            assert!(solved.residual <= crate::fit::RELAX_TOLERANCE);
            let reweighted = lifts
                .neighbours
                .iter()
                .zip(&original.neighbours)
                .any(|(a, b)| a.iter().zip(b).any(|(x, y)| x.0 != y.0));
            assert_eq!(reweighted, failing == 3, "round {failing} failed");
            if failing == 2 {
                assert!(
                    frame_gap(&lifts, &plain) < 1e-6,
                    "{}",
                    frame_gap(&lifts, &plain)
                );
            }
        }
        let (mut lifts, _) = start(3, 8);
        let other = lifts.settle_rounds_by(&positions, hyperbolic, 2, &|_| {}, &mut |_, _, _| {
            Err(EmbeddingError::NotAModel("not a map error".into()))
        });
        assert!(other.is_err());
    }

    /// Reproducible numbers in [−1, 1) from `seed` (SplitMix64), without a generator crate.
    fn uniform_numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut x = state;
            x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            (x ^ (x >> 31)) as f64 / u64::MAX as f64 * 2.0 - 1.0
        }
    }

    fn copy(lifts: &Lifts) -> Lifts {
        Lifts::from_parts(
            lifts.home.clone(),
            lifts.neighbours.clone(),
            lifts.corners.clone(),
            lifts.base,
        )
    }

    /// GMRES preconditioned by the LU of a perturbed matrix solves random sparse nonsymmetric
    /// systems (a mesh-like band with 2×2-block couplings) to its threshold, measured on the true
    /// residual; with too few iterations it says so rather than return a poor x.
    #[test]
    fn gmres_solves_to_its_threshold_with_a_nearby_factorization() {
        let mut uniform = uniform_numbers(7);
        for case in 0..20 {
            let n = 200 + 37 * case;
            let (mut exact, mut nearby) = (Vec::new(), Vec::new());
            for i in 0..n {
                let mut off = 0.0;
                for k in [1, 2, 17] {
                    for j in [(i + k) % n, (i + n - k) % n] {
                        let v = uniform();
                        off += v.abs();
                        exact.push(Triplet::new(i, j, v));
                        nearby.push(Triplet::new(i, j, v * (1.0 + 0.3 * uniform())));
                    }
                }
                let d = off * (1.05 + 0.5 * uniform().abs());
                exact.push(Triplet::new(i, i, d));
                nearby.push(Triplet::new(i, i, d * (1.0 + 0.1 * uniform())));
            }
            let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &exact).unwrap();
            let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &nearby).unwrap();
            let lu = m.sp_lu().unwrap();
            let b = Mat::<f64>::from_fn(n, 1, |_, _| uniform());
            let threshold = 1e-8 * b.norm_l2();
            let (x, iterations) = gmres(a.as_ref(), &lu, &b, threshold, 60)
                .unwrap_or_else(|| panic!("case {case}: no convergence in 60"));
            let residual = (&b - &a * &x).norm_l2();
            assert!(
                residual <= 1.01 * threshold,
                "case {case}: |b − A x| = {residual:e} against {threshold:e} ({iterations} iterations)"
            );
            assert!(iterations > 1, "case {case}: the perturbation did nothing");
            assert!(
                gmres(a.as_ref(), &lu, &b, threshold, 1).is_none(),
                "case {case}: one iteration claimed 1e-8"
            );
            // A breakdown (here a zero matrix: no direction reduces the residual) is a failure to
            // converge, not a step of NaNs.
            let zero = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &[]).unwrap();
            assert!(
                gmres(zero.as_ref(), &lu, &b, threshold, 5).is_none(),
                "case {case}"
            );
        }
    }

    /// J·e against central differences of F along random directions e, at Floater's map (far from
    /// the fixed point) for the torus and genus 2 to 5.
    #[test]
    fn the_jacobian_is_the_residual_s_derivative() {
        let mut uniform = uniform_numbers(12);
        for genus in 1..=5 {
            let (mut lifts, hyperbolic) = start(genus, 8);
            let n = lifts.home.len();
            let size = system_size(n, hyperbolic);
            let a = SparseColMat::<usize, f64>::try_new_from_triplets(
                size,
                size,
                &jacobian(&lifts, hyperbolic),
            )
            .unwrap();
            for _ in 0..4 {
                let dir: Vec<Complex64> = (0..n)
                    .map(|v| {
                        let scale = 1.0 - lifts.home[v].norm_sqr();
                        let e = Complex64::new(uniform(), uniform());
                        if !hyperbolic && v == lifts.base {
                            Complex64::ZERO
                        } else {
                            e * scale
                        }
                    })
                    .collect();
                let h = 1e-6;
                let home = lifts.home.clone();
                let at = |lifts: &mut Lifts, t: f64| {
                    for ((z, z0), d) in lifts.home.iter_mut().zip(&home).zip(&dir) {
                        *z = z0 + d * t;
                    }
                    residuals(lifts, hyperbolic, Complex64::ZERO)
                };
                let (plus, minus) = (at(&mut lifts, h), at(&mut lifts, -h));
                lifts.home = home.clone();
                let mut e = Mat::<f64>::zeros(size, 1);
                for (v, d) in dir.iter().enumerate() {
                    e[(2 * v, 0)] = d.re;
                    e[(2 * v + 1, 0)] = d.im;
                }
                let je = &a * &e;
                let mut worst = 0.0f64;
                let mut size = 0.0f64;
                for v in 0..n {
                    let fd = (plus[v] - minus[v]) / (2.0 * h);
                    let an = Complex64::new(je[(2 * v, 0)], je[(2 * v + 1, 0)]);
                    worst = worst.max((fd - an).norm());
                    size = size.max(an.norm());
                }
                assert!(
                    size > 1e-3,
                    "genus {genus}: a direction that changes nothing"
                );
                assert!(
                    worst < 1e-6 * size,
                    "genus {genus}: |J e − ΔF/Δt| = {worst:e} of {size:e}"
                );
            }
        }
    }

    /// From Floater's map, Newton's method reaches the fixed point in a handful of steps at every
    /// genus tried (at this resolution, 1 to 7 factorizations and up to 13 steps), and it is the
    /// fixed point the sweeps approach.
    #[test]
    fn newton_reaches_the_sweeps_fixed_point() {
        for genus in [1, 2, 3, 6] {
            let (mut lifts, hyperbolic) = start(genus, 8);
            let mut swept = copy(&lifts);
            let solved = solve(&mut lifts, hyperbolic, 1e-12, &mut None).unwrap();
            assert!(solved.residual <= 1e-12);
            // Steps with a kept factorization are cheap; the factorizations are the cost.
            assert!(
                solved.steps <= 16 && solved.factorizations <= 8,
                "genus {genus}: {solved:?}"
            );
            swept.relax(hyperbolic, 200_000, 1e-13);
            let gap = frame_gap(&lifts, &swept);
            // On the torus the sweeps slide the map along as they go (see `jacobian`), and a
            // Gauss–Seidel sweep sees half of its neighbours already slid: their fixed point is
            // off from "F_v = c for every v" by about the slide, ~1e-5 here.
            let bound = if hyperbolic { 1e-9 } else { 1e-4 };
            assert!(
                gap < bound,
                "genus {genus}: Newton and the sweeps differ by {gap:e}"
            );
            assert_eq!(lifts.folded_triangles(hyperbolic), 0, "genus {genus}");
        }
    }

    /// A vertex carried by [`advance`] stays in the disk however long its step, and to first
    /// order moves by the step: |advance(z, d) − (z + d)| ≤ 2|d|²/(1 − |z|²) while d is at most
    /// half a frame unit (d·z̄f/(1 + z̄f) with f = d/(1 − |z|²)).
    #[test]
    fn advanced_vertices_stay_in_the_disk_and_move_by_the_step_to_first_order() {
        use proptest::prelude::*;
        let config = ProptestConfig {
            cases: 2000,
            ..ProptestConfig::default()
        };
        proptest!(config, |(
            radius in 0.0f64..0.999_999,
            angle in 0.0f64..std::f64::consts::TAU,
            frame in 0.0f64..0.999,
            direction in 0.0f64..std::f64::consts::TAU,
        )| {
            let z = Complex64::from_polar(radius, angle);
            let room = 1.0 - z.norm_sqr();
            let d = Complex64::from_polar(frame * room, direction);
            let moved = advance(z, d, true);
            prop_assert!(moved.norm() < 1.0, "{z} + {d} went to {moved}");
            if frame <= 0.5 {
                let off = (moved - (z + d)).norm();
                prop_assert!(off <= 2.0 * d.norm_sqr() / room * (1.0 + 1e-9) + 1e-15,
                    "{z} + {d}: {moved} is {off:e} off");
            }
            prop_assert_eq!(advance(z, d, false), z + d);
        });
    }

    /// From Floater's map, far from the fixed point, a genus-16 plate is solved in a few whole
    /// steps. (With the steps added in a straight line it took 52 steps and 48 factorizations, and
    /// genus 24 at resolution 8 did not converge in 60.)
    #[test]
    fn newton_takes_whole_steps_from_floater_s_map_at_genus_16() {
        let (mut lifts, hyperbolic) = start(16, 10);
        let solved = solve(&mut lifts, hyperbolic, 1e-10, &mut None).unwrap();
        assert!(solved.residual <= 1e-10, "{solved:?}");
        assert!(solved.factorizations <= 15, "{solved:?}");
        assert_eq!(lifts.folded_triangles(hyperbolic), 0);
    }

    /// A second round (the map reweighted by its stretch, as `ntori new` and `ntori fit` do) that
    /// starts from the first round's kept Jacobian reaches the fixed point that a fresh solve
    /// reaches, with fewer factorizations.
    #[test]
    fn a_kept_jacobian_takes_the_next_round_to_the_same_fixed_point() {
        for (genus, resolution) in [(1, 12), (2, 12), (5, 10), (12, 8)] {
            let (mut lifts, hyperbolic, positions) = start_with_mesh(genus, resolution);
            let mut kept = None;
            solve(&mut lifts, hyperbolic, 1e-10, &mut kept).unwrap();
            assert!(kept.is_some(), "genus {genus}: nothing kept");
            let stretch = lifts.stretch(&positions, hyperbolic);
            lifts.reweight(&stretch);
            let mut fresh = copy(&lifts);
            let warm = solve(&mut lifts, hyperbolic, 1e-10, &mut kept).unwrap();
            let cold = solve(&mut fresh, hyperbolic, 1e-10, &mut None).unwrap();
            assert!(warm.residual <= 1e-10, "genus {genus}: {warm:?}");
            assert!(
                warm.factorizations < cold.factorizations,
                "genus {genus}: kept {warm:?}, fresh {cold:?}"
            );
            let gap = frame_gap(&lifts, &fresh);
            let bound = if hyperbolic { 1e-8 } else { 1e-6 };
            assert!(gap < bound, "genus {genus}: the two differ by {gap:e}");
        }
    }
}
