//! Brushes defined on the surface: how far an edit reaches is a radius in model units around the
//! picked point, with a falloff profile, whatever the charts and the fit's distortion there.
//!
//! A grab brush moves each surface point x by Δ · f(|x − c| / R): the falloff f of its distance from
//! the brush's centre c, in model space. That field is not a spline, so the brush moves the control
//! points by the least-squares spline nearest to it: per control point a share β_c of Δ (the field
//! is linear in Δ, so the shares are computed once per press), fitted over the surface's brush
//! samples ([`SurfaceSamples`]: a tessellation of its own, about 4 vertices per control point and
//! 25 000 at least, whatever the viewer shows) that the moving control points reach, each weighted by its area, so
//! that dense and sparse parts of the tessellation count alike. The moving control points are those
//! with a weight of at least 1e-3 at some sample inside the disc; the others' influence lies
//! outside it. The unknowns are few (one per moving control point), so the normal equations are
//! formed and solved by a dense Cholesky factorization. Samples beyond the radius that those
//! control points reach are in the fit with target 0, which keeps the edit inside the brush. The
//! dragged point and the pins are then made exact by the minimum-norm correction of
//! [`crate::edit`].
//!
//! The fit has two more kinds of rows, as the initial fit does: each chart's own patch is fitted to
//! the field as well, weighted by its blend (else patches disagree in the overlaps and ripple), and
//! the second differences of the shares over each chart's grid are kept small (fairness, so a steep
//! profile such as a dome's rim does not ring). What a spline of the model's grid can show sets a
//! floor on the radius: on the genus-2 plate at grid 32 footprints match the falloff from 0.12 of
//! the model's size in every chart (at grid 16 only from 0.2, and from 0.12 in the edge charts);
//! below that the bump comes out wider and lower, and the correction still takes the dragged point
//! to its target.
//!
//! Because the fit sees only model-space distances and surface samples, the same brush at the
//! same surface point gives the same shares whichever chart the point was picked in, and footprints
//! of the same width in every chart; and because the samples are the surface's, not the view's,
//! the same edit at any display resolution, mirror-symmetric on a symmetric surface whether or not
//! the view's tessellation is.
//!
//! The stroke brushes ([`dab`]) use the same least-squares problem (`Reach`) with other fields:
//! inflate along the outward normal, flatten towards a plane; smooth is an implicit fairing step
//! of the control grids instead. With [`Symmetry`] the brush acts at the centre's mirror images
//! too, in one solve.

mod samples;

pub use samples::{MIN_SAMPLES, SAMPLES_PER_CONTROL_POINT, SurfaceSamples};

use charts::ChartPoint;
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use num_complex::Complex64;

use crate::EmbeddingError;
use crate::spline_surface::ControlId;
use crate::stencil::{ColumnIndex, Stencil, mark_windows_holding, set_bits};
use crate::surface::{Layout, Point3, Vector3};

/// Weight of the patch terms against the blended surface's (the initial fit's default).
const PATCH_WEIGHT: f64 = 1.0;

/// Weight of the fairness rows (second differences of the shares; the data rows have mean weight
/// 1). Chosen by looking at a dome brush on the default model: 0.03 left ripples at the rim, 0.1
/// few, 0.3 fewer but a softer footprint (measured in `embedding/tests/edit.rs`).
const FAIRNESS: f64 = 0.1;

/// How a brush's effect fades from its centre (s = 0) to its radius (s = 1); nothing beyond.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Falloff {
    /// (1 − s²)³: flat at the centre and at the rim, a soft round bump.
    #[default]
    Smooth,
    /// √(1 − s²): a hemisphere's profile, a full dome.
    Dome,
    /// (1 − s)²: a pointed tip with a soft rim.
    Sharp,
    /// 1 inside the radius: the whole disc moves together.
    Constant,
}

impl Falloff {
    /// The profile at s = distance / radius (0 for s ≥ 1).
    pub fn at(self, s: f64) -> f64 {
        if !(0.0..1.0).contains(&s) {
            return if s < 0.0 { 1.0 } else { 0.0 };
        }
        match self {
            Falloff::Smooth => (1.0 - s * s).powi(3),
            Falloff::Dome => (1.0 - s * s).sqrt(),
            Falloff::Sharp => (1.0 - s).powi(2),
            Falloff::Constant => 1.0,
        }
    }
}

/// What a brush does to the surface under it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BrushKind {
    /// Drags the surface with the picked point (the editor's drag; see [`grab_shares`]).
    #[default]
    Grab,
    /// Pushes the surface out along its normal (a negative strength pulls it in: deflate).
    Inflate,
    /// Fairs the surface: one implicit step that lowers the thin-plate energy of the control
    /// grids under the brush, the centre free to move and the rim held (see [`dab`]): bumps sink,
    /// dents rise, ripples go, the bending energy goes down.
    Smooth,
    /// Moves the surface towards the plane through the brush's area (its weighted centroid, with
    /// the weighted mean normal).
    Flatten,
}

impl BrushKind {
    /// The name the command line and the panel use.
    pub fn name(self) -> &'static str {
        match self {
            BrushKind::Grab => "grab",
            BrushKind::Inflate => "inflate",
            BrushKind::Smooth => "smooth",
            BrushKind::Flatten => "flatten",
        }
    }

    /// Whether the brush acts on every step of a stroke (all but grab, which follows the pointer).
    pub fn is_stroke(self) -> bool {
        self != BrushKind::Grab
    }
}

/// One dab of a stroke brush: the kind, the radius (model units), the profile and the strength
/// (1: a full step; see [`dab`]; negative inflates inwards).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brush {
    pub kind: BrushKind,
    pub radius: f64,
    pub falloff: Falloff,
    pub strength: f64,
}

/// How far one dab of strength 1 moves the centre of an inflate brush, as a fraction of the
/// radius.
const STEP: f64 = 0.1;

/// Weight of a smooth dab's fairness rows against its data rows (which weigh about 2 per vertex
/// reached, times their stiffness): a full-strength dab removes most of a bump of the brush's
/// size in one step (measured in `tests/editor.rs`).
const SMOOTH_FAIRNESS: f64 = 48.0;

