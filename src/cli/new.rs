//! `ntori new`: the initial model of a genus, fitted to an n-holed mesh, with its checks.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use charts::ChartPoint;
use embedding::fit::{FitSettings, FitStage, InitialFit, default_mesh, initial_model_of};
use embedding::holed::{HoledMesh, PlateLayout};
use embedding::integrals::{CurvatureHistogram, cells_per_knot, surface_integrals_over};
use embedding::{SplineSettings, Surface};
use ntori::io::export::{self, ExportOptions, Format};
use serde::Serialize;

use super::report::{Report, emit};
use super::{FitArgs, FitProgress, GenusArg};

/// Make a new model: a smooth genus-n surface fitted to an n-holed mesh, written as a model file.
///
/// The paper's section 5.1. A genus-n mesh (a round plate with n holes, rims rounded; the sphere for
/// n = 0, the round torus for n = 1) is cut along 2n loops through one vertex into a disk whose
/// boundary reads a₁ b₁ a₁⁻¹ b₁⁻¹ …; Floater's mean value map flattens the disk onto the polygon
/// (in the Klein model, where it is convex), the map is relaxed on the closed surface so it has no
/// seams, and every chart's control points are fitted at once by regularised least squares.
///
/// Prints the fit's checks: folded triangles in the parameterization (0: a bijection), the
/// residual |S(p_i) − P_i| at the mesh vertices as a fraction of the mesh's size, and Gauss–Bonnet
/// (∫K dA from the analytic curvature against 2π(2 − 2n)). If a check fails, no model is written
/// (unless --keep-failed) and the exit status is 3. An existing file is not replaced unless --force
/// is given.
///
/// Also checks the shape, which topology cannot see: how far apart overlapping patches are where
/// both show (a ripple's cause; at most 1% of the diagonal); the largest principal curvature |κ|
/// against the intended shape's own peak, from its closed form (a crease or spike; at most 3×); the
/// angle between the surface's normal and the intended shape's exact normal at the input mesh's
/// vertices (median and 90th percentile; at most 5° at the 90th); and crossing triangles of the
/// t_e = t_r = 32 tessellation, or of 48 or 64 where 32's triangles are too coarse to tell (none).
/// From genus 2 it also reports, unchecked, how flat the plate's flat faces came out: their mean
/// curvature |H| (median, 90th percentile, and that times the half-thickness) and the normals'
/// angle from ±z.
///
/// Examples:
///   ntori new                                 genus 2, written to model.json
///   ntori new --genus 5 -o five.json --grid 16
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    #[command(flatten)]
    genus: GenusArg,
    /// Where to write the model.
    #[arg(short, long, default_value = "model.json", value_name = "FILE")]
    output: PathBuf,
    /// Replace the output file if it exists.
    #[arg(long)]
    force: bool,
    /// Write the model even if a check fails (the exit status is still 3).
    #[arg(long)]
    keep_failed: bool,
    /// Also write the mesh the fit targets (OBJ, PLY, STL, GLB, 3MF or OFF, from the extension),
    /// with each vertex's fitted chart coordinates as UVs, to compare it with the surface (placed
    /// as `ntori export` places it by default).
    #[arg(long, value_name = "FILE")]
    input_mesh: Option<PathBuf>,
    /// Input mesh resolution: points around each hole (around the equator for the sphere)
    /// [default: 48 for the torus, 40 for genus 3 to 16, 32 for the others, or for high
    /// genus nearly the finest within the default budget: 29 at genus 28 and 32, 16 at genus
    /// 48, 10 at genus 64; the rims are sampled twice as finely across up to genus 40].
    #[arg(long, value_name = "R", value_parser = clap::value_parser!(u64).range(8..=1024))]
    resolution: Option<u64>,
    /// Weight of the mesh's edge samples as fit targets besides its vertices: one point of the
    /// intended surface between the ends of each edge (0: none; 1: half the vertices' weight)
    /// [default: 2 for genus 16 to 32, whose charts' cells are as fine as the mesh's spacing and
    /// rippled between its vertices; 0 otherwise]
    #[arg(long, value_name = "W", value_parser = parse_edge_samples)]
    edge_samples: Option<f64>,
    #[command(flatten)]
    spline: FitArgs,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// No progress messages on stderr.
    #[arg(short, long)]
    quiet: bool,
}

/// The largest `--edge-samples` weight: a thousand times the vertices' (beyond it the fit hardly
/// sees them).
const MAX_EDGE_SAMPLES: f64 = 1e3;

