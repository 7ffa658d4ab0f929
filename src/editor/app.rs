//! The egui application: a thin [`eframe::App`] that, each frame, applies in order the [`Command`]s
//! given since the last one (by the last frame's UI, a finished background job, the keyboard; see
//! `commands.rs`), then lets its parts draw themselves and collects their commands: menu bar,
//! status bar and side panel (`panels.rs`), the viewport (`viewport.rs`, whose pointer input acts at
//! once), the dialogs (`dialogs.rs`). Background jobs are in `jobs.rs`. Nothing here computes
//! geometry: that is [`EditorState`]'s.

use std::path::{Path, PathBuf};
use std::time::Instant;

use egui::{Context, Rect};
use embedding::{SplineSettings, Surface};

use super::commands::{self, Command, Pending};
use super::dialogs::{Dialogs, native_dialogs_available};
use super::jobs::Jobs;
use super::panels::{self, Messages, SidePanel, Timings};
use super::recovery::{Orphan, Recovery};
use super::state::{EditorError, EditorState, Pick};
use super::viewport::Viewport;
use crate::io::export::Meshing;

/// How the editor starts.
#[derive(Clone, Debug)]
pub struct EditorOptions {
    /// A model to start with (and the file it came from); without one, the default genus-2 model
    /// is fitted in the background.
    pub model: Option<Surface>,
    pub file: Option<PathBuf>,
    /// Where autosaves go and crash recovery looks (None: no autosave).
    pub recovery_dir: Option<PathBuf>,
    /// How the viewport's mesh is made: the quality tessellation by default.
    pub meshing: Meshing,
    /// For smoke tests of the real window: close after this many frames with a model shown,
    /// writing the viewport's picture to `screenshot_on_exit` first (if set).
    pub exit_after_frames: Option<u32>,
    pub screenshot_on_exit: Option<PathBuf>,
    /// Native file dialogs (rfd) or the in-window path prompt; None: native where a desktop portal
    /// or zenity is there.
    pub native_dialogs: Option<bool>,
    /// A grab brush makes its next plan on a thread of its own, so no drag event waits for one
    /// (see [`EditorState::plan_in_background`]); off, each event's result depends on the
    /// events alone.
    pub plan_in_background: bool,
}

impl Default for EditorOptions {
    fn default() -> Self {
        EditorOptions {
            model: None,
            file: None,
            recovery_dir: Recovery::default_dir(),
            meshing: Meshing::default(),
            exit_after_frames: None,
            screenshot_on_exit: None,
            native_dialogs: None,
            plan_in_background: true,
        }
    }
}

/// The smoke test of the real window: how many frames were drawn with a model, when to stop, and
/// where the viewport's last picture goes.
struct SmokeTest {
    frames: u32,
    exit_after: Option<u32>,
    screenshot: Option<PathBuf>,
}

/// The editor application.
pub struct EditorApp {
    pub(super) state: Option<EditorState>,
    pub(super) viewport: Viewport,
    pub(super) panel: SidePanel,
    pub(super) dialogs: Dialogs,
    pub(super) jobs: Jobs,
    pub(super) messages: Messages,
    pub(super) recovery: Option<Recovery>,
    pub(super) orphans: Vec<Orphan>,
    /// What the UI asked for, applied in order at the start of the next frame.
    commands: Vec<Command>,
    timings: Timings,
    /// A close that needs no question (the changes were saved or dropped), and a close to ask for.
    pub(super) allow_close: bool,
    pub(super) close_now: bool,
    /// Where the viewport's picture is to be saved at the end of the frame.
    pub(super) pending_screenshot: Option<PathBuf>,
    /// The tessellation used when the first model arrives.
    meshing: Meshing,
    /// Handed to every model shown ([`EditorOptions::plan_in_background`]).
    plan_in_background: bool,
    smoke: SmokeTest,
    title: String,
}

impl EditorApp {
    pub fn new(cc: &eframe::CreationContext<'_>, options: EditorOptions) -> EditorApp {
        let recovery = options.recovery_dir.map(Recovery::new);
        let orphans = recovery.as_ref().map(Recovery::orphans).unwrap_or_default();
        let native = options
            .native_dialogs
            .unwrap_or_else(native_dialogs_available);
        let mut app = EditorApp {
            state: None,
            viewport: Viewport::new(cc.wgpu_render_state.clone()),
            panel: SidePanel::default(),
            dialogs: Dialogs::new(native),
            jobs: Jobs::default(),
            messages: Messages::default(),
            recovery,
            orphans,
            commands: Vec::new(),
            timings: Timings::default(),
            allow_close: false,
            close_now: false,
            pending_screenshot: None,
            meshing: options.meshing,
            plan_in_background: options.plan_in_background,
            smoke: SmokeTest {
                frames: 0,
                exit_after: options.exit_after_frames,
                screenshot: options.screenshot_on_exit,
            },
            title: String::new(),
        };
        match options
            .model
            .map(|model| EditorState::new(model, options.meshing))
        {
            Some(Ok(mut state)) => {
                state.set_path(options.file);
                app.install(state);
            }
            Some(Err(e)) => {
                app.messages.error(format!("cannot show the model: {e}"));
                app.jobs.new_model(2, embedding::fit::default_settings(2).0);
            }
            None => app.jobs.new_model(2, embedding::fit::default_settings(2).0),
        }
        app
    }

