//! Measures of shape: what a designer sees and topology cannot. χ and Gauss–Bonnet hold for any
//! closed surface, ripples and creases included; these look at the geometry itself.
//!
//! - **Patch disagreement**: where two charts both carry real blend weight, the distance between
//!   their two unblended patches E_c at the same surface point. The surface blends the patches, so
//!   patches that disagree draw ripples where the blend weights change.
//! - **Principal curvature**: the largest |κ| over a set of points (a crease or a spike shows up as
//!   an outlier far above what the intended shape has).
//! - **Normal deviation** from a reference mesh: the angle between the surface's normal at each
//!   mesh vertex's surface point and the mesh's own vertex normal ([`vertex_normals`]).
//! - **The input's curvature**: the largest principal curvature of a triangle mesh with normals
//!   ([`mesh_max_principal_curvature`]), what a fit's largest |κ| is compared with.
//! - **Self-intersections** of the surface's tessellation ([`tessellation_crossings`], and
//!   [`crossings_until_clear`], which tells the tessellation's from the surface's).
//!
//! ```
//! use charts::Atlas;
//! use embedding::quality::{patch_disagreement, sample_points};
//! use embedding::{Layout, Model, Point3, SplineSettings, Surface};
//! use std::sync::Arc;
//!
//! let atlas = Arc::new(Atlas::new(2)?);
//! let layout = Layout::new(&atlas, SplineSettings::default())?;
//! // Every patch the same constant: the patches agree everywhere.
//! let control = Model::constant(&layout, Point3::new(1.0, 2.0, 3.0)).points();
//! let surface = Surface::new(atlas.clone(), SplineSettings::default(), control)?;
//! let d = patch_disagreement(&surface, &sample_points(&surface, 4)?, 0.1);
//! assert!(d.max < 1e-12 && d.compared > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use charts::ChartPoint;

use crate::spline_surface::Surface;
use crate::surface::{Point3, Vector3};
use crate::{EmbeddingError, evaluate};

/// Largest distance of a fit from its data points, as a fraction of the diagonal, that `ntori new`
/// and `ntori fit` accept.
pub const RESIDUAL_TOLERANCE: f64 = 0.01;
/// Largest patch disagreement, as a fraction of the diagonal, that `ntori new` and `ntori fit`
/// accept.
pub const DISAGREEMENT_TOLERANCE: f64 = 0.01;
/// Largest ratio of a surface's |κ| to its input mesh's that `ntori fit` accepts (a crease or a
/// spike), where the input's comes from the mesh's own normals: those underestimate the peak of a
/// coarse mesh, whose triangles each span much of a rim's turn (the 1581-vertex
/// `assets/meshes/plate-genus-3.obj` reads 3.1 against its shape's 4.0). Against a shape's exact
/// normals (`ntori new`) the check takes 3.
pub const CURVATURE_RATIO_TOLERANCE_MESH: f64 = 4.0;
/// How far from a mesh's sharp edges (as a fraction of its diagonal) a fitted surface's curvature
/// is left out of the curvature check against the mesh's ([`CURVATURE_RATIO_TOLERANCE_MESH`]):
/// a smooth surface rounds a crease, and how tightly depends on its grid, not on the mesh (whose
/// own curvature there grows without bound as it is refined). Measured on a cube fitted by `ntori
/// fit` (grid 80): the largest |κ| falls from 38 at the edges to 10 at 2% of the diagonal, 4.9 at
/// 3% (the mesh's own estimate: 5.7) and 2.2 at 4%.
pub const CREASE_BAND: f64 = 0.03;
/// The tightest rounding of a sharp edge `ntori fit` accepts, as a radius (1/|κ|) over the
/// diagonal: a spike or a fold at a crease still fails (the cube above is rounded to 1.5%).
pub const MIN_CREASE_ROUNDING: f64 = 0.0025;
/// Largest 90th percentile of a surface's normals' deviation (degrees) from its input mesh's that
/// `ntori fit` accepts. The mesh's normals carry its faceting; against a shape's exact normals
/// (`ntori new`) the check takes 5°.
pub const NORMAL_TOLERANCE_MESH: f64 = 15.0;