pub(super) fn parse_edge_samples(s: &str) -> Result<f64, String> {
    super::parse_weight(s, "the edge samples' weight", MAX_EDGE_SAMPLES)
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        genus: GenusArg { genus },
        output,
        force,
        keep_failed,
        input_mesh,
        resolution,
        edge_samples,
        spline,
        json,
        quiet,
    } = args;
    let (settings, fit) = spline.settings(
        genus,
        embedding::fit::default_grid(genus),
        |grid| embedding::fit::default_disk_grid(genus, grid),
        |grid| embedding::fit::default_plate_smoothness(genus, grid),
        |spline| embedding::fit::plate_agreement(genus, spline),
    )?;
    let fit = FitSettings {
        edge_samples: edge_samples.unwrap_or_else(|| embedding::fit::plate_edge_samples(genus)),
        ..fit.plate_smoothness(genus, settings.grid)
    };
    // Before the fit (seconds to minutes): the directory exists and takes files, the output is no
    // special file, and without --force it does not exist yet.
    ntori::io::atomic::check_new_output(&output, &[], force)?;
    let input_mesh = match input_mesh {
        Some(path) => {
            // `new` has no --format: the mesh's format comes from its name alone.
            let format = Format::from_path(&path).map_err(|_| {
                anyhow::anyhow!(
                    "{} has no known extension (.obj, .ply, .stl, .glb, .3mf, .off): \
                     --input-mesh takes the mesh's format from it",
                    path.display()
                )
            })?;
            ntori::io::atomic::check_new_output(&path, &[&output], force)?;
            Some((path, format))
        }
        None => None,
    };
    let progress = FitProgress::new(quiet);
    let resolution = resolution.map(|r| r as usize);
    let made = make(genus, resolution, settings, fit, &progress);
    progress.finish();
    let Made {
        surface: model,
        report,
        mesh,
        points,
    } = made.with_context(|| format!("cannot make a genus-{genus} model"))?;
    // The input mesh is written whatever the checks say: it is what to compare a failed fit with.
    if let Some((path, format)) = &input_mesh {
        let exported = export::input_mesh(genus, &mesh.positions, &mesh.triangles, &points)?;
        // Placed as `ntori export` places the surface by default, so the two can be compared.
        let options = ExportOptions {
            name: Some(format!("ntori genus-{genus} input mesh")),
            ..ExportOptions::default()
        };
        export::write(&exported, path, *format, &options)?;
        if !quiet && !json {
            eprintln!("ntori: wrote the input mesh to {}", path.display());
        }
    }
    // A model that fails its checks is not what was asked for: unless the user wants it anyway,
    // nothing replaces the output or takes its place.
    let written = report.passed || keep_failed;
    if written && force {
        ntori::io::model_file::save(&output, &model)?;
    } else if written {
        // Exclusive: a file created at the output during the fit is kept, not replaced.
        ntori::io::model_file::save_new(&output, &model)?;
    }
    emit(
        &Written {
            report: &report,
            output: &output,
            written,
        },
        json,
    )
}

/// The report once the model is saved: as text it also says where the model went; as JSON it is
/// the report alone.
#[derive(Serialize)]
#[serde(transparent)]
struct Written<'a> {
    report: &'a NewReport,
    #[serde(skip)]
    output: &'a Path,
    #[serde(skip)]
    written: bool,
}

impl Report for Written<'_> {
    fn passed(&self) -> bool {
        self.report.passed
    }

    fn to_text(&self) -> String {
        let outcome = if self.written {
            format!("wrote {}\n", self.output.display())
        } else {
            format!(
                "not written to {}: a check failed (--keep-failed writes it anyway)\n",
                self.output.display()
            )
        };
        self.report.to_text() + &outcome
    }
}

/// What `ntori new` made and how well it fits.
#[derive(Clone, Debug, Serialize)]
pub struct NewReport {
    pub genus: u32,
    pub settings: SplineSettings,
    pub smoothness: f64,
    /// The agreement rows' weight (`FitSettings::agreement`; 0: none).
    pub agreement: f64,
    pub mesh_vertices: usize,
    /// Points of the intended surface between the input's vertices that the fit also targeted
    /// (`embedding::holed::HoledMesh::edge_samples`; 0: none).
    pub edge_samples: usize,
    pub mesh_triangles: usize,
    pub control_points: usize,
    /// Gauss–Seidel sweeps of the parameterization (the sphere's whole relaxation, or the polygon
    /// map's warm-up), Newton's solve of the polygon's map, and triangles the map folds (0: a
    /// bijection).
    pub sweeps: usize,
    /// Rounds of the sphere's map solved in the plane to even its area out, where taken.
    pub planar_rounds: usize,
    /// Whether the sphere's map was built coarse to fine rather than from its conformal map.
    pub coarse_to_fine: bool,
    /// Rounds of the sphere's density-equalizing flow, where taken.
    pub equalizing_rounds: usize,
    pub newton: Option<embedding::harmonic::Convergence>,
    /// How far the map onto the polygon is from conformal and area-preserving (plates only: it is
    /// measured on their cut disk).
    pub distortion: Option<embedding::fit::Distortion>,
    pub folded_triangles: usize,
    /// |S(p_i) − P_i| over the mesh vertices, as fractions of the mesh's bounding-box diagonal.
    pub rms_residual: f64,
    pub max_residual: f64,
    pub diagonal: f64,
    /// ∫ K dA from the analytic curvature, and 2π(2 − 2n).
    pub total_curvature: f64,
    pub expected_curvature: f64,
    /// |∫K dA − 2π(2 − 2n)| / max(|2π(2 − 2n)|, ∫|K| dA).
    pub curvature_error: f64,
    /// ∫|K| dA, which `curvature_error` is relative to where it is the larger.
    pub absolute_curvature: f64,
    pub area: f64,
    /// Measures of shape (see `embedding::quality`), and which of them pass.
    pub shape: ShapeReport,
    pub shape_verdict: ShapeVerdict,
    pub seconds: f64,
    pub passed: bool,
}

