//! `ntori fit`: a user's closed mesh becomes a smooth model.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use embedding::fit::FitStage;
use embedding::mesh_fit::{
    AgreementReport, LONG_EDGE_FACTOR, MeshFit, SPLIT_ALWAYS_FROM, SPLIT_FROM, SmoothnessReport,
    UserMeshFit, fit_user_mesh, mesh_fit_disk_grid, mesh_fit_grid, mesh_model,
};
use ntori::io::import::{self, ValidMesh, cage};
use serde::Serialize;

use super::new::{Fitted, NewReport, check};
use super::report::{Report, emit};
use super::{FitArgs, FitProgress};

/// Fit a smooth model to a closed mesh: OBJ, PLY, OFF, STL or GLB, of genus 0 to 64.
///
/// The mesh is read (polygons triangulated, coincident vertices merged where the format stores
/// none) and checked: one closed, consistently oriented manifold without degenerate triangles, or
/// an error that says what is wrong and where. Its genus comes from its Euler characteristic.
/// Edges longer than three times the mesh's lower-quartile edge and 5% of its diagonal (a CAD
/// tessellation's needles), or than 12% of it, are split at their midpoints, so the fit sees the
/// faces they span; the surface stays where it is.
///
/// A system of 2g loops through one vertex is grown (a shortest-path tree and its dual), the
/// relation the loops satisfy is brought to the canonical form a₁ b₁ a₁⁻¹ b₁⁻¹ …, and every edge
/// gets the side pairing of the polygon it crosses. The mesh is then mapped onto the surface by the
/// same relaxation and fit as `ntori new`, with the same checks: folded triangles (0: a bijection),
/// the residual at the mesh vertices, Gauss–Bonnet, and the shape checks (patch disagreement, the
/// largest |κ| against the mesh's own, normals against the mesh's, self-intersections). A mesh with
/// many long thin irregular triangles (a fifth or more with an angle under 20°, as marching cubes
/// and scanners make) is also mapped evened out along its own surface, a map that does not follow
/// the triangles' directions; the fit's data stay the mesh's own vertices, and the map whose fit
/// comes closer to them is kept. Where the fit at the default smoothness is rough by the checks
/// (|κ| over 4× the mesh's, patches over 1% apart, normals over 15° off at the 90th percentile, a
/// residual over 1%: a smooth surface rings beside sharp edges), it is fitted again with λ five
/// times larger, up to 1, and the first that passes, else the one with the fewest failing, is kept;
/// --smoothness fixes λ. If a check fails, no model is written (unless --keep-failed) and the exit
/// status is 3. A genus-0 mesh is mapped onto the sphere instead (no loops); where the relaxation
/// there leaves long limbs squeezed, the map is made again in rounds of planar solves that even its
/// area out.
///
/// Examples:
///   ntori fit assets/meshes/plate-genus-3.obj -o plate.json
///   ntori fit assets/meshes/gear-genus-1.obj -o gear.json --keep-failed
///   ntori fit scan.stl --largest --grid 16
///   ntori fit assets/meshes/slab-genus-2-cage.obj --cage
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    /// The mesh to fit (the format from the extension).
    #[arg(value_name = "MESH")]
    mesh: PathBuf,
    /// Where to write the model.
    #[arg(short, long, default_value = "model.json", value_name = "FILE")]
    output: PathBuf,
    /// Replace the output file if it exists.
    #[arg(long)]
    force: bool,
    /// Write the model even if a check fails (the exit status is still 3).
    #[arg(long)]
    keep_failed: bool,
    /// If the mesh has several separate pieces, fit the largest (by triangles).
    #[arg(long)]
    largest: bool,
    /// The file's up axis, turned to the model's +z [default: y for GLB and OBJ, z for the
    /// others: what `ntori export` writes, so a mesh exported and fitted again keeps its
    /// orientation].
    #[arg(long, value_enum, value_name = "AXIS")]
    up: Option<ntori::io::export::Up>,
    /// The unit of an OBJ's, PLY's or OFF's numbers (GLB's are metres, STL's millimetres); the
    /// model's unit is a centimetre, as `ntori export` takes it.
    #[arg(long, value_enum, default_value_t = ntori::io::export::DEFAULT_UNITS, value_name = "U")]
    units: ntori::io::export::Units,
    /// Read the mesh as a Catmull–Clark subdivision cage and fit its limit surface (refined and
    /// evaluated by OpenSubdiv), not its polygons; the limit normals are the intended shape's, and
    /// the grid is 32 unless --grid says otherwise.
    #[arg(long, conflicts_with = "largest")]
    cage: bool,
    /// Levels of uniform refinement of the cage [default: the fewest from 2 that make 12 000
    /// triangles].
    #[arg(long, value_name = "L", requires = "cage",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(cage::MAX_CAGE_LEVEL)))]
    cage_level: Option<u32>,
    /// Rounds of evening out a mesh with many long thin irregular triangles for a second map (0:
    /// map it once, as it is).
    #[arg(long, value_name = "N", default_value_t = embedding::mesh_fit::EVEN_ROUNDS as u32,
          value_parser = clap::value_parser!(u32).range(0..=1000))]
    even_rounds: u32,
    /// Weight of the mesh's edges' midpoints as fit targets besides its vertices: one point per
    /// edge, on the smooth curve through its ends that their normals are square to (the chord's
    /// middle across a sharp edge), so the surface follows the mesh between its vertices too
    /// (0: none; 1: a third of the vertices' weight; default 1, and 0 with --cage, whose limit mesh
    /// is dense already). At 1 the raw pretzel of issue 14's tests came from 0.61% to 0.57% of
    /// the diagonal apart, and `gear-genus-1.obj` passes every check within 1.2% of the diagonal
    /// (2.2% without, where its patches came 2.2% apart until the agreement rows were raised);
    /// a coarse mesh with sharp edges is followed more tightly (`plate-genus-3.obj`: 0.89% → 0.50%
    /// apart, its creases rounded to a radius of 0.89% of the diagonal instead of 3.3%, so λ rose
    /// to 0.25 and its |κ| from 1.10× to 2.04× its mesh's), and the fit takes longer (4 s → 9 s
    /// there).
    #[arg(long, value_name = "W", value_parser = super::new::parse_edge_samples)]
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

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let start = std::time::Instant::now();
    // A missing or unreadable input is the first thing to say, before anything about the output.
    import::check_input(&args.mesh)?;
    ntori::io::atomic::check_new_output(&args.output, &[&args.mesh], args.force)?;
    let read = import::read_mesh(&args.mesh)?;
    let (merged, triangulated) = (read.merged_vertices, read.triangulated_polygons);
    let (mut valid, mut cage) = if args.cage {
        let (valid, cage) = read_cage(&args.mesh, read, args.cage_level)?;
        (valid, Some(cage))
    } else {
        let valid = import::validate(read, args.largest)
            .with_context(|| format!("cannot fit {}", args.mesh.display()))?;
        (valid, None)
    };
    import::check_fittable(&valid)
        .with_context(|| format!("cannot fit {}", args.mesh.display()))?;
    // Into the model's frame only now: the checks above name places as the file has them.
    let placement = import::Placement::for_file(&args.mesh, args.up, args.units);
    placement.place_points(&mut valid.positions);
    if let Some(c) = &mut cage {
        c.normals
            .iter_mut()
            .for_each(|n| *n = placement.direction(*n));
    }
    // A cage's limit mesh is as dense as `new`'s plates, so it takes `new`'s grid, one for every
    // chart: the genus-2 slab cage at 20 / 32 fits with patches 0.84% / 0.42% apart, normals
    // 4.5° / 1.6° off its limit normals at the 90th percentile. A user's mesh gets finer disk
    // charts, as `new`'s plates do (`mesh_fit::default_settings` says what was measured).
    let (settings, mut fit) = if cage.is_some() {
        args.spline.settings(
            valid.genus,
            embedding::SplineSettings::default().grid,
            |_| None,
            embedding::fit::default_smoothness,
            |_| 0.0,
        )?
    } else {
        args.spline.settings(
            valid.genus,
            mesh_fit_grid(valid.genus, valid.positions.len()),
            |grid| mesh_fit_disk_grid(valid.genus, grid),
            embedding::fit::default_smoothness,
            |_| 0.0,
        )?
    };
    fit.even_rounds = args.even_rounds as usize;
    fit.edge_samples = args.edge_samples.unwrap_or(if cage.is_some() {
        0.0
    } else {
        embedding::mesh_fit::MESH_EDGE_SAMPLES
    });
    // In arc length where the map allows (`mesh_fit::surface_smoothness`, decided once mapped).
    fit.surface_smoothness = true;
    // λ is raised where the default leaves the surface rough, not where the user chose it.
    fit.raise_smoothness = args.spline.smoothness.is_none();
    // And the agreement rows where the surface crosses itself, unless the user chose them.
    fit.raise_agreement = args.spline.agreement.is_none();
    let progress = FitProgress::new(args.quiet);
    let fit_stage = |s: FitStage| progress.fit_stage(s);
    let user = match cage {
        // A cage's limit mesh is refined evenly already, and its normals are its vertices'.
        Some(_) => mesh_model(
            &valid.positions,
            &valid.triangles,
            settings,
            fit,
            &fit_stage,
        )
        .map(|fit| UserMeshFit {
            fit,
            split: None,
            split_failed: None,
        }),
        None => fit_user_mesh(
            &valid.positions,
            &valid.triangles,
            settings,
            fit,
            &fit_stage,
        ),
    }
    .with_context(|| format!("cannot fit {}", args.mesh.display()))?;
    let fitted = &user.fit;
    let (positions, triangles) = user.mesh(&valid.positions, &valid.triangles);
    let squeeze = SqueezeReport::of(fitted, positions, triangles, placement);
    let mut checked = as_fitted(fitted, positions, triangles, settings);
    checked.intended_normals = cage.as_ref().map(|c| &c.normals[..]);
    let report = check(&checked, start, &|s| progress.stage(s))?;
    progress.finish();
    let written = report.passed || args.keep_failed;
    if written && args.force {
        ntori::io::model_file::save(&args.output, &fitted.surface)?;
    } else if written {
        ntori::io::model_file::save_new(&args.output, &fitted.surface)?;
    }
    let report = FitReport {
        evening: fitted.evening.map(|e| EveningReport {
            rounds: e.rounds,
            moved: e.moved,
            pinned: e.pinned,
            largest_move: e.largest_move / fitted.mesh_diagonal,
            max_residual_evened: e.max_residual_evened / fitted.mesh_diagonal,
            max_residual_as_it_is: e.max_residual_as_it_is / fitted.mesh_diagonal,
            kept: e.kept,
        }),
        sphere_choice: fitted.sphere_choice.map(|c| SphereChoiceReport {
            max_residual_conformal: c.max_residual_conformal / fitted.mesh_diagonal,
            max_residual_coarse_to_fine: c.max_residual_coarse_to_fine / fitted.mesh_diagonal,
            kept_coarse_to_fine: c.kept_coarse_to_fine,
        }),
        input: InputReport {
            path: args.mesh.display().to_string(),
            up: placement.up,
            factor: placement.factor,
            merged_vertices: merged,
            triangulated_polygons: triangulated,
            dropped_components: valid.dropped_components,
            reoriented_triangles: valid.reoriented_triangles,
            // A cage is turned (if at all) before it is refined, and its limit mesh comes out
            // outward: what was done to the file is the cage's.
            flipped: cage.as_ref().map_or(valid.flipped, |c| c.report.flipped),
            cage: cage.map(|c| c.report),
            split: user.split.as_ref().map(|s| SplitReport {
                added_vertices: s.added,
                longest_edge: s.limit,
            }),
            split_failed: user.split_failed.clone(),
        },
        smoothness: fitted.smoothness.clone(),
        agreement: fitted.agreement.clone(),
        loops: LoopsReport::of(fitted),
        squeeze,
        fit: report,
        output: &args.output,
        written,
    };
    emit(&report, args.json)
}

