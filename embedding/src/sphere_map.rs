//! A genus-0 mesh mapped onto the unit sphere: the sphere's counterpart of the equivariant Tutte map
//! that [`crate::mesh_fit`] builds for genus ≥ 1.
//!
//! 1. One triangle is taken out and the rest, a disk, is flattened by Floater's mean value map with
//!    the triangle's corners pinned to an equilateral triangle: a bijection onto the triangle's
//!    inside (Floater's theorem). Inverse stereographic projection puts it on the sphere with the
//!    removed triangle round the north pole, after a scale that puts half the surface's area on
//!    either hemisphere. It is close to conformal except round the removed triangle, whose
//!    neighbours the pins stretch along the equilateral triangle's sides.
//! 2. So the map is made again, twice, punctured elsewhere: the triangle furthest round the sphere
//!    from the last puncture is taken out, the sphere is projected stereographically from its
//!    centre, its corners are pinned where that projection puts them, and the rest is solved as a
//!    Tutte map again (a bijection in the plane, harmonic in the mean value sense except at the new
//!    puncture). Back on the sphere, a puncture's neighbours can still span so much of it that their
//!    chords turn over, so of the three maps the one with fewest such triangles goes on, turned so
//!    the first removed triangle is at the north pole again (the two caps' seam is the equator).
//! 3. Harmonic maps of the sphere are conformal, and the conformal maps of the sphere form a
//!    six-dimensional (Möbius) family: after every solve or sweep a Möbius transformation of the
//!    ball brings the centre of the surface's area back to the centre of the sphere (Möbius
//!    centering).
//! 4. Relaxation on the closed sphere: every vertex moves to the mean value average of its
//!    neighbours, taken in its own conformal frame (stereographic projection from its antipode onto
//!    its tangent plane), in rounds of the plates' stretch reweighting (Yoshizawa, Belyaev and
//!    Seidel), which evens the area out. A round that leaves more folded triangles than it found is
//!    dropped, and the rounds stop there.
//! 5. Where the map is still uneven after them (areas ×4 and more on average: a long limb stays
//!    squeezed, its rounds dropped), the conformal map of step 2 is evened out in the plane
//!    instead ([`even_out`]): rounds of the same reweighting, each solved as a Tutte map punctured
//!    at one fixed triangle, which is a bijection in the plane whatever the weights; the few thin
//!    triangles whose images on the sphere turn over are opened out locally ([`untangle`]). The
//!    more even of the two maps goes on. On the animal that took the mean from ×55 to ×1.7; on a
//!    body with two long arms, which the sweeps even out to ×1.06, the planar rounds reach only ×4.3
//!    (their pins hold the puncture's neighbours), so they are the fallback, not the rule.
//! 6. Either way a long limb stays squeezed: the bunny's ears ×260 in area at worst after step 5.
//!    A density-equalizing flow ([`equalize_areas`]) spreads them: rounds of heat-smoothed log area
//!    ratio, every vertex moved down its gradient, each round kept free of folds and of needles.
//!    On the bunny it took the largest ratio to ×20, and the fit's distance from the mesh from
//!    3.9% to 1.05% of the diagonal.
//! 7. All that can leave a limb squeezed, or sheared, or a triangle folded. A rival is made
//!    without the conformal map: coarse to fine, from a tetrahedron, each vertex put back inside
//!    its hole and the whole kept at low symmetric Dirichlet energy ([`progressive`]), then
//!    evened out by the same flow. Where the conformal path's map folds, the rival replaces it;
//!    elsewhere `mesh_fit` fits through the conformal path's map first, and where that fit fails
//!    what it measures or is more than 0.5% of the diagonal off, builds the rival, fits through
//!    it too and keeps the map whose fit is smooth enough, where only one is, else the one that
//!    comes closer to the mesh's vertices. On pymeshlab's cow the
//!    conformal path left its tail's tip ×2·10⁸ and its fit 10.9% of the diagonal off at worst;
//!    built coarse to fine its worst triangle is ×16 and its fit 1.2% off.
//! 8. The map is turned so the caps' seam runs through the parts that stay squeezed, where each
//!    cap's grid is densest ([`seam_through_squeezed`]).
//!
//! Why 2 and the dropped rounds: on real genus-0 meshes (a cow of 2 904 vertices, a bone of 1 513,
//! an airplane of 5 400) and on `tests/shapes`' animal, the conformal map squeezes long limbs to
//! specks, where the sweeps crawl; started from step 1 alone they ran 5 000 sweeps a round without
//! converging and left hundreds of folded triangles. The Tutte maps cannot fold in the plane.

use nalgebra::Vector3;

use crate::EmbeddingError;
use num_complex::Complex64;

use crate::fit::{Distortion, relative_stretch, stretch_divisor, triangle_distortion};
use crate::floater;
use crate::surface::Point3;
use faer::prelude::*;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, Triplet};

mod progressive;

/// Each vertex's neighbours with their weights, (weight, neighbour), as the sweeps take them.
type Neighbours = Vec<Vec<(f64, u32)>>;

/// `weights` ((neighbour, weight) per vertex, as [`floater::mean_value_weights`] gives them) in
/// the sweeps' order.
fn neighbours_of(weights: &[Vec<(u32, f64)>]) -> Neighbours {
    weights
        .iter()
        .map(|list| list.iter().map(|&(u, w)| (w, u)).collect())
        .collect()
}

/// Every vertex of a genus-0 mesh on the unit sphere.
#[derive(Clone, Debug)]
pub(crate) struct SphereMap {
    /// One unit vector per mesh vertex.
    pub points: Vec<Vector3<f64>>,
    /// Triangles that are not counter-clockwise seen from outside the sphere (0 for a bijection).
    pub folded: usize,
    /// Relaxation sweeps run in all rounds.
    pub sweeps: usize,
    /// Rounds of [`even_out`] whose map was taken (0: the sweeps' map was kept).
    pub planar_rounds: usize,
    /// Whether the map was built coarse to fine ([`progressive`]) rather than from the conformal
    /// map.
    pub coarse_to_fine: bool,
    /// The round of [`equalize_areas`] whose map was taken (0: none).
    pub equalizing_rounds: usize,
    /// How far from conformal and from area-preserving the map is.
    pub distortion: Option<Distortion>,
}

/// Rounds of stretch reweighting the sphere takes beyond what the settings ask of the polygon's maps:
/// the sphere's conformal map squeezes the ends of a long shape far more than the polygon's maps
/// squeeze a plate (an ellipsoid 2.8 : 1 with lobes fitted to 1.5% of its diagonal with one round,
/// within 1% with three).
pub(crate) const EXTRA_ROUNDS: usize = 2;

/// How a map is relaxed on the sphere where it is ([`swept`]): at most `sweeps` sweeps a round,
/// each round ending once no vertex moves by `tolerance` in a sweep, over `stretch_rounds` +
/// [`EXTRA_ROUNDS`] rounds of stretch reweighting after the first.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Relaxation {
    pub sweeps: usize,
    pub stretch_rounds: usize,
    pub tolerance: f64,
}

