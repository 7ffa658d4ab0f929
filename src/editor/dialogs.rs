//! The editor's windows over the viewport: help, a new model, the file prompt (where no native file
//! dialog can be shown), "save changes?" and crash recovery. What the user answers becomes a
//! [`Command`].

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use egui::{Context, Key};
use embedding::SplineSettings;

use super::commands::{Command, FileAction, Pending, SHORTCUTS};
use super::panels::settings_grid;
use super::recovery::Orphan;

/// The in-window file prompt: for what, the path typed so far, what comes after.
struct Prompt {
    action: FileAction,
    text: String,
    then: Option<Pending>,
}

/// The dialogs and what they show.
pub struct Dialogs {
    pub show_help: bool,
    /// The new-model dialog's genus and settings, while it is open.
    pub new_model: Option<(u32, SplineSettings)>,
    prompt: Option<Prompt>,
    /// The action that waits for the answer to "save changes?".
    pub unsaved: Option<Pending>,
    /// Native file dialogs (rfd) rather than the prompt.
    native: bool,
}

impl Dialogs {
    pub fn new(native: bool) -> Dialogs {
        Dialogs {
            show_help: false,
            new_model: None,
            prompt: None,
            unsaved: None,
            native,
        }
    }

    /// Closes help, the prompt and the new-model dialog (Esc).
    pub fn close(&mut self) {
        self.show_help = false;
        self.prompt = None;
        self.new_model = None;
    }

    /// Asks for a file: with the native dialog, its answer comes back at once (as the command to
    /// apply); with the in-window prompt, as a command of a later frame. `current` is the model's
    /// file, if it has one (for the folder and the suggested name).
    pub fn ask_file(
        &mut self,
        action: FileAction,
        then: Option<Pending>,
        current: Option<&Path>,
    ) -> Option<Command> {
        if !self.native {
            let text = match action {
                FileAction::Open | FileAction::Import => String::new(),
                _ => suggested_name(current, action),
            };
            self.prompt = Some(Prompt { action, text, then });
            return None;
        }
        let mut dialog = rfd::FileDialog::new().set_title(action.title());
        dialog = match action {
            FileAction::Open | FileAction::SaveAs => dialog.add_filter("ntori model", &["json"]),
            FileAction::Export => dialog.add_filter(
                "Mesh",
                &crate::io::export::Format::ALL.map(crate::io::export::Format::extension),
            ),
            FileAction::Screenshot => dialog.add_filter("PNG image", &["png"]),
            FileAction::Import => {
                dialog.add_filter("Mesh", &crate::io::import::MeshFormat::EXTENSION_LIST)
            }
        };
        if let Some(dir) = current.and_then(Path::parent) {
            dialog = dialog.set_directory(dir);
        }
        let chosen = match action {
            FileAction::Open | FileAction::Import => dialog.pick_file(),
            _ => dialog
                .set_file_name(suggested_name(current, action))
                .save_file(),
        };
        chosen.map(|path| Command::FileChosen(action, path, then))
    }

    /// Every dialog that is open. `current` is the model's file, if it has one.
    pub fn ui(
        &mut self,
        ctx: &Context,
        current: Option<&Path>,
        orphans: &[Orphan],
        commands: &mut Vec<Command>,
    ) {
        if self.show_help {
            self.show_help = help(ctx);
        }
        if let Some((genus, settings)) = self.new_model {
            self.new_model = new_model(ctx, genus, settings, commands);
        }
        if let Some(prompt) = self.prompt.take() {
            self.prompt = file_prompt(ctx, prompt, commands);
        }
        if let Some(action) = self.unsaved.clone() {
            let name = current.map_or("the untitled model".to_owned(), |p| p.display().to_string());
            let answer = ask(
                ctx,
                "unsaved",
                "Unsaved changes",
                &format!("Save the changes to {name} first?"),
                ["Save", "Don't save", "Cancel"],
            );
            if let Some(answer) = answer {
                self.unsaved = None;
                match answer {
                    0 => commands.push(Command::Save(Some(action))),
                    1 => commands.push(Command::Run(action)),
                    _ => {}
                }
            }
        } else if let Some(orphan) = orphans.first() {
            let text = format!(
                "ntori did not close cleanly. A genus-{} model with unsaved changes ({}, autosaved {}) \
                 can be recovered.",
                orphan.file.model.genus,
                orphan
                    .file
                    .original
                    .as_ref()
                    .map_or("untitled".to_owned(), |p| p.display().to_string()),
                ago(orphan.file.saved_at)
            );
            let answer = ask(
                ctx,
                "recover",
                "Recover unsaved work?",
                &text,
                ["Recover", "Discard", "Later"],
            );
            match answer {
                Some(0) => commands.push(Command::Guarded(Pending::Recover(0))),
                Some(1) => commands.push(Command::DiscardOrphan(0)),
                Some(_) => commands.push(Command::DismissOrphan(0)),
                None => {}
            }
        }
    }
}

