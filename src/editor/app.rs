//! The egui side: panels, menus, dialogs and the viewport's input, turned into calls on
//! [`EditorState`]. Nothing here computes geometry.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use charts::ChartId;
use egui::{
    Align2, Color32, Context, FontId, Key, KeyboardShortcut, Modifiers, PointerButton, Pos2, Rect,
    Sense, Stroke, Vec2,
};
use embedding::fit::{FitSettings, initial_model};
use embedding::{Point3, SplineSettings, Surface};

use super::gpu::ViewportRenderer;
use super::recovery::{Orphan, Recovery};
use super::state::{DEFAULT_T, EditorError, EditorState, Grab, MAX_T, Pick, refit};
use crate::render::{CurvatureKind, Style};

/// How the editor starts.
#[derive(Clone, Debug)]
pub struct EditorOptions {
    /// A model to start with (and the file it came from); without one, the default genus-2 model
    /// is fitted in the background.
    pub model: Option<Surface>,
    pub file: Option<PathBuf>,
    /// Where autosaves go and crash recovery looks (None: no autosave).
    pub recovery_dir: Option<PathBuf>,
    /// The tessellation (t_e, t_r).
    pub tessellation: (u32, u32),
    /// For smoke tests of the real window: close after this many frames with a model shown,
    /// writing the viewport's picture to `screenshot_on_exit` first (if set).
    pub exit_after_frames: Option<u32>,
    pub screenshot_on_exit: Option<PathBuf>,
    /// Native file dialogs (rfd) or the in-window path prompt; None: native where a desktop portal
    /// or zenity is there.
    pub native_dialogs: Option<bool>,
}

impl Default for EditorOptions {
    fn default() -> Self {
        EditorOptions {
            model: None,
            file: None,
            recovery_dir: Recovery::default_dir(),
            tessellation: (DEFAULT_T, DEFAULT_T),
            exit_after_frames: None,
            screenshot_on_exit: None,
            native_dialogs: None,
        }
    }
}

/// Resolution of the input meshes of new models (points around each hole), as `ntori new` uses.
const NEW_MODEL_RESOLUTION: usize = 32;

/// Work done off the UI thread.
enum JobOutput {
    NewModel {
        genus: u32,
        result: Result<Surface, String>,
    },
    Refit {
        settings: SplineSettings,
        result: Result<(Vec<Point3>, f64), String>,
    },
    Exported(Result<String, String>),
}

struct Job {
    what: String,
    started: Instant,
    receiver: Receiver<JobOutput>,
}

/// What a pointer drag in the viewport does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Interaction {
    None,
    Orbit,
    Pan,
    Edit,
}

/// A file the user is asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FileAction {
    Open,
    SaveAs,
    Export,
    Screenshot,
}

impl FileAction {
    fn title(self) -> &'static str {
        match self {
            FileAction::Open => "Open model",
            FileAction::SaveAs => "Save model as",
            FileAction::Export => "Export mesh",
            FileAction::Screenshot => "Save screenshot",
        }
    }
    fn button(self) -> &'static str {
        match self {
            FileAction::Open => "Open",
            FileAction::SaveAs => "Save",
            FileAction::Export => "Export",
            FileAction::Screenshot => "Save",
        }
    }
}