/// What topology cannot see: patch disagreement, curvature extremes, normal deviation,
/// self-intersections.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ShapeReport {
    /// The largest and the rms distance between overlapping patches that both carry blend weight
    /// ≥ 0.1, as fractions of the diagonal, over the vertices of the t_e = t_r = 16 tessellation.
    pub patch_disagreement: f64,
    pub patch_disagreement_rms: f64,
    /// The largest |κ| of a principal curvature over the same points and the Gauss–Bonnet
    /// check's quadrature points (model units⁻¹): those are dense (several per knot interval of
    /// every chart's grid), so a spike between the tessellation's vertices is seen (genus 3's
    /// default plate: 5.58 at the vertices, 6.05 at the quadrature points).
    pub max_principal_curvature: f64,
    /// The input's largest |κ|: the intended shape's own where its closed form is known (`new`'s
    /// plates, sphere and torus: `embedding::holed::HoledMesh::max_principal_curvature`), else
    /// estimated on the mesh with the reference normals
    /// ([`embedding::quality::mesh_max_principal_curvature`]); and the surface's as a multiple of
    /// it. (Until 2026-11-30 `new` took the estimate too, which reads the rims' peak only where
    /// the mesh samples them finely: 4.7–4.8 of the smooth rims' 4.85 up to genus 32, 3.9–4.1
    /// of the eased rims' 4.15 from 33 to 40, but 2.9–3.4 from 41, whose rims get no rings of
    /// their own, so the check held those fits to a reference a quarter lower.)
    pub input_max_principal_curvature: f64,
    pub curvature_ratio: f64,
    /// Where `input_max_principal_curvature` comes from.
    pub curvature_from: NormalReference,
    /// The input mesh's sharp edges (`embedding::quality::SharpEdges`; none for `new`'s plates):
    /// the largest |κ| above leaves out the points within `CREASE_BAND` of the diagonal of them,
    /// and `crease_rounding` is the tightest radius (over the diagonal) the surface rounds them
    /// to, checked against `MIN_CREASE_ROUNDING`; `None` where no point is near one.
    pub sharp_edges: usize,
    pub crease_rounding: Option<f64>,
    /// Whether any point measured lies away from the sharp edges: on a coarse polygon mesh every
    /// edge may be sharp, and then the largest |κ| above is 0 and only the rounding is checked.
    pub away_from_creases: bool,
    /// The angle between the surface's normal and the reference normal at the input mesh's
    /// vertices, in degrees: median and 90th percentile.
    pub normal_deviation_median: f64,
    pub normal_deviation_p90: f64,
    /// What the normals are measured against.
    pub normals_from: NormalReference,
    /// Pairs of triangles of the t_e = t_r = `intersection_samples` tessellation that cross: the
    /// first of [`embedding::quality::INTERSECTION_SAMPLES`] without any, or the finest. `coarse_crossings` is how
    /// many the first had when it was not that one (0 otherwise).
    pub self_intersections: usize,
    pub intersection_samples: u32,
    pub coarse_crossings: usize,
    /// The two-sided Hausdorff distance between the surface's t_e = t_r = `distance_samples`
    /// tessellation and the input mesh, as a fraction of the diagonal: how far apart they are
    /// anywhere, where the residual sees only the mesh's vertices. Reported, not gated.
    pub distance_to_input: f64,
    /// [`DISTANCE_SAMPLES`], or finer up to [`FINEST_DISTANCE_SAMPLES`] where its edges are longer
    /// than the input's ([`embedding::quality::hausdorff_to_mesh_resolved`]).
    pub distance_samples: u32,
    /// On a plate's flat faces (`new`'s plates of genus 2 and up), where the intended surface is
    /// a plane: how far the surface bends and turns there (a ripple). Reported, not gated.
    pub flat_faces: Option<FlatFacesReport>,
}

/// [`ShapeReport::flat_faces`]: the mean curvature |H| (model units⁻¹) at the input's vertices on
/// the plate's flat faces, median and 90th percentile weighted by their areas; the 90th
/// percentile times the plate's half-thickness (dimensionless: issue 12 asks for at most 0.02);
/// the normal's angle from ±z at the 90th percentile, in degrees.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FlatFacesReport {
    pub vertices: usize,
    pub half_thickness: f64,
    pub mean_curvature_median: f64,
    pub mean_curvature_p90: f64,
    pub mean_curvature_p90_times_half_thickness: f64,
    pub normal_p90: f64,
    /// The same |H| between the vertices too: at the Gauss–Bonnet check's quadrature points.
    pub dense: Option<DenseFlatFaces>,
}

