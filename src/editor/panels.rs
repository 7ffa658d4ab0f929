//! The panels around the viewport: the menu bar, the side panel (model, spline settings,
//! tessellation, display, editing, the picked point) and the status bar, with the messages and
//! frame timings it shows. What the user asks for becomes a [`Command`]; the side panel keeps its
//! drafts (spline settings, tessellation) until they are applied.

use std::time::{Duration, Instant};

use charts::ChartId;
use egui::Color32;
use embedding::SplineSettings;

use super::commands::{Command, FileAction, Pending};
use super::jobs::Jobs;
use super::state::{DEFAULT_T, EditorState, MAX_T, Pick};
use crate::io::export::Meshing;
use crate::render::{CurvatureKind, Style};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Info,
    Error,
}

/// What the editor told the user, newest last; the status bar shows the newest for a while.
#[derive(Default)]
pub struct Messages {
    entries: Vec<(String, Level, Instant)>,
}

impl Messages {
    pub fn push(&mut self, text: String, level: Level) {
        self.entries.push((text, level, Instant::now()));
    }

    pub fn info(&mut self, text: impl Into<String>) {
        self.push(text.into(), Level::Info);
    }

    /// An error, logged too.
    pub fn error(&mut self, text: impl Into<String>) {
        let text = text.into();
        tracing::warn!("{text}");
        self.push(text, Level::Error);
    }

    /// Every message, errors marked.
    pub fn all(&self) -> Vec<(String, bool)> {
        self.entries
            .iter()
            .map(|(m, l, _)| (m.clone(), *l == Level::Error))
            .collect()
    }
}

/// Rolling frame timings.
#[derive(Default)]
pub struct Timings {
    last_frame: Option<Instant>,
    intervals: Vec<f64>,
    cpu: Vec<f64>,
}

impl Timings {
    /// A frame ends that took `cpu` on the CPU.
    pub fn record(&mut self, cpu: Duration) {
        let now = Instant::now();
        if let Some(last) = self.last_frame {
            push_capped(&mut self.intervals, (now - last).as_secs_f64());
        }
        self.last_frame = Some(now);
        push_capped(&mut self.cpu, cpu.as_secs_f64());
    }

    /// The mean time between frames, in seconds.
    pub fn frame(&self) -> Option<f64> {
        mean(&self.intervals)
    }

