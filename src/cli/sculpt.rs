//! `ntori sculpt`: one grab-brush stroke on a model, without a window (the editor's brush).

use std::path::PathBuf;
use std::process::ExitCode;

use charts::ChartPoint;
use embedding::brush::Falloff;
use embedding::{Point3, Surface};
use ntori::editor::EditorState;
use ntori::editor::state::Grab;
use ntori::io::atomic::{FileError, check_output};
use ntori::io::export::Meshing;
use serde::Serialize;

use super::report::{Report, emit};

/// Sculpt a model without a window: drag the surface point nearest to --at to --to.
///
/// The stroke is the editor's drag. With --radius it is a grab brush: the surface within R (model
/// units) of the picked point follows, fading out at the radius as --falloff says (smooth: a
/// soft round bump; dome: a hemisphere's profile; sharp: a pointed tip; constant: the whole disc
/// moves together). Without --radius it is the smallest change of the control points that moves
/// the point (the paper's edit). Either way the picked point reaches --to exactly, and the
/// model's pins and the --pin points stay where they are (--pin holds for this stroke only; the
/// output keeps the model's own pins).
///
/// Points are picked on the quality tessellation the editor shows: the vertex nearest to --at
/// (and to each --pin). The report says how far that was from the point given.
///
/// The output is written atomically; it may not be the input, and an existing file is replaced
/// only with --force. Where pins keep the point from reaching --to (a pin at the point itself),
/// the closest compromise is written and the exit status is 3.
///
/// Examples:
///   ntori sculpt model.json -o pulled.json --at 1.5,0,0.4 --to 1.5,0,1.2 --radius 1.5
///   ntori sculpt model.json -o dome.json --at 1.5,0,0.4 --to 1.5,0,1.2 --radius 1.5 --falloff dome
///   ntori sculpt model.json -o held.json --at 1.5,0,0.4 --to 1.5,0,1.2 --radius 2 --pin 2.2,0,0.4
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
    /// The point to grab: the surface point nearest to X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_point)]
    at: Point3,
    /// Where the grabbed point goes.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_point)]
    to: Point3,
    /// The brush's radius in model units (a finite number above 0); without it, the smallest
    /// change of the control points.
    #[arg(long, value_name = "R", allow_negative_numbers = true, value_parser = parse_radius)]
    radius: Option<f64>,
    /// How the brush fades towards its radius.
    #[arg(long, value_enum, default_value_t = FalloffArg::Smooth, requires = "radius")]
    falloff: FalloffArg,
    /// Hold the surface point nearest to X,Y,Z in place during the stroke (repeatable).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_point)]
    pin: Vec<Point3>,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
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

/// What the stroke did.
#[derive(Debug, Serialize)]
struct SculptReport {
    /// The picked surface point: its chart and coordinates there.
    chart: u32,
    coords: [f64; 2],
    /// How far the picked point was from --at.
    picked_from_at: f64,
    /// Where the picked point is now, and how far from --to.
    reached: [f64; 3],
    reached_from_to: f64,
    control_points_moved: usize,
    /// The model's size (the diagonal of its tessellation's bounding box).
    size: f64,
}

impl Report for SculptReport {
    fn passed(&self) -> bool {
        self.reached_from_to <= 1e-6 * self.size
    }

    fn to_text(&self) -> String {
        let [x, y, z] = self.reached;
        format!(
            "grabbed chart {} ({:.4}, {:.4}), {:.3e} from --at\n\
             moved {} control points; the point is at ({x:.6}, {y:.6}, {z:.6}), {:.3e} from --to\n",
            self.chart,
            self.coords[0],
            self.coords[1],
            self.picked_from_at,
            self.control_points_moved,
            self.reached_from_to
        )
    }
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let target = check_output(&args.output, &[&args.model])?;
    if !args.force && std::fs::symlink_metadata(&target).is_ok() {
        return Err(FileError::Exists { path: args.output }.into());
    }
    let surface = ntori::io::model_file::load(&args.model)?;
    let own_pins = surface.pins().len();
    let mut state = EditorState::new(surface.clone(), Meshing::default())?;
    let (point, picked_from_at) = nearest(&state, args.at);
    for &p in &args.pin {
        state.add_pin(nearest(&state, p).0);
    }
    state.influence = args.radius.map_or(0.0, |r| r / state.size());
    state.falloff = args.falloff.into();
    state.start_drag(point, Grab::Surface, [0.0, 0.0])?;
    state.drag_to_target(args.to)?;
    state.release();
    // The --pin points held for this stroke only.
    while state.pins().len() > own_pins {
        state.remove_pin(state.pins().len() - 1);
    }
    let sculpted: &Surface = state.surface();
    if args.force {
        ntori::io::model_file::save(&args.output, sculpted)?;
    } else {
        ntori::io::model_file::save_new(&args.output, sculpted)?;
    }
    let reached = state.surface_point(point);
    let report = SculptReport {
        chart: point.chart.0,
        coords: [point.coords.re, point.coords.im],
        picked_from_at,
        reached: reached.coords.into(),
        reached_from_to: (reached - args.to).norm(),
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

/// The tessellation vertex nearest to `p`, and its distance.
fn nearest(state: &EditorState, p: Point3) -> (ChartPoint, f64) {
    let mesh = state.mesh();
    let (k, d) = mesh
        .positions()
        .iter()
        .map(|q| (q - p).norm())
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("a tessellation has vertices");
    (mesh.tessellation.vertices[k], d)
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
