//! What the user asks for: the keyboard, the menus, the side panel and the dialogs each add a
//! [`Command`] while a frame's UI is drawn, and `EditorApp::apply` carries them out, in order, at
//! the start of the next frame, before anything is drawn (the keyboard's at the start of its own
//! frame). The viewport's pointer input alone acts at once: a drag follows the pointer within its
//! frame. A finished background job and a held close come back as commands too.

use std::path::{Path, PathBuf};

use charts::ChartId;
use egui::{Context, Key, Modifiers};
use embedding::{SplineSettings, Surface};

use super::app::EditorApp;
use super::jobs::{JobOutput, JobResult};
use super::recovery::Recovery;
use super::state::EditorState;
use crate::io::export::Meshing;
use crate::render::{CurvatureKind, Style};

/// A file the user is asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileAction {
    Open,
    /// A user's mesh, fitted into a new model.
    Import,
    SaveAs,
    Export,
    Screenshot,
}

impl FileAction {
    pub fn title(self) -> &'static str {
        match self {
            FileAction::Open => "Open model",
            FileAction::Import => "Import mesh",
            FileAction::SaveAs => "Save model as",
            FileAction::Export => "Export mesh",
            FileAction::Screenshot => "Save screenshot",
        }
    }

    pub fn button(self) -> &'static str {
        match self {
            FileAction::Open => "Open",
            FileAction::Import => "Import",
            FileAction::SaveAs => "Save",
            FileAction::Export => "Export",
            FileAction::Screenshot => "Save",
        }
    }
}

/// The largest residual of an imported mesh's fit that is not said as an error (`ntori fit`'s).
const IMPORT_RESIDUAL_TOLERANCE: f64 = 0.01;

/// An action that drops unsaved changes, so waits for the answer to "save changes?".
#[derive(Clone, Debug, PartialEq)]
pub enum Pending {
    /// A new model of this genus and settings.
    New(u32, SplineSettings),
    /// Open this file (None: ask for one).
    Open(Option<PathBuf>),
    /// Fit this mesh into a new model (None: ask for one).
    Import(Option<PathBuf>),
    Close,
    /// Recover the i-th recovery file offered.
    Recover(usize),
}

/// One user action.
#[derive(Debug)]
pub enum Command {
    Undo,
    Redo,
    /// Save to the model's file (asking for one if it has none), then go on with the action.
    Save(Option<Pending>),
    /// Ask for a file for `action`, then go on with the action.
    AskFile(FileAction, Option<Pending>),
    /// The file for `action` was chosen.
    FileChosen(FileAction, PathBuf, Option<Pending>),
    /// An action, asking first about unsaved changes.
    Guarded(Pending),
    /// An action, the changes saved or dropped.
    Run(Pending),
    /// Open the new-model dialog with this genus and these settings.
    NewModelDialog(u32, SplineSettings),
    ToggleHelp,
    ShowHelp,
    /// Cancel the drag in progress, else close the dialogs.
    Escape,
    Quit,
    Frame,
    ResetView,
    SetStyle(Style),
    /// Show this chart's control net (None: none).
    ShowControlNet(Option<ChartId>),
    /// Show the next chart's control net (after the last: none).
    NextControlNet,
    /// Refit the surface to new spline settings (in the background).
    Refit(SplineSettings),
    /// Tessellate the viewport's mesh this way (again, if it already is: after edits the quality
    /// tessellation is made anew for the new shape).
    SetMeshing(Meshing),
    RemovePin(usize),
    ClearPins,
    /// Scale the brush's radius by this factor (`[` and `]`).
    ScaleRadius(f64),
    /// Change the stroke brushes' strength by this much (Shift + `[` and `]`).
    AddStrength(f64),
    /// Delete the i-th recovery file offered and stop offering it.
    DiscardOrphan(usize),
    /// Stop offering the i-th recovery file (it stays for the next start).
    DismissOrphan(usize),
    /// The background job finished.
    JobDone(JobResult),
}

/// `[` and `]` scale the brush's radius by this factor.
const RADIUS_STEP: f64 = 1.1;
/// Shift + `[` and `]` change the strength by this much.
const STRENGTH_STEP: f64 = 0.05;