/// [`FlatFacesReport::dense`]: |H| times the half-thickness at the curvature quadrature's points
/// on the flat faces at least `margin` inside them ([`DENSE_FLAT_MARGIN`]), its quantiles weighted
/// by area (to within 1%: [`CurvatureHistogram`]). A ripple narrower than the input's spacing (the
/// fine hairlines a mean-curvature picture shows) lifts the 99th and 99.9th percentiles while the
/// vertices' 90th stays low. Reported, not gated.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DenseFlatFaces {
    pub points: usize,
    pub margin: f64,
    pub p90: f64,
    pub p99: f64,
    pub p999: f64,
    pub max: f64,
}

/// The coarsest tessellation (t_e = t_r) the distance to the input is measured from.
pub const DISTANCE_SAMPLES: u32 = 32;
/// The finest: 128 (genus 1: 163 000 vertices).
pub const FINEST_DISTANCE_SAMPLES: u32 = 128;

/// The tessellation the shape measures sample (t_e = t_r).
const SHAPE_SAMPLES: u32 = 16;

/// The shape measures; `dense` is the largest |κ| the Gauss–Bonnet check's quadrature found, and
/// `flat_curvature` the |H| it found on a plate's flat faces.
fn measure_shape(
    fitted: &Fitted,
    diagonal: f64,
    dense: embedding::quality::CurvatureExtreme,
    flat_curvature: &CurvatureHistogram,
    stage: &dyn Fn(&str),
) -> Result<ShapeReport, embedding::EmbeddingError> {
    use embedding::quality;
    let surface = fitted.surface;
    let points = quality::sample_points(surface, SHAPE_SAMPLES)?;
    let disagreement = quality::patch_disagreement(surface, &points, 0.1);
    let at = &fitted.parameterization.points;
    let mesh_normals;
    // A user's mesh may have sharp edges, which the surface rounds: its curvature is checked
    // away from them, and how tightly it rounds them on its own. The plates have none.
    let (reference, normals_from, sharp) = match fitted.intended_normals {
        Some(intended) => (
            intended,
            NormalReference::Intended,
            quality::SharpEdges::default(),
        ),
        None => {
            mesh_normals = quality::vertex_normals(fitted.positions, fitted.triangles);
            let sharp = quality::SharpEdges::of(fitted.positions, fitted.triangles);
            (&mesh_normals[..], NormalReference::Mesh, sharp)
        }
    };
    let band = quality::CREASE_BAND * diagonal;
    let mut curvature = quality::max_principal_curvature_by_creases(surface, &points, &sharp, band);
    if let Some(at) = dense.at {
        curvature.include(dense, surface.position(at), &sharp, band);
    }
    let largest = curvature.away.max_abs;
    let normals = quality::normal_deviation_from(surface, at, reference);
    stage("measuring the distance to the input");
    let (distance, distance_samples) = quality::hausdorff_to_mesh_resolved(
        surface,
        fitted.positions,
        fitted.triangles,
        DISTANCE_SAMPLES,
        FINEST_DISTANCE_SAMPLES,
    )?;
    stage("looking for self-intersections");
    let crossings = match fitted.crossings {
        Some(known) => known.to_vec(),
        None => quality::crossings_until_clear(surface, &quality::INTERSECTION_SAMPLES)?,
    };
    let (first, last) = (crossings[0], crossings[crossings.len() - 1]);
    let (input_curvature, curvature_from) = match fitted.intended_max_curvature {
        Some(k) => (k, NormalReference::Intended),
        None => (
            quality::mesh_max_principal_curvature(fitted.positions, fitted.triangles, reference),
            NormalReference::Mesh,
        ),
    };
    Ok(ShapeReport {
        patch_disagreement: disagreement.max / diagonal,
        patch_disagreement_rms: disagreement.rms / diagonal,
        max_principal_curvature: largest,
        input_max_principal_curvature: input_curvature,
        curvature_ratio: largest / input_curvature,
        curvature_from,
        sharp_edges: sharp.len(),
        crease_rounding: curvature.rounding(diagonal),
        away_from_creases: curvature.away.at.is_some(),
        normal_deviation_median: normals.median,
        normal_deviation_p90: normals.p90,
        normals_from,
        self_intersections: last.1,
        intersection_samples: last.0,
        coarse_crossings: if crossings.len() > 1 { first.1 } else { 0 },
        distance_to_input: distance.symmetric / diagonal,
        distance_samples,
        flat_faces: fitted
            .flat_faces
            .and_then(|f| flat_faces(fitted, f, flat_curvature)),
    })
}

