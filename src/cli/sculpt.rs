//! `ntori sculpt`: brush strokes on a model without a window (the editor's brushes), from the
//! command line or a script of strokes.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use charts::ChartPoint;
use clap::Parser as _;
use embedding::brush::{BrushKind, Falloff, Symmetry};
use embedding::{Point3, Surface};
use ntori::editor::EditorState;
use ntori::editor::state::Grab;
use ntori::io::atomic::check_new_output;
use ntori::io::export::Meshing;
use serde::Serialize;

use super::report::{Report, emit};

/// Sculpt a model without a window: the editor's brushes, one stroke or a script of many.
///
/// grab (the default) drags the surface point nearest to --at to --to. With --radius the surface
/// within R (model units) of it follows, fading out at the radius as --falloff says (smooth: a
/// soft round bump; dome: a hemisphere's profile; sharp: a pointed tip; constant: the whole disc
/// moves together), planned anew every quarter of the radius of the way, so a long pull along
/// the surface drags a bump along instead of folding it; without, the smallest change of the
/// control points moves it (the paper's edit). Either way the point reaches --to exactly, and the
/// model's pins and the --pin points stay where they are (--pin holds for this stroke only; the
/// output keeps the model's own pins).
///
/// inflate, smooth and flatten are stroke brushes: a dab at the surface point nearest to --at,
/// or, with --to, dabs a quarter of the radius apart along the way from --at to --to (each at the
/// surface point nearest to the line). inflate pushes the surface out along its normal (a
/// negative --strength pulls it in); smooth fairs it (bumps sink, dents rise); flatten moves it
/// towards the plane of the area under the brush. --strength is the step of one dab (1: a full
/// step; default 0.5); --radius defaults to 0.15 of the model's size.
///
/// --symmetry x (y, z, or any combination: xz) acts on the mirror images across those planes
/// through the origin too, found on the surface, in the same solve. A grabbed point near a plane
/// is held to its side, so that it and its image neither tear the surface apart nor fold it:
/// across the plane it moves by the pull times its distance from its image in radii (at most
/// the pull), towards the plane at most half the way (or to R/2 from it); a point on the plane
/// moves along it.
///
/// --script FILE reads one stroke per line, written with the same options (--brush, --at, --to,
/// --radius, --falloff, --strength, --symmetry, --pin); blank lines and lines starting with # are
/// skipped. The strokes apply in order, and the output is written once, after the last.
///
/// Points are picked on the quality tessellation the editor shows: the vertex nearest to --at
/// (and to each --pin). The report says how far that was from the point given.
///
/// The output is written atomically; it may not be the input, and an existing file is replaced
/// only with --force. Where pins keep a grabbed point from reaching --to (a pin at the point
/// itself), or symmetry does (above), the closest compromise is written and the exit status is
/// 3.
///
/// Examples:
///   ntori sculpt model.json -o pulled.json --at 1.5,0,0.4 --to 1.5,0,1.2 --radius 1.5
///   ntori sculpt model.json -o dome.json --at 1.5,0,0.4 --to 1.5,0,1.2 --radius 1.5 --falloff dome
///   ntori sculpt model.json -o held.json --at 1.5,0,0.4 --to 1.5,0,1.2 --radius 2 --pin 2.2,0,0.4
///   ntori sculpt model.json -o puffed.json --brush inflate --at 2.3,0,0.35 --radius 1 --symmetry x
///   ntori sculpt model.json -o smoothed.json --brush smooth --at 2.3,-1,0.35 --to 2.3,1,0.35
///   ntori sculpt model.json -o out.json --script strokes.txt
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    /// The model file (as written by `ntori new`).
    #[arg(value_name = "MODEL")]
    model: PathBuf,
    /// Where to write the sculpted model.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Replace the output file if it exists.
    #[arg(long)]
    force: bool,
    /// Strokes to apply, one per line, written with this command's stroke options.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["at", "to", "brush", "radius", "strength", "symmetry", "pin"])]
    script: Option<PathBuf>,
    #[command(flatten)]
    stroke: StrokeArgs,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