/// A cage read (its polygons checked as a closed oriented manifold) and replaced by its limit
/// surface, which is checked in turn.
fn read_cage(
    path: &Path,
    read: import::ImportedMesh,
    level: Option<u32>,
) -> anyhow::Result<(ValidMesh, Cage)> {
    let context = || format!("cannot fit {} as a subdivision cage", path.display());
    let checked = import::validate(read.clone(), false).with_context(context)?;
    let limit = cage::limit_surface(&read, &checked, level).with_context(context)?;
    let vertices = limit.mesh.positions.len();
    let valid = import::validate(limit.mesh, false).with_context(context)?;
    // The limit mesh comes out outward; if validation still turned it, its normals turn with it.
    let sign = if valid.flipped { -1.0 } else { 1.0 };
    Ok((
        valid,
        Cage {
            normals: limit.normals.iter().map(|n| n * sign).collect(),
            report: CageReport {
                faces: limit.cage_faces,
                non_quads: limit.cage_non_quads,
                level: limit.level,
                limit_vertices: vertices,
                flipped: limit.flipped,
                unused_vertices: limit.unused_vertices,
            },
        },
    ))
}

/// A cage's limit surface: its exact normals at the limit mesh's vertices, and what was done.
struct Cage {
    normals: Vec<embedding::Vector3>,
    report: CageReport,
}