/// [`FlatFacesReport`] for the plate's faces `faces`, against the intended normals there (±z), and
/// at the dense quadrature's points on them (`dense`).
fn flat_faces(
    fitted: &Fitted,
    faces: PlateFaces,
    dense: &CurvatureHistogram,
) -> Option<FlatFacesReport> {
    let intended = fitted.intended_normals?;
    let areas = embedding::fit::vertex_areas(fitted.positions, fitted.triangles);
    let at = &fitted.parameterization.points;
    let points: Vec<_> = faces.vertices.iter().map(|&i| at[i]).collect();
    let weights: Vec<f64> = faces.vertices.iter().map(|&i| areas[i]).collect();
    let normals: Vec<_> = faces.vertices.iter().map(|&i| intended[i]).collect();
    let flat = embedding::quality::flat_faces(fitted.surface, &points, &normals, &weights)?;
    Some(FlatFacesReport {
        vertices: flat.points,
        half_thickness: faces.half_thickness,
        mean_curvature_median: flat.mean_curvature_median,
        mean_curvature_p90: flat.mean_curvature_p90,
        mean_curvature_p90_times_half_thickness: flat.mean_curvature_p90 * faces.half_thickness,
        normal_p90: flat.normal_p90,
        dense: (dense.points() > 0).then(|| {
            let times_t = |q| dense.quantile(q) * faces.half_thickness;
            DenseFlatFaces {
                points: dense.points(),
                margin: DENSE_FLAT_MARGIN,
                p90: times_t(0.9),
                p99: times_t(0.99),
                p999: times_t(0.999),
                max: dense.max() * faces.half_thickness,
            }
        }),
    })
}

impl ShapeReport {
    /// Whether the shape is one a designer would accept: see the tolerances.
    pub fn verdict(&self) -> ShapeVerdict {
        let (curvature_tolerance, normal_tolerance) = match self.normals_from {
            NormalReference::Intended => (
                CURVATURE_RATIO_TOLERANCE_INTENDED,
                NORMAL_TOLERANCE_INTENDED,
            ),
            NormalReference::Mesh => (CURVATURE_RATIO_TOLERANCE_MESH, NORMAL_TOLERANCE_MESH),
        };
        ShapeVerdict {
            disagreement: self.patch_disagreement <= DISAGREEMENT_TOLERANCE,
            curvature: self.curvature_ratio <= curvature_tolerance
                && self
                    .crease_rounding
                    .is_none_or(|r| r >= embedding::quality::MIN_CREASE_ROUNDING),
            normals: self.normal_deviation_p90 <= normal_tolerance,
            embedded: self.self_intersections == 0,
        }
    }
}

/// Which shape checks passed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct ShapeVerdict {
    pub disagreement: bool,
    pub curvature: bool,
    pub normals: bool,
    pub embedded: bool,
}

impl ShapeVerdict {
    pub fn passed(self) -> bool {
        self.disagreement && self.curvature && self.normals && self.embedded
    }
}

/// What the fitted surface's normals are measured against.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalReference {
    /// The intended shape's exact normals (`new`'s plates, sphere and torus).
    Intended,
    /// The input mesh's vertex normals (`fit`'s meshes; `quality::vertex_normals`), which carry
    /// the mesh's own faceting: at resolution 32 a plate's mesh normals are 4° to 5° off its
    /// shape's at the 90th percentile.
    Mesh,
}

/// Largest relative Gauss–Bonnet error the check accepts (relative to ∫|K| dA for the torus).
pub const CURVATURE_TOLERANCE: f64 = 1e-3;
/// Largest residual, as a fraction of the diagonal, the check accepts.
pub const RESIDUAL_TOLERANCE: f64 = embedding::quality::RESIDUAL_TOLERANCE;
/// Largest patch disagreement, as a fraction of the diagonal, the check accepts.
pub const DISAGREEMENT_TOLERANCE: f64 = embedding::quality::DISAGREEMENT_TOLERANCE;
/// Largest ratio of the surface's |κ| to the input's the check accepts (a crease or a spike), where
/// the input's comes from the intended shape's exact normals, and where it comes from a mesh's own
/// ([`embedding::quality::CURVATURE_RATIO_TOLERANCE_MESH`] says why that is larger).
pub const CURVATURE_RATIO_TOLERANCE_INTENDED: f64 = 3.0;
pub const CURVATURE_RATIO_TOLERANCE_MESH: f64 = embedding::quality::CURVATURE_RATIO_TOLERANCE_MESH;
/// Largest 90th percentile of the normal deviation (degrees) the check accepts, against the
/// intended shape's exact normals and against a mesh's own (which carry its faceting).
pub const NORMAL_TOLERANCE_INTENDED: f64 = 5.0;
pub const NORMAL_TOLERANCE_MESH: f64 = embedding::quality::NORMAL_TOLERANCE_MESH;

/// A fitted model and what it was fitted to, for [`check`].
pub struct Fitted<'a> {
    pub surface: &'a Surface,
    pub genus: u32,
    pub parameterization: &'a embedding::fit::Parameterization,
    pub positions: &'a [embedding::Point3],
    pub triangles: &'a [[u32; 3]],
    /// The intended shape's exact normals at the mesh's vertices, where known (`new`'s plates); the
    /// normal deviation is measured against them, and otherwise against the mesh's own.
    pub intended_normals: Option<&'a [embedding::Vector3]>,
    /// The intended shape's largest principal |κ|, where its closed form is known (`new`'s
    /// sphere, torus and plates); the curvature check compares against it, and otherwise against
    /// the mesh's estimate with the reference normals.
    pub intended_max_curvature: Option<f64>,
    /// A plate's flat faces, where known (`new`'s plates; none for the sphere and the torus),
    /// measured against `intended_normals`.
    pub flat_faces: Option<PlateFaces<'a>>,
    pub rms_residual: f64,
    pub max_residual: f64,
    pub mesh_diagonal: f64,
    pub settings: SplineSettings,
    pub smoothness: f64,
    pub agreement: f64,
    /// Points between the input's vertices the fit also targeted (`FitSettings::edge_samples`).
    pub edge_samples: usize,
    /// The surface's Gauss–Bonnet quadrature at `cells_per_knot`, where the fit already took it
    /// (`embedding::mesh_fit::MeshFit::integrals`); used where there are no flat faces to look at.
    pub integrals: Option<&'a embedding::integrals::SurfaceIntegrals>,
    /// The surface's crossings at each of `embedding::quality::INTERSECTION_SAMPLES` up to the
    /// first without, where the fit counted them (`MeshFit::crossings`).
    pub crossings: Option<&'a [(u32, usize)]>,
}