    /// The mean time on the CPU per frame, in seconds.
    pub fn cpu(&self) -> Option<f64> {
        mean(&self.cpu)
    }
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn push_capped(v: &mut Vec<f64>, x: f64) {
    if v.len() >= 30 {
        v.remove(0);
    }
    v.push(x);
}

/// The menu bar. `new_model` is what the new-model dialog starts with.
pub fn menu_bar(
    ui: &mut egui::Ui,
    state: Option<&EditorState>,
    busy: bool,
    new_model: (u32, SplineSettings),
    commands: &mut Vec<Command>,
) {
    let has = state.is_some();
    egui::MenuBar::new().ui(ui, |ui| {
        ui.menu_button("File", |ui| {
            let items = [
                (!busy, "New model…", "Ctrl+N", {
                    let (genus, settings) = new_model;
                    Command::NewModelDialog(genus, settings)
                }),
                (
                    !busy,
                    "Open…",
                    "Ctrl+O",
                    Command::Guarded(Pending::Open(None)),
                ),
                (
                    !busy,
                    "Import mesh…",
                    "Ctrl+I",
                    Command::Guarded(Pending::Import(None)),
                ),
                (has && !busy, "Save", "Ctrl+S", Command::Save(None)),
                (
                    has && !busy,
                    "Save as…",
                    "Ctrl+Shift+S",
                    Command::AskFile(FileAction::SaveAs, None),
                ),
            ];
            menu_items(ui, items, commands);
            ui.separator();
            let items = [
                (
                    has && !busy,
                    "Export mesh…",
                    "Ctrl+E",
                    Command::AskFile(FileAction::Export, None),
                ),
                (
                    has,
                    "Screenshot…",
                    "F12",
                    Command::AskFile(FileAction::Screenshot, None),
                ),
            ];
            menu_items(ui, items, commands);
            ui.separator();
            menu_items(ui, [(true, "Quit", "Ctrl+Q", Command::Quit)], commands);
        });
        ui.menu_button("Edit", |ui| {
            let (undo, redo) = state.map_or((None, None), |s| {
                (
                    s.can_undo()
                        .then(|| s.history().undo_label().unwrap_or("").to_owned()),
                    s.can_redo()
                        .then(|| s.history().redo_label().unwrap_or("").to_owned()),
                )
            });
            let undo_text = undo.as_ref().map_or("Undo".into(), |l| format!("Undo {l}"));
            let redo_text = redo.as_ref().map_or("Redo".into(), |l| format!("Redo {l}"));
            let items = [
                (undo.is_some(), undo_text.as_str(), "Ctrl+Z", Command::Undo),
                (
                    redo.is_some(),
                    redo_text.as_str(),
                    "Ctrl+Shift+Z",
                    Command::Redo,
                ),
            ];
            menu_items(ui, items, commands);
            ui.separator();
            let pins = state.is_some_and(|s| !s.pins().is_empty());
            if ui
                .add_enabled(pins, egui::Button::new("Clear pins"))
                .clicked()
            {
                commands.push(Command::ClearPins);
            }
        });
        ui.menu_button("View", |ui| {
            let Some(state) = state else { return };
            let items = [
                (true, "Frame model", "F", Command::Frame),
                (true, "Reset view", "Home", Command::ResetView),
            ];
            menu_items(ui, items, commands);
            ui.separator();
            style_radio(ui, state.style(), commands);
        });
        ui.menu_button("Help", |ui| {
            menu_items(ui, [(true, "Shortcuts", "F1", Command::ShowHelp)], commands);
        });
    });
}

/// Menu buttons (enabled or not, text, shortcut) and the command each one gives when clicked.
fn menu_items<const N: usize>(
    ui: &mut egui::Ui,
    items: [(bool, &str, &str, Command); N],
    commands: &mut Vec<Command>,
) {
    for (enabled, text, keys, command) in items {
        let button = egui::Button::new(text).shortcut_text(keys);
        if ui.add_enabled(enabled, button).clicked() {
            commands.push(command);
        }
    }
}

/// The side panel's drafts: spline settings and tessellation, applied when the user says so.
#[derive(Default)]
pub struct SidePanel {
    draft_settings: SplineSettings,
    /// The tessellation's sliders while they move (applied when let go).
    draft_meshing: Option<Meshing>,
}

impl SidePanel {
    /// The drafts of a new model: its own settings.
    pub fn reset(&mut self, settings: SplineSettings) {
        self.draft_settings = settings;
        self.draft_meshing = None;
    }

    /// New settings were applied: the draft is them.
    pub fn settings_applied(&mut self, settings: SplineSettings) {
        self.draft_settings = settings;
    }