/// What reading a subdivision cage did.
#[derive(Serialize)]
struct CageReport {
    faces: usize,
    non_quads: usize,
    /// Levels of uniform refinement, and the vertices of the limit mesh they made.
    level: u32,
    limit_vertices: usize,
    /// Whether the cage was inside out (turned before it was refined), and its vertices no face
    /// uses (left out).
    flipped: bool,
    unused_vertices: usize,
}

fn as_fitted<'a>(
    fit: &'a MeshFit,
    positions: &'a [embedding::Point3],
    triangles: &'a [[u32; 3]],
    settings: embedding::SplineSettings,
) -> Fitted<'a> {
    Fitted {
        surface: &fit.surface,
        genus: fit.genus,
        parameterization: &fit.parameterization,
        positions,
        triangles,
        intended_normals: None,
        intended_max_curvature: None,
        flat_faces: None,
        rms_residual: fit.rms_residual,
        max_residual: fit.max_residual,
        mesh_diagonal: fit.mesh_diagonal,
        settings,
        smoothness: fit.smoothness.used,
        agreement: fit.agreement.used,
        edge_samples: fit.edge_samples,
        integrals: fit.integrals.as_ref(),
        crossings: fit.crossings.as_deref(),
    }
}

/// What `ntori fit` read and made.
#[derive(Serialize)]
struct FitReport<'a> {
    input: InputReport,
    loops: LoopsReport,
    /// How the mesh was evened out for its map, where it has long thin triangles.
    evening: Option<EveningReport>,
    /// Genus 0: which of the sphere's two maps went on, where a rival was built coarse to fine.
    sphere_choice: Option<SphereChoiceReport>,
    /// The smoothness weight asked for and used, and each one tried where it was raised.
    smoothness: SmoothnessReport,
    /// The agreement weight asked for and used, and each one tried where the surface crossed
    /// itself.
    agreement: AgreementReport,
    /// Where a genus-0 map onto the sphere still squeezes a limb (none where it is even enough).
    squeeze: Option<SqueezeReport>,
    fit: NewReport,
    #[serde(skip)]
    output: &'a Path,
    #[serde(skip)]
    written: bool,
}