/// Points spread over the whole surface: the vertices of its t × t tessellation.
pub fn sample_points(surface: &Surface, t: u32) -> Result<Vec<ChartPoint>, EmbeddingError> {
    Ok(surface.atlas().tessellate(t, t)?.vertices)
}

/// How far apart overlapping patches are (see the module documentation), in model units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Disagreement {
    /// The largest distance between two patches that both carry blend weight ≥ the threshold.
    pub max: f64,
    /// The root mean square of each compared point's largest distance.
    pub rms: f64,
    /// Where the largest distance was found.
    pub worst: Option<ChartPoint>,
    /// How many points had two or more patches to compare.
    pub compared: usize,
}

/// The patch disagreement over `points`, comparing the patches whose normalised blend weight is at
/// least `min_blend` (0.1 is a good threshold: below it a patch hardly shows).
pub fn patch_disagreement(
    surface: &Surface,
    points: &[ChartPoint],
    min_blend: f64,
) -> Disagreement {
    let layout = surface.layout();
    let atlas = surface.atlas();
    let control = surface.control_points();
    let mut weights = Vec::with_capacity(16);
    let (mut out, mut sum_squares) = (Disagreement::default(), 0.0);
    for &p in points {
        let reps = atlas.locate_with_transitions(p);
        let raw: Vec<f64> = reps
            .iter()
            .map(|(r, _)| {
                layout
                    .raw_blend(atlas.charts()[r.chart.index()].domain(), r.coords)
                    .val
            })
            .collect();
        let total: f64 = raw.iter().sum();
        let patches: Vec<Point3> = reps
            .iter()
            .zip(&raw)
            .filter(|&(_, &b)| b >= min_blend * total)
            .map(|((r, _), _)| {
                weights.clear();
                layout.patch_weights(*r, &mut weights);
                // The B-spline basis sums to one: an affine combination of control points.
                let sum: Vector3 = weights
                    .iter()
                    .map(|&(c, w)| control[c as usize].coords * w)
                    .sum();
                Point3::from(sum)
            })
            .collect();
        if patches.len() < 2 {
            continue;
        }
        let mut largest = 0.0f64;
        for (i, a) in patches.iter().enumerate() {
            for b in &patches[i + 1..] {
                largest = largest.max((a - b).norm());
            }
        }
        out.compared += 1;
        sum_squares += largest * largest;
        if largest > out.max || out.worst.is_none() {
            out.max = largest;
            out.worst = Some(p);
        }
    }
    out.rms = (sum_squares / out.compared.max(1) as f64).sqrt();
    out
}

/// The largest principal curvature in absolute value over `points`, and where it is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurvatureExtreme {
    pub max_abs: f64,
    pub at: Option<ChartPoint>,
}

/// The largest |κ₁|, |κ₂| over `points` (points where the surface is singular, S_u × S_v = 0,
/// count as infinite curvature).
pub fn max_principal_curvature(surface: &Surface, points: &[ChartPoint]) -> CurvatureExtreme {
    max_principal_curvature_by_creases(surface, points, &SharpEdges::default(), 0.0).away
}

/// The largest |κ| of a sample: infinite where the surface is singular or the value not a number.
fn sample_curvature(s: &evaluate::Sample) -> f64 {
    let k = match s.curvature {
        Some(c) if s.normal.is_some() => {
            let (k1, k2) = c.principal();
            k1.abs().max(k2.abs())
        }
        _ => f64::INFINITY,
    };
    if k.is_nan() { f64::INFINITY } else { k }
}

/// A mesh's sharp edges (`mesh::even::sharp_edges`: its normals turn more than
/// [`mesh::even::SHARP_DIHEDRAL_DEGREES`] across them), as segments: where a smooth surface fitted
/// to the mesh must round a crease, with a curvature set by how tightly the fit can turn, not by
/// the mesh.
#[derive(Clone, Debug, Default)]
pub struct SharpEdges {
    segments: Vec<[Point3; 2]>,
}