/// The map of a genus-0 mesh onto the sphere, evened out in the plane or relaxed there with
/// `relaxation`, and its rival, to be built coarse to fine when asked. `areas` are the
/// mesh's vertex areas (the mass that is centred).
pub(crate) fn sphere_map(
    positions: &[Point3],
    triangles: &[[u32; 3]],
    areas: &[f64],
    relaxation: Relaxation,
) -> Result<SphereMaps, EmbeddingError> {
    let weights = floater::mean_value_weights(positions, triangles)?;
    let removed = largest_triangle(positions, triangles)?;
    let first = initial_map(triangles, areas, &weights, removed)?;
    // Re-punctured twice, far from the last puncture each time. Each is a bijection in the plane,
    // but on the sphere a puncture's neighbours can span so much of it that their chords turn over
    // once the area is centred; of the three maps, the one with fewest such triangles goes on (the
    // later one on a tie: its pins come from a map without the equilateral pins' stretch).
    let mut best = (folded_triangles(&first, triangles), first);
    let (mut points, mut puncture) = (best.1.clone(), removed);
    for _ in 0..2 {
        puncture = furthest(&points, triangles, puncture);
        points = punctured_map(&points, &weights, triangles[puncture])?;
        centre(&mut points, areas);
        let folded = folded_triangles(&points, triangles);
        if folded <= best.0 {
            best = (folded, points.clone());
        }
    }
    let mut points = best.1;
    // The caps' seam runs round the equator: turn the largest triangle back to the north pole, where
    // the first map put it, so the seam falls where it did before the re-punctured solves.
    let north = nalgebra::Rotation3::rotation_between(
        &centroid(&points, &triangles[removed]),
        &Vector3::z(),
    )
    .unwrap_or_else(nalgebra::Rotation3::identity);
    points.iter_mut().for_each(|p| *p = north * *p);
    // A long limb squeezed by the conformal map (areas ×4 and more on average) is evened out in
    // the plane, where no round can fold; on the sphere the sweeps crawl into the limb and fold it.
    // The sweeps are not run there: on every mesh measured whose map was evened out, the evened
    // map was kept (the bunny, the bone, the airplane, the cow, the animal of the tests), and the
    // bone's, the airplane's and the cow's first round of sweeps had folded and been dropped
    // after 5 000 sweeps (the bunny: 10 000 sweeps, 35 of its fit's 50 s, for a map then dropped).
    let mut evened_out = points.clone();
    let (evened, evened_weights) =
        even_out(&mut evened_out, &weights, positions, triangles, areas)?;
    let (mut points, neighbours, folded, used) = if evened > 0 {
        (evened_out, evened_weights, 0, 0)
    } else {
        swept(points, &weights, positions, triangles, areas, relaxation)
    };
    let mut distortion = distortion(&points, positions, triangles);
    // Conformal or evened out, a long limb stays squeezed (the bunny's ears ×260 in area): the
    // flow spreads it, where the map is a bijection to start from. Its sweeps use the weights the
    // map was last solved with, so they hold the map's shape rather than pull it back to the
    // conformal map (on the thin-legged animal, with the plain mean value weights, the mean area
    // ratio rose from ×2.7 to ×3.6 while the largest fell).
    let mut equalized = 0;
    if folded == 0 {
        equalized = equalize_areas(&mut points, &neighbours, positions, triangles, areas);
        if equalized > 0 {
            distortion = self::distortion(&points, positions, triangles);
        }
    }
    // The conformal map squeezes a long limb exponentially in its length over its girth, and the
    // rounds above leave it squeezed (the cow's tail ×2·10⁸) or sheared (the bone's ends); a map
    // built coarse to fine never passes through that squeeze. Where this one folds, that one
    // replaces it at once; elsewhere it is its rival, built only where the fit through this map
    // asks for it (`mesh_fit::mesh_model`), as it costs about as much as this map on a large mesh.
    let built = (folded > 0)
        .then(|| built_coarse_to_fine(positions, triangles, areas, &weights))
        .flatten();
    seam_through_squeezed(&mut points, triangles, areas);
    let conformal = SphereMap {
        distortion,
        points,
        folded,
        sweeps: used,
        planar_rounds: evened,
        coarse_to_fine: false,
        equalizing_rounds: equalized,
    };
    Ok(match built {
        Some(built) => SphereMaps {
            map: built,
            rival: None,
        },
        None => SphereMaps {
            map: conformal,
            rival: (folded == 0).then_some(Rival { weights }),
        },
    })
}

/// The maps of a genus-0 mesh onto the sphere ([`sphere_map`]): the one from its conformal map
/// (or built coarse to fine, where the conformal path's folds) and, where it is the conformal
/// path's, its rival, to be built coarse to fine when asked.
#[derive(Clone, Debug)]
pub(crate) struct SphereMaps {
    pub map: SphereMap,
    pub rival: Option<Rival>,
}

/// The conformal path's map's rival, not yet built: [`Rival::build`] costs about as much as the
/// conformal path on a large mesh, so it is built only where the fit through that path's map asks
/// for it.
#[derive(Clone, Debug)]
pub(crate) struct Rival {
    /// The mesh's mean value weights.
    weights: Vec<Vec<(u32, f64)>>,
}

impl Rival {
    /// The map built coarse to fine for the mesh [`sphere_map`] was given; None where it cannot
    /// be built.
    pub fn build(
        &self,
        positions: &[Point3],
        triangles: &[[u32; 3]],
        areas: &[f64],
    ) -> Option<SphereMap> {
        built_coarse_to_fine(positions, triangles, areas, &self.weights)
    }
}

/// The mesh mapped coarse to fine ([`progressive::progressive_map`]), evened out by
/// [`equalize_areas`] (with the mean value weights holding the triangles' shapes) and turned so
/// the caps' seam runs through what stays squeezed; None where it cannot be built.
fn built_coarse_to_fine(
    positions: &[Point3],
    triangles: &[[u32; 3]],
    areas: &[f64],
    weights: &[Vec<(u32, f64)>],
) -> Option<SphereMap> {
    let mut points = progressive::progressive_map(positions, triangles)?;
    let neighbours = neighbours_of(weights);
    let rounds = equalize_areas(&mut points, &neighbours, positions, triangles, areas);
    let distortion = distortion(&points, positions, triangles);
    tracing::debug!(
        "coarse to fine: areas ×{:.3e} at worst after {rounds} equalizing rounds",
        distortion.as_ref().map_or(f64::NAN, |d| d.area_max),
    );
    seam_through_squeezed(&mut points, triangles, areas);
    Some(SphereMap {
        folded: folded_triangles(&points, triangles),
        points,
        sweeps: 0,
        planar_rounds: 0,
        coarse_to_fine: true,
        equalizing_rounds: rounds,
        distortion,
    })
}

/// The map relaxed on the sphere: rounds of mean value sweeps ([`Relaxation`]), the weights
/// divided by the map's stretch from the second round on, each round kept only if it folds no
/// more triangles than the map it started from. Returns the map, the weights it was last solved
/// with, its folded triangles and the sweeps run.
fn swept(
    mut points: Vec<Vector3<f64>>,
    weights: &[Vec<(u32, f64)>],
    positions: &[Point3],
    triangles: &[[u32; 3]],
    areas: &[f64],
    relaxation: Relaxation,
) -> (Vec<Vector3<f64>>, Neighbours, usize, usize) {
    let Relaxation {
        sweeps,
        stretch_rounds,
        tolerance,
    } = relaxation;
    let mut neighbours = neighbours_of(weights);
    let mut folded = folded_triangles(&points, triangles);
    let mut used = 0;
    for round in 0..=stretch_rounds + EXTRA_ROUNDS {
        let mut trial_weights = neighbours.clone();
        if round > 0 {
            let stretch = stretch(&points, positions, triangles);
            for list in &mut trial_weights {
                for (w, u) in list.iter_mut() {
                    *w /= stretch_divisor(stretch[*u as usize]);
                }
            }
        }
        let mut trial = points.clone();
        used += relax(&mut trial, &trial_weights, areas, sweeps, tolerance);
        let trial_folded = folded_triangles(&trial, triangles);
        if trial_folded > folded {
            // The sweeps crawl where the map squeezes a long limb and can leave it folded: keep
            // the last bijective map rather than trade it for an even one.
            break;
        }
        (points, neighbours, folded) = (trial, trial_weights, trial_folded);
    }
    (points, neighbours, folded, used)
}

/// Most rounds of [`equalize_areas`]' flow. The Stanford bunny's ears (pymeshlab's sample of
/// 28 088 vertices: ×260 in area after the sweeps and the planar rounds) are at their most even
/// after about 75. A round costs one sparse Cholesky factorisation of the sphere's Laplacian
/// (0.07 s at 28 000 vertices).
const EQUALIZE_ROUNDS: usize = 150;

/// Rounds without a more even map after which [`equalize_areas`] stops.
const EQUALIZE_PATIENCE: usize = 20;

/// Each round's implicit heat step, as a fraction of the surface's area: the log area ratio is
/// smoothed over about √(0.04 A), a fifth of the surface's size, so the flow moves whole limbs
/// rather than single triangles.
const DIFFUSION_TIME: f64 = 0.04;

/// The largest strain a round's step gives an edge: the difference of its ends' motions over its
/// length.
const MAX_STRAIN: f64 = 0.1;