/// A plate's flat faces: the input's vertices on them (`embedding::holed::HoledMesh::flat_vertices`),
/// the plate's half-thickness, and its plan (where the faces lie, for the dense look between the
/// vertices).
#[derive(Clone, Copy)]
pub struct PlateFaces<'a> {
    pub vertices: &'a [usize],
    pub half_thickness: f64,
    pub plan: PlateLayout,
}

/// How far inside the flat faces (beyond the rims' bands, in the plan; model units) the dense look
/// at their curvature starts: a seventh of the band, so that the rims' own rise in curvature,
/// which the spline approaches over a cell or two, is not counted as a ripple on the face.
pub const DENSE_FLAT_MARGIN: f64 = 0.05;

/// The checks and measures of a fit (`ntori new` and `ntori fit` alike): folds, residual,
/// Gauss–Bonnet and the shape measures. `start` is when the work began.
pub fn check(
    fitted: &Fitted,
    start: std::time::Instant,
    stage: &dyn Fn(&str),
) -> Result<NewReport, embedding::EmbeddingError> {
    let Fitted {
        surface,
        genus,
        parameterization,
        positions,
        triangles,
        intended_normals: _,
        intended_max_curvature: _,
        flat_faces: _,
        rms_residual,
        max_residual,
        mesh_diagonal,
        settings,
        smoothness,
        agreement,
        edge_samples,
        integrals,
        crossings: _,
    } = *fitted;
    let layout = surface.layout();
    let cells = cells_per_knot(layout.settings());
    // The quadrature evaluates the curvature densely anyway: it also gathers |H| where the plate
    // is intended flat, between the input's vertices as well as at them.
    let plan = fitted
        .flat_faces
        .filter(|f| !f.vertices.is_empty())
        .map(|f| f.plan);
    let on_flat_face = |p: &embedding::Point3| {
        plan.is_some_and(|plan| plan.is_flat_beyond(p.x, p.y, DENSE_FLAT_MARGIN))
    };
    // A user's mesh has no flat faces to look at, and its fit may have integrated the surface
    // already (`mesh_fit`'s smoothness ladder).
    let (sums, flat_curvature) = match (integrals, plan) {
        (Some(sums), None) => (*sums, CurvatureHistogram::default()),
        _ => {
            stage("integrating the curvature");
            surface_integrals_over(&layout, surface.control_points(), cells, &on_flat_face)
        }
    };
    let expected = std::f64::consts::TAU * (2.0 - 2.0 * f64::from(genus));
    let curvature_error = sums.gauss_bonnet_error(genus);
    stage("measuring the shape");
    let shape = measure_shape(
        fitted,
        mesh_diagonal,
        sums.curvature_peak(),
        &flat_curvature,
        stage,
    )?;
    let shape_verdict = shape.verdict();
    Ok(NewReport {
        genus,
        settings,
        smoothness,
        agreement,
        mesh_vertices: positions.len(),
        edge_samples,
        mesh_triangles: triangles.len(),
        control_points: surface.control_points().len(),
        sweeps: parameterization.sweeps,
        planar_rounds: parameterization.planar_rounds,
        coarse_to_fine: parameterization.coarse_to_fine,
        equalizing_rounds: parameterization.equalizing_rounds,
        newton: parameterization.newton,
        distortion: parameterization.distortion(positions, surface.atlas().geometry()),
        folded_triangles: parameterization.folded,
        rms_residual: rms_residual / mesh_diagonal,
        max_residual: max_residual / mesh_diagonal,
        diagonal: mesh_diagonal,
        total_curvature: sums.gaussian_curvature,
        expected_curvature: expected,
        curvature_error,
        absolute_curvature: sums.absolute_curvature,
        area: sums.area,
        shape,
        shape_verdict,
        seconds: start.elapsed().as_secs_f64(),
        passed: parameterization.folded == 0
            && curvature_error <= CURVATURE_TOLERANCE
            && max_residual <= RESIDUAL_TOLERANCE * mesh_diagonal
            && shape_verdict.passed(),
    })
}

/// What [`make`] produced: the model, its report, and the mesh it was fitted to with the chart
/// point each mesh vertex was fitted at.
pub struct Made {
    pub surface: Surface,
    pub report: NewReport,
    pub mesh: HoledMesh,
    pub points: Vec<ChartPoint>,
}