impl SharpEdges {
    pub fn of(positions: &[Point3], triangles: &[[u32; 3]]) -> SharpEdges {
        let points: Vec<[f64; 3]> = positions.iter().map(|p| [p.x, p.y, p.z]).collect();
        let segments = mesh::even::sharp_edges(&points, triangles)
            .into_iter()
            .map(|(a, b)| [positions[a as usize], positions[b as usize]])
            .collect();
        SharpEdges { segments }
    }

    /// How many edges are sharp.
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// The distance from `p` to the nearest sharp edge (infinite where there is none).
    pub fn distance(&self, p: Point3) -> f64 {
        self.segments
            .iter()
            .map(|[a, b]| {
                let ab = b - a;
                let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
                let t = if t.is_finite() { t } else { 0.0 };
                (p - (a + ab * t)).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }
}

/// [`max_principal_curvature`] split by a mesh's sharp edges: over the points farther than `band`
/// from every one of them (`away`), and over the rest (`near`, where the surface rounds them).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CreaseCurvature {
    pub away: CurvatureExtreme,
    pub near: CurvatureExtreme,
}

impl CreaseCurvature {
    /// The tightest rounding of a sharp edge, as a radius over `diagonal`; `None` where no point
    /// is near one.
    pub fn rounding(&self, diagonal: f64) -> Option<f64> {
        self.near.at.map(|_| 1.0 / (self.near.max_abs * diagonal))
    }

    /// Takes in a largest |κ| found elsewhere (`extreme`, at surface position `position`) on the
    /// side of `sharp` it lies on: within `band` of a sharp edge or not.
    pub fn include(
        &mut self,
        extreme: CurvatureExtreme,
        position: Point3,
        sharp: &SharpEdges,
        band: f64,
    ) {
        let side = if sharp.is_empty() || sharp.distance(position) > band {
            &mut self.away
        } else {
            &mut self.near
        };
        if extreme.at.is_some() && (side.at.is_none() || extreme.max_abs > side.max_abs) {
            *side = extreme;
        }
    }
}

/// The largest |κ| over `points`, apart for those within `band` of a sharp edge.
pub fn max_principal_curvature_by_creases(
    surface: &Surface,
    points: &[ChartPoint],
    sharp: &SharpEdges,
    band: f64,
) -> CreaseCurvature {
    let mut out = CreaseCurvature::default();
    let wants = evaluate::Wants {
        curvature: true,
        blends: false,
    };
    evaluate::evaluate(surface, points, wants, 0.0, &mut |s: &evaluate::Sample| {
        let here = CurvatureExtreme {
            max_abs: sample_curvature(s),
            at: Some(s.point),
        };
        out.include(here, s.position, sharp, band);
    });
    out
}

/// Angles in degrees: the median, the 90th and 95th percentiles and the largest.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AngleSpread {
    pub median: f64,
    pub p90: f64,
    pub p95: f64,
    pub max: f64,
}

impl AngleSpread {
    fn of(mut angles: Vec<f64>) -> AngleSpread {
        angles.sort_by(f64::total_cmp);
        let at = |q: f64| sorted_quantile(&angles, q).unwrap_or_default();
        AngleSpread {
            median: at(0.5),
            p90: at(0.9),
            p95: at(0.95),
            max: at(1.0),
        }
    }
}

/// The fitted surface where the intended one is a plane (a plate's flat faces): how far it bends
/// and turns there, as a designer sees a ripple. Quantiles are weighted (by area), so a mesh
/// denser near the rims does not count the faces' rim-side edges more than their middles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlatFaces {
    /// The points measured.
    pub points: usize,
    /// |H| (model units⁻¹): the median and the 90th percentile.
    pub mean_curvature_median: f64,
    pub mean_curvature_p90: f64,
    /// The angle between the surface's normal and the plane's (degrees), 90th percentile.
    pub normal_p90: f64,
}