/// After each round every vertex takes this fraction of its step to its neighbours' weighted mean,
/// with the weights the map was last solved with (one Gauss–Seidel sweep). The flow governs area
/// only: without the sweep, thin triangles sheared into needles within a few rounds (the bunny:
/// the largest σ₁/σ₂ from 32 to 500 in 10 rounds); with it the same map reached areas ×20 at
/// worst with σ₁/σ₂ at most 77.
const SHEAR_DAMPING: f64 = 0.3;

/// The largest σ₁/σ₂ of a map [`equalize_areas`] keeps (or the map's own at the start, if larger);
/// the flow stops at twice this.
const EQUALIZE_ANGLE_BOUND: f64 = 80.0;

/// The log area ratios are clamped to ±this, so a triangle squeezed to nothing does not swamp the
/// field.
const MAX_LOG_RATIO: f64 = 12.0;

/// How many times a round's step is halved to avoid folding a triangle before the flow stops.
const STEP_HALVINGS: usize = 12;

/// Evens out the map's area by a density-equalizing flow on the sphere (after Choi and Rycroft's
/// density-equalizing maps, here with the density measured anew each round). Each vertex's log
/// area ratio (its triangles' area on the surface over their chord triangles' on the sphere,
/// relative to the whole) is smoothed by one implicit heat step ([`diffused_log_ratio`]), every
/// vertex moves down the smoothed field's gradient scaled to its own size ([`flow_velocity`],
/// [`take_step`]), and a damped sweep with `neighbours` (the weights the map was last solved with)
/// keeps the triangles' shapes ([`SHEAR_DAMPING`]).
/// Squeezed parts spread, and the stretched parts round them give them room. Of the maps made, the
/// one with the smallest largest area ratio whose σ₁/σ₂ stays within [`EQUALIZE_ANGLE_BOUND`] is
/// kept: returns its round (0: `points` unchanged). `areas` are the mesh's vertex areas
/// ([`crate::fit::vertex_areas`]). `points` must fold no triangle; no round folds one.
fn equalize_areas(
    points: &mut [Vector3<f64>],
    neighbours: &[Vec<(f64, u32)>],
    positions: &[Point3],
    triangles: &[[u32; 3]],
    areas: &[f64],
) -> usize {
    let Some(start) = distortion(points, positions, triangles) else {
        return 0;
    };
    let mut analysis = None;
    let angle_bound = EQUALIZE_ANGLE_BOUND.max(start.angle_max);
    let mut best = (start.area_max, points.to_vec(), 0);
    for round in 1..=EQUALIZE_ROUNDS {
        // The flow only improves a map that is already a bijection: where its system cannot be
        // solved (a vertex whose triangles have no area on the surface) it stops, keeping the best.
        let Ok(field) = diffused_log_ratio(points, triangles, areas, &mut analysis) else {
            break;
        };
        if !field.iter().all(|g| g.is_finite()) {
            break;
        }
        let velocity = flow_velocity(points, triangles, &field);
        if !take_step(points, triangles, &velocity) {
            break;
        }
        damp_shear(points, neighbours, triangles);
        let Some(now) = distortion(points, positions, triangles) else {
            break;
        };
        tracing::debug!(
            "equalizing round {round}: areas ×{:.2} mean, ×{:.1} max; σ₁/σ₂ {:.2} mean, {:.1} max",
            now.area_mean,
            now.area_max,
            now.angle_mean,
            now.angle_max
        );
        if now.angle_max > 2.0 * angle_bound {
            break;
        }
        if now.angle_max <= angle_bound && now.area_max < best.0 {
            best = (now.area_max, points.to_vec(), round);
        } else if round - best.2 >= EQUALIZE_PATIENCE {
            break;
        }
    }
    points.copy_from_slice(&best.1);
    best.2
}

/// Per vertex, a third of its triangles' chord areas on the sphere: the map's counterpart of the
/// mesh's vertex areas ([`crate::fit::vertex_areas`]).
fn chord_areas(points: &[Vector3<f64>], triangles: &[[u32; 3]]) -> Vec<f64> {
    let mut areas = vec![0.0; points.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| points[v as usize]);
        let third = (b - a).cross(&(c - a)).norm() / 6.0;
        t.iter().for_each(|&v| areas[v as usize] += third);
    }
    areas
}

/// Each vertex's log area ratio (surface over sphere, relative to the whole), smoothed by one
/// implicit heat step of [`DIFFUSION_TIME`]: (M + τL) g = M f with M the surface's vertex areas and L
/// the sphere's cotangent Laplacian (negative cotangents dropped, so the system stays positive
/// definite). The Dirichlet energy is conformally invariant, so this is heat flow on the surface
/// itself as far as the map is conformal, and a squeezed limb is smoothed over its own size.
fn diffused_log_ratio(
    points: &[Vector3<f64>],
    triangles: &[[u32; 3]],
    surface_mass: &[f64],
    analysis: &mut Option<SymbolicLlt<usize>>,
) -> Result<Vec<f64>, EmbeddingError> {
    let n = points.len();
    let sphere_mass = chord_areas(points, triangles);
    let surface_total: f64 = surface_mass.iter().sum();
    let sphere_total: f64 = sphere_mass.iter().sum();
    let time = DIFFUSION_TIME * surface_total;
    let mut triplets: Vec<Triplet<usize, usize, f64>> = (0..n)
        .map(|v| Triplet::new(v, v, surface_mass[v]))
        .collect();
    for t in triangles {
        for k in 0..3 {
            let [i, j, o] = [t[k], t[(k + 1) % 3], t[(k + 2) % 3]].map(|v| v as usize);
            let (a, b) = (points[i] - points[o], points[j] - points[o]);
            let cot = a.dot(&b) / a.cross(&b).norm().max(f64::MIN_POSITIVE);
            let w = time * 0.5 * cot.max(0.0);
            triplets.extend([
                Triplet::new(i, j, -w),
                Triplet::new(j, i, -w),
                Triplet::new(i, i, w),
                Triplet::new(j, j, w),
            ]);
        }
    }
    let failed = |e: String| EmbeddingError::Parameterization(format!("equalizing areas: {e}"));
    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| failed(format!("{e:?}")))?;
    // Every round's matrix has the same pattern (the mesh's edges, zero weights included), so its
    // ordering and symbolic factorisation are made once.
    let symbolic = match analysis {
        Some(symbolic) => symbolic.clone(),
        None => analysis
            .insert(
                SymbolicLlt::try_new(matrix.symbolic(), faer::Side::Lower)
                    .map_err(|e| failed(format!("{e:?}")))?,
            )
            .clone(),
    };
    let factor = Llt::try_new_with_symbolic(symbolic, matrix.as_ref(), faer::Side::Lower)
        .map_err(|e| failed(format!("{e:?}")))?;
    let rhs = Mat::<f64>::from_fn(n, 1, |v, _| {
        let ratio = (surface_mass[v] / surface_total)
            / (sphere_mass[v] / sphere_total).max(f64::MIN_POSITIVE);
        surface_mass[v] * ratio.ln().clamp(-MAX_LOG_RATIO, MAX_LOG_RATIO)
    });
    let g = factor.solve(&rhs);
    Ok((0..n).map(|v| g[(v, 0)]).collect())
}

/// Per vertex, the flow's velocity on the sphere: −∇g · exp(−g), g the smoothed log area ratio,
/// each chord triangle's gradient weighted by its area and projected onto the vertex's tangent
/// plane. The factor exp(−g) scales the motion to the map's local size, so a limb squeezed ×100
/// spreads at the same relative rate as the body round it.
fn flow_velocity(
    points: &[Vector3<f64>],
    triangles: &[[u32; 3]],
    field: &[f64],
) -> Vec<Vector3<f64>> {
    let n = points.len();
    let (mut velocity, mut weight) = (vec![Vector3::zeros(); n], vec![0.0; n]);
    for t in triangles {
        let p = t.map(|v| points[v as usize]);
        let g = t.map(|v| field[v as usize]);
        let normal = (p[1] - p[0]).cross(&(p[2] - p[0]));
        let twice_area = normal.norm();
        if twice_area <= 0.0 {
            continue;
        }
        let unit = normal / twice_area;
        // The gradient of the linear interpolant: Σ g_k n × e_k / 2A, e_k the edge facing corner k.
        let gradient = (0..3).fold(Vector3::zeros(), |sum, k| {
            sum + unit.cross(&(p[(k + 2) % 3] - p[(k + 1) % 3])) * g[k]
        }) / twice_area;
        let scale = (-(g[0] + g[1] + g[2]) / 3.0).exp();
        for &v in t {
            velocity[v as usize] -= gradient * (scale * twice_area);
            weight[v as usize] += twice_area;
        }
    }
    (0..n)
        .map(|v| {
            let d = velocity[v] / weight[v].max(f64::MIN_POSITIVE);
            d - points[v] * points[v].dot(&d)
        })
        .collect()
}