    /// The spline settings as edited (what a new model starts with).
    pub fn draft_settings(&self) -> SplineSettings {
        self.draft_settings
    }

    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        state: Option<&mut EditorState>,
        busy: bool,
        selected: Option<&Pick>,
        commands: &mut Vec<Command>,
    ) {
        ui.heading("Model");
        let Some(state) = state else {
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
            commands.push(Command::NewModelDialog(state.genus(), state.settings()));
        }

        ui.separator();
        ui.label("Spline (applying refits the surface)");
        let d = &mut self.draft_settings;
        egui::Grid::new("settings")
            .num_columns(2)
            .show(ui, |ui| settings_grid(ui, d));
        d.grid = d.grid.max(d.degree + 1);
        d.disk_grid = d.disk_grid.map(|g| g.max(d.degree + 1));
        let changed = *d != state.settings();
        let draft = *d;
        ui.horizontal(|ui| {
            if ui
                .add_enabled(changed && !busy, egui::Button::new("Apply"))
                .clicked()
            {
                commands.push(Command::Refit(draft));
            }
            if ui
                .add_enabled(changed, egui::Button::new("Revert"))
                .clicked()
            {
                self.draft_settings = state.settings();
            }
        });

        ui.separator();
        self.tessellation(ui, state, commands);

        ui.separator();
        ui.label("Display");
        style_radio(ui, state.style(), commands);
        if let Some(range) = state.mesh().curvature_range() {
            ui.label(format!("Colour scale: ±{range:.4} (blue < 0 < red)"));
        }
        let chart_name = |c: Option<ChartId>| match c {
            None => "none".to_owned(),
            Some(c) => state
                .atlas()
                .charts()
                .get(c.index())
                .map_or("?".into(), |k| format!("{} ({})", c.0, k.kind().label())),
        };
        let mut chart = state.control_chart;
        egui::ComboBox::from_label("control points")
            .selected_text(chart_name(chart))
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut chart, None, "none");
                for c in 0..state.atlas().charts().len() as u32 {
                    let name = chart_name(Some(ChartId(c)));
                    ui.selectable_value(&mut chart, Some(ChartId(c)), name);
                }
            });
        if chart != state.control_chart {
            commands.push(Command::ShowControlNet(chart));
        }

        ui.separator();
        editing(ui, state, commands);

        if let Some(pick) = selected {
            ui.separator();
            picked(ui, pick);
        }
    }

    /// The tessellation: the quality one (its tolerance, and Remesh for the shape as it is now)
    /// or t_e/t_r (their sliders and the mesh size they make); a change is applied once let go.
    fn tessellation(
        &mut self,
        ui: &mut egui::Ui,
        state: &EditorState,
        commands: &mut Vec<Command>,
    ) {
        ui.label("Tessellation");
        let current = self.draft_meshing.unwrap_or(state.meshing());
        let mut meshing = current;
        ui.horizontal(|ui| {
            let quality = Meshing::default();
            let is_quality = matches!(meshing, Meshing::Quality { .. });
            if ui.radio(is_quality, "Quality").clicked() && !is_quality {
                meshing = quality;
            }
            if ui.radio(!is_quality, "t_e, t_r").clicked() && is_quality {
                meshing = Meshing::TeTr {
                    te: DEFAULT_T,
                    tr: DEFAULT_T,
                };
            }
        });
        let dragged = match &mut meshing {
            Meshing::Quality { tolerance } | Meshing::Quads { tolerance } => {
                let slider = ui.add(
                    egui::Slider::new(tolerance, 1e-4..=1e-2)
                        .logarithmic(true)
                        .text("tolerance"),
                );
                let dragged = slider.dragged();
                slider.on_hover_text(
                    "The most a flat triangle strays from the surface, as a fraction of the \
                     model's size; triangles follow the curvature",
                );
                if ui
                    .button("Remesh")
                    .on_hover_text("A new quality tessellation for the shape as it is now")
                    .clicked()
                {
                    commands.push(Command::SetMeshing(meshing));
                }
                dragged
            }
            Meshing::TeTr { te, tr } => {
                let a = ui.add(
                    egui::Slider::new(te, 1..=MAX_T)
                        .logarithmic(true)
                        .text("t_e"),
                );
                let b = ui.add(
                    egui::Slider::new(tr, 1..=MAX_T)
                        .logarithmic(true)
                        .text("t_r"),
                );
                let vertices = charts::Tessellation::expected_vertices(state.genus(), *te, *tr);
                if vertices > 1_000_000 {
                    ui.colored_label(
                        Color32::from_rgb(230, 160, 60),
                        "Over a million vertices: about 1 GB of memory per million",
                    );
                }
                a.dragged() || b.dragged()
            }
        };
        let mesh = state.mesh();
        ui.label(format!(
            "{} vertices, {} triangles",
            thousands(mesh.vertex_count() as u64),
            thousands(mesh.triangle_count() as u64)
        ));
        if meshing != current {
            self.draft_meshing = Some(meshing);
        }
        if !dragged
            && let Some(m) = self.draft_meshing.take()
            && m != state.meshing()
        {
            commands.push(Command::SetMeshing(m));
        }
    }
}