/// Mirror planes through the origin: the X plane (x ↦ −x), Y and Z, in any combination.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Symmetry {
    pub x: bool,
    pub y: bool,
    pub z: bool,
}

impl Symmetry {
    /// The mirror images to act on as well as the identity: every product of the chosen
    /// reflections, as the signs they put on x, y and z (the identity first).
    pub fn images(self) -> Vec<Vector3> {
        let mut images = vec![Vector3::new(1.0, 1.0, 1.0)];
        for (on, axis) in [(self.x, 0), (self.y, 1), (self.z, 2)] {
            if on {
                let flipped: Vec<Vector3> = images
                    .iter()
                    .map(|s| {
                        let mut s = *s;
                        s[axis] = -s[axis];
                        s
                    })
                    .collect();
                images.extend(flipped);
            }
        }
        images
    }

    pub fn is_empty(self) -> bool {
        !(self.x || self.y || self.z)
    }

    /// The part of a grab's displacement `delta` that a point at `at` follows under this
    /// symmetry, for a brush of `radius` and `falloff` (radius 0: the paper's edit, where only a
    /// point closer than `tolerance` to a plane counts as on it).
    ///
    /// A grab pulls the point by Δ and each mirror image by the mirrored Δ, so along an axis a
    /// plane flips, the two move in opposite ways, and near the plane they are close:
    /// - the brush's own field ([`grab_shares_mirrored`]: the images' falloffs, shared where
    ///   they overlap) moves the point by Σ_k w_k s_k ⊙ Δ, which near a plane is across it a
    ///   small part of what it is along it; the point follows that ratio of Δ across the plane
    ///   (and Δ along it), so the exact constraint does not fight the field (it tore the surface into ripples at the control spacing). Beyond
    ///   a radius from every image that is Δ itself; on a plane, 0 across it;
    /// - towards the plane the two would meet and fold the surface between them: the point stops
    ///   at half its distance from the plane, or R/2 from it if that is nearer the plane.
    ///
    /// The result is as symmetric as the surface (a sculpting tool's two mirrored brushes cancel
    /// across the plane likewise).
    pub fn limit_grab(
        self,
        at: Point3,
        delta: Vector3,
        radius: f64,
        falloff: Falloff,
        tolerance: f64,
    ) -> Vector3 {
        let images = self.images();
        let share: Vector3 = if radius > 0.0 {
            let centres: Vec<(Point3, Vector3)> = images
                .iter()
                .map(|&s| (Point3::from(at.coords.component_mul(&s)), s))
                .collect();
            // The field's motion across each plane relative to its motion along it.
            let (across, along) = ImageField::new(&centres, radius, falloff)
                .weights(at)
                .fold((Vector3::zeros(), 0.0), |(v, total), (k, w)| {
                    (v + centres[k].1 * w, total + w)
                });
            across / along
        } else {
            let mut share = Vector3::new(1.0, 1.0, 1.0);
            for signs in images.iter().skip(1) {
                let apart = (at.coords - at.coords.component_mul(signs)).norm();
                if apart <= tolerance {
                    share = share.zip_map(signs, |v, s| if s < 0.0 { 0.0 } else { v });
                }
            }
            share
        };
        let mut limited = delta.component_mul(&share);
        let chosen = [self.x, self.y, self.z];
        for axis in (0..3).filter(|&a| chosen[a]) {
            let (x, d) = (at[axis], limited[axis]);
            if x * d < 0.0 {
                // Towards the plane: at most to the stopping distance from it.
                let stop = 0.5 * x.abs().min(radius);
                limited[axis] = d.signum() * d.abs().min(x.abs() - stop);
            }
        }
        limited
    }
}

/// The tessellation a brush is fitted over: the surface's layout and control points, the vertices
/// (as chart points), their stencil and its column index, their current positions, tangents and
/// areas (a third of the triangles' around each), and which way the normal S_u × S_v points (+1
/// outwards, −1 inwards: [`outward`]).
pub struct BrushSamples<'a> {
    pub layout: Layout<'a>,
    pub control: &'a [Point3],
    pub points: &'a [ChartPoint],
    pub stencil: &'a Stencil,
    pub columns: &'a ColumnIndex,
    pub positions: &'a [Point3],
    pub tangents: &'a [[Vector3; 2]],
    pub areas: &'a [f64],
    pub outward: f64,
}

/// +1 where S_u × S_v points out of the closed surface, −1 where in: the sign of the enclosed
/// volume ∫ x·n dA / 3 over the tessellation.
pub fn outward(positions: &[Point3], tangents: &[[Vector3; 2]], areas: &[f64]) -> f64 {
    let volume: f64 = positions
        .iter()
        .zip(tangents)
        .zip(areas)
        .map(|((p, t), a)| a * p.coords.dot(&unit_normal(*t)))
        .sum();
    if volume < 0.0 { -1.0 } else { 1.0 }
}

/// A grab brush of `radius` (model units) centred at `centre` with profile `falloff`: each control
/// point that moves, with its share β of the displacement (sorted by control point). Empty when no
/// sample lies within the radius.
pub fn grab_shares(
    samples: &BrushSamples,
    centre: Point3,
    radius: f64,
    falloff: Falloff,
) -> Result<Vec<(ControlId, f64)>, EmbeddingError> {
    let Some(reach) = Reach::new(samples, &[centre], radius)? else {
        return Ok(Vec::new());
    };
    let targets: Vec<f64> = reach
        .samples
        .iter()
        .map(|&r| falloff.at((samples.positions[r as usize] - centre).norm() / radius))
        .collect();
    reach.fit(&samples.layout, &targets)
}