/// One stroke: on the command line, or one line of a script.
#[derive(clap::Args, Debug, Clone)]
struct StrokeArgs {
    /// What the stroke does.
    #[arg(long, value_enum, default_value_t = BrushArg::Grab)]
    brush: BrushArg,
    /// The point to act on: the surface point nearest to X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_point)]
    at: Option<Point3>,
    /// grab: where the grabbed point goes (required); stroke brushes: where the stroke ends.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_point)]
    to: Option<Point3>,
    /// The brush's radius in model units (a finite number above 0); without it, grab is the
    /// smallest change of the control points and the other brushes use 0.15 of the model's size.
    #[arg(long, value_name = "R", allow_negative_numbers = true, value_parser = parse_radius)]
    radius: Option<f64>,
    /// How the brush fades towards its radius.
    #[arg(long, value_enum, default_value_t = FalloffArg::Smooth)]
    falloff: FalloffArg,
    /// A stroke brush's step per dab (1: a full step; negative: the other way).
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = parse_strength, default_value_t = 0.5)]
    strength: f64,
    /// Mirror planes through the origin to act across too: x, y, z or a combination (xz).
    #[arg(long, value_name = "PLANES", value_parser = parse_symmetry)]
    symmetry: Option<Symmetry>,
    /// Hold the surface point nearest to X,Y,Z in place during the stroke (repeatable).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_point)]
    pin: Vec<Point3>,
}

/// A script line, parsed by the same options.
#[derive(clap::Parser, Debug)]
#[command(no_binary_name = true, disable_help_flag = true)]
struct ScriptLine {
    #[command(flatten)]
    stroke: StrokeArgs,
}

/// `--brush`'s values.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum BrushArg {
    Grab,
    Inflate,
    Smooth,
    Flatten,
}

impl From<BrushArg> for BrushKind {
    fn from(b: BrushArg) -> BrushKind {
        match b {
            BrushArg::Grab => BrushKind::Grab,
            BrushArg::Inflate => BrushKind::Inflate,
            BrushArg::Smooth => BrushKind::Smooth,
            BrushArg::Flatten => BrushKind::Flatten,
        }
    }
}

/// `--falloff`'s values.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum FalloffArg {
    Smooth,
    Dome,
    Sharp,
    Constant,
}

impl From<FalloffArg> for Falloff {
    fn from(f: FalloffArg) -> Falloff {
        match f {
            FalloffArg::Smooth => Falloff::Smooth,
            FalloffArg::Dome => Falloff::Dome,
            FalloffArg::Sharp => Falloff::Sharp,
            FalloffArg::Constant => Falloff::Constant,
        }
    }
}

/// What a stroke did.
#[derive(Debug, Serialize)]
struct StrokeReport {
    brush: &'static str,
    /// The picked surface point: its chart and coordinates there.
    chart: u32,
    coords: [f64; 2],
    /// How far the picked point was from --at.
    picked_from_at: f64,
    /// Mirror images acted on.
    images: usize,
    /// grab: where the picked point is now, and how far from --to.
    #[serde(skip_serializing_if = "Option::is_none")]
    reached: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    reached_from_to: Option<f64>,
    /// Stroke brushes: the dabs made.
    dabs: u32,
}

/// What the strokes did.
#[derive(Debug, Serialize)]
struct SculptReport {
    strokes: Vec<StrokeReport>,
    control_points_moved: usize,
    /// The model's size (the diagonal of its tessellation's bounding box).
    size: f64,
}

impl Report for SculptReport {
    fn passed(&self) -> bool {
        self.strokes
            .iter()
            .all(|s| s.reached_from_to.is_none_or(|d| d <= 1e-6 * self.size))
    }