/// Fits the model to the plate of `genus` at `resolution` (else its default, the finest within its
/// budget: `embedding::fit::default_mesh`) and checks it. `progress` is told what is being done.
pub fn make(
    genus: u32,
    resolution: Option<usize>,
    settings: SplineSettings,
    fit: FitSettings,
    progress: &FitProgress,
) -> Result<Made, embedding::EmbeddingError> {
    let start = std::time::Instant::now();
    progress.fit_stage(FitStage::Meshing);
    let (resolution, mesh) = match resolution {
        Some(r) => (r, HoledMesh::new(genus, r)?),
        None => default_mesh(genus)?,
    };
    let InitialFit {
        surface,
        mesh,
        parameterization,
        rms_residual,
        max_residual,
        mesh_diagonal,
        edge_samples,
    } = initial_model_of(mesh, resolution, settings, fit, &|s| progress.fit_stage(s))?;
    let flat_vertices = mesh.flat_vertices();
    let checked = Fitted {
        surface: &surface,
        genus,
        parameterization: &parameterization,
        positions: &mesh.positions,
        triangles: &mesh.triangles,
        intended_normals: Some(&mesh.normals),
        intended_max_curvature: Some(mesh.max_principal_curvature),
        flat_faces: Some(PlateFaces {
            vertices: &flat_vertices,
            half_thickness: mesh.thickness,
            plan: PlateLayout::new(genus),
        }),
        rms_residual,
        max_residual,
        mesh_diagonal,
        settings,
        smoothness: fit.smoothness,
        agreement: fit.agreement,
        edge_samples,
        integrals: None,
        crossings: None,
    };
    let report = check(&checked, start, &|s| progress.stage(s))?;
    Ok(Made {
        surface,
        report,
        mesh,
        points: parameterization.points,
    })
}

impl NewReport {
    /// A plate's flat faces, as a line of their own (else nothing).
    fn flat_faces_text(&self) -> String {
        self.shape.flat_faces.map_or(String::new(), |f| {
            format!(
                "flat faces: |H| {:.4} median, {:.4} at 90% (times the half-thickness {}: {:.4}); \
                 normals {:.2}° off ±z (90%)\n{}",
                f.mean_curvature_median,
                f.mean_curvature_p90,
                f.half_thickness,
                f.mean_curvature_p90_times_half_thickness,
                f.normal_p90,
                f.dense.map_or(String::new(), |d| format!(
                    "  between the vertices ({} points, {} inside the rims): |H| times the \
                     half-thickness {:.4} at 90%, {:.4} at 99%, {:.4} at 99.9%, {:.4} at most\n",
                    d.points, d.margin, d.p90, d.p99, d.p999, d.max
                ))
            )
        })
    }

    /// The curvature check's numbers, in words: the largest |κ| against the input's, away from
    /// the input's sharp edges where it has them, and how tightly those are rounded.
    fn curvature_text(&self) -> String {
        let shape = &self.shape;
        let input = match shape.curvature_from {
            NormalReference::Intended => "intended shape's",
            NormalReference::Mesh => "input's",
        };
        let largest = format!(
            "largest |κ| {:.2}, {:.2}× the {input} {:.2}",
            shape.max_principal_curvature,
            shape.curvature_ratio,
            shape.input_max_principal_curvature
        );
        if shape.sharp_edges == 0 {
            return largest;
        }
        let edges = count(shape.sharp_edges, "sharp mesh edge", "sharp mesh edges");
        let band = 100.0 * embedding::quality::CREASE_BAND;
        let rounding = shape.crease_rounding.map_or(String::new(), |r| {
            format!(
                "; rounds them to a radius of {:.2}% of the diagonal (at least {}%)",
                100.0 * r,
                100.0 * embedding::quality::MIN_CREASE_ROUNDING
            )
        });
        if shape.away_from_creases {
            format!("{largest} away from its {edges} (within {band}% of the diagonal){rounding}")
        } else {
            format!(
                "every point lies within {band}% of the diagonal of the input's {edges}{rounding}"
            )
        }
    }

    /// How the map was solved, in words.
    fn solve_text(&self) -> String {
        match self.newton {
            None => {
                let text = count(self.sweeps, "relaxation sweep", "relaxation sweeps");
                let later = [
                    (self.planar_rounds, "planar round", "planar rounds"),
                    (
                        self.equalizing_rounds,
                        "equalizing round",
                        "equalizing rounds",
                    ),
                ];
                let later: Vec<String> = later
                    .into_iter()
                    .filter(|&(n, _, _)| n > 0)
                    .map(|(n, one, many)| count(n, one, many))
                    .collect();
                if self.coarse_to_fine {
                    let then = if later.is_empty() {
                        String::new()
                    } else {
                        format!(", then {}", later.join(" and "))
                    };
                    return format!("built coarse to fine{then}");
                }
                // A genus-0 map evened out in the plane runs no sweeps.
                match (self.sweeps, later.is_empty()) {
                    (0, false) => later.join(" and "),
                    (_, false) => format!("{text}, then {}", later.join(" and ")),
                    (_, true) => text,
                }
            }
            Some(n) => format!(
                "{} and {} ({}, residual {:.0e}){}",
                count(self.sweeps, "sweep", "sweeps"),
                count(n.steps, "Newton step", "Newton steps"),
                count(n.factorizations, "factorization", "factorizations"),
                n.residual,
                if n.rounds_dropped > 0 {
                    format!(
                        "; {} dropped (reweighted by the stretch, the map did not settle)",
                        count(n.rounds_dropped, "stretch round", "stretch rounds")
                    )
                } else {
                    String::new()
                }
            ),
        }
    }