/// A grab brush with mirror images: the centres (the picked point and its mirror images found on
/// the surface, in [`Symmetry::images`]'s order) and for each control point that moves, its share
/// of the displacement per axis: ΔP_c = share ⊙ Δ (the images move by the mirrored Δ, so along each
/// axis the change is still a multiple of Δ's component). Where images' discs overlap they share
/// the motion (see `ImageField`), so a point on a mirror plane moves once, and the picked point
/// moves by Δ (limited as [`Symmetry::limit_grab`] says).
pub fn grab_shares_mirrored(
    samples: &BrushSamples,
    centres: &[(Point3, Vector3)],
    radius: f64,
    falloff: Falloff,
) -> Result<Vec<(ControlId, Vector3)>, EmbeddingError> {
    let only: Vec<Point3> = centres.iter().map(|c| c.0).collect();
    let Some(reach) = Reach::new(samples, &only, radius)? else {
        return Ok(Vec::new());
    };
    let field = ImageField::new(centres, radius, falloff);
    let targets: Vec<Vector3> = reach
        .samples
        .iter()
        .map(|&r| {
            field
                .weights(samples.positions[r as usize])
                .map(|(k, w)| centres[k].1 * w)
                .sum()
        })
        .collect();
    reach.fit(&samples.layout, &targets)
}

/// The brush's field where mirror images of it overlap: each image's weight at a point x.
///
/// Where only one image's disc reaches x, its falloff f. Where two images' discs do, together they
/// move x by T = U(f_j, f_k; g), with g = |c_j − c_k| / 2R (at most 1) saying how far apart the
/// discs are and U(a, b; g) the larger root of z² − (a + b) z + (1 − g²) a b = 0:
/// - where the discs only touch (g = 1), the sum a + b (the images act apart);
/// - where they coincide (g = 0), the larger falloff (the images act as one brush);
/// - in between at least the larger falloff and at most the sum, so the field never dips between
///   the images; and smooth wherever a disc reaches, a falloff that fades smoothly to 0 at its rim
///   fading out of T as smoothly (U(a, b) ≈ a + g² b for small b).
///
/// With several planes the images are combined a plane at a time: each image with its mirror
/// image in the X plane, then those pairs with theirs in the Y plane, then Z. Images a caller left
/// out (the editor leaves out those that fall on an earlier one, for a point on a plane) count as
/// the one they fall on. T is shared among the images in proportion to their falloffs, and the
/// whole field is divided by T at the first centre (the picked point): an image's disc that
/// reaches the picked point raises T there above 1, and the picked point is to move by Δ exactly,
/// as [`Symmetry::limit_grab`] has it, so that the edit's correction has nothing to add.
///
/// (What this replaces: Σ f² / Σ f, which dips between two discs, to 2(√2 − 1) of the larger
/// falloff, so a grab 0.1–0.3 R off a plane came out with two crests and a spike at the picked
/// point; before that, the falloffs divided by their sum where it passed 1, which put a kink in
/// the field there.)
struct ImageField<'a> {
    centres: &'a [(Point3, Vector3)],
    radius: f64,
    falloff: Falloff,
    /// 1 / T at the first centre.
    scale: f64,
}

impl<'a> ImageField<'a> {
    fn new(centres: &'a [(Point3, Vector3)], radius: f64, falloff: Falloff) -> Self {
        let mut field = ImageField {
            centres,
            radius,
            falloff,
            scale: 1.0,
        };
        if let Some(&(first, _)) = centres.first() {
            let total = field.total(&field.falloffs(first));
            if total > 0.0 {
                field.scale = 1.0 / total;
            }
        }
        field
    }

    /// Each image's falloff at x.
    fn falloffs(&self, x: Point3) -> Vec<f64> {
        self.centres
            .iter()
            .map(|(c, _)| self.falloff.at((x - c).norm() / self.radius))
            .collect()
    }

    /// U(a, b; g) for discs whose centres are `p` and `q`.
    fn union(&self, (a, p): (f64, Point3), (b, q): (f64, Point3)) -> f64 {
        let g = ((p - q).norm() / (2.0 * self.radius)).min(1.0);
        0.5 * (a + b) + (0.5 * (a - b)).hypot(g * (a * b).sqrt())
    }

    /// T: how far the images together move a point with these falloffs. Each image has a slot
    /// by the planes its signs flip (bit 0: X, 1: Y, 2: Z); the slots are merged a plane at a time.
    fn total(&self, f: &[f64]) -> f64 {
        let mut slots: [Option<(f64, Point3)>; 8] = [None; 8];
        for (&(centre, signs), &f) in self.centres.iter().zip(f) {
            let slot = (0..3)
                .filter(|&a| signs[a] < 0.0)
                .map(|a| 1 << a)
                .sum::<usize>();
            slots[slot] = Some(match slots[slot] {
                Some(there) => (self.union(there, (f, centre)), there.1),
                None => (f, centre),
            });
        }
        for plane in [1, 2, 4] {
            for slot in (0..8).filter(|s| s & plane == 0) {
                slots[slot] = match (slots[slot], slots[slot | plane].take()) {
                    (Some(a), Some(b)) => Some((self.union(a, b), a.1)),
                    (a, b) => a.or(b),
                };
            }
        }
        slots[0].map_or(0.0, |(t, _)| t)
    }

    /// Each reaching image's weight at x.
    fn weights(&self, x: Point3) -> impl Iterator<Item = (usize, f64)> + use<> {
        let f = self.falloffs(x);
        let sum: f64 = f.iter().sum();
        let share = if sum > 0.0 {
            self.total(&f) * self.scale / sum
        } else {
            0.0
        };
        f.into_iter()
            .enumerate()
            .map(move |(k, f)| (k, f * share))
            .filter(|&(_, w)| w > 0.0)
    }
}

/// S_u × S_v made a unit vector.
fn unit_normal([u, v]: [Vector3; 2]) -> Vector3 {
    u.cross(&v).normalize()
}