/// Every shortcut, for the help window and the menus.
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("Left drag on the surface", "drag that point (pins hold)"),
    ("Left drag on a pin", "drag the pinned point"),
    ("Left drag elsewhere, Alt + left drag", "orbit"),
    ("Right or middle drag, Shift + left drag", "pan"),
    ("Mouse wheel, pinch, Ctrl + scroll", "zoom"),
    ("Two fingers on a trackpad", "orbit (with Shift: pan)"),
    ("Ctrl + click", "pin or unpin a point"),
    ("Double click", "orbit about the clicked point"),
    ("Esc", "cancel the drag in progress"),
    ("F", "frame the model"),
    ("Home", "reset the view"),
    (
        "1 2 3 4 5",
        "shaded, wireframe, charts, Gaussian, mean curvature",
    ),
    ("C", "show the next chart's control points (then none)"),
    ("[ ]", "brush radius smaller, larger"),
    ("Shift + [ ]", "brush strength lower, higher"),
    ("Ctrl + Z", "undo"),
    ("Ctrl + Shift + Z, Ctrl + Y", "redo"),
    ("Ctrl + N", "new model"),
    ("Ctrl + O", "open"),
    (
        "Ctrl + I",
        "import a mesh (OBJ, PLY, OFF, STL, GLB) and fit it",
    ),
    ("Ctrl + S", "save"),
    ("Ctrl + Shift + S", "save as"),
    ("Ctrl + E", "export the mesh"),
    ("F12", "screenshot of the viewport"),
    ("F1", "this help"),
    ("Ctrl + Q", "quit"),
];

/// The keyboard's commands this frame, one per key press and in the order pressed (three quick
/// Ctrl + Z in one frame undo three steps). `new_model` is what the new-model dialog starts with; the
/// view's keys need a model.
pub fn shortcuts(
    ctx: &Context,
    busy: bool,
    has_model: bool,
    new_model: (u32, SplineSettings),
    commands: &mut Vec<Command>,
) {
    let typing = ctx.egui_wants_keyboard_input();
    let context = KeyContext {
        busy,
        has_model,
        typing,
        new_model,
    };
    ctx.input_mut(|i| {
        i.events.retain(|event| {
            let egui::Event::Key {
                key,
                pressed: true,
                modifiers,
                ..
            } = event
            else {
                return true;
            };
            match context.action(*key, *modifiers) {
                KeyAction::Run(command) => {
                    commands.push(command);
                    false
                }
                KeyAction::Swallow => false,
                KeyAction::Pass => true,
            }
        })
    });
}

/// What decides a key's meaning besides the key.
struct KeyContext {
    busy: bool,
    has_model: bool,
    /// A text field has the keyboard: plain keys are its.
    typing: bool,
    new_model: (u32, SplineSettings),
}

/// What one key press does.
enum KeyAction {
    Run(Command),
    /// A shortcut that cannot act now (a file action while a job runs): used up all the same.
    Swallow,
    /// Not ours: left for the widgets.
    Pass,
}

impl KeyContext {
    fn action(&self, key: Key, m: Modifiers) -> KeyAction {
        let run = KeyAction::Run;
        let unless_busy = |command| {
            if self.busy {
                KeyAction::Swallow
            } else {
                KeyAction::Run(command)
            }
        };
        if m.command {
            // As egui's shortcuts match: extra Shift or Alt does not stop a shortcut without them.
            return match (key, m.shift) {
                (Key::Z, true) | (Key::Y, _) => run(Command::Redo),
                (Key::Z, false) => run(Command::Undo),
                (Key::S, true) => unless_busy(Command::AskFile(FileAction::SaveAs, None)),
                (Key::S, false) => unless_busy(Command::Save(None)),
                (Key::O, _) => unless_busy(Command::Guarded(Pending::Open(None))),
                (Key::I, _) => unless_busy(Command::Guarded(Pending::Import(None))),
                (Key::N, _) => {
                    unless_busy(Command::NewModelDialog(self.new_model.0, self.new_model.1))
                }
                (Key::E, _) => unless_busy(Command::AskFile(FileAction::Export, None)),
                (Key::Q, _) => run(Command::Quit),
                _ => KeyAction::Pass,
            };
        }
        if m.ctrl {
            return KeyAction::Pass;
        }
        match key {
            Key::F12 => return run(Command::AskFile(FileAction::Screenshot, None)),
            Key::F1 => return run(Command::ToggleHelp),
            _ if self.typing => return KeyAction::Pass,
            Key::Escape => return run(Command::Escape),
            _ if !self.has_model => return KeyAction::Pass,
            _ => {}
        }
        let command = match key {
            Key::F => Command::Frame,
            Key::Home => Command::ResetView,
            Key::Num1 => Command::SetStyle(Style::Shaded),
            Key::Num2 => Command::SetStyle(Style::Wireframe),
            Key::Num3 => Command::SetStyle(Style::Charts),
            Key::Num4 => Command::SetStyle(Style::Curvature(CurvatureKind::Gaussian)),
            Key::Num5 => Command::SetStyle(Style::Curvature(CurvatureKind::Mean)),
            Key::C => Command::NextControlNet,
            // Blender's keys: [ and ] resize the brush, with Shift they change its strength.
            Key::OpenBracket if m.shift => Command::AddStrength(-STRENGTH_STEP),
            Key::CloseBracket if m.shift => Command::AddStrength(STRENGTH_STEP),
            Key::OpenBracket => Command::ScaleRadius(1.0 / RADIUS_STEP),
            Key::CloseBracket => Command::ScaleRadius(RADIUS_STEP),
            _ => return KeyAction::Pass,
        };
        run(command)
    }
}