/// The help window (the shortcuts); whether it stays open.
fn help(ctx: &Context) -> bool {
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
    open
}

/// The new-model dialog: genus and spline settings; what it shows next frame (None: closed).
fn new_model(
    ctx: &Context,
    mut genus: u32,
    mut settings: SplineSettings,
    commands: &mut Vec<Command>,
) -> Option<(u32, SplineSettings)> {
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
            settings.disk_grid = settings.disk_grid.map(|g| g.max(settings.degree + 1));
            ui.label("The surface is fitted to a mesh with that many holes (as `ntori new` does).");
            create = ui.button("Create").clicked();
        });
    if create {
        commands.push(Command::Guarded(Pending::New(genus, settings)));
    }
    (open && !create).then_some((genus, settings))
}

/// The in-window file prompt; what it shows next frame (None: closed).
fn file_prompt(ctx: &Context, mut prompt: Prompt, commands: &mut Vec<Command>) -> Option<Prompt> {
    let mut keep = true;
    let mut chosen = None;
    egui::Window::new(prompt.action.title())
        .collapsible(false)
        .show(ctx, |ui| {
            let label = ui.label("File:");
            let edit = ui
                .add(egui::TextEdit::singleline(&mut prompt.text).desired_width(360.0))
                .labelled_by(label.id);
            let enter = edit.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
            ui.horizontal(|ui| {
                if ui.button(prompt.action.button()).clicked() || enter {
                    chosen = Some(PathBuf::from(prompt.text.trim()));
                }
                if ui.button("Cancel").clicked() {
                    keep = false;
                }
            });
        });
    match chosen {
        Some(path) if !path.as_os_str().is_empty() => {
            commands.push(Command::FileChosen(prompt.action, path, prompt.then));
            None
        }
        _ => keep.then_some(prompt),
    }
}

/// A modal question with three buttons; the index of the one clicked.
fn ask(ctx: &Context, id: &str, heading: &str, text: &str, buttons: [&str; 3]) -> Option<usize> {
    let mut answer = None;
    egui::Modal::new(egui::Id::unique(id)).show(ctx, |ui| {
        ui.heading(heading);
        ui.label(text);
        ui.horizontal(|ui| {
            for (i, button) in buttons.into_iter().enumerate() {
                if ui.button(button).clicked() {
                    answer = Some(i);
                }
            }
        });
    });
    answer
}

/// The file name offered for `action`: the model's own stem, or "model".
fn suggested_name(current: Option<&Path>, action: FileAction) -> String {
    let stem = current
        .and_then(Path::file_stem)
        .and_then(|s| s.to_str())
        .unwrap_or("model");
    match action {
        FileAction::Open | FileAction::SaveAs => format!("{stem}.json"),
        FileAction::Export | FileAction::Import => format!("{stem}.obj"),
        FileAction::Screenshot => format!("{stem}.png"),
    }
}

/// Whether rfd can show a dialog: an XDG desktop portal on the session bus, or zenity.
pub fn native_dialogs_available() -> bool {
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