/// One dab of a stroke brush at `centres` (the brush's centre on the surface, then its mirror
/// images with their signs, as for [`grab_shares_mirrored`]): how far each moving control point
/// goes. Inflate and flatten have a field — inflate: strength · 0.1 · R along the outward
/// normal; flatten: strength times the way to the plane — faded by the falloff and fitted by the
/// spline nearest to it, as the grab brush's is. Smooth is one implicit fairing step: the moving
/// control points minimise the thin-plate energy of their control grids (second differences,
/// the points outside the brush held) plus each sample's displacement squared times its
/// stiffness (1/(strength · falloff) − 1: free at a full-strength centre, held at the rim), so
/// the grids' bending energy can only go down. Grab has no dab (it follows the pointer).
pub fn dab(
    samples: &BrushSamples,
    brush: Brush,
    centres: &[(Point3, Vector3)],
) -> Result<Vec<(ControlId, Vector3)>, EmbeddingError> {
    let Brush {
        kind,
        radius,
        falloff,
        strength,
    } = brush;
    if kind == BrushKind::Grab {
        return Err(EmbeddingError::NoDab(kind.name()));
    }
    let only: Vec<Point3> = centres.iter().map(|c| c.0).collect();
    let Some(reach) = Reach::new(samples, &only, radius)? else {
        return Ok(Vec::new());
    };
    // The images' weights at a vertex, summed (1 at the brush's centre; see `ImageField`).
    let images = ImageField::new(centres, radius, falloff);
    let weight = |x: Point3| -> f64 { images.weights(x).map(|(_, w)| w).sum() };
    let field: Box<dyn Fn(usize) -> Vector3> = match kind {
        BrushKind::Grab => return Err(EmbeddingError::NoDab(kind.name())),
        BrushKind::Smooth => {
            // How firmly each sample holds its place: 1/(s·w) − 1 for strength s and weight w
            // (so the centre of a full-strength brush is free and the rim held), never below 0.
            let stiffness: Vec<f64> = reach
                .samples
                .iter()
                .map(|&r| {
                    let s = (strength.abs() * weight(samples.positions[r as usize])).min(1.0);
                    (1.0 - s) / (s + 1e-3)
                })
                .collect();
            return reach.fair(samples, &stiffness);
        }
        BrushKind::Inflate => Box::new(move |r| {
            unit_normal(samples.tangents[r])
                * (samples.outward * strength * STEP * radius * weight(samples.positions[r]))
        }),
        BrushKind::Flatten => {
            // Only the side that faces the plane's way moves (see `planes`).
            let planes = planes(samples, &reach, centres, radius, falloff);
            Box::new(move |r| {
                let (x, here) = (samples.positions[r], unit_normal(samples.tangents[r]));
                images
                    .weights(x)
                    .map(|(k, w)| {
                        let (c, n) = planes[k];
                        let facing = here.dot(&n).max(0.0);
                        n * ((c - x.coords).dot(&n) * strength * w * facing)
                    })
                    .sum()
            })
        }
    };
    let targets: Vec<Vector3> = reach.samples.iter().map(|&r| field(r as usize)).collect();
    reach.fit(&samples.layout, &targets)
}

/// For each centre, the plane a flatten brush pulls towards: through the falloff- and
/// area-weighted centroid of the vertices within the radius that face the way the surface faces at
/// the centre (a radius wider than a thin part's thickness reaches its far side, which is not
/// flattened onto the near one), facing their weighted mean normal.
fn planes(
    samples: &BrushSamples,
    reach: &Reach,
    centres: &[(Point3, Vector3)],
    radius: f64,
    falloff: Falloff,
) -> Vec<(Vector3, Vector3)> {
    let unit = |r: usize| unit_normal(samples.tangents[r]);
    centres
        .iter()
        .map(|(c, _)| {
            let nearest = reach.inside.iter().map(|&r| r as usize).min_by(|&a, &b| {
                (samples.positions[a] - c)
                    .norm()
                    .total_cmp(&(samples.positions[b] - c).norm())
            });
            let facing = nearest.map_or_else(Vector3::z, unit);
            let (mut sum, mut normal, mut total) = (Vector3::zeros(), Vector3::zeros(), 0.0);
            for &r in &reach.inside {
                let r = r as usize;
                let n = unit(r);
                let w = samples.areas[r]
                    * falloff.at((samples.positions[r] - c).norm() / radius)
                    * n.dot(&facing).max(0.0);
                if w > 0.0 {
                    sum += samples.positions[r].coords * w;
                    normal += n * w;
                    total += w;
                }
            }
            let n = normal.try_normalize(1e-300).unwrap_or(facing);
            (sum / total.max(f64::MIN_POSITIVE), n)
        })
        .collect()
}

/// The surface point nearest to `q`, found by Gauss–Newton from `start` (a point near it, e.g. the
/// nearest tessellation vertex), changing to a deeper chart whenever a step nears the current
/// one's border. For mirror images "found on the surface".
pub fn nearest_on_surface(
    layout: &Layout,
    control: &[Point3],
    start: ChartPoint,
    q: Point3,
) -> ChartPoint {
    let atlas = layout.atlas();
    let mut p = start;
    for _ in 0..30 {
        let jet = layout.eval(control, p);
        let r = q - jet.pos;
        let (a, b, c) = (
            jet.du.dot(&jet.du),
            jet.du.dot(&jet.dv),
            jet.dv.dot(&jet.dv),
        );
        let (g1, g2) = (jet.du.dot(&r), jet.dv.dot(&r));
        let det = a * c - b * b;
        if det.abs() < 1e-300 {
            break;
        }
        let step = Complex64::new((c * g1 - b * g2) / det, (a * g2 - b * g1) / det);
        let next = ChartPoint::new(p.chart, p.coords + step);
        let Ok(chart) = atlas.chart(p.chart) else {
            break;
        };
        if chart.domain().margin(next.coords) <= 0.05 {
            // Near the border: carry on in the chart where the point lies deepest.
            let here = atlas.locate_unchecked(p);
            let best = here
                .representations()
                .iter()
                .copied()
                .max_by(|x, y| {
                    let m = |z: &ChartPoint| {
                        atlas
                            .chart(z.chart)
                            .map_or(f64::NEG_INFINITY, |ch| ch.domain().margin(z.coords))
                    };
                    m(x).total_cmp(&m(y))
                })
                .unwrap_or(p);
            if best.chart == p.chart {
                break;
            }
            p = best;
            continue;
        }
        p = next;
        if step.norm() < 1e-14 {
            break;
        }
    }
    p
}

/// The least-squares problem of a brush at some centres: the control points that reach the
/// brush's discs, the samples they reach (thinned) and the rows of the normal equations over them.
/// They depend on where the brush is, not on the field it fits, so one factorization serves the
/// three coordinates of a displacement (or a scalar share).
struct Reach {
    /// The moving control points, sorted.
    controls: Vec<u32>,
    /// The samples the fit uses (each with its rows below).
    samples: Vec<u32>,
    /// The samples within the radius of some centre.
    inside: Vec<u32>,
    /// The data rows: the sample they belong to (index into `samples`), their weight and their
    /// entries' range in `entries` (column in `controls`, weight).
    rows: Vec<(u32, f64, std::ops::Range<u32>)>,
    entries: Vec<(u32, f64)>,
}