/// Moves every vertex along `velocity` by the longest step, at most 1, that keeps every edge's
/// strain within [`MAX_STRAIN`], halved until no triangle folds that did not before. Returns false,
/// `points` unchanged, if [`STEP_HALVINGS`] halvings do not get there.
fn take_step(
    points: &mut [Vector3<f64>],
    triangles: &[[u32; 3]],
    velocity: &[Vector3<f64>],
) -> bool {
    let mut fastest: f64 = 0.0;
    for t in triangles {
        for k in 0..3 {
            let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let length = (points[i] - points[j]).norm().max(f64::MIN_POSITIVE);
            fastest = fastest.max((velocity[i] - velocity[j]).norm() / length);
        }
    }
    let before = points.to_vec();
    let folded = folded_triangles(points, triangles);
    let mut step = (MAX_STRAIN / fastest.max(f64::MIN_POSITIVE)).min(1.0);
    for _ in 0..=STEP_HALVINGS {
        for (p, (x, d)) in points.iter_mut().zip(before.iter().zip(velocity)) {
            *p = (x + d * step).normalize();
        }
        let finite = points.iter().all(|p| p.iter().all(|c| c.is_finite()));
        if finite && folded_triangles(points, triangles) <= folded {
            return true;
        }
        step /= 2.0;
    }
    points.copy_from_slice(&before);
    false
}

/// One Gauss–Seidel sweep of every vertex a [`SHEAR_DAMPING`] part of the way to the mean value
/// average of its neighbours, undone if it folds a triangle.
fn damp_shear(points: &mut [Vector3<f64>], neighbours: &[Vec<(f64, u32)>], triangles: &[[u32; 3]]) {
    let (kept, folded) = (points.to_vec(), folded_triangles(points, triangles));
    for v in 0..points.len() {
        if let Some(d) = mean_value_step(points, &neighbours[v], points[v], SHEAR_DAMPING) {
            points[v] = from_frame(points[v], d);
        }
    }
    if folded_triangles(points, triangles) > folded {
        points.copy_from_slice(&kept);
    }
}

/// Turns the map so that the caps' seam, the equator, runs through its squeezed parts. Each cap's
/// control grid is uniform in its stereographic plane, which puts four times as many control
/// points on a unit of the sphere's area at the equator as at the cap's pole. The pole is the axis
/// about which the vertices, weighted by their surface area times how squeezed they are (the area
/// ratio where above 1), have the largest moment of inertia: the eigenvector of the smallest
/// eigenvalue of Σ w x xᵀ. On the bunny, on its own, this took the fit's distance from 3.9% to
/// 2.5% of the diagonal, and after an earlier form of the flow from 2.4% to 1.2%.
fn seam_through_squeezed(points: &mut [Vector3<f64>], triangles: &[[u32; 3]], surface: &[f64]) {
    let n = points.len();
    let sphere = chord_areas(points, triangles);
    let (surface_total, sphere_total) = (surface.iter().sum::<f64>(), sphere.iter().sum::<f64>());
    let mut scatter = nalgebra::Matrix3::zeros();
    for v in 0..n {
        let ratio =
            (surface[v] / surface_total) / (sphere[v] / sphere_total).max(f64::MIN_POSITIVE);
        scatter += points[v] * points[v].transpose() * (surface[v] * ratio.max(1.0));
    }
    let eigen = scatter.symmetric_eigen();
    let pole = eigen
        .eigenvectors
        .column(eigen.eigenvalues.imin())
        .into_owned();
    if let Some(turn) = nalgebra::Rotation3::rotation_between(&pole, &Vector3::z()) {
        points.iter_mut().for_each(|p| *p = turn * *p);
    }
}

/// Most rounds of [`even_out`], each one sparse solve. The thin-legged animal of the tests
/// (areas ×55 on average from the punctured Tutte map) is within ×2 after 8.
const EVEN_ROUNDS: usize = 16;

/// How often [`even_out`] averages each vertex's log stretch with its neighbours' before dividing
/// the weights by it. Divided by the raw stretch, the weights change sharply from one vertex to
/// the next where a limb meets the body, and the map's triangles there grow so thin that their
/// images on the sphere turn over. Measured on the animal after 8 rounds (before `untangle`):
/// raw, 28 turned over; averaged twice, 3, with areas ×2.24 on average and ×4 600 at worst;
/// averaged 8 times, 6, with ×1.99 and ×85.
const STRETCH_SMOOTHING: usize = 8;

/// The mean area distortion ([`Distortion::area_mean`]) of the conformal map from which it is
/// evened out in the plane ([`even_out`]) rather than relaxed by sweeps on the sphere. Below it
/// the sweeps do better: the planar rounds leave the puncture's
/// neighbours as the pins hold them (the dumbbell, ×2.1 from the conformal map: ×1.01 by the
/// sweeps, ×1.33 by the planar rounds).
const EVEN_FROM: f64 = 4.0;

/// A round of [`even_out`] that lowers the mean area distortion by less than this fraction is
/// not taken, and the rounds end.
const EVEN_GAIN: f64 = 0.02;

/// Evens out the map's area by rounds of stretch reweighting, each solved in the plane rather
/// than relaxed on the sphere: the weights are divided by the map's smoothed stretch (as the
/// sweeps' rounds divide them, but cumulatively), the sphere is punctured at the largest triangle
/// of the map it started from (every round at the same one) and solved as a Tutte map ([`punctured_map`]), centred, and cleared of the few thin triangles
/// whose images turned over ([`untangle`]). Each solve is a bijection in the plane whatever the
/// weights, where sweeps on the sphere crawl into a squeezed limb and fold it. A round is taken
/// only if it leaves no folded triangle and lowers the mean area distortion
/// ([`Distortion::area_mean`]) by [`EVEN_GAIN`]; returns the rounds taken (0 leaves `points` as
/// it was). A map more even than [`EVEN_FROM`] takes none.
fn even_out(
    points: &mut Vec<Vector3<f64>>,
    weights: &[Vec<(u32, f64)>],
    positions: &[Point3],
    triangles: &[[u32; 3]],
    areas: &[f64],
) -> Result<(usize, Neighbours), EmbeddingError> {
    let area_mean = |points: &[Vector3<f64>]| {
        distortion(points, positions, triangles).map_or(f64::INFINITY, |d| d.area_mean)
    };
    let neighbours = neighbours_of(weights);
    let mut weights = weights.to_vec();
    // One puncture for every round: moved from round to round, the pins jolt the map and the
    // rounds do not settle (the animal's mean went ×55 → 11 → 6.6 → 5.4 → 2.8 → 4.8).
    let puncture = triangles[largest_on_sphere(points, triangles)];
    let (mut current, mut mean) = (points.clone(), area_mean(points));
    if mean < EVEN_FROM {
        return Ok((0, Vec::new()));
    }
    let mut taken = 0;
    let mut taken_weights = Vec::new();
    for round in 0..EVEN_ROUNDS {
        let stretch = smoothed(stretch(&current, positions, triangles), &neighbours);
        for list in &mut weights {
            for (u, w) in list.iter_mut() {
                *w /= stretch_divisor(stretch[*u as usize]);
            }
        }
        let mut trial = punctured_map(&current, &weights, puncture)?;
        centre(&mut trial, areas);
        let left = untangle(&mut trial, &neighbours, triangles);
        let trial_mean = area_mean(&trial);
        tracing::debug!(
            "evening round {round}: areas ×{trial_mean:.2} mean (was ×{mean:.2}), {left} folded"
        );
        if left > 0 || trial_mean > mean * (1.0 - EVEN_GAIN) {
            break;
        }
        (*points, taken) = (trial.clone(), round + 1);
        (current, mean) = (trial, trial_mean);
        taken_weights = neighbours_of(&weights);
    }
    Ok((taken, taken_weights))
}

