//! `ntori edit`: the editor window.

use std::path::PathBuf;
use std::process::ExitCode;

/// Open the editor: a window to sculpt the surface by dragging its points.
///
/// Opens MODEL (as written by `ntori new`), or fits the default genus-2 model when none is
/// given. Drag a point of the surface and the smallest change to the control points moves it
/// under the cursor (the paper's minimum-norm least squares); Ctrl + click pins points so they
/// stay put. Orbit with a left drag off the surface, pan with a right or middle drag, zoom with
/// the wheel; F frames the model, F1 lists every shortcut. Undo and redo, open, save, mesh
/// export and screenshots are in the menus. Unsaved work is autosaved to
/// $XDG_STATE_HOME/ntori (or ~/.local/state/ntori) and offered back after a crash.
///
/// The viewport shows the quality tessellation (well-shaped triangles sized by the curvature;
/// the side panel's Remesh makes it anew for the shape after edits), or t_e/t_r's with --te/--tr.
/// Needs a display and a GPU (or Mesa's software Vulkan, lavapipe).
///
/// Examples:
///   ntori edit                         the default genus-2 model
///   ntori edit model.json --tolerance 0.0005
///   ntori edit model.json --te 48 --tr 48       (the t_e/t_r tessellation)
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    /// The model file to open.
    #[arg(value_name = "MODEL")]
    model: Option<PathBuf>,
    /// The viewport's quality tessellation: the most a flat triangle strays from the surface, as
    /// a fraction of its diagonal (1e-5 to 0.1) [default: 0.001].
    #[arg(long, value_name = "T", conflicts_with_all = ["te", "tr"],
          value_parser = super::export::parse_tolerance)]
    tolerance: Option<f64>,
    /// Show the t_e/t_r tessellation instead, with A divisions of each edge chart's square (and
    /// each arc), 1 to 256 (t_r is 32 unless given).
    #[arg(long, value_name = "A",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::editor::state::MAX_T)))]
    te: Option<u32>,
    /// Show the t_e/t_r tessellation instead, with B divisions of each wheel spoke, 1 to 256 (t_e
    /// is 32 unless given).
    #[arg(long, value_name = "B",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::editor::state::MAX_T)))]
    tr: Option<u32>,
    /// For smoke tests: close after this many frames.
    #[arg(long, hide = true, value_name = "N")]
    exit_after_frames: Option<u32>,
    /// For smoke tests: write the viewport's picture here before closing.
    #[arg(long, hide = true, value_name = "PNG")]
    screenshot_on_exit: Option<PathBuf>,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        model,
        tolerance,
        te,
        tr,
        exit_after_frames,
        screenshot_on_exit,
    } = args;
    use ntori::editor::state::DEFAULT_T;
    use ntori::io::export::Meshing;
    let meshing = match (te, tr, tolerance) {
        (None, None, Some(tolerance)) => Meshing::Quality { tolerance },
        (None, None, None) => Meshing::default(),
        (te, tr, _) => Meshing::TeTr {
            te: te.unwrap_or(DEFAULT_T),
            tr: tr.unwrap_or(DEFAULT_T),
        },
    };
    let loaded = model
        .as_deref()
        .map(ntori::io::model_file::load)
        .transpose()?;
    let options = ntori::editor::EditorOptions {
        model: loaded,
        file: model,
        meshing,
        exit_after_frames,
        screenshot_on_exit,
        ..Default::default()
    };
    no_display_is_an_error()?;
    ntori::editor::run(options).map_err(|e| anyhow::anyhow!("the editor failed: {e}"))?;
    Ok(ExitCode::SUCCESS)
}

/// On Linux and the BSDs the editor needs an X11 or Wayland display; without one winit fails deep
/// inside its event loop with a message naming its own source file. Said plainly instead, before
/// the model is loaded into a window that cannot open.
fn no_display_is_an_error() -> anyhow::Result<()> {
    if !cfg!(all(unix, not(target_os = "macos"))) {
        return Ok(());
    }
    let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    if ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
        .into_iter()
        .any(set)
    {
        return Ok(());
    }
    anyhow::bail!(
        "the editor needs a display, and neither DISPLAY nor WAYLAND_DISPLAY is set: run it in a \
         desktop session, or under a virtual one (xvfb-run ntori edit …); `ntori render` and \
         `ntori sculpt` work without one"
    )
}