impl Reach {
    /// None when no vertex lies within `radius` of any centre.
    fn new(
        samples: &BrushSamples,
        centres: &[Point3],
        radius: f64,
    ) -> Result<Option<Reach>, EmbeddingError> {
        let BrushSamples {
            layout,
            stencil,
            columns,
            positions,
            areas,
            ..
        } = samples;
        let (stencil, columns, positions, areas) = (*stencil, *columns, *positions, *areas);
        // The control points that reach the brush's discs, then every vertex they reach.
        let r2 = radius * radius;
        let inside: Vec<u32> = (0..positions.len() as u32)
            .filter(|&r| {
                let p = positions[r as usize];
                centres.iter().any(|c| (p - c).norm_squared() < r2)
            })
            .collect();
        // A bit per control point (few), read out in order: those with a weight of at least
        // MIN_INFLUENCE on some sample inside.
        let mut moving = vec![0u64; layout.control_count().div_ceil(64)];
        for &r in &inside {
            for (c, w) in stencil.row(r as usize) {
                if w[0] >= MIN_INFLUENCE {
                    moving[c as usize / 64] |= 1u64 << (c % 64);
                }
            }
        }
        let controls = set_bits(&moving);
        if controls.is_empty() {
            return Ok(None);
        }
        let reached = stencil.rows_of_controls(columns, controls.iter().map(|&c| c as usize));
        // Where the samples reached are many more than the spline has freedom there, one in k of
        // them (about SAMPLES_PER_CONTROL per moving control point) fits the same field, each
        // standing for k samples' area. Which ones is decided by a hash of |x|, |y|, |z|, not by
        // index: mirror images on a symmetric tessellation are both taken or both left, so a
        // symmetric stroke stays symmetric.
        let stride = reached
            .len()
            .div_ceil(SAMPLES_PER_CONTROL * controls.len())
            .max(1);
        // Below the samples' spacing (the disc holds hundreds of them; samples in one cell are
        // taken or left together), far above how well a surface edited by earlier solves is
        // still mirror-symmetric (to about 1e-9 of its size), so mirror pairs rarely straddle a
        // cell's edge. A quantum of 2⁻³⁰ units, near that, thinned the two sides of a sphere
        // differently once a grab had planned anew (2e-4 of its size apart), R/2¹⁶ still did
        // (9e-6).
        let quantum = radius / 256.0;
        // Each control point's column among the moving ones (u32::MAX: held), by look-up: a
        // binary search per stencil entry took as long as the rest of the dab's fit.
        let mut columns_of = vec![u32::MAX; layout.control_count()];
        for (j, &c) in controls.iter().enumerate() {
            columns_of[c as usize] = j as u32;
        }
        let column = |c: u32| Some(columns_of[c as usize]).filter(|&j| j != u32::MAX);
        let mut reach = Reach {
            samples: reached
                .iter()
                .copied()
                .filter(|&r| {
                    stride == 1
                        || mirror_hash(positions[r as usize], quantum).is_multiple_of(stride as u64)
                })
                .collect(),
            inside,
            rows: Vec::new(),
            entries: Vec::new(),
            controls: Vec::new(),
        };
        // Room for every sample's rows at once (a row and its patches hold at most twice a stencil
        // row's entries): growing by doubling copied megabytes per dab. Pages never written cost
        // nothing.
        let widest = reach
            .samples
            .iter()
            .map(|&r| stencil.row(r as usize).len())
            .max()
            .unwrap_or(0);
        reach.entries.reserve(2 * widest * reach.samples.len());
        reach.rows.reserve(4 * reach.samples.len());
        // Each chart's own patch is fitted too, weighted by its blend (as the initial fit does):
        // the blend alone leaves the patches free to disagree in the overlaps, and they would
        // ripple. A stencil row's entries of chart i are β_i N_c (uniform B-splines sum to 1), so
        // chart i's patch row is those entries over their sum β_i: no second evaluation.
        let grids = layout.grids();
        let chart_of = |c: u32| grids.locate(c as usize).0;
        let mut row = Vec::new();
        for (k, &r) in reach.samples.iter().enumerate() {
            let (r, area) = (r as usize, areas[r as usize]);
            row.clear();
            row.extend(stencil.row(r).map(|(c, w)| (c, w[0])));
            // The blended surface's row.
            let first = reach.entries.len() as u32;
            reach
                .entries
                .extend(row.iter().filter_map(|&(c, w)| Some((column(c)?, w))));
            reach
                .rows
                .push((k as u32, area, first..reach.entries.len() as u32));
            // Per chart (the row is sorted by control point, so by chart).
            for group in row.chunk_by(|a, b| chart_of(a.0) == chart_of(b.0)) {
                let blend: f64 = group.iter().map(|e| e.1).sum();
                if blend <= 1e-12 {
                    continue;
                }
                let first = reach.entries.len() as u32;
                reach.entries.extend(
                    group
                        .iter()
                        .filter_map(|&(c, w)| Some((column(c)?, w / blend))),
                );
                reach.rows.push((
                    k as u32,
                    area * PATCH_WEIGHT * blend,
                    first..reach.entries.len() as u32,
                ));
            }
        }
        // The data rows (blended and patch, about two per vertex reached) as if each had weight 1
        // on average, against fairness rows of weight FAIRNESS²: the second differences of the
        // shares over each chart's control grid, with the control points outside the set held at
        // 0, so steep profiles (a dome's rim) do not ring.
        let total: f64 = reach.rows.iter().map(|r| r.1).sum();
        let scale = 2.0 * reached.len() as f64 / total.max(f64::MIN_POSITIVE);
        for row in &mut reach.rows {
            row.1 *= scale;
        }
        reach.controls = controls;
        Ok(Some(reach))
    }

