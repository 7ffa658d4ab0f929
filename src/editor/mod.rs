//! `ntori edit`: the desktop editor (eframe and egui over wgpu).
//!
//! The state ([`state::EditorState`]: document, live mesh, camera, picking, pins, the drag in
//! progress, history) knows nothing of egui; [`app::EditorApp`] lets its parts draw panels, dialogs
//! and the viewport, and turns what the user does into calls on it, so tests drive the same code the
//! window does.
//!
//! - `camera.rs` — the orbit camera in f64: pick rays, projection, the drag plane, GPU uniforms
//!   (the key light and uniforms of `render::camera`).
//! - `pick.rs` — a bounding volume hierarchy over the tessellation's triangles (refitted after
//!   edits), the exact ray–triangle test, the hit as a chart point.
//! - `mesh.rs` — the live mesh: tessellation (the quality one or t_e/t_r's), stencil, exact positions and tangents, the vertices as
//!   the GPU reads them, what changed since the last upload.
//! - `drag.rs` — one drag: the minimum-norm solve per event and the vertex update it implies.
//! - `history.rs` — undo and redo (exact copies of what changed).
//! - `recovery.rs` — autosave and crash recovery.
//! - `gpu.rs` — the viewport's pipeline (vertices pulled through the index buffer,
//!   `shaders/pulled.wgsl`) over the renderer's shared GPU setup (`render::gpu`).
//! - `app.rs` — the egui application: a thin `eframe::App` over the parts below, applying the
//!   commands given since the last frame before drawing the next.
//! - `commands.rs` — the user's actions ([`commands::Command`]), the keyboard shortcuts, and the
//!   one function that applies them.
//! - `viewport.rs` — the viewport's pointer input, its picture and the overlays.
//! - `panels.rs` — the menu bar, the side panel, the status bar (messages, frame timings).
//! - `dialogs.rs` — help, new model, the file prompt, "save changes?", crash recovery.
//! - `jobs.rs` — background jobs (fitting, refitting, exporting) and their typed errors.

pub mod app;
pub mod camera;
pub mod commands;
mod dialogs;
pub mod drag;
pub mod gpu;
pub mod history;
pub mod jobs;
pub mod mesh;
mod panels;
pub mod pick;
pub mod recovery;
pub mod state;
pub mod stroke;
mod viewport;

pub use app::{EditorApp, EditorOptions};
pub use state::{EditorError, EditorState, Pick};

/// Opens the editor window and returns when it is closed.
pub fn run(options: EditorOptions) -> Result<(), eframe::Error> {
    let title = match &options.file {
        Some(path) => format!("ntori — {}", path.display()),
        None => "ntori".to_owned(),
    };
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(title)
            .with_app_id("ntori")
            .with_inner_size([1280.0, 800.0])
            .with_min_inner_size([640.0, 400.0]),
        renderer: eframe::Renderer::Wgpu,
        ..Default::default()
    };
    eframe::run_native(
        "ntori",
        native,
        Box::new(move |cc| Ok(Box::new(EditorApp::new(cc, options)))),
    )
}