    /// The map's distortion as a line of its own, where measured.
    fn distortion_text(&self) -> String {
        self.distortion.map_or(String::new(), |d| {
            format!(
                "\nmap distortion: angles (σ₁/σ₂) {:.2} mean, {:.2} max; areas ×{:.2} mean, ×{:.2} max",
                d.angle_mean, d.angle_max, d.area_mean, d.area_max
            )
        })
    }

    /// What the Gauss–Bonnet error is a fraction of: ∫|K| dA or |2π(2 − 2n)|, the larger (the
    /// torus's 2π(2 − 2n) is 0, and a bumpy sphere's ∫|K| dA is many times its 4π).
    fn gauss_bonnet_scale(&self) -> String {
        if self.absolute_curvature >= self.expected_curvature.abs() {
            format!("∫|K| dA = {:.3}", self.absolute_curvature)
        } else {
            "|2π(2 − 2n)|".to_string()
        }
    }

    /// The human-readable form (without the line saying where the model went).
    pub fn to_text(&self) -> String {
        let verdict = |ok: bool| if ok { "ok" } else { "FAILED" };
        format!(
            "genus {genus}: degree {degree}, C^{cont} blends, {grid}, \
             {controls} control points\n\
             input mesh: {v} vertices, {f} triangles, bounding-box diagonal {diag:.3}{samples}\n\
             parameterization: {solve}, {folded} folded triangles ({bij}){distortion}\n\
             fit residual: rms {rms:.3}%, max {max:.3}% of the diagonal ({res})\n\
             distance: surface and input mesh within {dist:.3}% of the diagonal of each other \
             (Hausdorff, t_e = t_r = {dist_t})\n\
             Gauss–Bonnet: ∫K dA = {k:.6}, 2π(2 − 2n) = {e:.6}, off by {gb:.1e} of {gb_of} ({gbv})\n\
             patches: disagree by up to {pd:.3}% of the diagonal (rms {pdr:.3}%) ({pdv})\n\
             curvature: {curvature} ({kv})\n\
             normals: {nmed:.2}° from the {reference} (90%: {n90:.2}°) ({nv})\n\
             {flat}self-intersections: {crossings} crossing triangle pairs at t_e = t_r = {t} ({ev}){coarse}\n\
             area {area:.4}, {secs:.2} s\n",
            genus = self.genus,
            degree = self.settings.degree,
            cont = self.settings.continuity,
            grid = self.settings.grid_text(),
            controls = self.control_points,
            v = self.mesh_vertices,
            samples = match self.edge_samples {
                0 => String::new(),
                n => format!("; the fit also targets {n} points between the vertices"),
            },
            f = self.mesh_triangles,
            diag = self.diagonal,
            solve = self.solve_text(),
            distortion = self.distortion_text(),
            folded = self.folded_triangles,
            bij = verdict(self.folded_triangles == 0),
            rms = 100.0 * self.rms_residual,
            max = 100.0 * self.max_residual,
            res = verdict(self.max_residual <= RESIDUAL_TOLERANCE),
            dist = 100.0 * self.shape.distance_to_input,
            dist_t = self.shape.distance_samples,
            k = self.total_curvature,
            e = self.expected_curvature,
            gb = self.curvature_error,
            gb_of = self.gauss_bonnet_scale(),
            gbv = verdict(self.curvature_error <= CURVATURE_TOLERANCE),
            pd = 100.0 * self.shape.patch_disagreement,
            pdr = 100.0 * self.shape.patch_disagreement_rms,
            pdv = verdict(self.shape_verdict.disagreement),
            curvature = self.curvature_text(),
            kv = verdict(self.shape_verdict.curvature),
            nmed = self.shape.normal_deviation_median,
            reference = match self.shape.normals_from {
                NormalReference::Intended => "intended shape's",
                NormalReference::Mesh => "input mesh's",
            },
            n90 = self.shape.normal_deviation_p90,
            nv = verdict(self.shape_verdict.normals),
            flat = self.flat_faces_text(),
            crossings = self.shape.self_intersections,
            t = self.shape.intersection_samples,
            ev = verdict(self.shape_verdict.embedded),
            coarse = if self.shape.coarse_crossings > 0 && self.shape.self_intersections == 0 {
                format!(
                    "; {} at {}, whose triangles are coarse",
                    self.shape.coarse_crossings,
                    embedding::quality::INTERSECTION_SAMPLES[0]
                )
            } else {
                String::new()
            },
            area = self.area,
            secs = self.seconds,
        )
    }
}

/// `n` and the noun that goes with it.
fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}