/// Where a genus-0 mesh's map onto the sphere distorts area most, where that is more than
/// `mesh_fit::MAX_SQUEEZE_FOR_ARC_LENGTH`: a limb or a tail many times longer than thick, which the
/// sphere's map squeezes and the fit follows poorly (the cow's tail, ×2·10⁸ at its tip).
#[derive(Serialize)]
struct SqueezeReport {
    /// The largest area factor ([`embedding::fit::Distortion::area_max`]).
    factor: f64,
    /// The middle of the triangle it is at, in the file's coordinates.
    at: [f64; 3],
}

impl SqueezeReport {
    fn of(
        fitted: &embedding::mesh_fit::MeshFit,
        positions: &[embedding::Point3],
        triangles: &[[u32; 3]],
        placement: import::Placement,
    ) -> Option<SqueezeReport> {
        let map = fitted.parameterization.map_distortion?;
        Self::of_map(fitted.genus, map, positions, triangles, placement)
    }

    /// Where a genus-0 map of distortion `map` squeezes most, if it squeezes more than
    /// `MAX_SQUEEZE_FOR_ARC_LENGTH`.
    fn of_map(
        genus: u32,
        map: embedding::fit::Distortion,
        positions: &[embedding::Point3],
        triangles: &[[u32; 3]],
        placement: import::Placement,
    ) -> Option<SqueezeReport> {
        if genus != 0 || map.area_max <= embedding::mesh_fit::MAX_SQUEEZE_FOR_ARC_LENGTH {
            return None;
        }
        let corners = triangles.get(map.area_max_triangle)?;
        let middle = corners
            .iter()
            .map(|&v| positions[v as usize].coords)
            .sum::<embedding::Vector3>()
            / 3.0;
        let at = placement.up.apply(middle / placement.factor);
        Some(SqueezeReport {
            factor: map.area_max,
            at: [at.x, at.y, at.z],
        })
    }