    fn to_text(&self) -> String {
        let mut text = String::new();
        for s in &self.strokes {
            text += &format!(
                "{}: chart {} ({:.4}, {:.4}), {:.3e} from --at",
                s.brush, s.chart, s.coords[0], s.coords[1], s.picked_from_at
            );
            if s.images > 0 {
                text += &format!(", {} mirror image(s)", s.images);
            }
            match (s.reached, s.reached_from_to) {
                (Some([x, y, z]), Some(d)) => {
                    text +=
                        &format!("; the point is at ({x:.6}, {y:.6}, {z:.6}), {d:.3e} from --to")
                }
                _ => text += &format!("; {} dab(s)", s.dabs),
            }
            text += "\n";
        }
        text + &format!("moved {} control points\n", self.control_points_moved)
    }
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    check_new_output(&args.output, &[&args.model], args.force)?;
    let strokes = match &args.script {
        Some(script) => read_script(script)?,
        None if args.stroke.at.is_none() => {
            anyhow::bail!("give --at X,Y,Z (the point to act on), or --script FILE")
        }
        None => vec![args.stroke.clone()],
    };
    let surface = ntori::io::model_file::load(&args.model)?;
    let mut state = EditorState::new(surface.clone(), Meshing::default())?;
    let mut reports = Vec::with_capacity(strokes.len());
    for (k, stroke) in strokes.iter().enumerate() {
        if k > 0 {
            // Each stroke picks and samples the surface as it stands (the quality tessellation
            // follows the shape), so a script gives what the strokes one command at a time give.
            state.remesh(state.meshing())?;
        }
        let report = apply(&mut state, stroke).with_context(|| match &args.script {
            Some(script) => format!("stroke {} of {}", k + 1, script.display()),
            None => "the stroke".to_string(),
        })?;
        reports.push(report);
    }
    let sculpted: &Surface = state.surface();
    if args.force {
        ntori::io::model_file::save(&args.output, sculpted)?;
    } else {
        ntori::io::model_file::save_new(&args.output, sculpted)?;
    }
    let report = SculptReport {
        strokes: reports,
        control_points_moved: surface
            .control_points()
            .iter()
            .zip(sculpted.control_points())
            .filter(|(a, b)| a != b)
            .count(),
        size: state.size(),
    };
    emit(&report, args.json)
}

/// The strokes of a script file: one per line, blank lines and # comments skipped.
fn read_script(path: &Path) -> anyhow::Result<Vec<StrokeArgs>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the script {}", path.display()))?;
    let mut strokes = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        // Split at whitespace, no quoting: points and names have no spaces.
        let words: Vec<&str> = line.split_whitespace().collect();
        let parsed = ScriptLine::try_parse_from(&words).map_err(|e| {
            let message = e.to_string();
            let first = message
                .lines()
                .next()
                .unwrap_or("")
                .trim_start_matches("error: ");
            anyhow::anyhow!("{}:{}: {first}", path.display(), n + 1)
        })?;
        if parsed.stroke.at.is_none() {
            anyhow::bail!("{}:{}: a stroke needs --at", path.display(), n + 1);
        }
        strokes.push(parsed.stroke);
    }
    if strokes.is_empty() {
        anyhow::bail!("{}: the script has no strokes", path.display());
    }
    Ok(strokes)
}

/// How far a grab may move its point, in multiples of the model's size ([`EditorState::size`]).
const MAX_GRAB_REACH: f64 = 10.0;