    // ------------------------------------------------------------------ for tests and scripts

    pub fn state(&self) -> Option<&EditorState> {
        self.state.as_ref()
    }
    pub fn state_mut(&mut self) -> Option<&mut EditorState> {
        self.state.as_mut()
    }
    /// The viewport's rectangle in egui points (as of the last frame).
    pub fn viewport_rect(&self) -> Rect {
        self.viewport.rect()
    }
    /// The surface point under the pointer (as of the last frame).
    pub fn hover(&self) -> Option<&Pick> {
        self.viewport.hover()
    }
    /// The last clicked surface point.
    pub fn selected(&self) -> Option<&Pick> {
        self.viewport.selected()
    }
    /// Whether a background job (fitting, refitting, exporting) is running.
    pub fn busy(&self) -> bool {
        self.jobs.busy()
    }
    /// Blocks until the background job, if any, is done, and applies its result.
    pub fn wait_for_job(&mut self) {
        if let Some(result) = self.jobs.wait() {
            self.apply(Command::JobDone(result));
        }
    }
    /// The messages shown so far (newest last), errors marked.
    pub fn messages(&self) -> Vec<(String, bool)> {
        self.messages.all()
    }
    /// The recovery files offered at start.
    pub fn orphans(&self) -> &[Orphan] {
        &self.orphans
    }
    /// The autosave, if on.
    pub fn recovery(&self) -> Option<&Recovery> {
        self.recovery.as_ref()
    }
    /// Saves to `path` as File → Save As does.
    pub fn save_to(&mut self, path: &Path) -> Result<(), EditorError> {
        let Some(state) = &mut self.state else {
            return Err(EditorError::Other("no model yet".into()));
        };
        state.save(path)?;
        if let Some(r) = &mut self.recovery {
            r.clear();
        }
        Ok(())
    }
    /// Opens `path` as File → Open does (unsaved changes are dropped).
    pub fn open(&mut self, path: &Path) -> Result<(), EditorError> {
        let state = EditorState::open(path, self.current_meshing())?;
        self.install(state);
        Ok(())
    }
    /// The viewport's last picture.
    pub fn screenshot(&self) -> Result<crate::render::Image, EditorError> {
        self.viewport.screenshot()
    }
    /// Recovers the i-th recovery file offered at start (as the dialog's button does).
    pub fn recover(&mut self, i: usize) -> Result<(), EditorError> {
        let Some(orphan) = self.orphans.get(i).cloned() else {
            return Err(EditorError::Other("no such recovery file".into()));
        };
        let surface = Surface::from_model(&orphan.file.model)?;
        let mut state = EditorState::new(surface, self.current_meshing())?;
        state.set_path(orphan.file.original.clone());
        state.mark_modified();
        self.install(state);
        self.autosave(true);
        Recovery::discard(&orphan);
        self.orphans.remove(i);
        Ok(())
    }

    // ------------------------------------------------------------------ state changes

    pub(super) fn current_meshing(&self) -> Meshing {
        self.state
            .as_ref()
            .map_or(self.meshing, EditorState::meshing)
    }

    /// Shows `state` in place of the current model, in the same viewport.
    pub(super) fn install(&mut self, mut state: EditorState) {
        state.plan_in_background = self.plan_in_background;
        state.viewport = self.state.as_ref().map_or([800.0, 600.0], |s| s.viewport);
        state.frame();
        self.panel.reset(state.settings());
        self.viewport.reset();
        self.state = Some(state);
    }

    /// What the new-model dialog starts with: the current genus and the side panel's settings.
    fn new_model_defaults(&self) -> (u32, SplineSettings) {
        let genus = self.state.as_ref().map_or(2, EditorState::genus);
        (genus, self.panel.draft_settings())
    }

    fn autosave(&mut self, force: bool) {
        let (Some(recovery), Some(state)) = (&mut self.recovery, &self.state) else {
            return;
        };
        if state.drag().is_some() {
            return;
        }
        if !state.is_modified() {
            recovery.clear();
            return;
        }
        let result = recovery.autosave(
            state.history().state(),
            || state.surface().to_model(),
            state.path(),
            force,
        );
        if let Err(e) = result {
            self.messages.error(format!("autosave failed: {e}"));
        }
    }