    fn to_text(&self) -> String {
        format!(
            "squeezed: the sphere's map still distorts area ×{:.2e} near ({:.4}, {:.4}, {:.4}) in \
             the file: a limb or tail many times longer than thick, which the fit follows poorly \
             there\n",
            self.factor, self.at[0], self.at[1], self.at[2]
        )
    }
}

/// What reading the mesh changed.
#[derive(Serialize)]
struct InputReport {
    path: String,
    /// The file's up axis (turned to the model's +z) and what one of its units is in model units.
    up: ntori::io::export::Up,
    factor: f64,
    merged_vertices: usize,
    triangulated_polygons: usize,
    dropped_components: usize,
    reoriented_triangles: usize,
    flipped: bool,
    /// With --cage: the cage and its refinement.
    cage: Option<CageReport>,
    /// Where the mesh had long edges: how they were split for the fit.
    split: Option<SplitReport>,
    /// Where the mesh with its long edges split did not map: why (it was fitted as it is).
    split_failed: Option<String>,
}

/// Long edges split at their midpoints before the map and the fit
/// (`embedding::mesh_fit::split_long_edges`): the surface is the same, sampled more densely.
#[derive(Serialize)]
struct SplitReport {
    added_vertices: usize,
    /// No edge is longer than this now (model units): `LONG_EDGE_FACTOR` times the lower quartile,
    /// kept within `SPLIT_FROM` to `SPLIT_ALWAYS_FROM` of the diagonal.
    longest_edge: f64,
}

/// Vertices near long thin triangles slid along the mesh for a second map (the fit's data stay
/// the mesh's own vertices), and which map was kept.
#[derive(Serialize)]
struct EveningReport {
    rounds: usize,
    /// Vertices that moved, and vertices near thin triangles held on sharp edges.
    moved: usize,
    pinned: usize,
    /// The largest move, as a fraction of the mesh's bounding-box diagonal.
    largest_move: f64,
    /// The largest residual of the fit through each map (fractions of the diagonal), and whether
    /// the evened map's (the closer) was kept.
    max_residual_evened: f64,
    max_residual_as_it_is: f64,
    kept: bool,
}

/// Which of a genus-0 mesh's two maps onto the sphere went on.
#[derive(Serialize)]
struct SphereChoiceReport {
    /// The largest residual of the fit through each map (fractions of the diagonal), and whether
    /// the map built coarse to fine went on.
    max_residual_conformal: f64,
    max_residual_coarse_to_fine: f64,
    kept_coarse_to_fine: bool,
}

impl SphereChoiceReport {
    fn to_text(&self) -> String {
        let (built, conformal) = (
            self.max_residual_coarse_to_fine,
            self.max_residual_conformal,
        );
        let (kept, residual, other, other_residual) = if self.kept_coarse_to_fine {
            let other = "through the conformal map's";
            ("built coarse to fine", built, other, conformal)
        } else {
            (
                "the conformal map's",
                conformal,
                "through its rival built coarse to fine",
                built,
            )
        };
        format!(
            "map: {kept} (its fit's largest residual {:.3}% of the diagonal, {:.3}% {other})\n",
            100.0 * residual,
            100.0 * other_residual
        )
    }
}

/// The loop system the map was built on.
#[derive(Serialize)]
struct LoopsReport {
    base_vertex: u32,
    /// Base vertices whose markings were screened (more where the first few's maps were poor).
    bases_screened: usize,
    /// Edges in each generator loop.
    loop_edges: Vec<usize>,
    /// Letters in each generator's canonical word (1: the loop is a canonical loop itself).
    canonical_word_lengths: Vec<usize>,
}

impl LoopsReport {
    fn of(fit: &MeshFit) -> LoopsReport {
        LoopsReport {
            base_vertex: fit.loops.base,
            bases_screened: fit.loops.bases_screened,
            loop_edges: fit.loops.paths.iter().map(|p| p.len() - 1).collect(),
            canonical_word_lengths: fit.loops.canonical.iter().map(Vec::len).collect(),
        }
    }
}