/// [`FlatFaces`] at `points`, where the intended surface is flat with normal `normals[i]` (any
/// length), weighted by `weights` (e.g. the input's vertex areas). A point where the surface has
/// no normal or curvature counts as 180° and infinitely curved. `None` for no points, or where the
/// three slices' lengths differ.
pub fn flat_faces(
    surface: &Surface,
    points: &[ChartPoint],
    normals: &[Vector3],
    weights: &[f64],
) -> Option<FlatFaces> {
    let n = points.len();
    if n == 0 || normals.len() != n || weights.len() != n {
        return None;
    }
    let mut angles = vec![180.0; n];
    let mut curvatures = vec![f64::INFINITY; n];
    evaluate::evaluate(
        surface,
        points,
        evaluate::Wants {
            curvature: true,
            ..Default::default()
        },
        0.0,
        &mut |s: &evaluate::Sample| {
            if let Some(normal) = s.normal
                && normals[s.index].norm() > 0.0
            {
                angles[s.index] = normal.angle(&normals[s.index]).to_degrees();
            }
            if let Some(c) = s.curvature {
                curvatures[s.index] = c.mean.abs();
            }
        },
    );
    Some(FlatFaces {
        points: n,
        mean_curvature_median: weighted_quantile(&curvatures, weights, 0.5),
        mean_curvature_p90: weighted_quantile(&curvatures, weights, 0.9),
        normal_p90: weighted_quantile(&angles, weights, 0.9),
    })
}

/// The smallest of `values` below which at least `q` of the total weight lies.
fn weighted_quantile(values: &[f64], weights: &[f64], q: f64) -> f64 {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let total: f64 = weights.iter().sum();
    let mut seen = 0.0;
    for &i in &order {
        seen += weights[i];
        if seen >= q * total {
            return values[i];
        }
    }
    order.last().map_or(0.0, |&i| values[i])
}

/// The angle between the surface's normal at `points[i]` and the vertex normal of the mesh
/// (`positions`, `triangles`, counter-clockwise seen from outside) at vertex i, over every vertex.
/// A vertex whose mesh normal or surface normal is undefined counts as 180°.
pub fn normal_deviation(
    surface: &Surface,
    points: &[ChartPoint],
    positions: &[Point3],
    triangles: &[[u32; 3]],
) -> AngleSpread {
    normal_deviation_from(surface, points, &vertex_normals(positions, triangles))
}

/// The mesh's vertex normals (not unit length; zero where the triangles cancel), by Max's weights
/// ("Weights for computing vertex normals from facet normals", 1999): each triangle's corner adds
/// e₁ × e₂ / (|e₁|² |e₂|²) for its two edges from the vertex, which is exact where the vertex and
/// its neighbours lie on a sphere. Area weights are off by the order of the edge length wherever
/// triangle sizes vary (O(1) in the curvature estimated from them: 1.8 instead of 1 on a
/// resolution-32 unit sphere).
pub fn vertex_normals(positions: &[Point3], triangles: &[[u32; 3]]) -> Vec<Vector3> {
    let mut normals = vec![Vector3::zeros(); positions.len()];
    for t in triangles {
        for i in 0..3 {
            let (v, a, b) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            let p = positions[v as usize];
            let (e1, e2) = (positions[a as usize] - p, positions[b as usize] - p);
            let weight = e1.norm_squared() * e2.norm_squared();
            if weight > 0.0 {
                normals[v as usize] += e1.cross(&e2) / weight;
            }
        }
    }
    normals
}

/// The largest |κ| of a principal curvature of a triangle mesh whose vertices carry `normals` (any
/// length, e.g. [`vertex_normals`] or a shape's exact normals), as the 99th percentile over its
/// triangles.
///
/// Each triangle's shape operator is the 2 × 2 symmetric map that best takes its three edges to
/// the changes of the normal along them, by least squares in the triangle's plane (Rusinkiewicz,
/// "Estimating curvatures and their derivatives on triangle meshes", 2004); its largest
/// |eigenvalue| is the triangle's |κ|. With exact normals this converges to the shape's own |κ| as
/// the mesh is refined. A mesh's own normals are off by the order of the edge length where the
/// triangulation is irregular, which is O(1) in κ at single triangles: the 99th percentile, not
/// the largest, keeps those out, while a curved feature (a rim, a tube) covers far more than 1%
/// of the triangles. Triangles without area, or with a vertex whose normal is zero, are skipped.
pub fn mesh_max_principal_curvature(
    positions: &[Point3],
    triangles: &[[u32; 3]],
    normals: &[Vector3],
) -> f64 {
    let mut curvatures: Vec<f64> = triangles
        .iter()
        .filter_map(|t| {
            let p = t.map(|v| positions[v as usize]);
            let n = t.map(|v| normals[v as usize].try_normalize(0.0));
            triangle_max_curvature(p, [n[0]?, n[1]?, n[2]?])
        })
        .collect();
    if curvatures.is_empty() {
        return 0.0;
    }
    let at = ((curvatures.len() - 1) as f64 * 0.99).round() as usize;
    *curvatures.select_nth_unstable_by(at, f64::total_cmp).1
}