    fn take_screenshot(&mut self) {
        let Some(path) = self.pending_screenshot.take() else {
            return;
        };
        let result = self
            .screenshot()
            .and_then(|image| Ok(image.to_png()?))
            .and_then(|png| Ok(crate::io::atomic::write_atomically(&path, &png)?));
        match result {
            Ok(()) => self
                .messages
                .info(format!("saved a screenshot to {}", path.display())),
            Err(e) => self.messages.error(format!("screenshot failed: {e}")),
        }
    }

    fn update_title(&mut self, ctx: &Context) {
        let title = match &self.state {
            Some(state) => format!(
                "{}{} — ntori",
                state
                    .path()
                    .and_then(Path::file_name)
                    .map_or("untitled".into(), |n| n.to_string_lossy().into_owned()),
                if state.is_modified() {
                    " (modified)"
                } else {
                    ""
                }
            ),
            None => "ntori".into(),
        };
        if title != self.title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
    }

    /// A close asked for with unsaved changes is held (in this frame) until the user answers.
    fn handle_close(&mut self, ctx: &Context) {
        let modified = self.state.as_ref().is_some_and(EditorState::is_modified);
        if ctx.input(|i| i.viewport().close_requested()) && !self.allow_close && modified {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.commands.push(Command::Guarded(Pending::Close));
        }
    }

    /// The smoke test's end: after its frames, the picture, the messages and timings, and close.
    fn count_frame(&mut self, ctx: &Context) {
        if self.state.is_none() {
            return;
        }
        self.smoke.frames += 1;
        let frames = self.smoke.frames;
        if self.smoke.exit_after.is_some_and(|n| frames >= n) {
            self.smoke.exit_after = None;
            if let Some(path) = self.smoke.screenshot.take() {
                self.pending_screenshot = Some(path);
                self.take_screenshot();
            }
            for (text, _) in self.messages() {
                eprintln!("ntori edit: {text}");
            }
            let frame = self.timings.frame().unwrap_or(0.0);
            let cpu = self.timings.cpu().unwrap_or(0.0);
            eprintln!(
                "ntori edit: {frames} frames, {:.1} ms per frame ({:.1} ms on the CPU)",
                1e3 * frame,
                1e3 * cpu
            );
            self.allow_close = true;
            self.close_now = true;
        } else if self.smoke.exit_after.is_some() {
            ctx.request_repaint();
        }
    }
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let started = Instant::now();
        let ctx = ui.ctx().clone();
        // What was asked for since the last frame (its UI's commands, the finished job, a close, the
        // keyboard), applied in order before anything is drawn: the keyboard acts before the
        // viewport sees the pointer (Esc cancels a drag before egui's own end of it releases it).
        if let Some(result) = self.jobs.poll(&ctx) {
            self.commands.push(Command::JobDone(result));
        }
        self.handle_close(&ctx);
        let new_model = self.new_model_defaults();
        let (busy, has_model) = (self.jobs.busy(), self.state.is_some());
        commands::shortcuts(&ctx, busy, has_model, new_model, &mut self.commands);
        for command in std::mem::take(&mut self.commands) {
            self.apply(command);
        }

        let busy = self.jobs.busy();
        let new_model = self.new_model_defaults();
        let commands = &mut self.commands;
        egui::Panel::top("menu").show(ui, |ui| {
            panels::menu_bar(ui, self.state.as_ref(), busy, new_model, commands);
        });
        egui::Panel::bottom("status").show(ui, |ui| {
            let state = self.state.as_ref();
            panels::status_bar(ui, state, &self.jobs, &self.timings, &self.messages);
        });
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(270.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    let (state, selected) = (self.state.as_mut(), self.viewport.selected());
                    self.panel.ui(ui, state, busy, selected, commands);
                });
            });
        egui::CentralPanel::no_frame().show(ui, |ui| {
            let job = self.jobs.running().map(|(what, _)| what);
            let state = self.state.as_mut();
            self.viewport.ui(ui, frame, state, job, &mut self.messages);
        });
        let current = self.state.as_ref().and_then(EditorState::path);
        self.dialogs.ui(&ctx, current, &self.orphans, commands);
        if !self.commands.is_empty() {
            // They are applied at the start of the next frame.
            ctx.request_repaint();
        }

        self.take_screenshot();
        self.autosave(false);
        self.update_title(&ctx);
        self.count_frame(&ctx);
        if self.close_now {
            self.close_now = false;
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        self.timings.record(started.elapsed());
    }

    fn on_exit(&mut self) {
        // A clean exit: nothing to recover (the user saved or chose not to).
        if let Some(r) = &mut self.recovery {
            r.clear();
        }
    }
}