impl Report for FitReport<'_> {
    fn passed(&self) -> bool {
        self.fit.passed
    }

    fn to_text(&self) -> String {
        let i = &self.input;
        let mut notes = Vec::new();
        if i.merged_vertices > 0 {
            notes.push(format!("{} coincident vertices merged", i.merged_vertices));
        }
        // A cage's polygons are triangulated only to be checked; its own line says what was made.
        if i.triangulated_polygons > 0 && i.cage.is_none() {
            notes.push(format!("{} polygons triangulated", i.triangulated_polygons));
        }
        if i.dropped_components > 0 {
            notes.push(format!("{} smaller pieces left out", i.dropped_components));
        }
        if i.reoriented_triangles > 0 {
            notes.push(format!(
                "{} triangles turned to agree",
                i.reoriented_triangles
            ));
        }
        if i.flipped {
            notes.push("turned right side out".to_string());
        }
        if i.up == ntori::io::export::Up::Y {
            notes.push("its +y up turned to the model's +z".to_string());
        }
        if i.factor != 1.0 {
            notes.push(format!(
                "a file unit is {} model units (centimetres)",
                i.factor
            ));
        }
        if let Some(unused) = i
            .cage
            .as_ref()
            .map(|c| c.unused_vertices)
            .filter(|&u| u > 0)
        {
            notes.push(format!("{unused} vertices no face uses left out"));
        }
        let notes = if notes.is_empty() {
            String::new()
        } else {
            format!(" ({})", notes.join(", "))
        };
        let longest = self.loops.canonical_word_lengths.iter().max().unwrap_or(&0);
        let outcome = if self.written {
            format!("wrote {}\n", self.output.display())
        } else {
            format!(
                "not written to {}: a check failed (--keep-failed writes it anyway)\n",
                self.output.display()
            )
        };
        let loops = if self.loops.loop_edges.is_empty() {
            "loops: none (genus 0: mapped onto the sphere)".to_string()
        } else {
            format!(
                "loops: {} through vertex {} (the best of {} base vertices' markings), canonical \
                 words of up to {longest} {}",
                self.loops.loop_edges.len(),
                self.loops.base_vertex,
                self.loops.bases_screened,
                if *longest == 1 { "letter" } else { "letters" },
            )
        };
        let evening = self.evening.as_ref().map_or(String::new(), |e| {
            let pinned = if e.pinned > 0 {
                format!(", {} held on sharp edges", e.pinned)
            } else {
                String::new()
            };
            let (kept, other) = if e.kept {
                ("the mesh evened out", "as it is")
            } else {
                ("the mesh as it is", "evened out")
            };
            format!(
                "map: made from {kept} (its fit's largest residual {:.3}% of the diagonal, {:.3}% \
                 {other}: {} vertices near long thin triangles slid along it, up to {:.2}% of the \
                 diagonal{pinned}); the fit's data are its own vertices\n",
                100.0 * e.max_residual_evened.min(e.max_residual_as_it_is),
                100.0 * e.max_residual_evened.max(e.max_residual_as_it_is),
                e.moved,
                100.0 * e.largest_move
            )
        });
        let cage = i.cage.as_ref().map_or(String::new(), |c| {
            format!(
                "cage: {} faces ({} not quads), refined {} times by OpenSubdiv to its limit surface ({} vertices)\n",
                c.faces, c.non_quads, c.level, c.limit_vertices
            )
        });
        let split_failed = i.split_failed.as_ref().map_or(String::new(), |why| {
            format!("long edges: the mesh with them split did not map ({why}); fitted as it is\n")
        });
        let split = i.split.as_ref().map_or(split_failed, |s| {
            format!(
                "long edges: split at their midpoints until none is longer than {:.4} ({LONG_EDGE_FACTOR}× \
                 the lower-quartile edge, kept within {}% to {}% of the diagonal), {} vertices added, \
                 so the fit sees the faces they spanned\n",
                s.longest_edge,
                100.0 * SPLIT_FROM,
                100.0 * SPLIT_ALWAYS_FROM,
                s.added_vertices
            )
        });
        let choice = self
            .sphere_choice
            .as_ref()
            .map_or(String::new(), SphereChoiceReport::to_text);
        let smoothness = smoothness_text(&self.smoothness)
            + &agreement_text(&self.agreement, self.smoothness.used);
        let squeeze = self
            .squeeze
            .as_ref()
            .map_or(String::new(), SqueezeReport::to_text);
        format!(
            "read {}{notes}\n{cage}{split}{loops}\n{evening}{choice}{smoothness}",
            i.path
        ) + &self.fit.to_text()
            + &squeeze
            + &outcome
    }
}