/// One triangle's shape operator (see [`mesh_max_principal_curvature`]) and its largest |κ|.
fn triangle_max_curvature(p: [Point3; 3], n: [Vector3; 3]) -> Option<f64> {
    let face = (p[1] - p[0]).cross(&(p[2] - p[0])).try_normalize(0.0)?;
    let u = (p[1] - p[0]).normalize();
    let v = face.cross(&u);
    // S = [[a, b], [b, c]] with S·(e·u, e·v) = (dn·u, dn·v) for each edge e and the normal's change
    // dn along it: six equations in (a, b, c), solved by their normal equations.
    let mut ata = nalgebra::Matrix3::<f64>::zeros();
    let mut atb = nalgebra::Vector3::<f64>::zeros();
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let (e, dn) = (p[k] - p[j], n[k] - n[j]);
        let (eu, ev) = (e.dot(&u), e.dot(&v));
        for (row, rhs) in [
            (nalgebra::Vector3::new(eu, ev, 0.0), dn.dot(&u)),
            (nalgebra::Vector3::new(0.0, eu, ev), dn.dot(&v)),
        ] {
            ata += row * row.transpose();
            atb += row * rhs;
        }
    }
    let [a, b, c]: [f64; 3] = ata.lu().solve(&atb)?.into();
    let (mean, spread) = ((a + c) / 2.0, ((a - c) / 2.0).hypot(b));
    Some(mean.abs() + spread)
}

/// Pairs of triangles of the surface's t × t tessellation that cross (share no vertex or edge and
/// meet, by exact predicates): 0 for an embedded surface, at that resolution.
pub fn tessellation_crossings(surface: &Surface, t: u32) -> Result<usize, EmbeddingError> {
    let (positions, triangles) = tessellated(surface, t)?;
    Ok(mesh::spatial::self_intersections(&positions, &triangles)?.len())
}

/// A triangle mesh as plain arrays: positions and corner indices.
type PlainMesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// The surface's t × t tessellation, evaluated: its vertices' positions and its triangles.
fn tessellated(surface: &Surface, t: u32) -> Result<PlainMesh, EmbeddingError> {
    let tessellation = surface.atlas().tessellate(t, t)?;
    let mut positions = vec![[0.0; 3]; tessellation.vertices.len()];
    evaluate::evaluate(
        surface,
        &tessellation.vertices,
        evaluate::Wants::default(),
        0.0,
        &mut |s: &evaluate::Sample| positions[s.index] = s.position.coords.into(),
    );
    Ok((positions, tessellation.triangles))
}

/// The two-sided Hausdorff distance between the surface's t × t tessellation (mesh a) and a mesh
/// (b: `positions`, `triangles`), sampled as [`mesh::spatial::hausdorff`] does: how far a fit
/// strays from the mesh it was fitted to, and the mesh from it, between the vertices as well as at
/// them (the fit's residual sees only the vertices).
pub fn hausdorff_to_mesh(
    surface: &Surface,
    t: u32,
    positions: &[Point3],
    triangles: &[[u32; 3]],
) -> Result<mesh::spatial::Hausdorff, EmbeddingError> {
    let input: Vec<[f64; 3]> = positions.iter().map(|p| p.coords.into()).collect();
    hausdorff_between(&tessellated(surface, t)?, &input, triangles)
}