/// An action that waits for the answer to "save changes?".
#[derive(Clone, Debug, PartialEq)]
enum Pending {
    New(u32, SplineSettings),
    Open(Option<PathBuf>),
    Close,
    Recover(usize),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Level {
    Info,
    Error,
}

/// Rolling frame timings.
#[derive(Default)]
struct Timings {
    last_frame: Option<Instant>,
    intervals: Vec<f64>,
    cpu: Vec<f64>,
}

impl Timings {
    fn record(&mut self, cpu: Duration) {
        let now = Instant::now();
        if let Some(last) = self.last_frame {
            push_capped(&mut self.intervals, (now - last).as_secs_f64());
        }
        self.last_frame = Some(now);
        push_capped(&mut self.cpu, cpu.as_secs_f64());
    }
    fn mean(v: &[f64]) -> Option<f64> {
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    }
}

fn push_capped(v: &mut Vec<f64>, x: f64) {
    if v.len() >= 30 {
        v.remove(0);
    }
    v.push(x);
}

/// The editor application.
pub struct EditorApp {
    state: Option<EditorState>,
    render_state: Option<egui_wgpu::RenderState>,
    gpu: Option<ViewportRenderer>,
    texture: Option<(egui::TextureId, u64)>,
    job: Option<Job>,
    recovery: Option<Recovery>,
    orphans: Vec<Orphan>,
    interaction: Interaction,
    hover: Option<Pick>,
    selected: Option<Pick>,
    viewport_rect: Rect,
    timings: Timings,
    messages: Vec<(String, Level, Instant)>,
    // Dialogs.
    show_help: bool,
    new_dialog: Option<(u32, SplineSettings)>,
    prompt: Option<(FileAction, String, Option<Pending>)>,
    pending: Option<Pending>,
    allow_close: bool,
    close_now: bool,
    pending_screenshot: Option<PathBuf>,
    // Drafts for the side panel.
    draft_settings: SplineSettings,
    /// The tessellation sliders while they move (applied when let go).
    draft_t: Option<(u32, u32)>,
    /// The tessellation used when the first model arrives.
    tessellation: (u32, u32),
    native_dialogs: bool,
    /// Frames drawn with a model (for `exit_after_frames`).
    frames: u32,
    exit_after_frames: Option<u32>,
    screenshot_on_exit: Option<PathBuf>,
    title: String,
    /// What the viewport last drew (uniforms, size, texture), to skip drawing an unchanged view.
    last_drawn: Option<(Vec<u8>, [u32; 2])>,
}

impl EditorApp {
    pub fn new(cc: &eframe::CreationContext<'_>, options: EditorOptions) -> EditorApp {
        let recovery = options.recovery_dir.map(Recovery::new);
        let orphans = recovery.as_ref().map(Recovery::orphans).unwrap_or_default();
        let mut app = EditorApp {
            state: None,
            render_state: cc.wgpu_render_state.clone(),
            gpu: None,
            texture: None,
            job: None,
            recovery,
            orphans,
            interaction: Interaction::None,
            hover: None,
            selected: None,
            viewport_rect: Rect::from_min_size(Pos2::ZERO, Vec2::new(800.0, 600.0)),
            timings: Timings::default(),
            messages: Vec::new(),
            show_help: false,
            new_dialog: None,
            prompt: None,
            pending: None,
            allow_close: false,
            close_now: false,
            pending_screenshot: None,
            draft_settings: SplineSettings::default(),
            draft_t: None,
            tessellation: options.tessellation,
            native_dialogs: options
                .native_dialogs
                .unwrap_or_else(native_dialogs_available),
            frames: 0,
            exit_after_frames: options.exit_after_frames,
            screenshot_on_exit: options.screenshot_on_exit,
            title: String::new(),
            last_drawn: None,
        };
        match options.model {
            Some(model) => {
                match EditorState::new(model, options.tessellation.0, options.tessellation.1) {
                    Ok(mut state) => {
                        state.set_path(options.file);
                        app.install(state);
                    }
                    Err(e) => {
                        app.error(format!("cannot show the model: {e}"));
                        app.start_new_model(2, SplineSettings::default());
                    }
                }
            }
            None => app.start_new_model(2, SplineSettings::default()),
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
        self.viewport_rect
    }
    /// The surface point under the pointer (as of the last frame).
    pub fn hover(&self) -> Option<&Pick> {
        self.hover.as_ref()
    }
    /// The last clicked surface point.
    pub fn selected(&self) -> Option<&Pick> {
        self.selected.as_ref()
    }
    /// Whether a background job (fitting, refitting, exporting) is running.
    pub fn busy(&self) -> bool {
        self.job.is_some()
    }
    /// Blocks until the background job, if any, is done, and applies its result.
    pub fn wait_for_job(&mut self) {
        if let Some(job) = self.job.take()
            && let Ok(output) = job.receiver.recv()
        {
            self.finish_job(output);
        }
    }
    /// The messages shown so far (newest last), errors marked.
    pub fn messages(&self) -> Vec<(String, bool)> {
        self.messages
            .iter()
            .map(|(m, l, _)| (m.clone(), *l == Level::Error))
            .collect()
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
        let (te, tr) = self.current_t();
        let state = EditorState::open(path, te, tr)?;
        self.install(state);
        Ok(())
    }
    /// The viewport's last picture.
    pub fn screenshot(&self) -> Result<crate::render::Image, EditorError> {
        let (Some(gpu), Some(rs)) = (&self.gpu, &self.render_state) else {
            return Err(EditorError::Other("no GPU viewport".into()));
        };
        Ok(gpu.read_back(&rs.device, &rs.queue)?)
    }
    /// Recovers the i-th recovery file offered at start (as the dialog's button does).
    pub fn recover(&mut self, i: usize) -> Result<(), EditorError> {
        let Some(orphan) = self.orphans.get(i).cloned() else {
            return Err(EditorError::Other("no such recovery file".into()));
        };
        let (te, tr) = self.current_t();
        let surface = Surface::from_model(&orphan.file.model)?;
        let mut state = EditorState::new(surface, te, tr)?;
        state.set_path(orphan.file.original.clone());
        state.mark_modified();
        self.install(state);
        self.autosave(true);
        Recovery::discard(&orphan);
        self.orphans.remove(i);
        Ok(())
    }

    // ------------------------------------------------------------------ state changes

    fn current_t(&self) -> (u32, u32) {
        self.state
            .as_ref()
            .map_or(self.tessellation, EditorState::tessellation)
    }

    fn install(&mut self, mut state: EditorState) {
        state.viewport = self.state.as_ref().map_or([800.0, 600.0], |s| s.viewport);
        state.frame();
        self.draft_settings = state.settings();
        self.draft_t = None;
        self.hover = None;
        self.selected = None;
        self.interaction = Interaction::None;
        self.state = Some(state);
    }

    fn info(&mut self, text: impl Into<String>) {
        self.messages
            .push((text.into(), Level::Info, Instant::now()));
    }
    fn error(&mut self, text: impl Into<String>) {
        let text = text.into();
        tracing::warn!("{text}");
        self.messages.push((text, Level::Error, Instant::now()));
    }

    fn start_new_model(&mut self, genus: u32, settings: SplineSettings) {
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let result = initial_model(
                genus,
                NEW_MODEL_RESOLUTION,
                settings,
                FitSettings::default(),
            )
            .map(|fit| fit.surface)
            .map_err(|e| e.to_string());
            let _ = sender.send(JobOutput::NewModel { genus, result });
        });
        self.job = Some(Job {
            what: format!("fitting a new genus-{genus} model"),
            started: Instant::now(),
            receiver,
        });
    }