/// The brush, its radius, profile and strength, symmetry, and the pins.
fn editing(ui: &mut egui::Ui, state: &mut EditorState, commands: &mut Vec<Command>) {
    use embedding::brush::BrushKind;
    ui.label("Editing");
    egui::ComboBox::from_label("brush")
        .selected_text(state.brush.name())
        .show_ui(ui, |ui| {
            for (kind, tip) in [
                (BrushKind::Grab, "drag the surface with the pointer"),
                (BrushKind::Inflate, "push the surface out along its normal"),
                (
                    BrushKind::Smooth,
                    "fair the surface: bumps sink, dents rise",
                ),
                (
                    BrushKind::Flatten,
                    "move the surface towards the plane under the brush",
                ),
            ] {
                ui.selectable_value(&mut state.brush, kind, kind.name())
                    .on_hover_text(tip);
            }
        });
    if state.brush.is_stroke() && state.influence <= 0.0 {
        // A stroke brush needs a radius.
        state.influence = crate::editor::state::DEFAULT_STROKE_RADIUS;
    }
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
         (the paper's edit). Otherwise the brush acts on the surface within this fraction of the \
         model's size, fading out at the radius as the profile says. [ and ] change it.",
    );
    if state.brush.is_stroke() {
        ui.add(egui::Slider::new(&mut state.strength, -1.0..=1.0).text("strength"))
            .on_hover_text(
                "How far one dab goes (1: a full step; negative: the other way, e.g. deflate). \
                 Shift + [ and ] change it.",
            );
    }
    ui.horizontal(|ui| {
        ui.label("symmetry");
        ui.checkbox(&mut state.symmetry.x, "X");
        ui.checkbox(&mut state.symmetry.y, "Y");
        ui.checkbox(&mut state.symmetry.z, "Z");
    })
    .response
    .on_hover_text("Act on the mirror images across these planes through the origin too.");
    if state.influence > 0.0 {
        use embedding::brush::Falloff;
        egui::ComboBox::from_label("profile")
            .selected_text(format!("{:?}", state.falloff).to_lowercase())
            .show_ui(ui, |ui| {
                for f in [
                    Falloff::Smooth,
                    Falloff::Dome,
                    Falloff::Sharp,
                    Falloff::Constant,
                ] {
                    let name = format!("{f:?}").to_lowercase();
                    ui.selectable_value(&mut state.falloff, f, name);
                }
            });
    }
    ui.label(format!(
        "Pins ({}): Ctrl + click to add or remove",
        state.pins().len()
    ));
    for (i, p) in state.pins().iter().enumerate() {
        ui.horizontal(|ui| {
            if ui.small_button("x").on_hover_text("unpin").clicked() {
                commands.push(Command::RemovePin(i));
            }
            ui.label(format!(
                "chart {} ({:.3}, {:.3})",
                p.chart.0, p.coords.re, p.coords.im
            ));
        });
    }
    if !state.pins().is_empty() && ui.button("Clear pins").clicked() {
        commands.push(Command::ClearPins);
    }
}

/// The picked point: its triangle, its chart coordinates in every chart, its surface point.
fn picked(ui: &mut egui::Ui, pick: &Pick) {
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

/// The status bar: the background job, the model, frame and drag timings, the file, the newest
/// message.
pub fn status_bar(
    ui: &mut egui::Ui,
    state: Option<&EditorState>,
    jobs: &Jobs,
    timings: &Timings,
    messages: &Messages,
) {
    ui.horizontal(|ui| {
        if let Some((what, started)) = jobs.running() {
            ui.spinner();
            ui.label(format!("{what}… {:.0} s", started.elapsed().as_secs_f64()));
            ui.separator();
        }
        if let Some(state) = state {
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
        if let (Some(f), Some(c)) = (timings.frame(), timings.cpu()) {
            ui.label(format!("frame {:.1} ms (CPU {:.1} ms)", 1e3 * f, 1e3 * c));
            ui.separator();
        }
        if let Some(state) = state {
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
        if let Some((text, level, at)) = messages.entries.last()
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

/// Degree, continuity and grid size as labelled fields of a two-column grid.
pub fn settings_grid(ui: &mut egui::Ui, s: &mut SplineSettings) {
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
    // The inside and vertex charts (the sphere's caps) carry more of the surface, with coarser
    // cells at their rims: they may take a finer grid (it follows the grid until set apart).
    let label = ui.label("Grid per disk chart");
    let mut disk = s.disk_grid();
    ui.add(egui::DragValue::new(&mut disk).range(s.degree + 1..=MAX_DISK_GRID))
        .labelled_by(label.id);
    s.disk_grid = (disk != s.grid).then_some(disk);
    ui.end_row();
}

/// The finest disk-chart grid the settings panels offer (as `ntori new --disk-grid`).
pub const MAX_DISK_GRID: usize = 192;

/// The five styles as radio buttons; choosing another one is a command.
fn style_radio(ui: &mut egui::Ui, current: Style, commands: &mut Vec<Command>) {
    let mut style = current;
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
    if style != current {
        commands.push(Command::SetStyle(style));
    }
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