    /// The normal matrix of the data rows, each weighted by `stiffness` of its sample too, and
    /// of the fairness rows with weight `fairness`; `each_fairness_row(moving entries, whole row)`
    /// sees every fairness row that touches the moving control points.
    fn assemble(
        &self,
        layout: &Layout,
        stiffness: impl Fn(usize) -> f64 + Sync,
        fairness: f64,
        mut each_fairness_row: impl FnMut(&[(usize, f64)], &[(usize, f64)]),
    ) -> Normal {
        let column = |c: u32| self.controls.binary_search(&c).ok();
        let n = self.controls.len();
        // The data rows on all cores, each thread into its own matrix, summed.
        let add_rows = |rows: &[(u32, f64, std::ops::Range<u32>)]| {
            let mut part = Normal::new(n);
            let mut entries = Vec::new();
            for (k, w, range) in rows {
                entries.clear();
                entries.extend(
                    self.entries[range.start as usize..range.end as usize]
                        .iter()
                        .map(|&(j, a)| (j as usize, a)),
                );
                part.add(&entries, w * stiffness(*k as usize));
            }
            part
        };
        let threads = std::thread::available_parallelism()
            .map_or(1, |t| t.get())
            .min(self.rows.len().div_ceil(4096))
            .max(1);
        let per = self.rows.len().div_ceil(threads).max(1);
        let mut system = if threads == 1 {
            add_rows(&self.rows)
        } else {
            let parts: Vec<Normal> = std::thread::scope(|scope| {
                let handles: Vec<_> = self
                    .rows
                    .chunks(per)
                    .map(|chunk| scope.spawn(|| add_rows(chunk)))
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().expect("an assembly thread"))
                    .collect()
            });
            let mut parts = parts.into_iter();
            let mut sum = parts.next().expect("one part at least");
            for part in parts {
                sum.matrix += part.matrix;
            }
            sum
        };
        // Only the rows near the moving control points can touch them: those whose first point
        // lies up to two steps before one of them along each grid direction, each taken once.
        let grids = layout.grids();
        let mut origins = vec![0u64; layout.control_count().div_ceil(64)];
        for &c in &self.controls {
            mark_windows_holding(&mut origins, c as usize, grids, 3);
        }
        let mut entries = Vec::new();
        for o in set_bits(&origins) {
            let (chart, i, j) = grids.locate(o as usize);
            crate::fit::smoothness_rows_at(layout, chart, i, j, |row| {
                entries.clear();
                entries.extend(
                    row.iter()
                        .filter_map(|&(c, w)| Some((column(c as u32)?, w))),
                );
                if !entries.is_empty() {
                    system.add(&entries, fairness);
                    each_fairness_row(&entries, row);
                }
            });
        }
        system
    }

    /// One implicit fairing step (see [`dab`]): the displacements of the moving control points
    /// that minimise the fairness rows' energy of the displaced control points plus Σ stiffness ·
    /// |displacement|² over the samples.
    fn fair(
        &self,
        samples: &BrushSamples,
        stiffness: &[f64],
    ) -> Result<Vec<(ControlId, Vector3)>, EmbeddingError> {
        let n = self.controls.len();
        let mut rhs = Mat::<f64>::zeros(n, 3);
        let system = self.assemble(
            &samples.layout,
            |k| stiffness[k],
            SMOOTH_FAIRNESS,
            |moving, row| {
                let now: Vector3 = row
                    .iter()
                    .map(|&(c, w)| samples.control[c].coords * w)
                    .sum();
                for &(j, a) in moving {
                    for d in 0..3 {
                        rhs[(j, d)] -= SMOOTH_FAIRNESS * a * now[d];
                    }
                }
            },
        );
        let factor = system.factor().ok_or(EmbeddingError::Unsolvable)?;
        let x = factor.solve(&rhs);
        Ok(self
            .controls
            .iter()
            .enumerate()
            .map(|(j, &c)| (ControlId(c), Vector3::new(x[(j, 0)], x[(j, 1)], x[(j, 2)])))
            .filter(|(_, d)| *d != Vector3::zeros() && d.iter().all(|v| v.is_finite()))
            .collect())
    }

    /// The spline displacement nearest to `targets` (one per sample; f64 for shares, Vector3 for
    /// displacements): each moving control point's value, zeros left out.
    fn fit<T: Target>(
        &self,
        layout: &Layout,
        targets: &[T],
    ) -> Result<Vec<(ControlId, T)>, EmbeddingError> {
        let factor = self
            .assemble(layout, |_| 1.0, FAIRNESS * FAIRNESS, |_, _| {})
            .factor()
            .ok_or(EmbeddingError::Unsolvable)?;
        let n = self.controls.len();
        let mut rhs = Mat::<f64>::zeros(n, T::DIM);
        for (k, w, range) in &self.rows {
            let t = targets[*k as usize].components();
            for &(j, a) in &self.entries[range.start as usize..range.end as usize] {
                for (d, t) in t.iter().enumerate().take(T::DIM) {
                    rhs[(j as usize, d)] += w * a * t;
                }
            }
        }
        let x = factor.solve(&rhs);
        Ok(self
            .controls
            .iter()
            .enumerate()
            .map(|(j, &c)| (ControlId(c), T::from_row((0..T::DIM).map(|d| x[(j, d)]))))
            .filter(|(_, t)| !t.is_zero() && t.is_finite())
            .collect())
    }
}

/// What a brush fits: a scalar share or a displacement.
trait Target: Copy {
    const DIM: usize;
    fn components(&self) -> [f64; 3];
    fn from_row(row: impl Iterator<Item = f64>) -> Self;
    fn is_zero(&self) -> bool;
    fn is_finite(&self) -> bool;
}

impl Target for f64 {
    const DIM: usize = 1;
    fn components(&self) -> [f64; 3] {
        [*self, 0.0, 0.0]
    }
    fn from_row(mut row: impl Iterator<Item = f64>) -> f64 {
        row.next().unwrap_or(0.0)
    }
    fn is_zero(&self) -> bool {
        *self == 0.0
    }
    fn is_finite(&self) -> bool {
        f64::is_finite(*self)
    }
}

