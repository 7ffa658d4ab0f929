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
/// Needs a display and a GPU (or Mesa's software Vulkan, lavapipe).
///
/// Examples:
///   ntori edit                         the default genus-2 model
///   ntori edit model.json --te 48 --tr 48
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    /// The model file to open.
    #[arg(value_name = "MODEL")]
    model: Option<PathBuf>,
    /// Divisions of each edge chart's square (and each arc) in the viewport, 1 to 256.
    #[arg(long, default_value_t = ntori::editor::state::DEFAULT_T, value_name = "A",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::editor::state::MAX_T)))]
    te: u32,
    /// Divisions of each wheel spoke in the viewport, 1 to 256.
    #[arg(long, default_value_t = ntori::editor::state::DEFAULT_T, value_name = "B",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::editor::state::MAX_T)))]
    tr: u32,
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
        te,
        tr,
        exit_after_frames,
        screenshot_on_exit,
    } = args;
    let loaded = model
        .as_deref()
        .map(ntori::io::model_file::load)
        .transpose()?;
    let options = ntori::editor::EditorOptions {
        model: loaded,
        file: model,
        tessellation: (te, tr),
        exit_after_frames,
        screenshot_on_exit,
        ..Default::default()
    };
    ntori::editor::run(options).map_err(|e| anyhow::anyhow!("the editor failed: {e}"))?;
    Ok(ExitCode::SUCCESS)
}