/// `stretch` with each vertex's logarithm averaged with its neighbours' [`STRETCH_SMOOTHING`]
/// times.
fn smoothed(stretch: Vec<f64>, neighbours: &[Vec<(f64, u32)>]) -> Vec<f64> {
    let mut logs: Vec<f64> = stretch.iter().map(|s| s.ln()).collect();
    for _ in 0..STRETCH_SMOOTHING {
        logs = neighbours
            .iter()
            .enumerate()
            .map(|(v, list)| {
                let sum: f64 = list.iter().map(|&(_, u)| logs[u as usize]).sum();
                (logs[v] + sum) / (1 + list.len()) as f64
            })
            .collect();
    }
    logs.into_iter().map(f64::exp).collect()
}

/// Rings round the folded triangles that [`untangle`] frees, one more each time, before it gives up.
const UNTANGLE_RINGS: usize = 8;

/// Sweeps [`untangle`] runs over the freed vertices each time.
const UNTANGLE_SWEEPS: usize = 200;

/// Frees the vertices of the folded triangles and `k` rings round them (k = 1, 2, …,
/// [`UNTANGLE_RINGS`]) and moves them to the mean value average of their neighbours in their own
/// frames (the sweeps' step cap, the rest held), keeping a try only if it leaves fewer folded
/// triangles, until none is left. Returns how many are left. After a round of [`even_out`] the
/// folded triangles are a few thin ones, each alone, which the mean value weights open out.
fn untangle(
    points: &mut [Vector3<f64>],
    neighbours: &[Vec<(f64, u32)>],
    triangles: &[[u32; 3]],
) -> usize {
    let mut folded = folded_triangles(points, triangles);
    for rings in 1..=UNTANGLE_RINGS {
        if folded == 0 {
            break;
        }
        let mut free = vec![false; points.len()];
        for t in triangles.iter().filter(|t| orientation(points, t) <= 0.0) {
            t.iter().for_each(|&v| free[v as usize] = true);
        }
        for _ in 0..rings {
            let ring: Vec<usize> = (0..points.len()).filter(|&v| free[v]).collect();
            for v in ring {
                neighbours[v]
                    .iter()
                    .for_each(|&(_, u)| free[u as usize] = true);
            }
        }
        let set: Vec<usize> = (0..points.len()).filter(|&v| free[v]).collect();
        let before: Vec<Vector3<f64>> = set.iter().map(|&v| points[v]).collect();
        for _ in 0..UNTANGLE_SWEEPS {
            for &v in &set {
                if let Some(d) = mean_value_step(points, &neighbours[v], points[v], 1.0) {
                    points[v] = from_frame(points[v], d);
                }
            }
        }
        let now = folded_triangles(points, triangles);
        if now < folded {
            folded = now;
        } else {
            set.iter().zip(&before).for_each(|(&v, &p)| points[v] = p);
        }
    }
    folded
}

/// The step in x's frame to the weighted mean of its neighbours, times `over` (over-relaxation),
/// capped at [`MAX_STEP`] (None for a vertex without weight).
fn mean_value_step(
    points: &[Vector3<f64>],
    neighbours: &[(f64, u32)],
    x: Vector3<f64>,
    over: f64,
) -> Option<Vector3<f64>> {
    let (mut sum, mut total) = (Vector3::zeros(), 0.0);
    for &(w, u) in neighbours {
        sum += to_frame(x, points[u as usize]) * w;
        total += w;
    }
    (total > 0.0).then(|| {
        let d = sum / total * over;
        if d.norm() > MAX_STEP {
            d * (MAX_STEP / d.norm())
        } else {
            d
        }
    })
}

/// The triangle of largest area on the sphere (its chord triangle's), where [`even_out`]
/// punctures: the pins hold its corners, and its neighbours have room to move.
fn largest_on_sphere(points: &[Vector3<f64>], triangles: &[[u32; 3]]) -> usize {
    let area = |t: usize| {
        let [a, b, c] = triangles[t].map(|v| points[v as usize]);
        (b - a).cross(&(c - a)).norm()
    };
    (0..triangles.len())
        .max_by(|&a, &b| area(a).total_cmp(&area(b)))
        .unwrap_or(0)
}

/// The map's [`Distortion`]: each triangle against its chord triangle on the sphere (flat, and the
/// spherical triangle to first order), measured in the chord triangle's plane. Shows how much a
/// shape's long parts are squeezed: the conformal map of a limb shrinks it exponentially.
pub(crate) fn distortion(
    points: &[Vector3<f64>],
    positions: &[Point3],
    triangles: &[[u32; 3]],
) -> Option<Distortion> {
    let per_triangle: Vec<_> = triangles
        .iter()
        .map(|t| {
            let [q0, q1, q2] = t.map(|v| points[v as usize]);
            let (u, w) = (q1 - q0, q2 - q0);
            let e1 = u.try_normalize(0.0).unwrap_or_else(Vector3::x);
            let e2 = u
                .cross(&w)
                .try_normalize(0.0)
                .map_or_else(Vector3::y, |n| n.cross(&e1));
            let flat = |d: Vector3<f64>| Complex64::new(d.dot(&e1), d.dot(&e2));
            let z = [Complex64::ZERO, flat(u), flat(w)];
            triangle_distortion(t.map(|v| positions[v as usize]), z, false)
        })
        .collect();
    Distortion::of(&per_triangle)
}

/// Triangles that are not counter-clockwise seen from outside the sphere.
fn folded_triangles(points: &[Vector3<f64>], triangles: &[[u32; 3]]) -> usize {
    triangles
        .iter()
        .filter(|t| orientation(points, t) <= 0.0)
        .count()
}

/// The triangle of largest area in space: where the first puncture's stretch harms least.
fn largest_triangle(positions: &[Point3], triangles: &[[u32; 3]]) -> Result<usize, EmbeddingError> {
    let area = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        (b - a).cross(&(c - a)).norm()
    };
    (0..triangles.len())
        .max_by(|&a, &b| area(&triangles[a]).total_cmp(&area(&triangles[b])))
        .ok_or_else(|| EmbeddingError::Parameterization("the mesh has no triangles".into()))
}

/// Floater's map of the mesh less triangle `removed`, lifted to the sphere and centred.
fn initial_map(
    triangles: &[[u32; 3]],
    areas: &[f64],
    weights: &[Vec<(u32, f64)>],
    removed: usize,
) -> Result<Vec<Vector3<f64>>, EmbeddingError> {
    // The disk's boundary runs against the removed triangle's orientation: its corners go clockwise.
    // (No free vertex's weights involve the removed triangle, which touches only the pinned corners.)
    let pins: Vec<(u32, [f64; 2])> = triangles[removed]
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            let angle = -(k as f64) * std::f64::consts::TAU / 3.0;
            (v, [angle.cos(), angle.sin()])
        })
        .collect();
    let flat = floater::solve_pinned(weights, &pins)?;
    // Half the area inside radius s: then |w/s| < 1 is the southern hemisphere.
    let mut by_radius: Vec<(f64, f64)> = flat
        .iter()
        .zip(areas)
        .map(|(w, &a)| (w[0].hypot(w[1]), a))
        .collect();
    by_radius.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = areas.iter().sum::<f64>() / 2.0;
    let mut seen = 0.0;
    let scale = by_radius
        .iter()
        .find(|(_, a)| {
            seen += a;
            seen >= half
        })
        .map_or(1.0, |(r, _)| *r)
        .max(f64::MIN_POSITIVE);
    // Inverse stereographic projection from the north pole. It reverses orientation seen from
    // outside, and the pins' clockwise order reverses it once more.
    let mut points: Vec<Vector3<f64>> = flat
        .iter()
        .map(|w| {
            let (x, y) = (w[0] / scale, w[1] / scale);
            let r2 = x * x + y * y;
            Vector3::new(2.0 * x, 2.0 * y, r2 - 1.0) / (r2 + 1.0)
        })
        .collect();
    let positive = triangles
        .iter()
        .filter(|t| orientation(&points, t) > 0.0)
        .count();
    if 2 * positive < triangles.len() {
        // A mesh whose triangles turn the other way round: mirror the map to keep it orientation
        // preserving (the atlas's charts are counter-clockwise seen from outside).
        points.iter_mut().for_each(|p| p.y = -p.y);
    }
    centre(&mut points, areas);
    Ok(points)
}