/// [`mesh::spatial::hausdorff`] between a tessellation and a mesh as plain arrays.
fn hausdorff_between(
    (surface_positions, surface_triangles): &PlainMesh,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<mesh::spatial::Hausdorff, EmbeddingError> {
    let a = mesh::spatial::MeshRef {
        positions: surface_positions,
        triangles: surface_triangles,
    };
    let b = mesh::spatial::MeshRef {
        positions,
        triangles,
    };
    Ok(mesh::spatial::hausdorff(a, b)?)
}

/// [`hausdorff_to_mesh`] on a tessellation fine enough to measure the surface by (t_e = t_r from
/// `coarsest`, doubling up to `finest`): its edges (95th percentile) no longer than the mesh's
/// median edge. Returns the distance and the t it was measured at. A coarser tessellation measures
/// its own chords: a map that stretches the surface one way (a tube 12 times longer than round on
/// the square torus) gives the tessellation edges 12 times longer along the tube than round it.
/// CGAL's `knot.off` fitted read 0.99% at 32, 0.53% at 64 and 0.445% at 128 (its 95th-percentile
/// edge 0.035, 0.0176: the mesh's median is 0.036), against 0.43% on a tessellation to 0.1% of
/// the diagonal. Edges halve as t doubles, so the choice is made on the coarsest alone; finer
/// ones stop within [`DISTANCE_VERTEX_BUDGET`] vertices.
pub fn hausdorff_to_mesh_resolved(
    surface: &Surface,
    positions: &[Point3],
    triangles: &[[u32; 3]],
    coarsest: u32,
    finest: u32,
) -> Result<(mesh::spatial::Hausdorff, u32), EmbeddingError> {
    let coarse = tessellated(surface, coarsest)?;
    let input: Vec<[f64; 3]> = positions.iter().map(|p| p.coords.into()).collect();
    let mut t = coarsest;
    if let (Some(mut longest), Some(median)) = (
        quantile(edge_lengths(&coarse.0, &coarse.1), 0.95),
        quantile(edge_lengths(&input, triangles), 0.5),
    ) {
        // The tessellation's vertices grow as t².
        let vertices_at =
            |t: u32| coarse.0.len() as f64 * (f64::from(t) / f64::from(coarsest)).powi(2);
        while t < finest && longest > median && vertices_at(2 * t) <= DISTANCE_VERTEX_BUDGET {
            t *= 2;
            longest /= 2.0;
        }
    }
    let tessellation = if t == coarsest {
        coarse
    } else {
        tessellated(surface, t)?
    };
    Ok((hausdorff_between(&tessellation, &input, triangles)?, t))
}

/// The most vertices [`hausdorff_to_mesh_resolved`] lets the tessellation have (genus 1 at 128
/// has 163 000; a plate of genus 10 at 64, 230 000, stays at 32).
pub const DISTANCE_VERTEX_BUDGET: f64 = 200_000.0;

/// The length of every triangle's every edge (shared edges twice).
fn edge_lengths(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<f64> {
    let at = |v: u32| Point3::from(positions[v as usize]);
    triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (at(a) - at(b)).norm())
        .collect()
}

/// The `q` quantile of `values` (nearest rank), or `None` for none.
fn quantile(mut values: Vec<f64>, q: f64) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    sorted_quantile(&values, q)
}

/// The `q` quantile (nearest rank) of values sorted ascending, or `None` for none.
fn sorted_quantile(sorted: &[f64], q: f64) -> Option<f64> {
    let last = sorted.len().checked_sub(1)?;
    Some(sorted[(last as f64 * q).round() as usize])
}

/// The tessellations whose triangles must not cross (t_e = t_r), tried in turn until one has no
/// crossings ([`crossings_until_clear`]). Coarse triangles cut across rims: at
/// 16 a genus-10 plate's cross in 15 pairs and a genus-16 plate's in 598, at 32 the genus-16
/// plate's in 36 and at 48 none, and the surface is embedded. A surface that crosses itself
/// keeps its crossings at 64. (Genus 16: 1.7 s at 32, 3.9 s at 48, 6.9 s at 64.)
pub const INTERSECTION_SAMPLES: [u32; 3] = [32, 48, 64];