    fn start_refit(&mut self, settings: SplineSettings) {
        let Some(state) = &self.state else { return };
        let surface = state.surface().clone();
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let result = refit(&surface, settings).map_err(|e| e.to_string());
            let _ = sender.send(JobOutput::Refit { settings, result });
        });
        self.job = Some(Job {
            what: format!(
                "refitting to degree {}, C^{}, grid {}",
                settings.degree, settings.continuity, settings.grid
            ),
            started: Instant::now(),
            receiver,
        });
    }

    fn start_export(&mut self, path: PathBuf) {
        let Some(state) = &self.state else { return };
        let surface = state.surface().clone();
        let (te, tr) = state.tessellation();
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let result = (|| -> Result<String, EditorError> {
                let format = crate::io::export::Format::from_path(&path)?;
                let mesh = crate::io::export::surface_mesh(&surface, te, tr)?;
                crate::io::export::write(&mesh, &path, format, crate::io::export::Encoding::Binary)?;
                Ok(format!(
                    "exported {} triangles to {}",
                    mesh.triangles.len(),
                    path.display()
                ))
            })()
            .map_err(|e| e.to_string());
            let _ = sender.send(JobOutput::Exported(result));
        });
        self.job = Some(Job {
            what: "exporting".into(),
            started: Instant::now(),
            receiver,
        });
    }

    fn poll_job(&mut self, ctx: &Context) {
        let Some(job) = &self.job else { return };
        match job.receiver.try_recv() {
            Ok(output) => {
                self.job = None;
                self.finish_job(output);
            }
            Err(TryRecvError::Empty) => ctx.request_repaint_after(Duration::from_millis(50)),
            Err(TryRecvError::Disconnected) => {
                self.job = None;
                self.error("a background job stopped unexpectedly");
            }
        }
    }

    fn finish_job(&mut self, output: JobOutput) {
        match output {
            JobOutput::NewModel { genus, result } => match result {
                Ok(model) => {
                    let (te, tr) = self.current_t();
                    match EditorState::new(model, te, tr) {
                        Ok(state) => {
                            self.install(state);
                            self.info(format!("new genus-{genus} model"));
                        }
                        Err(e) => self.error(format!("cannot show the new model: {e}")),
                    }
                }
                Err(e) => self.error(format!("cannot make a genus-{genus} model: {e}")),
            },
            JobOutput::Refit { settings, result } => match result {
                Ok((control, worst)) => {
                    let Some(state) = &mut self.state else { return };
                    let size = state.size();
                    match state.set_settings(settings, control) {
                        Ok(()) => {
                            self.draft_settings = settings;
                            self.info(format!(
                                "refitted: the surface moved by at most {:.3}% of its size",
                                100.0 * worst / size.max(f64::MIN_POSITIVE)
                            ));
                        }
                        Err(e) => self.error(format!("cannot use the new settings: {e}")),
                    }
                }
                Err(e) => self.error(format!("cannot refit: {e}")),
            },
            JobOutput::Exported(result) => match result {
                Ok(text) => self.info(text),
                Err(e) => self.error(format!("export failed: {e}")),
            },
        }
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
            self.error(format!("autosave failed: {e}"));
        }
    }

    fn undo(&mut self) {
        let Some(state) = &mut self.state else { return };
        match state.undo() {
            Ok(Some(label)) => self.info(format!("undid {label}")),
            Ok(None) => {}
            Err(e) => self.error(format!("cannot undo: {e}")),
        }
    }

    fn redo(&mut self) {
        let Some(state) = &mut self.state else { return };
        match state.redo() {
            Ok(Some(label)) => self.info(format!("redid {label}")),
            Ok(None) => {}
            Err(e) => self.error(format!("cannot redo: {e}")),
        }
    }

    fn modified(&self) -> bool {
        self.state.as_ref().is_some_and(EditorState::is_modified)
    }

    /// Runs `action`, first asking about unsaved changes.
    fn guarded(&mut self, action: Pending) {
        if self.modified() {
            self.pending = Some(action);
        } else {
            self.run_pending(action);
        }
    }

    fn run_pending(&mut self, action: Pending) {
        match action {
            Pending::New(genus, settings) => self.start_new_model(genus, settings),
            Pending::Open(Some(path)) => {
                if let Err(e) = self.open(&path) {
                    self.error(e.to_string());
                }
            }
            Pending::Open(None) => self.ask_file(FileAction::Open, None),
            Pending::Close => {
                self.allow_close = true;
                self.close_now = true;
            }
            Pending::Recover(i) => {
                if let Err(e) = self.recover(i) {
                    self.error(format!("cannot recover: {e}"));
                }
            }
        }
    }

    /// Asks for a file: the native dialog where one can be shown, else a path prompt.
    fn ask_file(&mut self, action: FileAction, then: Option<Pending>) {
        if self.native_dialogs {
            let mut dialog = rfd::FileDialog::new().set_title(action.title());
            dialog = match action {
                FileAction::Open | FileAction::SaveAs => {
                    dialog.add_filter("ntori model", &["json"])
                }
                FileAction::Export => dialog.add_filter(
                    "Mesh",
                    &crate::io::export::Format::ALL.map(crate::io::export::Format::extension),
                ),
                FileAction::Screenshot => dialog.add_filter("PNG image", &["png"]),
            };
            if let Some(dir) = self
                .state
                .as_ref()
                .and_then(|s| s.path())
                .and_then(Path::parent)
            {
                dialog = dialog.set_directory(dir);
            }
            let chosen = match action {
                FileAction::Open => dialog.pick_file(),
                _ => dialog
                    .set_file_name(self.suggested_name(action))
                    .save_file(),
            };
            if let Some(path) = chosen {
                self.file_chosen(action, path, then);
            }
            return;
        }
        let text = match action {
            FileAction::Open => String::new(),
            _ => self.suggested_name(action),
        };
        self.prompt = Some((action, text, then));
    }

    fn suggested_name(&self, action: FileAction) -> String {
        let stem = self
            .state
            .as_ref()
            .and_then(|s| s.path())
            .and_then(Path::file_stem)
            .and_then(|s| s.to_str())
            .unwrap_or("model")
            .to_owned();
        match action {
            FileAction::Open | FileAction::SaveAs => format!("{stem}.json"),
            FileAction::Export => format!("{stem}.obj"),
            FileAction::Screenshot => format!("{stem}.png"),
        }
    }

    fn file_chosen(&mut self, action: FileAction, path: PathBuf, then: Option<Pending>) {
        match action {
            FileAction::Open => {
                if let Err(e) = self.open(&path) {
                    self.error(e.to_string());
                }
            }
            FileAction::SaveAs => match self.save_to(&path) {
                Ok(()) => {
                    self.info(format!("saved {}", path.display()));
                    if let Some(next) = then {
                        self.run_pending(next);
                    }
                }
                Err(e) => self.error(e.to_string()),
            },
            FileAction::Export => self.start_export(path),
            FileAction::Screenshot => self.pending_screenshot = Some(path),
        }
    }

    fn save(&mut self, then: Option<Pending>) {
        match self
            .state
            .as_ref()
            .and_then(|s| s.path())
            .map(Path::to_owned)
        {
            Some(path) => match self.save_to(&path) {
                Ok(()) => {
                    self.info(format!("saved {}", path.display()));
                    if let Some(next) = then {
                        self.run_pending(next);
                    }
                }
                Err(e) => self.error(e.to_string()),
            },
            None => self.ask_file(FileAction::SaveAs, then),
        }
    }
}

/// Whether rfd can show a dialog: an XDG desktop portal on the session bus, or zenity.
fn native_dialogs_available() -> bool {
    if std::env::var_os("NTORI_NO_NATIVE_DIALOGS").is_some() {
        return false;
    }
    if !cfg!(target_os = "linux") {
        return true;
    }
    let bus = std::env::var_os("DBUS_SESSION_BUS_ADDRESS").is_some_and(|s| !s.is_empty());
    let zenity = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join("zenity").is_file()));
    bus || zenity
}

// ---------------------------------------------------------------------------------------- drawing

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let started = Instant::now();
        let ctx = ui.ctx().clone();
        self.poll_job(&ctx);
        self.handle_close(&ctx);
        self.shortcuts(&ctx);

        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(270.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_panel(ui));
            });
        egui::CentralPanel::no_frame().show(ui, |ui| self.viewport(ui, frame));

        self.dialogs(&ctx);
        self.take_screenshot();
        self.autosave(false);
        self.update_title(&ctx);
        if self.state.is_some() {
            self.frames += 1;
            if self.exit_after_frames.is_some_and(|n| self.frames >= n) {
                self.exit_after_frames = None;
                if let Some(path) = self.screenshot_on_exit.take() {
                    self.pending_screenshot = Some(path);
                    self.take_screenshot();
                }
                for (text, _) in self.messages() {
                    eprintln!("ntori edit: {text}");
                }
                let frame = Timings::mean(&self.timings.intervals).unwrap_or(0.0);
                let cpu = Timings::mean(&self.timings.cpu).unwrap_or(0.0);
                eprintln!(
                    "ntori edit: {} frames, {:.1} ms per frame ({:.1} ms on the CPU)",
                    self.frames,
                    1e3 * frame,
                    1e3 * cpu
                );
                self.allow_close = true;
                self.close_now = true;
            } else if self.exit_after_frames.is_some() {
                ctx.request_repaint();
            }
        }
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

/// A keyboard shortcut: Ctrl (Cmd on macOS) with `key`.
fn command(key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(Modifiers::COMMAND, key)
}
fn command_shift(key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, key)
}

/// Every shortcut, for the help panel and the menus.
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
    ("Ctrl + Z", "undo"),
    ("Ctrl + Shift + Z, Ctrl + Y", "redo"),
    ("Ctrl + N", "new model"),
    ("Ctrl + O", "open"),
    ("Ctrl + S", "save"),
    ("Ctrl + Shift + S", "save as"),
    ("Ctrl + E", "export the mesh"),
    ("F12", "screenshot of the viewport"),
    ("F1", "this help"),
    ("Ctrl + Q", "quit"),
];