impl Target for Vector3 {
    const DIM: usize = 3;
    fn components(&self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
    fn from_row(row: impl Iterator<Item = f64>) -> Vector3 {
        Vector3::from_iterator(row)
    }
    fn is_zero(&self) -> bool {
        *self == Vector3::zeros()
    }
    fn is_finite(&self) -> bool {
        self.iter().all(|x| x.is_finite())
    }
}

/// A hash of a point's coordinates' magnitudes, each rounded to a multiple of `quantum`: the same
/// for a point and its mirror images, as long as they are mirror images to well within it.
fn mirror_hash(p: Point3, quantum: f64) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for x in p.iter() {
        let q = (x.abs() / quantum).round() as u64;
        h = (h ^ q).wrapping_mul(0x0000_0100_0000_01b3);
        h ^= h >> 29;
    }
    h
}

/// A control point moves with a brush when its weight at some sample inside the brush's disc is
/// at least this; the others, whose influence lies outside the disc (the far tails of B-splines
/// that only graze it, charts whose blend barely reaches it), stay where they are. Leaving them
/// out halves a dab's unknowns and its factorization's time by five, while the footprints and each
/// brush's effect stay within their tests' bounds (measured in `embedding/tests/edit.rs` and
/// `tests/editor.rs`).
const MIN_INFLUENCE: f64 = 1e-3;

/// Samples per moving control point (about; where there are more, the rest are skipped). 16 and
/// 32 gave the same footprints and brush effects to three digits (`embedding/tests/edit.rs`,
/// `tests/editor.rs`); 16 takes a fifth off a dab at 10⁵ vertices.
const SAMPLES_PER_CONTROL: usize = 16;

/// The normal matrix Σ w aᵢaᵢᵀ of a weighted least-squares problem whose rows are sparse: small
/// (one unknown per moving control point) and dense.
struct Normal {
    matrix: Mat<f64>,
}

impl Normal {
    fn new(n: usize) -> Normal {
        Normal {
            matrix: Mat::zeros(n, n),
        }
    }

    /// Adds the row a with weight w (to the lower triangle: the factorization reads no more).
    /// Column by column, so the inner loop walks down one column of the (column-major) matrix.
    fn add(&mut self, row: &[(usize, f64)], w: f64) {
        for &(j, b) in row {
            let wb = w * b;
            let column = self
                .matrix
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous");
            let column = column.as_slice_mut();
            for &(i, a) in row {
                if i >= j {
                    column[i] += wb * a;
                }
            }
        }
    }

    /// The Cholesky factor (faer's blocked one: several times nalgebra's unblocked speed at the
    /// few hundred unknowns of a dab), with ε² on the diagonal so that control points the samples
    /// cannot tell apart still get a unique (small) value.
    fn factor(mut self) -> Option<faer::linalg::solvers::Llt<f64>> {
        const EPSILON: f64 = 1e-6;
        for i in 0..self.matrix.nrows() {
            self.matrix[(i, i)] += EPSILON * EPSILON;
        }
        self.matrix.llt(Side::Lower).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A grab's displacement limited by [`Symmetry::limit_grab`] moves the point as the
        /// brush's own field does there (each image's falloff, normalised where they overlap),
        /// which pulls it and an image across a plane apart by at most 4|Δ|/R of their distance;
        /// towards a plane it stays on its side, at least half as far from it (or R/2); a point
        /// on a plane moves along it; axes no plane flips, and points a radius or more from every
        /// image moving away, follow Δ.
        #[test]
        fn a_grab_near_a_mirror_plane_neither_tears_nor_folds(
            x in -2.0f64..2.0, y in -2.0f64..2.0, z in -2.0f64..2.0,
            on_plane in any::<bool>(),
            planes in 1u8..8,
            radius in 0.05f64..3.0,
            falloff in prop::sample::select(vec![Falloff::Smooth, Falloff::Dome, Falloff::Sharp, Falloff::Constant]),
            d in prop::array::uniform3(-3.0f64..3.0),
        ) {
            let symmetry = Symmetry { x: planes & 1 != 0, y: planes & 2 != 0, z: planes & 4 != 0 };
            let at = Point3::new(if on_plane { 0.0 } else { x }, y, z);
            let delta = Vector3::from(d);
            let limited = symmetry.limit_grab(at, delta, radius, falloff, 1e-12);
            let images = symmetry.images();
            let far = images.iter().skip(1).all(|s| (at.coords - at.coords.component_mul(s)).norm() >= radius);
            for signs in images.iter().skip(1) {
                let apart = (at.coords - at.coords.component_mul(signs)).norm();
                let pulled = (limited - limited.component_mul(signs)).norm();
                prop_assert!(pulled <= 4.0 * delta.norm() / radius * apart + 1e-9,
                    "{signs:?}: pulled apart by {pulled} at {apart}");
            }
            let chosen = [symmetry.x, symmetry.y, symmetry.z];
            for axis in 0..3 {
                let (x, moved) = (at[axis], limited[axis]);
                if !chosen[axis] {
                    prop_assert!((moved - delta[axis]).abs() <= 1e-12 * delta[axis].abs());
                } else if x == 0.0 {
                    prop_assert_eq!(moved, 0.0);
                } else if x * delta[axis] >= 0.0 {
                    prop_assert!(moved.abs() <= delta[axis].abs() + 1e-12);
                    if far {
                        prop_assert!((moved - delta[axis]).abs() <= 1e-12 * delta[axis].abs());
                    }
                } else {
                    let after = x + moved;
                    prop_assert!(after * x > 0.0, "crossed the plane");
                    prop_assert!(after.abs() >= 0.5 * x.abs().min(radius) - 1e-12);
                }
            }
        }

        /// The images' field (`ImageField`), for a point and its mirror images under 1–3 planes
        /// (those that fall on an earlier one left out, as the editor does), at random points:
        /// together the images move a point at least as far as the largest falloff and at most as
        /// far as their sum (so it never dips between them), by exactly the one falloff where only
        /// one disc reaches and where all the discs coincide; the field is as symmetric as the
        /// images (the same at a point's mirror images, each image's weight carried to its
        /// own); and the picked point moves by exactly Δ.
        #[test]
        fn the_images_field_lies_between_the_largest_falloff_and_the_sum(
            p in prop::array::uniform3(-1.0f64..1.0),
            on_plane in prop::array::uniform3(any::<bool>()),
            planes in 1u8..8,
            radius in 0.05f64..3.0,
            falloff in prop::sample::select(vec![Falloff::Smooth, Falloff::Dome, Falloff::Sharp, Falloff::Constant]),
            xs in prop::collection::vec(prop::array::uniform3(-1.5f64..1.5), 16),
        ) {
            let symmetry = Symmetry { x: planes & 1 != 0, y: planes & 2 != 0, z: planes & 4 != 0 };
            let p = Point3::from(Vector3::from(p).zip_map(&Vector3::from(on_plane.map(|o| !o).map(f64::from)), |a, b| a * b));
            let centres = mirror_centres(symmetry, p);
            let field = ImageField::new(&centres, radius, falloff);
            let first: f64 = field.weights(p).map(|(_, w)| w).sum();
            prop_assert!((first - 1.0).abs() < 1e-12, "the picked point moves by {first} of Δ");
            for x in xs {
                let x = Point3::from(Vector3::from(x));
                let f = field.falloffs(x);
                let total = field.total(&f);
                let (largest, sum) = (f.iter().copied().fold(0.0, f64::max), f.iter().sum::<f64>());
                prop_assert!(total >= largest * (1.0 - 1e-12) && total <= sum * (1.0 + 1e-12),
                    "{total} outside [{largest}, {sum}]");
                if f.iter().filter(|&&f| f > 0.0).count() <= 1 || centres.len() == 1 {
                    prop_assert!((total - largest).abs() <= 1e-12 * largest);
                }
                let weights: Vec<(usize, f64)> = field.weights(x).collect();
                for signs in symmetry.images() {
                    let mirrored = Point3::from(x.coords.component_mul(&signs));
                    let there: Vec<(usize, f64)> = field.weights(mirrored).collect();
                    let total_there = field.total(&field.falloffs(mirrored));
                    prop_assert!((total_there - total).abs() <= 1e-9 * total.max(1e-300),
                        "{total} at x, {total_there} at its image {signs:?}");
                    for &(k, w) in &weights {
                        // The image that x's k-th image's centre becomes under the mirror.
                        let carried = Point3::from(centres[k].0.coords.component_mul(&signs));
                        let j = centres.iter().position(|c| (c.0 - carried).norm() < 1e-9).expect("a group");
                        let w_there = there.iter().find(|t| t.0 == j).map_or(0.0, |t| t.1);
                        prop_assert!((w_there - w).abs() <= 1e-9 * w.max(1.0), "image {k}: {w} against {w_there}");
                    }
                }
            }
        }
    }