/// Applies one stroke to the editor's state.
fn apply(state: &mut EditorState, stroke: &StrokeArgs) -> anyhow::Result<StrokeReport> {
    let at = stroke.at.context("a stroke needs --at")?;
    let kind: BrushKind = stroke.brush.into();
    state.brush = kind;
    state.falloff = stroke.falloff.into();
    state.strength = stroke.strength;
    state.symmetry = stroke.symmetry.unwrap_or_default();
    state.influence = stroke.radius.map_or(0.0, |r| r / state.size());
    let own_pins = state.pins().len();
    let (point, picked_from_at) = nearest(state, at);
    if picked_from_at > state.size() {
        eprintln!(
            "ntori: warning: --at lies {picked_from_at:.4e} from the surface, farther than the \
             model's size ({:.4e}); the stroke acts at the surface point nearest it",
            state.size()
        );
    }
    let images = state.mirror_images(point).len();
    let mut report = StrokeReport {
        brush: kind.name(),
        chart: point.chart.0,
        coords: [point.coords.re, point.coords.im],
        picked_from_at,
        images,
        reached: None,
        reached_from_to: None,
        dabs: 0,
    };
    if kind == BrushKind::Grab {
        let to = stroke
            .to
            .context("the grab brush needs --to (where the point goes)")?;
        // The drag re-plans at steps of a fraction of the brush, so its time grows with the reach:
        // refused before any work where no sculpting would go (--to 1e9 had run for minutes).
        let reach = (to - state.surface_point(point)).norm();
        if reach.is_nan() || reach > MAX_GRAB_REACH * state.size() {
            anyhow::bail!(
                "--to lies {reach:.4e} from the grabbed point, more than {MAX_GRAB_REACH} times \
                 the model's size ({:.4e}); grab in smaller steps (several strokes)",
                state.size()
            );
        }
        for &p in &stroke.pin {
            let pin = nearest(state, p).0;
            state.add_pin(pin);
        }
        state.start_drag(point, Grab::Surface, [0.0, 0.0])?;
        state.drag_to_target(to)?;
        state.release();
        // The --pin points held for this stroke only.
        while state.pins().len() > own_pins {
            state.remove_pin(state.pins().len() - 1);
        }
        let reached = state.surface_point(point);
        report.reached = Some(reached.coords.into());
        report.reached_from_to = Some((reached - to).norm());
        return Ok(report);
    }
    if !stroke.pin.is_empty() {
        anyhow::bail!(
            "--pin holds points for a grab; the {} brush has no pins",
            kind.name()
        );
    }
    state.start_stroke(point)?;
    if let Some(to) = stroke.to {
        // Dabs along the way, at the surface points nearest to the line (each is made when the
        // point is a quarter of the radius from the last dab).
        let steps = ((to - at).norm() / (0.05 * state.radius())).ceil().max(1.0) as usize;
        for k in 1..=steps {
            let on_line = at + (to - at) * (k as f64 / steps as f64);
            let (p, _) = nearest(state, on_line);
            state.stroke_at(p)?;
        }
    }
    report.dabs = state.stroke().map_or(0, |s| s.dabs);
    state.release();
    Ok(report)
}

/// The tessellation vertex nearest to `p`, and its distance.
fn nearest(state: &EditorState, p: Point3) -> (ChartPoint, f64) {
    let point = state.nearest_vertex(p);
    (point, (state.surface_point(point) - p).norm())
}

fn parse_symmetry(s: &str) -> Result<Symmetry, String> {
    let mut symmetry = Symmetry::default();
    for c in s.trim().chars() {
        match c.to_ascii_lowercase() {
            'x' => symmetry.x = true,
            'y' => symmetry.y = true,
            'z' => symmetry.z = true,
            ',' => {}
            _ => {
                return Err(format!(
                    "symmetry planes are x, y and z (any combination, e.g. xz), got {s:?}"
                ));
            }
        }
    }
    if symmetry.is_empty() {
        return Err("name at least one mirror plane: x, y or z".into());
    }
    Ok(symmetry)
}

fn parse_strength(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() <= 10.0 => Ok(v),
        Ok(v) => Err(format!(
            "the strength must be a number from -10 to 10, got {v}"
        )),
        Err(_) => Err(format!("the strength must be a number, got {s:?}")),
    }
}

fn parse_point(s: &str) -> Result<Point3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let numbers: Vec<f64> = parts
        .iter()
        .map(|x| x.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("a point is X,Y,Z (three numbers), got {s:?}"))?;
    match numbers[..] {
        [x, y, z] if numbers.iter().all(|v| v.is_finite()) => Ok(Point3::new(x, y, z)),
        [_, _, _] => Err(format!("a point's coordinates must be finite, got {s:?}")),
        _ => Err(format!(
            "a point is X,Y,Z (three numbers), got {} in {s:?}",
            numbers.len()
        )),
    }
}

fn parse_radius(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(r) if r.is_finite() && r > 0.0 => Ok(r),
        Ok(r) => Err(format!(
            "the radius must be a finite number above 0, got {r}"
        )),
        Err(_) => Err(format!("the radius must be a number, got {s:?}")),
    }
}