/// The line saying that λ was raised, and why (nothing where the first λ passed or none was tried).
fn smoothness_text(report: &SmoothnessReport) -> String {
    let (Some(first), Some(kept)) = (
        report.tried.first(),
        report.tried.iter().find(|t| t.smoothness == report.used),
    ) else {
        return String::new();
    };
    if report.used == report.asked {
        return String::new();
    }
    let (asked, first, last) = (first.smoothness, first.roughness, kept.roughness);
    let largest = report.tried.last().map_or(report.used, |t| t.smoothness);
    format!(
        "smoothness: λ raised from {asked} to {} (tried up to {largest}; measured at t = {}, |κ| \
         also at the quadrature's points where the rest passed): at {asked} the surface's largest \
         |κ| was {:.2}× the mesh's{}, its patches {:.3}% of the diagonal apart, its normals {:.1}° \
         off the mesh's (90%) and its residual {:.3}%; at {}, {:.2}×, {:.3}%, {:.1}° and {:.3}%\n",
        report.used,
        embedding::mesh_fit::ROUGHNESS_SAMPLES,
        first.curvature_ratio,
        if first.crease_rounding.is_some() {
            " away from its sharp edges"
        } else {
            ""
        },
        100.0 * first.disagreement,
        first.normals_p90,
        100.0 * first.residual,
        report.used,
        last.curvature_ratio,
        100.0 * last.disagreement,
        last.normals_p90,
        100.0 * last.residual,
    )
}