impl EditorApp {
    fn shortcuts(&mut self, ctx: &Context) {
        let busy = self.job.is_some();
        let consume = |s: KeyboardShortcut| ctx.input_mut(|i| i.consume_shortcut(&s));
        // The shifted forms first: Ctrl + Z also matches Ctrl + Shift + Z.
        if consume(command_shift(Key::Z)) || consume(command(Key::Y)) {
            self.redo();
        }
        if consume(command(Key::Z)) {
            self.undo();
        }
        if consume(command_shift(Key::S)) && !busy {
            self.ask_file(FileAction::SaveAs, None);
        }
        if consume(command(Key::S)) && !busy {
            self.save(None);
        }
        if consume(command(Key::O)) && !busy {
            self.guarded(Pending::Open(None));
        }
        if consume(command(Key::N)) && !busy {
            let genus = self.state.as_ref().map_or(2, EditorState::genus);
            self.new_dialog = Some((genus, self.draft_settings));
        }
        if consume(command(Key::E)) && !busy {
            self.ask_file(FileAction::Export, None);
        }
        if consume(command(Key::Q)) {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
        if consume(KeyboardShortcut::new(Modifiers::NONE, Key::F12)) {
            self.ask_file(FileAction::Screenshot, None);
        }
        if consume(KeyboardShortcut::new(Modifiers::NONE, Key::F1)) {
            self.show_help = !self.show_help;
        }
        if ctx.egui_wants_keyboard_input() {
            return;
        }
        let plain = |key: Key| consume(KeyboardShortcut::new(Modifiers::NONE, key));
        if plain(Key::Escape) {
            if let Some(state) = &mut self.state
                && state.drag().is_some()
            {
                state.cancel_drag();
                self.interaction = Interaction::None;
                self.info("drag cancelled");
            } else {
                self.show_help = false;
                self.prompt = None;
                self.new_dialog = None;
            }
        }
        let Some(state) = &mut self.state else { return };
        if plain(Key::F) {
            state.frame();
        }
        if plain(Key::Home) {
            state.reset_view();
        }
        let styles = [
            (Key::Num1, Style::Shaded),
            (Key::Num2, Style::Wireframe),
            (Key::Num3, Style::Charts),
            (Key::Num4, Style::Curvature(CurvatureKind::Gaussian)),
            (Key::Num5, Style::Curvature(CurvatureKind::Mean)),
        ];
        for (key, style) in styles {
            if plain(key) {
                state.set_style(style);
            }
        }
        if plain(Key::C) {
            let charts = state.atlas().charts().len() as u32;
            state.control_chart = match state.control_chart {
                None => Some(ChartId(0)),
                Some(c) if c.0 + 1 < charts => Some(ChartId(c.0 + 1)),
                Some(_) => None,
            };
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

    fn handle_close(&mut self, ctx: &Context) {
        if ctx.input(|i| i.viewport().close_requested()) && !self.allow_close && self.modified() {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.pending = Some(Pending::Close);
        }
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        let busy = self.job.is_some();
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui
                    .add_enabled(
                        !busy,
                        egui::Button::new("New model…").shortcut_text("Ctrl+N"),
                    )
                    .clicked()
                {
                    let genus = self.state.as_ref().map_or(2, EditorState::genus);
                    self.new_dialog = Some((genus, self.draft_settings));
                }
                if ui
                    .add_enabled(!busy, egui::Button::new("Open…").shortcut_text("Ctrl+O"))
                    .clicked()
                {
                    self.guarded(Pending::Open(None));
                }
                let has = self.state.is_some();
                if ui
                    .add_enabled(
                        has && !busy,
                        egui::Button::new("Save").shortcut_text("Ctrl+S"),
                    )
                    .clicked()
                {
                    self.save(None);
                }
                if ui
                    .add_enabled(
                        has && !busy,
                        egui::Button::new("Save as…").shortcut_text("Ctrl+Shift+S"),
                    )
                    .clicked()
                {
                    self.ask_file(FileAction::SaveAs, None);
                }
                ui.separator();
                if ui
                    .add_enabled(
                        has && !busy,
                        egui::Button::new("Export mesh…").shortcut_text("Ctrl+E"),
                    )
                    .clicked()
                {
                    self.ask_file(FileAction::Export, None);
                }
                if ui
                    .add_enabled(has, egui::Button::new("Screenshot…").shortcut_text("F12"))
                    .clicked()
                {
                    self.ask_file(FileAction::Screenshot, None);
                }
                ui.separator();
                if ui
                    .add(egui::Button::new("Quit").shortcut_text("Ctrl+Q"))
                    .clicked()
                {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Edit", |ui| {
                let (undo, redo) = self.state.as_ref().map_or((None, None), |s| {
                    (
                        s.can_undo()
                            .then(|| s.history().undo_label().unwrap_or("").to_owned()),
                        s.can_redo()
                            .then(|| s.history().redo_label().unwrap_or("").to_owned()),
                    )
                });
                let undo_text = undo.as_ref().map_or("Undo".into(), |l| format!("Undo {l}"));
                if ui
                    .add_enabled(
                        undo.is_some(),
                        egui::Button::new(undo_text).shortcut_text("Ctrl+Z"),
                    )
                    .clicked()
                {
                    self.undo();
                }
                let redo_text = redo.as_ref().map_or("Redo".into(), |l| format!("Redo {l}"));
                if ui
                    .add_enabled(
                        redo.is_some(),
                        egui::Button::new(redo_text).shortcut_text("Ctrl+Shift+Z"),
                    )
                    .clicked()
                {
                    self.redo();
                }
                ui.separator();
                let pins = self.state.as_ref().is_some_and(|s| !s.pins().is_empty());
                if ui
                    .add_enabled(pins, egui::Button::new("Clear pins"))
                    .clicked()
                    && let Some(s) = &mut self.state
                {
                    s.clear_pins();
                }
            });
            ui.menu_button("View", |ui| {
                let Some(state) = &mut self.state else { return };
                if ui
                    .add(egui::Button::new("Frame model").shortcut_text("F"))
                    .clicked()
                {
                    state.frame();
                }
                if ui
                    .add(egui::Button::new("Reset view").shortcut_text("Home"))
                    .clicked()
                {
                    state.reset_view();
                }
                ui.separator();
                style_radio(ui, state);
            });
            ui.menu_button("Help", |ui| {
                if ui
                    .add(egui::Button::new("Shortcuts").shortcut_text("F1"))
                    .clicked()
                {
                    self.show_help = true;
                }
            });
        });
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        let busy = self.job.is_some();
        ui.heading("Model");
        let Some(state) = &mut self.state else {
            ui.label("No model yet.");
            return;
        };
        ui.label(format!(
            "Genus {}: {} charts, {} control points",
            state.genus(),
            state.atlas().charts().len(),
            state.control().len()
        ));
        if ui
            .add_enabled(!busy, egui::Button::new("New model…"))
            .clicked()
        {
            self.new_dialog = Some((state.genus(), state.settings()));
        }

        ui.separator();
        ui.label("Spline (applying refits the surface)");
        let d = &mut self.draft_settings;
        egui::Grid::new("settings")
            .num_columns(2)
            .show(ui, |ui| settings_grid(ui, d));
        d.grid = d.grid.max(d.degree + 1);
        let changed = *d != state.settings();
        let draft = *d;
        ui.horizontal(|ui| {
            if ui
                .add_enabled(changed && !busy, egui::Button::new("Apply"))
                .clicked()
            {
                self.start_refit(draft);
            }
            if ui
                .add_enabled(changed, egui::Button::new("Revert"))
                .clicked()
                && let Some(s) = &self.state
            {
                self.draft_settings = s.settings();
            }
        });
        let Some(state) = &mut self.state else { return };

        ui.separator();
        ui.label("Tessellation");
        let (mut te, mut tr) = self.draft_t.unwrap_or(state.tessellation());
        let a = ui.add(
            egui::Slider::new(&mut te, 1..=MAX_T)
                .logarithmic(true)
                .text("t_e"),
        );
        let b = ui.add(
            egui::Slider::new(&mut tr, 1..=MAX_T)
                .logarithmic(true)
                .text("t_r"),
        );
        if a.changed() || b.changed() {
            self.draft_t = Some((te, tr));
        }
        let vertices = charts::Tessellation::expected_vertices(state.genus(), te, tr);
        let triangles = charts::Tessellation::expected_triangles(state.genus(), te, tr);
        ui.label(format!(
            "{} vertices, {} triangles",
            thousands(vertices),
            thousands(triangles)
        ));
        if vertices > 1_000_000 {
            ui.colored_label(
                Color32::from_rgb(230, 160, 60),
                "Over a million vertices: about 1 GB of memory per million",
            );
        }
        let released = !(a.dragged() || b.dragged());
        if released
            && let Some(t) = self.draft_t.take()
            && t != state.tessellation()
            && let Err(e) = state.set_tessellation(t.0, t.1)
        {
            self.error(e.to_string());
            return;
        }

        ui.separator();
        ui.label("Display");
        style_radio(ui, state);
        if let Some(range) = state.mesh().curvature_range() {
            ui.label(format!("Colour scale: ±{range:.4} (blue < 0 < red)"));
        }
        let chart_name = |c: Option<ChartId>, state: &EditorState| match c {
            None => "none".to_owned(),
            Some(c) => state
                .atlas()
                .charts()
                .get(c.index())
                .map_or("?".into(), |k| format!("{} ({})", c.0, k.kind().label())),
        };
        let current = chart_name(state.control_chart, state);
        egui::ComboBox::from_label("control points")
            .selected_text(current)
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut state.control_chart, None, "none");
                for c in 0..state.atlas().charts().len() as u32 {
                    let name = chart_name(Some(ChartId(c)), state);
                    ui.selectable_value(&mut state.control_chart, Some(ChartId(c)), name);
                }
            });

        ui.separator();
        ui.label("Editing");
        ui.add(
            egui::Slider::new(&mut state.influence, 0.0..=0.5)
                .text("influence radius")
                .custom_formatter(|v, _| {
                    if v == 0.0 {
                        "off".into()
                    } else {
                        format!("{:.0}%", 100.0 * v)
                    }
                }),
        )
        .on_hover_text(
            "Off: the smallest change to the control points that moves the dragged point \
             (the paper's edit). Otherwise control points within this fraction of the model's \
             size also follow the drag, fading out at the radius.",
        );
        ui.label(format!(
            "Pins ({}): Ctrl + click to add or remove",
            state.pins().len()
        ));
        let mut remove = None;
        for (i, p) in state.pins().iter().enumerate() {
            ui.horizontal(|ui| {
                if ui.small_button("x").on_hover_text("unpin").clicked() {
                    remove = Some(i);
                }
                ui.label(format!(
                    "chart {} ({:.3}, {:.3})",
                    p.chart.0, p.coords.re, p.coords.im
                ));
            });
        }
        if let Some(i) = remove {
            state.remove_pin(i);
        }
        if !state.pins().is_empty() && ui.button("Clear pins").clicked() {
            state.clear_pins();
        }

        if let Some(pick) = &self.selected {
            ui.separator();
            ui.label("Picked point");
            ui.label(format!(
                "triangle {}, barycentric ({:.4}, {:.4}, {:.4})",
                pick.hit.triangle, pick.hit.bary[0], pick.hit.bary[1], pick.hit.bary[2]
            ));
            for rep in pick.manifold.representations() {
                ui.label(format!(
                    "chart {}: ({:.6}, {:.6})",
                    rep.chart.0, rep.coords.re, rep.coords.im
                ));
            }
            ui.label(format!(
                "S = ({:.5}, {:.5}, {:.5})",
                pick.surface.x, pick.surface.y, pick.surface.z
            ));
        }
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            if let Some(job) = &self.job {
                ui.spinner();
                ui.label(format!(
                    "{}… {:.0} s",
                    job.what,
                    job.started.elapsed().as_secs_f64()
                ));
                ui.separator();
            }
            if let Some(state) = &self.state {
                let s = state.settings();
                ui.label(format!(
                    "genus {} · degree {} · C^{} · grid {} · {} triangles · {} vertices",
                    state.genus(),
                    s.degree,
                    s.continuity,
                    s.grid,
                    thousands(state.mesh().triangle_count() as u64),
                    thousands(state.mesh().vertex_count() as u64),
                ));
                ui.separator();
            }
            let frame = Timings::mean(&self.timings.intervals);
            let cpu = Timings::mean(&self.timings.cpu);
            if let (Some(f), Some(c)) = (frame, cpu) {
                ui.label(format!("frame {:.1} ms (CPU {:.1} ms)", 1e3 * f, 1e3 * c));
                ui.separator();
            }
            if let Some(state) = &self.state {
                let drag = state
                    .drag()
                    .map(|d| (d.last, d.plan.rows.len()))
                    .or_else(|| state.last_drag.map(|d| (d.mean, d.vertices)));
                if let Some((t, n)) = drag {
                    ui.label(format!(
                        "drag event {:.2} ms ({} vertices)",
                        1e3 * t.as_secs_f64(),
                        thousands(n as u64)
                    ));
                    ui.separator();
                }
                let name = state
                    .path()
                    .map_or("untitled".to_owned(), |p| p.display().to_string());
                let mark = if state.is_modified() {
                    " (modified)"
                } else {
                    ""
                };
                ui.label(format!("{name}{mark}"));
            }
            if let Some((text, level, at)) = self.messages.last()
                && at.elapsed() < Duration::from_secs(8)
            {
                ui.separator();
                let colour = match level {
                    Level::Info => ui.visuals().text_color(),
                    Level::Error => Color32::from_rgb(240, 110, 100),
                };
                ui.colored_label(colour, text);
            }
        });
    }

    fn viewport(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        self.viewport_rect = rect;
        let ctx = ui.ctx().clone();
        let ppp = ctx.pixels_per_point();
        let size_px = [
            (rect.width() * ppp).round().max(1.0) as u32,
            (rect.height() * ppp).round().max(1.0) as u32,
        ];
        let painter = ui.painter_at(rect);
        let Some(state) = &mut self.state else {
            painter.rect_filled(rect, 0.0, background());
            let text = self.job.as_ref().map_or("No model".to_owned(), |j| {
                format!("{}…", capitalise(&j.what))
            });
            painter.text(
                rect.center(),
                Align2::CENTER_CENTER,
                text,
                FontId::proportional(18.0),
                Color32::LIGHT_GRAY,
            );
            ctx.request_repaint_after(Duration::from_millis(100));
            return;
        };
        state.viewport = [f64::from(size_px[0]), f64::from(size_px[1])];
        let to_pixel = |p: Pos2| {
            [
                f64::from(p.x - rect.min.x) * f64::from(size_px[0]) / f64::from(rect.width()),
                f64::from(p.y - rect.min.y) * f64::from(size_px[1]) / f64::from(rect.height()),
            ]
        };
        let to_pos = |q: [f64; 2]| {
            Pos2::new(
                rect.min.x + (q[0] * f64::from(rect.width()) / f64::from(size_px[0])) as f32,
                rect.min.y + (q[1] * f64::from(rect.height()) / f64::from(size_px[1])) as f32,
            )
        };

        // ---- input
        let modifiers = ctx.input(|i| i.modifiers);
        if response.drag_started() {
            let origin = ctx
                .input(|i| i.pointer.press_origin())
                .unwrap_or(rect.center());
            self.interaction = if response.drag_started_by(PointerButton::Secondary)
                || response.drag_started_by(PointerButton::Middle)
                || (response.drag_started_by(PointerButton::Primary) && modifiers.shift)
            {
                Interaction::Pan
            } else if !response.drag_started_by(PointerButton::Primary) || modifiers.alt {
                Interaction::Orbit
            } else {
                match state.press(to_pixel(origin)) {
                    Ok(Some(_)) => Interaction::Edit,
                    Ok(None) => Interaction::Orbit,
                    Err(e) => {
                        self.messages.push((
                            format!("cannot drag: {e}"),
                            Level::Error,
                            Instant::now(),
                        ));
                        Interaction::Orbit
                    }
                }
            };
            self.hover = None;
        }
        if response.dragged() {
            let delta = response.drag_delta() * ppp;
            let (dx, dy) = (f64::from(delta.x), f64::from(delta.y));
            let height = state.viewport[1];
            match self.interaction {
                Interaction::Orbit => state.camera.orbit([dx, dy], height),
                Interaction::Pan => state.camera.pan([dx, dy], height),
                Interaction::Edit => {
                    if let Some(pos) = response.interact_pointer_pos()
                        && let Err(e) = state.drag_to(to_pixel(pos))
                    {
                        self.messages
                            .push((format!("drag: {e}"), Level::Error, Instant::now()));
                    }
                }
                Interaction::None => {}
            }
        }
        if response.drag_stopped() {
            if self.interaction == Interaction::Edit {
                state.release();
            }
            self.interaction = Interaction::None;
        }
        if response.clicked()
            && let Some(pos) = response.interact_pointer_pos()
        {
            let pixel = to_pixel(pos);
            if modifiers.command {
                state.toggle_pin(pixel);
            } else {
                self.selected = state.pick(pixel);
            }
        }
        if response.double_clicked()
            && let Some(pick) = &self.selected
        {
            state.camera.target = super::camera::to_glam(pick.surface);
        }
        if response.hovered() {
            let (wheels, zoom) = ctx.input(|i| (wheel_gestures(&i.events), i.zoom_delta()));
            let height = state.viewport[1];
            for gesture in wheels {
                match gesture {
                    Wheel::Zoom(factor) => state.camera.zoom(factor),
                    Wheel::Orbit(d) => state
                        .camera
                        .orbit([-d[0] * f64::from(ppp), -d[1] * f64::from(ppp)], height),
                    Wheel::Pan(d) => state
                        .camera
                        .pan([d[0] * f64::from(ppp), d[1] * f64::from(ppp)], height),
                }
            }
            if zoom != 1.0 {
                state.camera.zoom(f64::from(zoom));
            }
        }
        if self.interaction == Interaction::None {
            self.hover = response.hover_pos().and_then(|p| state.pick(to_pixel(p)));
        }
        let cursor = match self.interaction {
            Interaction::Edit => Some(egui::CursorIcon::Grabbing),
            Interaction::Orbit | Interaction::Pan => Some(egui::CursorIcon::Move),
            Interaction::None if response.hovered() => {
                let on_pin = response.hover_pos().is_some_and(|p| {
                    state
                        .pin_near(to_pixel(p), super::state::PIN_RADIUS_PX)
                        .is_some()
                });
                (on_pin || self.hover.is_some()).then_some(egui::CursorIcon::Grab)
            }
            Interaction::None => None,
        };
        if let Some(icon) = cursor {
            ctx.set_cursor_icon(icon);
        }

        // ---- the 3D picture
        match frame.wgpu_render_state() {
            Some(rs) => {
                let gpu = self
                    .gpu
                    .get_or_insert_with(|| ViewportRenderer::new(&rs.device));
                let changed =
                    state.with_display(|mesh, drag| gpu.sync(&rs.device, &rs.queue, mesh, drag));
                let uniforms = state.camera.uniforms(state.style(), size_px);
                let key = (bytemuck::bytes_of(&uniforms).to_vec(), size_px);
                if changed || self.last_drawn.as_ref() != Some(&key) || gpu.texture_view().is_none()
                {
                    gpu.render(&rs.device, &rs.queue, size_px, &uniforms);
                    self.last_drawn = Some(key);
                }
                let generation = gpu.generation;
                let Some(view) = gpu.texture_view() else {
                    unreachable!("rendered above")
                };
                let mut renderer = rs.renderer.write();
                let id = match self.texture {
                    Some((id, g)) if g == generation => id,
                    Some((id, _)) => {
                        renderer.update_egui_texture_from_wgpu_texture(
                            &rs.device,
                            view,
                            wgpu::FilterMode::Linear,
                            id,
                        );
                        id
                    }
                    None => {
                        renderer.register_native_texture(&rs.device, view, wgpu::FilterMode::Linear)
                    }
                };
                self.texture = Some((id, generation));
                painter.image(
                    id,
                    rect,
                    Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
                    Color32::WHITE,
                );
            }
            None => {
                painter.rect_filled(rect, 0.0, background());
                painter.text(
                    rect.center(),
                    Align2::CENTER_CENTER,
                    "No GPU: the viewport needs wgpu (install a Vulkan driver, e.g. mesa-vulkan-drivers)",
                    FontId::proportional(15.0),
                    Color32::LIGHT_GRAY,
                );
            }
        }

        // ---- overlays
        let project = |p: Point3| {
            let (q, depth) = state.camera.project(p, state.viewport);
            (depth > 0.0).then(|| to_pos(q))
        };
        if let Some(chart) = state.control_chart {
            let g = state.settings().grid;
            let net = state.control_net(chart);
            let colour = {
                let c = state
                    .atlas()
                    .charts()
                    .get(chart.index())
                    .map_or([0.8; 3], |k| crate::render::palette::stroke_rgb(k.kind()));
                Color32::from_rgb(
                    (c[0] * 255.0) as u8,
                    (c[1] * 255.0) as u8,
                    (c[2] * 255.0) as u8,
                )
            };
            let points: Vec<Option<Pos2>> = net.iter().map(|&p| project(p)).collect();
            let stroke = Stroke::new(1.0, colour.gamma_multiply(0.8));
            for j in 0..g {
                for i in 0..g {
                    let k = j * g + i;
                    let Some(a) = points[k] else { continue };
                    if i + 1 < g
                        && let Some(b) = points[k + 1]
                    {
                        painter.line_segment([a, b], stroke);
                    }
                    if j + 1 < g
                        && let Some(b) = points[k + g]
                    {
                        painter.line_segment([a, b], stroke);
                    }
                }
            }
            for p in points.into_iter().flatten() {
                painter.circle_filled(p, 2.5, colour);
            }
        }
        let dragging = state
            .drag()
            .map(|d| (d.plan.start_position, d.plan.point, d.grab));
        for (i, &pin) in state.pins().iter().enumerate() {
            if matches!(dragging, Some((_, _, Grab::Pin(k))) if k == i) {
                continue;
            }
            if let Some(p) = project(state.surface_point(pin)) {
                painter.circle(
                    p,
                    5.0,
                    Color32::from_rgb(220, 50, 50),
                    Stroke::new(1.5, Color32::WHITE),
                );
            }
        }
        if let Some((start, point, _)) = dragging {
            let now = state.surface_point(point);
            if let (Some(a), Some(b)) = (project(start), project(now)) {
                painter.line_segment([a, b], Stroke::new(1.0, Color32::from_rgb(250, 210, 60)));
                painter.circle(
                    b,
                    5.0,
                    Color32::from_rgb(250, 210, 60),
                    Stroke::new(1.5, Color32::BLACK),
                );
            }
        } else if let Some(pick) = &self.hover
            && let Some(p) = project(pick.surface)
        {
            painter.circle_stroke(p, 4.0, Stroke::new(1.5, Color32::from_rgb(250, 210, 60)));
        }
        if let Some(pick) = &self.selected
            && let Some(p) = project(state.surface_point(pick.point))
        {
            painter.circle_stroke(p, 6.0, Stroke::new(1.5, Color32::WHITE));
        }
        if let (Style::Curvature(kind), Some(range)) =
            (state.style(), state.mesh().curvature_range())
        {
            curvature_legend(&painter, rect, kind, range);
        }
        if let Some(job) = &self.job {
            painter.text(
                rect.left_top() + Vec2::new(12.0, 12.0),
                Align2::LEFT_TOP,
                format!("{}…", capitalise(&job.what)),
                FontId::proportional(15.0),
                Color32::LIGHT_GRAY,
            );
        }
        if let Some(pick) = &self.hover {
            painter.text(
                rect.left_bottom() + Vec2::new(8.0, -8.0),
                Align2::LEFT_BOTTOM,
                state.describe(pick),
                FontId::monospace(12.0),
                Color32::from_gray(220),
            );
        }
        if self.interaction != Interaction::None {
            ctx.request_repaint();
        }
    }

    fn dialogs(&mut self, ctx: &Context) {
        if self.show_help {
            let mut open = true;
            egui::Window::new("Help")
                .open(&mut open)
                .collapsible(false)
                .show(ctx, |ui| {
                    ui.label(
                        "ntori edits a smooth closed surface through its control points. Drag a \
                         point of the surface: the smallest change to the control points moves it \
                         under the cursor (in the plane facing you) while pinned points stay.",
                    );
                    ui.separator();
                    egui::Grid::new("shortcuts").striped(true).show(ui, |ui| {
                        for (keys, what) in SHORTCUTS {
                            ui.strong(*keys);
                            ui.label(*what);
                            ui.end_row();
                        }
                    });
                });
            self.show_help = open;
        }

        if let Some((mut genus, mut settings)) = self.new_dialog {
            let mut open = true;
            let mut create = false;
            egui::Window::new("New model")
                .open(&mut open)
                .collapsible(false)
                .show(ctx, |ui| {
                    egui::Grid::new("new").num_columns(2).show(ui, |ui| {
                        let label = ui.label("Genus");
                        ui.add(egui::DragValue::new(&mut genus).range(0..=64))
                            .labelled_by(label.id);
                        ui.end_row();
                        settings_grid(ui, &mut settings);
                    });
                    settings.grid = settings.grid.max(settings.degree + 1);
                    ui.label("The surface is fitted to a mesh with that many holes (as `ntori new` does).");
                    create = ui.button("Create").clicked();
                });
            self.new_dialog = (open && !create).then_some((genus, settings));
            if create {
                self.guarded(Pending::New(genus, settings));
            }
        }

        if let Some((action, mut text, then)) = self.prompt.take() {
            let mut keep = true;
            let mut chosen = None;
            egui::Window::new(action.title())
                .collapsible(false)
                .show(ctx, |ui| {
                    let label = ui.label("File:");
                    let edit = ui
                        .add(egui::TextEdit::singleline(&mut text).desired_width(360.0))
                        .labelled_by(label.id);
                    let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
                    ui.horizontal(|ui| {
                        if ui.button(action.button()).clicked() || enter {
                            chosen = Some(PathBuf::from(text.trim()));
                        }
                        if ui.button("Cancel").clicked() {
                            keep = false;
                        }
                    });
                });
            match chosen {
                Some(path) if !path.as_os_str().is_empty() => self.file_chosen(action, path, then),
                _ if keep => self.prompt = Some((action, text, then)),
                _ => {}
            }
        }

        if let Some(action) = self.pending.clone() {
            let name = self
                .state
                .as_ref()
                .and_then(|s| s.path())
                .map_or("the untitled model".to_owned(), |p| p.display().to_string());
            let mut answer = None;
            egui::Modal::new(egui::Id::unique("unsaved")).show(ctx, |ui| {
                ui.heading("Unsaved changes");
                ui.label(format!("Save the changes to {name} first?"));
                ui.horizontal(|ui| {
                    if ui.button("Save").clicked() {
                        answer = Some(0);
                    }
                    if ui.button("Don't save").clicked() {
                        answer = Some(1);
                    }
                    if ui.button("Cancel").clicked() {
                        answer = Some(2);
                    }
                });
            });
            match answer {
                Some(0) => {
                    self.pending = None;
                    self.save(Some(action));
                }
                Some(1) => {
                    self.pending = None;
                    self.run_pending(action);
                }
                Some(_) => self.pending = None,
                None => {}
            }
        }

        if self.pending.is_none()
            && let Some(orphan) = self.orphans.first().cloned()
        {
            let mut answer = None;
            egui::Modal::new(egui::Id::unique("recover")).show(ctx, |ui| {
                ui.heading("Recover unsaved work?");
                ui.label(format!(
                    "ntori did not close cleanly. A genus-{} model with unsaved changes ({}, autosaved {}) can be recovered.",
                    orphan.file.model.genus,
                    orphan
                        .file
                        .original
                        .as_ref()
                        .map_or("untitled".to_owned(), |p| p.display().to_string()),
                    ago(orphan.file.saved_at)
                ));
                ui.horizontal(|ui| {
                    if ui.button("Recover").clicked() {
                        answer = Some(0);
                    }
                    if ui.button("Discard").clicked() {
                        answer = Some(1);
                    }
                    if ui.button("Later").clicked() {
                        answer = Some(2);
                    }
                });
            });
            match answer {
                Some(0) => self.guarded(Pending::Recover(0)),
                Some(1) => {
                    Recovery::discard(&orphan);
                    self.orphans.remove(0);
                }
                Some(_) => {
                    self.orphans.remove(0);
                }
                None => {}
            }
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
            Ok(()) => self.info(format!("saved a screenshot to {}", path.display())),
            Err(e) => self.error(format!("screenshot failed: {e}")),
        }
    }
}