/// [`tessellation_crossings`] at each resolution of `ts` in turn (coarse to fine), up to the first
/// without crossings: (t, crossing pairs) for each one checked. Crossings that go away under
/// refinement are the tessellation's, where a chord of a rim cuts through the triangles across
/// it (a genus-16 plate at grid 32: 36 pairs at t = 32, none at 48, 64 or 96); the surface's own
/// persist (a genus-32 plate whose outer rim crumples: 999 pairs at 32, 2058 at 64). The surface
/// is embedded, as far as these resolutions tell, when the last count is 0.
pub fn crossings_until_clear(
    surface: &Surface,
    ts: &[u32],
) -> Result<Vec<(u32, usize)>, EmbeddingError> {
    let mut checked = Vec::with_capacity(ts.len());
    for &t in ts {
        let pairs = tessellation_crossings(surface, t)?;
        checked.push((t, pairs));
        if pairs == 0 {
            break;
        }
    }
    Ok(checked)
}

/// The angle between the surface's normal at `points[i]` and `normals[i]` (any length; e.g. the
/// intended shape's exact normals, which [`crate::holed::HoledMesh`] knows), over every point. A
/// point whose normal is undefined, on either side, counts as 180°.
pub fn normal_deviation_from(
    surface: &Surface,
    points: &[ChartPoint],
    normals: &[Vector3],
) -> AngleSpread {
    let mut angles = vec![180.0; points.len().min(normals.len())];
    evaluate::evaluate(
        surface,
        &points[..angles.len()],
        evaluate::Wants::default(),
        0.0,
        &mut |s: &evaluate::Sample| {
            let (m, n) = (normals[s.index], s.normal);
            if let Some(n) = n
                && m.norm() > 0.0
            {
                angles[s.index] = n.angle(&m).to_degrees();
            }
        },
    );
    AngleSpread::of(angles)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weighted quantile is the nearest rank's where the weights are equal, follows a heavy
    /// weight, and ignores the order the values come in.
    #[test]
    fn weighted_quantiles_follow_the_weights() {
        let values = [5.0, 1.0, 4.0, 2.0, 3.0];
        let equal = [1.0; 5];
        assert_eq!(weighted_quantile(&values, &equal, 0.5), 3.0);
        assert_eq!(weighted_quantile(&values, &equal, 0.9), 5.0);
        assert_eq!(weighted_quantile(&values, &equal, 0.0), 1.0);
        // Most of the weight on 2: it is the median and the 70th percentile.
        let heavy = [1.0, 1.0, 1.0, 10.0, 1.0];
        assert_eq!(weighted_quantile(&values, &heavy, 0.5), 2.0);
        assert_eq!(weighted_quantile(&values, &heavy, 0.7), 2.0);
        assert_eq!(weighted_quantile(&values, &heavy, 0.95), 5.0);
    }

    /// The unit cube in twelve triangles: its twelve edges are sharp (90°), its six face diagonals
    /// are not; and the distance to them is the distance to the cube's edges, at random points
    /// inside and around it.
    #[test]
    fn a_cubes_sharp_edges_are_its_twelve_and_their_distance_is_exact() {
        let corners: Vec<Point3> = (0..8)
            .map(|i| Point3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles: Vec<[u32; 3]> = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        let sharp = SharpEdges::of(&corners, &triangles);
        assert_eq!(sharp.len(), 12);
        assert_eq!(
            SharpEdges::default().distance(Point3::origin()),
            f64::INFINITY
        );
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut random = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            let p = Point3::new(
                2.0 * random() - 0.5,
                2.0 * random() - 0.5,
                2.0 * random() - 0.5,
            );
            // An edge along axis k at the other two coordinates' values a, b ∈ {0, 1}: the
            // distance in the other two coordinates, and along k beyond the segment's ends.
            let mut expected = f64::INFINITY;
            for k in 0..3 {
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                let along = (p[k] - p[k].clamp(0.0, 1.0)).abs();
                for (a, b) in [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)] {
                    let d = (p[i] - a).hypot(p[j] - b).hypot(along);
                    expected = expected.min(d);
                }
            }
            let got = sharp.distance(p);
            assert!(
                (got - expected).abs() < 1e-12,
                "{p}: {got} against {expected}"
            );
        }
    }
}