/// The line saying that the agreement weight was raised, and why (nothing where it was not).
/// `smoothness` is the λ kept.
fn agreement_text(report: &AgreementReport, smoothness: f64) -> String {
    let (Some(first), Some(kept)) = (
        report.tried.first(),
        report.tried.iter().find(|t| t.agreement == report.used),
    ) else {
        return String::new();
    };
    if report.used == report.asked {
        return String::new();
    }
    // Raised by the smoothness ladder, at the λ it kept: the patches alone were too far apart.
    if report.used == first.agreement {
        return format!(
            "agreement: the patches' agreement weight raised from {} to {} at λ = {smoothness}, \
             where without it only the patches were more than {}% of the diagonal apart (now \
             {:.3}%)\n",
            report.asked,
            report.used,
            100.0 * embedding::quality::DISAGREEMENT_TOLERANCE,
            100.0 * first.roughness.disagreement,
        );
    }
    let (Some((t, pairs)), Some((kept_t, _))) = (first.crossings, kept.crossings) else {
        return String::new();
    };
    let (r0, r) = (first.roughness, kept.roughness);
    format!(
        "agreement: the patches' agreement weight raised from {} to {} (tried {}): at {} the \
         surface crossed itself in {pairs} triangle pairs at t_e = t_r = {t}, at {} in none at \
         {kept_t}; its patches {:.3}% → {:.3}% of the diagonal apart, |κ| {:.2}× → {:.2}× the \
         mesh's, normals {:.1}° → {:.1}° (90%), residual {:.3}% → {:.3}%\n",
        first.agreement,
        report.used,
        report.tried[1..]
            .iter()
            .map(|t| t.agreement.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        first.agreement,
        report.used,
        100.0 * r0.disagreement,
        100.0 * r.disagreement,
        r0.curvature_ratio,
        r.curvature_ratio,
        r0.normals_p90,
        r.normals_p90,
        100.0 * r0.residual,
        100.0 * r.residual,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedding::mesh_fit::{AgreementTried, Roughness};

    fn tried(agreement: f64, crossings: Option<(u32, usize)>, disagreement: f64) -> AgreementTried {
        AgreementTried {
            agreement,
            crossings,
            roughness: Roughness {
                curvature_ratio: 3.85,
                crease_rounding: None,
                disagreement,
                normals_p90: 3.8,
                residual: 0.0066,
            },
        }
    }

    /// The squeezed line says where a genus-0 map squeezes more than ×100, at the middle of the
    /// worst triangle in the file's coordinates (its up axis and units); nothing at ×100 or less,
    /// or at genus 1.
    #[test]
    fn the_squeezed_line_says_where_in_the_file() {
        let positions = [
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
            [0.0, 0.0, 6.0],
        ]
        .map(|[x, y, z]| embedding::Point3::new(x, y, z));
        let triangles = [[0, 2, 1], [0, 1, 3]];
        let map = |area_max| embedding::fit::Distortion {
            angle_mean: 2.0,
            angle_max: 9.0,
            area_mean: 3.0,
            area_max,
            area_max_triangle: 1,
        };
        // The file was read +y up in millimetres: the model is its z-up copy, in centimetres.
        let placement = import::Placement {
            up: ntori::io::export::Up::Y,
            factor: 0.1,
        };
        let report = SqueezeReport::of_map(0, map(2.5e3), &positions, &triangles, placement);
        let report = report.expect("squeezed more than ×100");
        // The worst triangle's middle (1, 0, 2) in the model is (10, 20, 0) in the file.
        assert_eq!(report.at, [10.0, 20.0, 0.0]);
        assert_eq!(
            report.to_text(),
            "squeezed: the sphere's map still distorts area ×2.50e3 near (10.0000, 20.0000, \
             -0.0000) in the file: a limb or tail many times longer than thick, which the fit \
             follows poorly there\n"
        );
        assert!(SqueezeReport::of_map(0, map(100.0), &positions, &triangles, placement).is_none());
        assert!(SqueezeReport::of_map(1, map(2.5e3), &positions, &triangles, placement).is_none());
    }

    /// The map line names the map kept first with its own fit's residual, then the other's.
    #[test]
    fn the_map_line_names_the_map_kept_and_both_residuals() {
        let built = SphereChoiceReport {
            max_residual_conformal: 0.109,
            max_residual_coarse_to_fine: 0.0142,
            kept_coarse_to_fine: true,
        };
        assert_eq!(
            built.to_text(),
            "map: built coarse to fine (its fit's largest residual 1.420% of the diagonal, \
             10.900% through the conformal map's)\n"
        );
        let conformal = SphereChoiceReport {
            max_residual_conformal: 0.00486,
            max_residual_coarse_to_fine: 0.0129,
            kept_coarse_to_fine: false,
        };
        assert_eq!(
            conformal.to_text(),
            "map: the conformal map's (its fit's largest residual 0.486% of the diagonal, \
             1.290% through its rival built coarse to fine)\n"
        );
    }

    /// The agreement line names the weights, the crossings before and after and what else moved;
    /// where the weight stayed as asked, or nothing was looked at, there is no line.
    #[test]
    fn the_agreement_line_says_why_it_was_raised() {
        let raised = AgreementReport {
            asked: 0.0,
            used: 30.0,
            tried: vec![
                tried(0.0, Some((64, 18)), 0.00836),
                tried(3.0, None, 0.02),
                tried(30.0, Some((32, 0)), 0.0037),
            ],
        };
        let line = agreement_text(&raised, 0.01);
        for part in [
            "raised from 0 to 30 (tried 3, 30)",
            "crossed itself in 18 triangle pairs at t_e = t_r = 64, at 30 in none at 32",
            "patches 0.836% → 0.370% of the diagonal apart",
        ] {
            assert!(line.contains(part), "{part:?} not in {line:?}");
        }
        assert!(line.ends_with('\n') && line.lines().count() == 1);
        let kept = AgreementReport {
            used: 0.0,
            ..raised.clone()
        };
        assert_eq!(agreement_text(&kept, 0.01), "");
        let untried = AgreementReport {
            tried: Vec::new(),
            ..raised
        };
        assert_eq!(agreement_text(&untried, 0.01), "");
    }

    /// Raised by the smoothness ladder (the first surface looked at for crossings already had the
    /// raised weight): the line says at which λ, and that the patches alone were too far apart.
    #[test]
    fn the_agreement_line_names_the_rung_that_raised_it() {
        let ladder = AgreementReport {
            asked: 0.0,
            used: 3.0,
            tried: vec![tried(3.0, Some((32, 0)), 0.0011)],
        };
        let line = agreement_text(&ladder, 1.0);
        for part in [
            "raised from 0 to 3 at λ = 1,",
            "only the patches were more than 1% of the diagonal apart (now 0.110%)",
        ] {
            assert!(line.contains(part), "{part:?} not in {line:?}");
        }
        assert!(!line.contains("crossed"), "{line:?}");
        assert!(line.ends_with('\n') && line.lines().count() == 1);
    }
}