/// Degree, continuity and grid size as labelled fields of a two-column grid.
fn settings_grid(ui: &mut egui::Ui, s: &mut SplineSettings) {
    let label = ui.label("Degree");
    ui.add(egui::DragValue::new(&mut s.degree).range(1..=embedding::bspline::MAX_DEGREE))
        .labelled_by(label.id);
    ui.end_row();
    let label = ui.label("Continuity C^k");
    ui.add(egui::DragValue::new(&mut s.continuity).range(1..=4))
        .labelled_by(label.id);
    ui.end_row();
    let label = ui.label("Grid per chart");
    ui.add(egui::DragValue::new(&mut s.grid).range(s.degree + 1..=64))
        .labelled_by(label.id);
    ui.end_row();
}

fn style_radio(ui: &mut egui::Ui, state: &mut EditorState) {
    let mut style = state.style();
    ui.radio_value(&mut style, Style::Shaded, "Shaded (1)");
    ui.radio_value(&mut style, Style::Wireframe, "Wireframe (2)");
    ui.radio_value(&mut style, Style::Charts, "Charts (3)");
    ui.radio_value(
        &mut style,
        Style::Curvature(CurvatureKind::Gaussian),
        "Gaussian curvature (4)",
    );
    ui.radio_value(
        &mut style,
        Style::Curvature(CurvatureKind::Mean),
        "Mean curvature (5)",
    );
    state.set_style(style);
}