    /// The centres a brush at `p` acts at under `symmetry`: `p`, then each mirror image that does
    /// not fall on an earlier one, with its signs (as the editor's `mirror_images`).
    fn mirror_centres(symmetry: Symmetry, p: Point3) -> Vec<(Point3, Vector3)> {
        let mut centres: Vec<(Point3, Vector3)> = Vec::new();
        for signs in symmetry.images() {
            let image = Point3::from(p.coords.component_mul(&signs));
            if centres.iter().all(|c| (c.0 - image).norm() > 1e-12) {
                centres.push((image, signs));
            }
        }
        centres
    }

    /// Two images of a smooth falloff at 0.03–1.9 R apart: where the discs coincide the field is
    /// the one falloff, where they only touch the sum; it has no kink (along the line through the
    /// centres and across it, halving the step leaves the largest second difference within 5%,
    /// where a kink would double it), and between the centres it stays within 5% of the picked
    /// point's 1 up to 0.3 R apart (one bump, not two crests).
    #[test]
    fn two_images_make_one_smooth_bump() {
        let symmetry = Symmetry {
            x: true,
            y: false,
            z: false,
        };
        let coincide = mirror_centres(symmetry, Point3::new(0.0, 0.2, 0.0));
        assert_eq!(coincide.len(), 1);
        let both = [coincide[0], (coincide[0].0, Vector3::new(-1.0, 1.0, 1.0))];
        let field = ImageField::new(&both, 1.0, Falloff::Smooth);
        for s in [0.1, 0.5, 0.9] {
            let x = Point3::new(s, 0.2, 0.0);
            let one = Falloff::Smooth.at(s);
            assert!((field.total(&field.falloffs(x)) - one).abs() < 1e-12);
        }
        let touch = mirror_centres(symmetry, Point3::new(1.0, 0.0, 0.0));
        let field = ImageField::new(&touch, 1.0, Falloff::Smooth);
        let f = [0.3, 0.4];
        assert!((field.total(&f) - 0.7).abs() < 1e-12);

        for apart in [0.03, 0.1, 0.2, 0.4, 0.6, 1.0, 1.5, 1.9] {
            let centres = mirror_centres(symmetry, Point3::new(apart / 2.0, 0.0, 0.0));
            let field = ImageField::new(&centres, 1.0, Falloff::Smooth);
            let value = |x: f64, y: f64| -> f64 {
                field.weights(Point3::new(x, y, 0.0)).map(|(_, w)| w).sum()
            };
            for (along, label) in [(true, "along"), (false, "across")] {
                let largest_second_difference = |h: f64| {
                    (1..(2.0 / h) as usize)
                        .map(|i| {
                            let t = -1.0 + i as f64 * h;
                            let at = |t: f64| if along { value(t, 0.0) } else { value(0.0, t) };
                            ((at(t + h) - 2.0 * at(t) + at(t - h)) / (h * h)).abs()
                        })
                        .fold(0.0, f64::max)
                };
                let (coarse, fine) = (
                    largest_second_difference(0.01),
                    largest_second_difference(0.005),
                );
                assert!(
                    fine < 1.05 * coarse,
                    "{apart} R apart, {label}: {coarse} then {fine}"
                );
            }
            if apart <= 0.6 {
                let lowest = (0..=100)
                    .map(|i| value(-apart / 2.0 + apart * i as f64 / 100.0, 0.0))
                    .fold(f64::INFINITY, f64::min);
                let highest = (0..=100)
                    .map(|i| value(-apart / 2.0 + apart * i as f64 / 100.0, 0.0))
                    .fold(0.0, f64::max);
                assert!(
                    lowest > 0.95 && highest < 1.05,
                    "{apart} R apart: {lowest}..{highest} between the centres"
                );
            }
        }
    }
}