/// The unit vector through a triangle's centroid on the sphere.
fn centroid(points: &[Vector3<f64>], t: &[u32; 3]) -> Vector3<f64> {
    let sum: Vector3<f64> = t.iter().map(|&v| points[v as usize]).sum();
    sum.try_normalize(0.0)
        .unwrap_or_else(|| points[t[0] as usize])
}

/// The triangle whose centroid lies furthest round the sphere from triangle `from`'s.
fn furthest(points: &[Vector3<f64>], triangles: &[[u32; 3]], from: usize) -> usize {
    let from = centroid(points, &triangles[from]);
    (0..triangles.len())
        .min_by(|&a, &b| {
            let along = |t: usize| centroid(points, &triangles[t]).dot(&from);
            along(a).total_cmp(&along(b))
        })
        .unwrap_or(0)
}

/// The Tutte map of the sphere punctured at triangle `puncture`: the current map `points`, projected
/// stereographically from the puncture's centroid, gives the puncture's corners their pins, and
/// every other vertex is solved as the weighted mean of its neighbours, then lifted back.
fn punctured_map(
    points: &[Vector3<f64>],
    weights: &[Vec<(u32, f64)>],
    puncture: [u32; 3],
) -> Result<Vec<Vector3<f64>>, EmbeddingError> {
    let c = centroid(points, &puncture);
    let (e1, e2) = tangent_frame(c);
    let project = |x: Vector3<f64>| {
        let gap = (1.0 - x.dot(&c)).max(f64::MIN_POSITIVE);
        [x.dot(&e1) / gap, x.dot(&e2) / gap]
    };
    let pins: Vec<(u32, [f64; 2])> = puncture
        .iter()
        .map(|&v| (v, project(points[v as usize])))
        .collect();
    let flat = floater::solve_pinned(weights, &pins)?;
    Ok(flat
        .iter()
        .map(|w| {
            let r2 = w[0] * w[0] + w[1] * w[1];
            (e1 * (2.0 * w[0]) + e2 * (2.0 * w[1]) + c * (r2 - 1.0)) / (r2 + 1.0)
        })
        .collect())
}

/// The longest step a vertex takes in a sweep, in its frame: the polygon's relaxation's cap
/// (`Lifts::relax`).
const MAX_STEP: f64 = 0.25;

/// Over-relaxed Gauss–Seidel sweeps, each followed by Möbius centering, until no vertex moves more
/// than `tolerance` in a sweep (centering included) or `sweeps` run out. Returns the sweeps used.
fn relax(
    points: &mut [Vector3<f64>],
    neighbours: &[Vec<(f64, u32)>],
    areas: &[f64],
    sweeps: usize,
    tolerance: f64,
) -> usize {
    // The same over-relaxation as the polygon's relaxation (`Lifts::relax`).
    const OVER: f64 = 1.3;
    for sweep in 0..sweeps {
        let before = points.to_vec();
        for v in 0..points.len() {
            if let Some(d) = mean_value_step(points, &neighbours[v], points[v], OVER) {
                points[v] = from_frame(points[v], d);
            }
        }
        centre(points, areas);
        if moved_beyond_rotation(&before, points) < tolerance {
            return sweep + 1;
        }
    }
    sweeps
}

/// The largest distance a point moved from `before` to `after`, once the rotation that best
/// carries the one onto the other is taken out (Kabsch: the SVD of Σ after·beforeᵀ, reflections
/// excluded). The sweeps turn the whole map slowly as they go, a rotation that changes nothing of
/// its shape: measured with it, the capsule's map (trimesh's, 2 306 vertices) kept moving by
/// 1.4e-5 a sweep for its whole 5 000 sweeps a round, 20 000 in all; without it, it settles to
/// 1e-8 in 9 829 (the fit 14 s → 7.7 s, its distance from the mesh 0.049% → 0.060% of the
/// diagonal: the caps' grids turned about the poles), and CGAL's `part.off` in 2 046 of 20 000.
fn moved_beyond_rotation(before: &[Vector3<f64>], after: &[Vector3<f64>]) -> f64 {
    let covariance = after
        .iter()
        .zip(before)
        .fold(nalgebra::Matrix3::zeros(), |sum, (a, b)| {
            sum + a * b.transpose()
        });
    let svd = covariance.svd(true, true);
    let rotation = match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => {
            let mut sign = nalgebra::Matrix3::identity();
            if (u * v_t).determinant() < 0.0 {
                sign[(2, 2)] = -1.0;
            }
            u * sign * v_t
        }
        _ => nalgebra::Matrix3::identity(),
    };
    after
        .iter()
        .zip(before)
        .map(|(a, b)| (a - rotation * b).norm())
        .fold(0.0, f64::max)
}

/// y seen from x's frame: stereographic projection from −x onto the tangent plane at x (a tangent
/// vector; x itself goes to 0, points a quarter turn away to unit length).
fn to_frame(x: Vector3<f64>, y: Vector3<f64>) -> Vector3<f64> {
    let along = y.dot(&x);
    // y = −x exactly would go to infinity; a neighbour is never there in a map worth relaxing, and
    // the step cap bounds what it would do.
    (y - x * along) / (1.0 + along).max(1e-12)
}

/// The inverse of [`to_frame`]: the sphere point of tangent vector d at x.
fn from_frame(x: Vector3<f64>, d: Vector3<f64>) -> Vector3<f64> {
    let d2 = d.norm_squared();
    ((x * (1.0 - d2) + d * 2.0) / (1.0 + d2)).normalize()
}

/// Möbius centering: ball isometries that move the area-weighted centroid of the points to the
/// origin (each T_a sends a to 0 and the sphere to itself, spreading the points round a/|a| apart).
fn centre(points: &mut [Vector3<f64>], areas: &[f64]) {
    const STEPS: usize = 20;
    let total: f64 = areas.iter().sum();
    for _ in 0..STEPS {
        let c = points
            .iter()
            .zip(areas)
            .fold(Vector3::zeros(), |s, (p, &a)| s + p * a)
            / total;
        if c.norm() < 1e-12 {
            return;
        }
        // The centroid of a measure is not the point the isometry must move, but close to it for
        // small offsets; capped at half way to the sphere so one step never crushes a hemisphere.
        let a = if c.norm() > 0.5 {
            c * (0.5 / c.norm())
        } else {
            c
        };
        points.iter_mut().for_each(|p| *p = ball_isometry(a, *p));
    }
}

/// T_a(x) = (1 − |a|²)(x − a)/|x − a|² − a for |x| = 1: a Möbius transformation of the unit ball that
/// maps the sphere onto itself and a to the origin.
fn ball_isometry(a: Vector3<f64>, x: Vector3<f64>) -> Vector3<f64> {
    let u = x - a;
    ((u * (1.0 - a.norm_squared())) / u.norm_squared() - a).normalize()
}

/// Twice the signed volume a·(b × c): positive where the triangle runs counter-clockwise seen from
/// outside the sphere. Formed as (b − a) × (c − a) · (a + b + c) / 3, the same number in exact
/// arithmetic, because a conformal map squeezes a long limb's triangles to 1e-8 and less, where
/// a·(b × c) of three nearly equal unit vectors is lost to rounding.
fn orientation(points: &[Vector3<f64>], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|v| points[v as usize]);
    orientation_of(a, b, c)
}

/// [`orientation`] of the triangle with corners a, b, c on the sphere.
fn orientation_of(a: Vector3<f64>, b: Vector3<f64>, c: Vector3<f64>) -> f64 {
    (b - a).cross(&(c - a)).dot(&(a + b + c)) / 3.0
}