/// What a wheel or trackpad event does in the viewport.
enum Wheel {
    Zoom(f64),
    Orbit([f64; 2]),
    Pan([f64; 2]),
}

/// A mouse wheel zooms; two fingers on a trackpad orbit (with Shift: pan); pinching, or the wheel
/// with Ctrl, zooms through egui's zoom delta (left out here).
fn wheel_gestures(events: &[egui::Event]) -> Vec<Wheel> {
    use egui::{MouseWheelSource, MouseWheelUnit};
    events
        .iter()
        .filter_map(|e| match e {
            egui::Event::MouseWheel {
                unit,
                delta,
                source,
                modifiers,
                ..
            } if !modifiers.command && !modifiers.ctrl => {
                let (dx, dy) = (f64::from(delta.x), f64::from(delta.y));
                let fingers = matches!(
                    source,
                    MouseWheelSource::Trackpad | MouseWheelSource::Momentum
                ) || (*source == MouseWheelSource::Unknown
                    && *unit == MouseWheelUnit::Point);
                Some(if fingers && modifiers.shift {
                    Wheel::Pan([dx, dy])
                } else if fingers {
                    Wheel::Orbit([dx, dy])
                } else {
                    let steps = match unit {
                        MouseWheelUnit::Point => dy / 50.0,
                        MouseWheelUnit::Line => dy,
                        MouseWheelUnit::Page => 4.0 * dy,
                    };
                    Wheel::Zoom(1.15f64.powf(steps))
                })
            }
            _ => None,
        })
        .collect()
}