impl EditorApp {
    /// Carries out one command.
    pub(super) fn apply(&mut self, command: Command) {
        match command {
            Command::Undo => self.undo_redo(false),
            Command::Redo => self.undo_redo(true),
            Command::Save(then) => {
                let path = self
                    .state
                    .as_ref()
                    .and_then(|s| s.path())
                    .map(Path::to_owned);
                match path {
                    Some(path) => self.save_as(&path, then),
                    None => self.apply(Command::AskFile(FileAction::SaveAs, then)),
                }
            }
            Command::AskFile(action, then) => {
                let current = self.state.as_ref().and_then(EditorState::path);
                if let Some(chosen) = self.dialogs.ask_file(action, then, current) {
                    self.apply(chosen);
                }
            }
            Command::FileChosen(action, path, then) => match action {
                FileAction::Open => self.open_or_tell(&path),
                FileAction::Import => self.jobs.import_mesh(path),
                FileAction::SaveAs => self.save_as(&path, then),
                FileAction::Export => {
                    if let Some(state) = &self.state {
                        let surface = state.surface().clone();
                        self.jobs.export(surface, state.meshing(), path);
                    }
                }
                FileAction::Screenshot => self.pending_screenshot = Some(path),
            },
            Command::Guarded(action) => {
                if self.state.as_ref().is_some_and(EditorState::is_modified) {
                    self.dialogs.unsaved = Some(action);
                } else {
                    self.apply(Command::Run(action));
                }
            }
            Command::Run(action) => self.run(action),
            Command::NewModelDialog(genus, settings) => {
                self.dialogs.new_model = Some((genus, settings));
            }
            Command::ToggleHelp => self.dialogs.show_help = !self.dialogs.show_help,
            Command::ShowHelp => self.dialogs.show_help = true,
            Command::Escape => match &mut self.state {
                Some(state) if state.drag().is_some() => {
                    state.cancel_drag();
                    self.viewport.end_interaction();
                    self.messages.info("drag cancelled");
                }
                _ => self.dialogs.close(),
            },
            Command::Quit => self.close_now = true,
            Command::Refit(settings) => {
                if let Some(state) = &self.state {
                    self.jobs.refit(state.surface().clone(), settings);
                }
            }
            Command::DiscardOrphan(i) => {
                if i < self.orphans.len() {
                    Recovery::discard(&self.orphans.remove(i));
                }
            }
            Command::DismissOrphan(i) => {
                if i < self.orphans.len() {
                    self.orphans.remove(i);
                }
            }
            Command::JobDone(result) => self.finish_job(result),
            command => self.apply_to_state(command),
        }
    }

    /// The commands that change the model or its view alone.
    fn apply_to_state(&mut self, command: Command) {
        let Some(state) = &mut self.state else { return };
        match command {
            Command::Frame => state.frame(),
            Command::ResetView => state.reset_view(),
            Command::SetStyle(style) => state.set_style(style),
            Command::ShowControlNet(chart) => state.control_chart = chart,
            Command::ScaleRadius(factor) => state.scale_radius(factor),
            Command::AddStrength(delta) => state.add_strength(delta),
            Command::NextControlNet => {
                let charts = state.atlas().charts().len() as u32;
                state.control_chart = match state.control_chart {
                    None => Some(ChartId(0)),
                    Some(c) if c.0 + 1 < charts => Some(ChartId(c.0 + 1)),
                    Some(_) => None,
                };
            }
            Command::SetMeshing(meshing) => {
                if let Err(e) = state.remesh(meshing) {
                    self.messages.error(e.to_string());
                }
            }
            Command::RemovePin(i) => state.remove_pin(i),
            Command::ClearPins => state.clear_pins(),
            _ => unreachable!("applied by EditorApp::apply"),
        }
    }

    fn run(&mut self, action: Pending) {
        match action {
            Pending::New(genus, settings) => self.jobs.new_model(genus, settings),
            Pending::Open(Some(path)) => self.open_or_tell(&path),
            Pending::Open(None) => self.apply(Command::AskFile(FileAction::Open, None)),
            Pending::Import(Some(path)) => self.jobs.import_mesh(path),
            Pending::Import(None) => self.apply(Command::AskFile(FileAction::Import, None)),
            Pending::Close => {
                self.allow_close = true;
                self.close_now = true;
            }
            Pending::Recover(i) => {
                if let Err(e) = self.recover(i) {
                    self.messages.error(format!("cannot recover: {e}"));
                }
            }
        }
    }