/// An orthonormal frame (e1, e2) of the plane through the origin perpendicular to unit vector c,
/// with (e1, e2, c) right-handed.
fn tangent_frame(c: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let e1 = c
        .cross(&Vector3::x())
        .try_normalize(1e-6)
        .unwrap_or_else(|| c.cross(&Vector3::y()).normalize());
    (e1, c.cross(&e1))
}

/// Per vertex: √(3D area / spherical area) of its triangles, relative to the whole surface's ratio.
fn stretch(points: &[Vector3<f64>], positions: &[Point3], triangles: &[[u32; 3]]) -> Vec<f64> {
    let n = points.len();
    let (mut surface, mut sphere) = (vec![0.0; n], vec![0.0; n]);
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let area3 = (b - a).cross(&(c - a)).norm() / 2.0;
        let [p, q, r] = t.map(|v| points[v as usize]);
        // Van Oosterom and Strackee: tan(E/2) = p·(q × r) / (1 + p·q + q·r + r·p).
        let excess = 2.0 * orientation(points, t).atan2(1.0 + p.dot(&q) + q.dot(&r) + r.dot(&p));
        for &v in t {
            surface[v as usize] += area3;
            sphere[v as usize] += excess.max(0.0);
        }
    }
    relative_stretch(&surface, &sphere)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::vertex_areas;

    /// A latitude–longitude sphere of radius `radius` stretched by `stretch` along x, and its
    /// vertices' directions (unit vectors), which are where a map onto the sphere would put them.
    fn ellipsoid(stretch: f64) -> (Vec<Point3>, Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        lat_long(12, 24, |d| {
            Point3::new(2.0 * stretch * d.x, 2.0 * d.y, 2.0 * d.z)
        })
    }

    /// A latitude–longitude sphere of `rings` × `segments` whose vertex in direction d is put at
    /// `shape(d)`, and the directions.
    fn lat_long(
        rings: u32,
        segments: u32,
        shape: impl Fn(Vector3<f64>) -> Point3,
    ) -> (Vec<Point3>, Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        let mut directions = vec![Vector3::z()];
        for i in 1..rings {
            let theta = std::f64::consts::PI * f64::from(i) / f64::from(rings);
            for j in 0..segments {
                let phi = std::f64::consts::TAU * f64::from(j) / f64::from(segments);
                directions.push(Vector3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ));
            }
        }
        directions.push(-Vector3::z());
        let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
        let south = directions.len() as u32 - 1;
        let mut triangles = Vec::new();
        for j in 0..segments {
            triangles.push([0, ring(1, j), ring(1, j + 1)]);
            triangles.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
            for i in 1..rings - 1 {
                let q = [
                    ring(i, j),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                    ring(i, j + 1),
                ];
                triangles.extend([[q[0], q[1], q[2]], [q[0], q[2], q[3]]]);
            }
        }
        let positions = directions.iter().map(|&d| shape(d)).collect();
        (positions, directions, triangles)
    }

    /// A mesh's vertex areas, mean value weights and first map.
    struct Conformal {
        areas: Vec<f64>,
        weights: Vec<Vec<(u32, f64)>>,
        map: Vec<Vector3<f64>>,
    }

    /// The mesh's [`Conformal`] start: Floater's map punctured at the largest triangle.
    fn conformal_map(positions: &[Point3], triangles: &[[u32; 3]]) -> Conformal {
        let areas = vertex_areas(positions, triangles);
        let weights = floater::mean_value_weights(positions, triangles).unwrap();
        let removed = largest_triangle(positions, triangles).unwrap();
        let map = initial_map(triangles, &areas, &weights, removed).unwrap();
        Conformal {
            areas,
            weights,
            map,
        }
    }

    /// A round body with an arm each way along x (radius 1 + arm·|x|¹²): the conformal map squeezes
    /// the arms' ends, ×6 and ×9 on average for arms of 4 and 6. Evened out in the plane, each
    /// round taken leaves no fold and a mean at least [`EVEN_GAIN`] lower, so the map comes out
    /// more even than it went in; a body without arms, or with short ones, is left as it is.
    #[test]
    fn long_arms_are_evened_out_in_the_plane_without_a_fold() {
        for arm in [0.0, 2.0, 4.0, 6.0] {
            let (positions, _, triangles) = lat_long(48, 48, |d| {
                Point3::from(d * (1.0 + arm * d.x.abs().powi(12)))
            });
            let Conformal {
                areas,
                weights,
                map: start,
            } = conformal_map(&positions, &triangles);
            let mut points = start.clone();
            let (rounds, _) =
                even_out(&mut points, &weights, &positions, &triangles, &areas).unwrap();
            let before = distortion(&start, &positions, &triangles).unwrap();
            let after = distortion(&points, &positions, &triangles).unwrap();
            if before.area_mean < EVEN_FROM {
                assert_eq!(rounds, 0, "arm {arm}: {before:?}");
                assert_eq!(points, start, "arm {arm}");
                continue;
            }
            assert!(arm >= 4.0, "arm {arm}: {before:?}");
            assert!(rounds > 0, "arm {arm}");
            assert_eq!(folded_triangles(&points, &triangles), 0, "arm {arm}");
            assert!(
                after.area_mean <= 0.75 * before.area_mean,
                "arm {arm}: {before:?} → {after:?}"
            );
        }
    }

    /// A turned copy of a map has not moved; one point pushed off has moved by as much, whichever
    /// way the copy is turned.
    #[test]
    fn motion_leaves_out_the_rotation() {
        let (_, points, _) = ellipsoid(1.0);
        for (axis, angle) in [(Vector3::z(), 0.3), (Vector3::new(1.0, 2.0, -0.5), 2.9)] {
            let turn =
                nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
            let mut after: Vec<_> = points.iter().map(|p| turn * p).collect();
            assert!(moved_beyond_rotation(&points, &after) < 1e-12);
            let push = 1e-3 * Vector3::new(0.3, -0.4, 0.5).normalize();
            after[7] += push;
            let moved = moved_beyond_rotation(&points, &after);
            assert!((moved - 1e-3).abs() < 1e-4, "{moved}");
        }
    }

    /// The body with long arms of `long_arms_are_evened_out_in_the_plane_without_a_fold`, from its
    /// conformal map (the Floater map's, whose pins stretch even the round sphere's): the flow
    /// leaves no fold, keeps σ₁/σ₂ within its bound and takes the largest area ratio down to a
    /// tenth or less, or within ×1.1 (measured: no arm ×3.4 → ×1.02, arms of 4 ×86 → ×5.6, of 6
    /// ×142 → ×9.0).
    #[test]
    fn the_flow_spreads_squeezed_arms_without_a_fold() {
        for arm in [0.0, 4.0, 6.0] {
            let (positions, _, triangles) = lat_long(48, 48, |d| {
                Point3::from(d * (1.0 + arm * d.x.abs().powi(12)))
            });
            let Conformal {
                areas,
                weights,
                map: start,
            } = conformal_map(&positions, &triangles);
            assert_eq!(folded_triangles(&start, &triangles), 0, "arm {arm}");
            let neighbours = neighbours_of(&weights);
            let mut points = start.clone();
            let round = equalize_areas(&mut points, &neighbours, &positions, &triangles, &areas);
            let before = distortion(&start, &positions, &triangles).unwrap();
            let after = distortion(&points, &positions, &triangles).unwrap();
            assert_eq!(folded_triangles(&points, &triangles), 0, "arm {arm}");
            assert!(
                after.area_max <= before.area_max,
                "arm {arm}: {before:?} → {after:?}"
            );
            assert!(
                after.angle_max <= EQUALIZE_ANGLE_BOUND.max(before.angle_max),
                "arm {arm}: {after:?}"
            );
            assert!(round > 0, "arm {arm}");
            assert!(
                after.area_max <= (0.1 * before.area_max).max(1.1),
                "arm {arm}: {before:?} → {after:?}"
            );
        }
    }

    /// With the arms along a slanted axis and the map turned so that one arm's end is at the north
    /// pole, turning the seam through the squeezed parts puts both ends on the equator.
    #[test]
    fn the_seam_runs_through_the_squeezed_arms() {
        let axis = Vector3::new(1.0, 2.0, 2.0) / 3.0;
        let (positions, _, triangles) = lat_long(48, 48, |d| {
            Point3::from(d * (1.0 + 6.0 * d.dot(&axis).abs().powi(12)))
        });
        let mut points = conformal_map(&positions, &triangles).map;
        // The arms' ends: the vertices farthest along the axis either way.
        let end = |sign: f64| {
            (0..positions.len())
                .max_by(|&a, &b| {
                    (sign * positions[a].coords.dot(&axis))
                        .total_cmp(&(sign * positions[b].coords.dot(&axis)))
                })
                .unwrap()
        };
        let ends = [end(1.0), end(-1.0)];
        let up = nalgebra::Rotation3::rotation_between(&points[ends[0]], &Vector3::z()).unwrap();
        points.iter_mut().for_each(|p| *p = up * *p);
        assert!(points[ends[0]].z > 0.999);
        seam_through_squeezed(
            &mut points,
            &triangles,
            &vertex_areas(&positions, &triangles),
        );
        for v in ends {
            assert!(points[v].z.abs() < 0.1, "{:?}", points[v]);
        }
    }

    /// A round sphere mapped onto the sphere by direction keeps every angle and area (its
    /// triangles and their chord triangles are similar); an ellipsoid three times longer than wide
    /// mapped the same way shows it: triangles 2.6 times longer one way on average (3 at most),
    /// areas up to twice the average either way (measured: 2.58, 3.00, 2.18).
    #[test]
    fn distortion_sees_a_stretched_map() {
        let (positions, directions, triangles) = ellipsoid(1.0);
        let round = distortion(&directions, &positions, &triangles).unwrap();
        assert!((round.angle_max - 1.0).abs() < 1e-9, "{round:?}");
        assert!((round.area_max - 1.0).abs() < 1e-9, "{round:?}");
        let (positions, directions, triangles) = ellipsoid(3.0);
        let long = distortion(&directions, &positions, &triangles).unwrap();
        assert!(
            long.angle_mean > 2.0 && long.angle_max < 3.0 + 1e-9,
            "{long:?}"
        );
        assert!(long.area_mean > 1.1 && long.area_max > 1.8, "{long:?}");
    }

    #[test]
    fn frames_invert_each_other() {
        let x = Vector3::new(0.3, -0.5, 0.8).normalize();
        for y in [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(-0.2, 0.9, 0.1).normalize(),
            Vector3::new(0.31, -0.49, 0.81).normalize(),
        ] {
            let back = from_frame(x, to_frame(x, y));
            assert!((back - y).norm() < 1e-12, "{back} vs {y}");
        }
    }

    #[test]
    fn ball_isometries_keep_the_sphere_and_move_a_to_the_centre() {
        let a = Vector3::new(0.2, 0.1, -0.3);
        for x in [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, -0.6, 0.8),
            Vector3::new(0.48, 0.6, 0.64),
        ] {
            assert!((ball_isometry(a, x).norm() - 1.0).abs() < 1e-12);
        }
        // On the axis through a, the points ±a/|a| stay put.
        let n = a.normalize();
        assert!((ball_isometry(a, n) - n).norm() < 1e-12);
        assert!((ball_isometry(a, -n) + n).norm() < 1e-12);
    }

    /// The body with arms of `long_arms_are_evened_out_in_the_plane_without_a_fold`, and one with
    /// arms of 12, mapped coarse to fine: no fold; the round sphere an isometry within 10%; with
    /// arms, a mean area factor under 2 and a worst one under 8, however long the arms (measured:
    /// ×1.62 and ×3.6 against the conformal map's ×9.1 and ×142 for arms of 6, ×1.70 and ×4.3
    /// against ×16 and ×293 for arms of 12), and less shear on average; and the same map each
    /// time (the simplification's order and the tetrahedron's placement depend on the mesh
    /// alone).
    #[test]
    fn a_map_built_coarse_to_fine_does_not_squeeze_long_arms() {
        for arm in [0.0, 6.0, 12.0] {
            let (positions, _, triangles) = lat_long(48, 48, |d| {
                Point3::from(d * (1.0 + arm * d.x.abs().powi(12)))
            });
            let conformal = conformal_map(&positions, &triangles).map;
            let before = distortion(&conformal, &positions, &triangles).unwrap();
            let points = progressive::progressive_map(&positions, &triangles).unwrap();
            assert_eq!(folded_triangles(&points, &triangles), 0, "arm {arm}");
            let after = distortion(&points, &positions, &triangles).unwrap();
            if arm == 0.0 {
                assert!(after.area_max <= 1.1, "{after:?}");
                assert!(after.angle_max <= 1.1, "{after:?}");
            } else {
                assert!(after.area_mean <= 2.0, "arm {arm}: {after:?}");
                assert!(after.area_max <= 8.0, "arm {arm}: {before:?} → {after:?}");
                assert!(
                    after.angle_mean < before.angle_mean,
                    "arm {arm}: {before:?} → {after:?}"
                );
            }
            let again = progressive::progressive_map(&positions, &triangles).unwrap();
            assert_eq!(again, points, "arm {arm}");
        }
    }

    /// The map built coarse to fine depends on the mesh's shape, not its units: scaled by powers of
    /// two (exact in floating point), the body with arms gets the very same map. (Its energy once
    /// weighed its two terms by the mesh's size, and the same shape in millimetres and in metres
    /// got different maps.)
    #[test]
    fn a_map_built_coarse_to_fine_does_not_depend_on_units() {
        let (positions, _, triangles) = lat_long(32, 32, |d| {
            Point3::from(d * (1.0 + 6.0 * d.x.abs().powi(12)))
        });
        let map = progressive::progressive_map(&positions, &triangles).unwrap();
        for scale in [1024.0, 1.0 / 64.0] {
            let scaled: Vec<Point3> = positions.iter().map(|p| p * scale).collect();
            let again = progressive::progressive_map(&scaled, &triangles).unwrap();
            assert_eq!(again, map, "scale {scale}");
        }
    }

    /// A mesh that is not a closed, consistently oriented surface is not mapped: one with a hole,
    /// and one with a triangle turned the other way.
    #[test]
    fn a_map_built_coarse_to_fine_needs_a_closed_oriented_mesh() {
        let (positions, _, mut triangles) = lat_long(8, 8, Point3::from);
        assert!(progressive::progressive_map(&positions, &triangles).is_some());
        let last = triangles.pop().unwrap();
        assert!(progressive::progressive_map(&positions, &triangles).is_none());
        triangles.push([last[0], last[2], last[1]]);
        assert!(progressive::progressive_map(&positions, &triangles).is_none());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(32))]
        /// Spheres of random resolution bent into random shapes (bumps and arms along random axes,
        /// each vertex pushed off at random, some triangles made needles or slivers in space): the
        /// map built coarse to fine is made, every point on the sphere, and no triangle folds.
        #[test]
        fn a_map_built_coarse_to_fine_never_folds(
            rings in 3u32..24,
            segments in 3u32..24,
            arms in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0, 0.0f64..10.0, 1i32..16), 0..4),
            jitter in proptest::collection::vec(-0.3f64..0.3, 600),
        ) {
            let (positions, _, triangles) = lat_long(rings, segments, |d| {
                let reach: f64 = arms
                    .iter()
                    .map(|&(x, y, z, length, power)| {
                        let axis = Vector3::new(x, y, z).try_normalize(1e-3).unwrap_or_else(Vector3::x);
                        length * d.dot(&axis).max(0.0).powi(power)
                    })
                    .sum();
                Point3::from(d * (1.0 + reach))
            });
            let positions: Vec<Point3> = positions
                .iter()
                .enumerate()
                .map(|(i, p)| p + Vector3::new(jitter[i % 600], jitter[(7 * i + 1) % 600], jitter[(13 * i + 2) % 600]))
                .collect();
            let points = progressive::progressive_map(&positions, &triangles);
            proptest::prop_assert!(points.is_some());
            let points = points.unwrap();
            proptest::prop_assert!(points.iter().all(|p| (p.norm() - 1.0).abs() < 1e-9));
            proptest::prop_assert_eq!(folded_triangles(&points, &triangles), 0);
        }
    }
}