/// The curvature style's colour scale, at the viewport's right edge.
fn curvature_legend(painter: &egui::Painter, rect: Rect, kind: CurvatureKind, range: f64) {
    let bar = Rect::from_min_size(
        Pos2::new(rect.right() - 70.0, rect.bottom() - 210.0),
        Vec2::new(14.0, 160.0),
    );
    const STEPS: usize = 40;
    let step = bar.height() / STEPS as f32;
    for i in 0..STEPS {
        let t = 1.0 - 2.0 * (i as f64 + 0.5) / STEPS as f64;
        let [r, g, b] = crate::render::scene::diverging(t).map(|x| (x * 255.0).round() as u8);
        painter.rect_filled(
            Rect::from_min_size(
                bar.min + Vec2::new(0.0, i as f32 * step),
                Vec2::new(bar.width(), step + 0.5),
            ),
            0.0,
            Color32::from_rgb(r, g, b),
        );
    }
    let font = FontId::proportional(12.0);
    let text = Color32::from_gray(225);
    let title = match kind {
        CurvatureKind::Gaussian => "K",
        CurvatureKind::Mean => "H",
    };
    painter.text(
        bar.center_top() - Vec2::new(0.0, 6.0),
        Align2::CENTER_BOTTOM,
        title,
        font.clone(),
        text,
    );
    for (y, value) in [
        (bar.top(), range),
        (bar.center().y, 0.0),
        (bar.bottom(), -range),
    ] {
        painter.text(
            Pos2::new(bar.right() + 5.0, y),
            Align2::LEFT_CENTER,
            format!("{value:+.3}"),
            font.clone(),
            text,
        );
    }
}

fn background() -> Color32 {
    let [r, g, b] = super::gpu::BACKGROUND.map(|x| (x * 255.0) as u8);
    Color32::from_rgb(r, g, b)
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or(String::new(), |f| {
        f.to_uppercase().collect::<String>() + c.as_str()
    })
}

/// 12345678 → "12 345 678".
pub fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(ch);
    }
    out
}

fn ago(unix: u64) -> String {
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let s = now.saturating_sub(unix);
    match s {
        0..60 => format!("{s} s ago"),
        60..3600 => format!("{} min ago", s / 60),
        3600..86400 => format!("{} h ago", s / 3600),
        _ => format!("{} days ago", s / 86400),
    }
}