    fn open_or_tell(&mut self, path: &Path) {
        if let Err(e) = self.open(path) {
            self.messages.error(e.to_string());
        }
    }

    /// Saves to `path`, then goes on with `then`.
    fn save_as(&mut self, path: &Path, then: Option<Pending>) {
        match self.save_to(path) {
            Ok(()) => {
                self.messages.info(format!("saved {}", path.display()));
                if let Some(next) = then {
                    self.run(next);
                }
            }
            Err(e) => self.messages.error(e.to_string()),
        }
    }

    /// Shows an imported mesh's model (untitled: the mesh file is not a model file), and says how
    /// well it fits: a fold or a residual over `ntori fit`'s 1% is said as an error, the model shown
    /// all the same, to look at what went wrong. (Gauss–Bonnet and the shape checks are
    /// `ntori fit`'s alone.)
    fn finish_import(
        &mut self,
        path: &Path,
        genus: u32,
        surface: Surface,
        max_residual: f64,
        folded: usize,
    ) {
        let state = match EditorState::new(surface, self.current_meshing()) {
            Ok(state) => state,
            Err(e) => {
                self.messages
                    .error(format!("cannot show the imported model: {e}"));
                return;
            }
        };
        self.install(state);
        let what = format!(
            "imported {} (genus {genus}): the surface passes within {:.2}% of the mesh's size of its vertices",
            path.display(),
            100.0 * max_residual
        );
        let mut missed = Vec::new();
        if folded > 0 {
            missed.push(format!("the map folds {folded} triangles"));
        }
        if max_residual > IMPORT_RESIDUAL_TOLERANCE {
            missed.push(format!(
                "the residual is over {:.0}%",
                100.0 * IMPORT_RESIDUAL_TOLERANCE
            ));
        }
        if missed.is_empty() {
            self.messages.info(what);
        } else {
            self.messages.error(format!(
                "{what}, but {}: `ntori fit` refuses this fit (and says more)",
                missed.join(" and ")
            ));
        }
    }

    /// Undoes (or redoes) the last change, saying which.
    fn undo_redo(&mut self, redo: bool) {
        let Some(state) = &mut self.state else { return };
        let settings = state.settings();
        let (result, done, verb) = if redo {
            (state.redo(), "redid", "redo")
        } else {
            (state.undo(), "undid", "undo")
        };
        // The panel shows the settings the surface now has (an undone refit takes its own back).
        if state.settings() != settings {
            self.panel.settings_applied(state.settings());
        }
        match result {
            Ok(Some(label)) => self.messages.info(format!("{done} {label}")),
            Ok(None) => {}
            Err(e) => self.messages.error(format!("cannot {verb}: {e}")),
        }
    }

    fn finish_job(&mut self, result: JobResult) {
        match result {
            Ok(JobOutput::NewModel { genus, surface }) => {
                match EditorState::new(surface, self.current_meshing()) {
                    Ok(state) => {
                        self.install(state);
                        self.messages.info(format!("new genus-{genus} model"));
                    }
                    Err(e) => self
                        .messages
                        .error(format!("cannot show the new model: {e}")),
                }
            }
            Ok(JobOutput::Imported {
                path,
                genus,
                surface,
                max_residual,
                folded,
            }) => self.finish_import(&path, genus, surface, max_residual, folded),
            Ok(JobOutput::Refit {
                settings,
                control,
                worst,
            }) => {
                let Some(state) = &mut self.state else { return };
                let size = state.size();
                match state.set_settings(settings, control) {
                    Ok(()) => {
                        self.panel.settings_applied(settings);
                        self.messages.info(format!(
                            "refitted: the surface moved by at most {:.3}% of its size",
                            100.0 * worst / size.max(f64::MIN_POSITIVE)
                        ));
                    }
                    Err(e) => self
                        .messages
                        .error(format!("cannot use the new settings: {e}")),
                }
            }
            Ok(JobOutput::Exported { exported, path }) if exported.folded > 0 => {
                self.messages.error(format!(
                    "exported {} to {}, but {} of them face against the surface: \
                     the tessellation is too coarse for this surface",
                    exported.face_count(),
                    path.display(),
                    exported.folded
                ))
            }
            Ok(JobOutput::Exported { exported, path }) => self.messages.info(format!(
                "exported {} to {}",
                exported.face_count(),
                path.display()
            )),
            Err(e) => self.messages.error(e.to_string()),
        }
    }
}
