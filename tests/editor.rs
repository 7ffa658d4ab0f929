//! The editor, driven through its window by egui_kittest (real input events into the real app,
//! rendered on wgpu — lavapipe on machines without a GPU): picking, dragging with pins, undo and
//! redo, save and open, the unsaved-changes prompt, crash recovery. A screenshot after a scripted
//! drag is written under the target directory (the test prints where).

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard, OnceLock};

use charts::ChartPoint;
use egui::{Event, Key, Modifiers, PointerButton, Pos2, Vec2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use embedding::fit::{FitSettings, initial_model};
use embedding::{Point3, SplineSettings, Surface, Vector3};
use ntori::editor::camera::Ray;
use ntori::editor::pick::cast_all;
use ntori::editor::recovery::{RECOVERY_FORMAT, Recovery, RecoveryFile};
use ntori::editor::state::Grab;
use ntori::editor::{EditorApp, EditorOptions, EditorState};
use ntori::io::export::Meshing;

/// The default genus-2 model, fitted once for all tests.
fn model() -> &'static Surface {
    static MODEL: OnceLock<Surface> = OnceLock::new();
    MODEL.get_or_init(|| {
        initial_model(2, 32, SplineSettings::default(), FitSettings::default())
            .expect("the default model fits")
            .surface
    })
}

/// One harness at a time: each opens a wgpu device, and lavapipe shares the machine's cores.
fn gpu_lock() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

fn harness_with(options: EditorOptions) -> Harness<'static, EditorApp> {
    let mut harness = Harness::builder()
        .with_size(Vec2::new(1100.0, 720.0))
        .wgpu()
        .build_eframe(move |cc| EditorApp::new(cc, options));
    harness.run_steps(3);
    harness
}

fn harness() -> Harness<'static, EditorApp> {
    harness_with(EditorOptions {
        model: Some(model().clone()),
        file: None,
        recovery_dir: None,
        // The quality tessellation, the editor's default.
        meshing: Meshing::default(),
        native_dialogs: Some(false),
        // Each grab plan made when due, so the pictures depend on the events alone (planning in
        // the background is tested on the state).
        plan_in_background: false,
        ..EditorOptions::default()
    })
}

/// The egui position of a viewport pixel.
fn pos_of(app: &EditorApp, pixel: [f64; 2]) -> Pos2 {
    let rect = app.viewport_rect();
    let state = app.state().unwrap();
    Pos2::new(
        rect.min.x + (pixel[0] * f64::from(rect.width()) / state.viewport[0]) as f32,
        rect.min.y + (pixel[1] * f64::from(rect.height()) / state.viewport[1]) as f32,
    )
}

/// The viewport pixel of an egui position (as the app maps it).
fn pixel_of(app: &EditorApp, pos: Pos2) -> [f64; 2] {
    let rect = app.viewport_rect();
    let state = app.state().unwrap();
    [
        f64::from(pos.x - rect.min.x) * state.viewport[0] / f64::from(rect.width()),
        f64::from(pos.y - rect.min.y) * state.viewport[1] / f64::from(rect.height()),
    ]
}

/// A tessellation vertex that the camera sees (its own triangles are the first the ray through it
/// meets), near the given fraction of the viewport. Returns the vertex index and its pixel.
fn visible_vertex(app: &mut EditorApp, at: [f64; 2]) -> (usize, [f64; 2]) {
    let state = app.state_mut().unwrap();
    let size = state.viewport;
    let goal = [at[0] * size[0], at[1] * size[1]];
    let mesh = state.mesh();
    let mut candidates: Vec<(f64, usize, [f64; 2])> = mesh
        .positions()
        .iter()
        .enumerate()
        .filter_map(|(k, &p)| {
            let (q, depth) = state.camera.project(p, size);
            (depth > 0.0).then(|| ((q[0] - goal[0]).hypot(q[1] - goal[1]), k, q))
        })
        .collect();
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    for &(_, k, q) in candidates.iter().take(50) {
        let ray = state.camera.ray(q, size);
        let hit = cast_all(&ray, mesh.positions(), &mesh.tessellation.triangles).unwrap();
        if (ray.at(hit.t) - mesh.positions()[k]).norm() < 1e-9 * state.size() {
            return (k, q);
        }
    }
    panic!("no visible vertex near {at:?}");
}

fn same_point(app: &EditorApp, a: ChartPoint, b: ChartPoint) -> f64 {
    let state = app.state().unwrap();
    let b_in_a = state.atlas().locate(b).unwrap().in_chart(a.chart).unwrap();
    (b_in_a - a.coords).norm()
}

fn command_click(harness: &mut Harness<'static, EditorApp>, pos: Pos2) {
    harness.event(Event::ModifiersChanged(Modifiers::COMMAND));
    harness.event(Event::PointerMoved(pos));
    harness.step();
    harness.event(Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::COMMAND,
    });
    harness.step();
    harness.event(Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::COMMAND,
    });
    harness.step();
    harness.event(Event::ModifiersChanged(Modifiers::NONE));
    harness.step();
}

fn artefact_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("editor");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_pick_at_a_known_pixel_returns_that_manifold_point() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    for at in [[0.5, 0.5], [0.35, 0.6], [0.62, 0.42]] {
        let (k, pixel) = visible_vertex(harness.state_mut(), at);
        let pos = pos_of(harness.state(), pixel);
        harness.hover_at(pos);
        harness.run();
        let app = harness.state();
        let pick = app
            .hover()
            .expect("the pointer is over the surface")
            .clone();
        let vertex = app.state().unwrap().mesh().tessellation.vertices[k];
        // The same manifold point, up to the pointer's f32 position.
        let off = same_point(app, pick.point, vertex);
        assert!(
            off < 1e-5,
            "picked {:?}, expected {vertex:?} ({off:e})",
            pick.point
        );
        // Exactly the brute-force hit of the same ray: same triangle, same barycentrics.
        let state = app.state().unwrap();
        let ray: Ray = state.camera.ray(pixel_of(app, pos), state.viewport);
        let mesh = state.mesh();
        let brute = cast_all(&ray, mesh.positions(), &mesh.tessellation.triangles).unwrap();
        assert_eq!(brute.triangle, pick.hit.triangle);
        for a in 0..3 {
            assert!((brute.bary[a] - pick.hit.bary[a]).abs() < 1e-12);
        }
        // The chart point is the barycentric combination of the triangle's corners, and every
        // representation of the manifold point is the same surface point.
        let corners = mesh.tessellation.triangle_coords[pick.hit.triangle as usize];
        let combined: num_complex::Complex64 =
            corners.iter().zip(pick.hit.bary).map(|(c, b)| c * b).sum();
        assert!((combined - pick.point.coords).norm() < 1e-15);
        for &rep in pick.manifold.representations() {
            assert!((state.surface_point(rep) - pick.surface).norm() < 1e-9);
        }
        // The exact surface is within the tessellation's chord error of the ray's hit.
        assert!((pick.surface - pick.on_mesh).norm() < 1e-2 * state.size());
    }
}

#[test]
fn a_drag_moves_the_point_to_the_cursor_pins_stay_and_undo_redo_are_exact() {
    let _gpu = gpu_lock();
    let mut harness = harness();

    // Pins by Ctrl + click: two far from the drag, one near it (sharing control points with the
    // dragged point, so the solve must hold it).
    let mut pins = Vec::new();
    for at in [[0.3, 0.45], [0.72, 0.55], [0.55, 0.53]] {
        let (_, pixel) = visible_vertex(harness.state_mut(), at);
        let pos = pos_of(harness.state(), pixel);
        command_click(&mut harness, pos);
        pins.push(pixel);
    }
    let state = harness.state().state().unwrap();
    assert_eq!(state.pins().len(), 3, "Ctrl + click pins");
    let pinned: Vec<(ChartPoint, Point3)> = state
        .pins()
        .iter()
        .map(|&p| (p, state.surface_point(p)))
        .collect();
    let before = state.control().to_vec();

    // Drag a point near the middle by N pixels, in several events.
    let (_, pixel) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    let start = pos_of(harness.state(), pixel);
    let shift = Vec2::new(40.0, -25.0);
    harness.hover_at(start);
    harness.step();
    harness.drag_at(start);
    harness.step();
    for i in 1..=8 {
        harness.hover_at(start + shift * (i as f32 / 8.0));
        harness.step();
    }
    let end = start + shift;
    // Mid-drag, the GPU moves the reached vertices from the displacement alone; the CPU reference
    // does the same arithmetic.
    let mid_picture = harness
        .state()
        .screenshot()
        .expect("the viewport was drawn");
    let (reference, rows) = {
        let state = harness.state().state().unwrap();
        let plan = &state.drag().expect("dragging").plan;
        assert!(
            !plan.pins.is_empty(),
            "the near pin takes part in the solve"
        );
        let mut vertices = state.mesh().vertices().to_vec();
        plan.move_vertices(plan.displacement, &mut vertices);
        (vertices, plan.rows.clone())
    };
    harness.drop_at(end);
    harness.step();
    harness.run();

    let app = harness.state();
    let state = app.state().unwrap();
    let drag = state.last_drag.expect("a drag happened");
    assert!(drag.events >= 2, "{} drag events", drag.events);
    // The target, independently: the start point moved by the pointer's motion, in the plane
    // through it facing the camera.
    let size = state.viewport;
    let normal = {
        let d = state.camera.direction();
        Vector3::new(d.x, d.y, d.z)
    };
    let on_plane = |pixel: [f64; 2]| {
        let ray = state.camera.ray(pixel, size);
        ray.at((drag.start - ray.origin).dot(&normal) / ray.direction.dot(&normal))
    };
    let target = drag.start + (on_plane(pixel_of(app, end)) - on_plane(pixel_of(app, start)));
    let moved = state.surface_point(drag.point);
    let model_size = state.size();
    assert!(
        (moved - target).norm() < 1e-6 * model_size,
        "the dragged point is {:e} from its target (model size {model_size})",
        (moved - target).norm()
    );
    assert!(
        (moved - drag.start).norm() > 1e-2 * model_size,
        "the drag moved the surface"
    );
    // It is where the cursor is.
    let (seen, _) = state.camera.project(moved, size);
    let cursor = pixel_of(app, end);
    assert!((seen[0] - cursor[0]).hypot(seen[1] - cursor[1]) < 1e-3);
    for (p, was) in &pinned {
        let now = state.surface_point(*p);
        assert!(
            (now - was).norm() < 1e-9,
            "a pin moved by {:e}",
            (now - was).norm()
        );
    }
    // The redraw: every vertex equals its stencil row, and the GPU copy agrees (f32).
    let mesh = state.mesh();
    let mut full = vec![Point3::origin(); mesh.vertex_count()];
    mesh.stencil().positions(state.control(), &mut full);
    for (k, (a, b)) in mesh.positions().iter().zip(&full).enumerate() {
        assert!((a - b).norm() <= 1e-12 * model_size, "vertex {k}");
        let v = mesh.vertices()[k].position;
        assert!(
            (Point3::new(v[0].into(), v[1].into(), v[2].into()) - b).norm() < 1e-5 * model_size
        );
    }
    let after = state.control().to_vec();
    assert_ne!(before, after);
    assert!(state.is_modified());
    // The drag's vertex update (p0 + gΔ, tangents likewise) agrees with the exact rows.
    for &r in rows.iter() {
        let v = reference[r as usize];
        let exact = mesh.positions()[r as usize];
        let p = Point3::new(
            v.position[0].into(),
            v.position[1].into(),
            v.position[2].into(),
        );
        assert!((p - exact).norm() < 1e-5 * model_size, "vertex {r}");
        let n = Vector3::new(v.normal[0].into(), v.normal[1].into(), v.normal[2].into());
        let [u, w] = mesh.tangents()[r as usize];
        assert!((n - u.cross(&w).normalize()).norm() < 1e-4, "normal {r}");
    }
    // And the picture drawn mid-drag matches the one drawn from the exact surface afterwards.
    let exact_picture = harness.state().screenshot().unwrap();
    assert_eq!(
        (mid_picture.width, mid_picture.height),
        (exact_picture.width, exact_picture.height)
    );
    let differing = mid_picture
        .rgba
        .chunks(4)
        .zip(exact_picture.rgba.chunks(4))
        .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    println!("{differing} pixels differ between the drag's picture and the exact one");
    assert!(differing * 1000 < mid_picture.rgba.len() / 4);
    let mid_path = artefact_dir().join("mid-drag-viewport.png");
    std::fs::write(&mid_path, mid_picture.to_png().unwrap()).unwrap();
    println!("the viewport mid-drag: {}", mid_path.display());

    // A screenshot of the whole window after the drag, kept as an artefact.
    let image = harness.render().expect("the window renders");
    let path = artefact_dir().join("after-drag.png");
    image.save(&path).unwrap();
    println!("screenshot after the drag: {}", path.display());

    // Undo restores the control points exactly; redo reapplies them.
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.run();
    let state = harness.state().state().unwrap();
    assert_eq!(state.control(), &before[..], "undo is exact");
    // Back at the pinned state: the drag is undone, the three pins (changes of their own) stay.
    assert_eq!(state.pins().len(), 3, "undoing the drag keeps the pins");
    assert!(state.is_modified(), "the pins are unsaved changes");
    let undone_picture = harness.state().screenshot().unwrap();
    let changed = mid_picture
        .rgba
        .chunks(4)
        .zip(undone_picture.rgba.chunks(4))
        .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    assert!(
        changed * 100 > mid_picture.rgba.len() / 4,
        "the drag showed on screen ({changed} pixels differ from the undone surface)"
    );
    let state = harness.state().state().unwrap();
    let mut full = vec![Point3::origin(); state.mesh().vertex_count()];
    state.mesh().stencil().positions(state.control(), &mut full);
    assert!(
        state
            .mesh()
            .positions()
            .iter()
            .zip(&full)
            .all(|(a, b)| (a - b).norm() <= 1e-12)
    );
    harness.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    harness.run();
    let state = harness.state().state().unwrap();
    assert_eq!(state.control(), &after[..], "redo is exact");
}

#[test]
fn save_then_open_round_trips_exactly() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    // Change the model first (a drag through the state), so the file is not the fit's.
    let (k, pixel) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    {
        let state = harness.state_mut().state_mut().unwrap();
        let vertex = state.mesh().tessellation.vertices[k];
        state
            .start_drag(vertex, ntori::editor::state::Grab::Surface, pixel)
            .unwrap();
        let target = state.surface_point(vertex) + Vector3::new(0.1, -0.05, 0.2);
        state.drag_to_target(target).unwrap();
        state.release();
        assert!(state.is_modified());
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("edited.json");
    let saved = harness.state().state().unwrap().surface().to_model();
    harness.state_mut().save_to(&path).unwrap();
    assert!(!harness.state().state().unwrap().is_modified());
    harness.state_mut().open(&path).unwrap();
    harness.run();
    let state = harness.state().state().unwrap();
    let opened = state.surface().to_model();
    assert_eq!(opened, saved, "bit for bit");
    assert_eq!(state.path(), Some(path.as_path()));
    assert!(!state.is_modified());
    assert_eq!(
        ntori::io::model_file::load(&path).unwrap().to_model(),
        saved
    );
}

/// Pins are part of the document: pinning is undoable and marks it modified, pins round-trip
/// through save and open (as a version 2 model; without pins the file stays version 1, which every
/// build reads) and survive a change of spline settings.
#[test]
fn pins_round_trip_through_undo_save_and_open() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let (k, _) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    let (k2, _) = visible_vertex(harness.state_mut(), [0.4, 0.6]);
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.json");
    harness.state_mut().save_to(&plain).unwrap();
    let text = std::fs::read_to_string(&plain).unwrap();
    assert!(
        text.contains("\"version\":1") && !text.contains("pins"),
        "no pins: version 1"
    );
    let (a, b) = {
        let state = harness.state_mut().state_mut().unwrap();
        let (a, b) = (
            state.mesh().tessellation.vertices[k],
            state.mesh().tessellation.vertices[k2],
        );
        assert!(!state.is_modified());
        state.add_pin(a);
        assert!(state.is_modified(), "pinning changes the document");
        state.add_pin(b);
        state.remove_pin(0);
        assert_eq!(state.pins(), &[b]);
        state.undo().unwrap();
        assert_eq!(state.pins(), &[a, b], "undo brings the pin back");
        state.undo().unwrap();
        assert_eq!(state.pins(), &[a]);
        state.redo().unwrap();
        assert_eq!(state.pins(), &[a, b]);
        (a, b)
    };
    let path = dir.path().join("pinned.json");
    harness.state_mut().save_to(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("\"version\":2") && text.contains("\"pins\""));
    harness.state_mut().open(&plain).unwrap();
    harness.run();
    assert!(harness.state().state().unwrap().pins().is_empty());
    harness.state_mut().open(&path).unwrap();
    harness.run();
    let state = harness.state_mut().state_mut().unwrap();
    assert_eq!(state.pins(), &[a, b], "bit for bit");
    assert!(!state.is_modified());
    // New spline settings keep the pins (they are surface points).
    let settings = embedding::SplineSettings {
        grid: state.settings().grid + 2,
        ..state.settings()
    };
    let (control, _) = ntori::editor::jobs::refit(state.surface(), settings).unwrap();
    state.set_settings(settings, control).unwrap();
    assert_eq!(state.pins(), &[a, b]);
    state.clear_pins();
    assert!(state.pins().is_empty());
    state.undo().unwrap();
    assert_eq!(state.pins(), &[a, b], "clearing is one undo step");
}

#[test]
fn closing_with_unsaved_changes_asks_first() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let (k, pixel) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    {
        let state = harness.state_mut().state_mut().unwrap();
        let vertex = state.mesh().tessellation.vertices[k];
        state
            .start_drag(vertex, ntori::editor::state::Grab::Surface, pixel)
            .unwrap();
        state
            .drag_to_target(state.surface_point(vertex) + Vector3::new(0.0, 0.0, 0.1))
            .unwrap();
        state.release();
    }
    harness
        .input_mut()
        .viewports
        .entry(egui::ViewportId::ROOT)
        .or_default()
        .events
        .push(egui::ViewportEvent::Close);
    harness.step();
    let commands = &harness.output().viewport_output[&egui::ViewportId::ROOT].commands;
    assert!(
        commands.contains(&egui::ViewportCommand::CancelClose),
        "the close is held: {commands:?}"
    );
    harness.run();
    assert!(harness.query_by_label("Unsaved changes").is_some());
    assert!(harness.query_by_label("Don't save").is_some());
}

#[test]
fn shortcuts_switch_styles_and_frame_the_view() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    use ntori::render::{CurvatureKind, Style};
    for (key, style) in [
        (Key::Num2, Style::Wireframe),
        (Key::Num3, Style::Charts),
        (Key::Num4, Style::Curvature(CurvatureKind::Gaussian)),
        (Key::Num1, Style::Shaded),
    ] {
        harness.key_press(key);
        harness.run();
        assert_eq!(harness.state().state().unwrap().style(), style);
    }
    let camera = harness.state().state().unwrap().camera;
    harness
        .state_mut()
        .state_mut()
        .unwrap()
        .camera
        .orbit([100.0, 30.0], 600.0);
    harness.key_press(Key::Home);
    harness.run();
    assert_eq!(
        harness.state().state().unwrap().camera.azimuth,
        camera.azimuth
    );
    harness.key_press(Key::F1);
    harness.run();
    assert!(
        harness
            .query_by_label_contains("smooth closed surface")
            .is_some()
    );
}

#[test]
fn a_crash_leaves_a_recovery_file_that_the_next_editor_offers() {
    let dir = tempfile::tempdir().unwrap();
    // What a crashed editor (a process that no longer exists) left behind.
    let orphan = RecoveryFile {
        format: RECOVERY_FORMAT.into(),
        pid: u32::MAX - 7,
        saved_at: 0,
        original: Some(PathBuf::from("/somewhere/sculpture.json")),
        model: model().to_model(),
        process: None,
    };
    std::fs::write(
        dir.path().join("recovery-4294967288.json"),
        serde_json::to_string(&orphan).unwrap(),
    )
    .unwrap();
    let _gpu = gpu_lock();
    let mut harness = harness_with(EditorOptions {
        model: Some(model().clone()),
        file: None,
        recovery_dir: Some(dir.path().to_owned()),
        meshing: Meshing::TeTr { te: 16, tr: 16 },
        ..EditorOptions::default()
    });
    harness.run();
    assert_eq!(harness.state().orphans().len(), 1);
    assert!(harness.query_by_label("Recover unsaved work?").is_some());
    harness.get_by_label("Recover").click();
    harness.run();
    let app = harness.state();
    let state = app.state().unwrap();
    assert!(state.is_modified(), "recovered work is unsaved");
    assert_eq!(
        state.path(),
        Some(std::path::Path::new("/somewhere/sculpture.json"))
    );
    assert_eq!(state.surface().to_model(), orphan.model);
    // The orphan is gone; this editor's own autosave holds the work now.
    let own = app.recovery().unwrap().own_file().to_owned();
    assert!(own.exists());
    assert!(!dir.path().join("recovery-4294967288.json").exists());
    let mine = Recovery::new(dir.path());
    assert!(
        mine.orphans().is_empty(),
        "a live process's file is not an orphan"
    );
}

/// A recovery file is not hidden by a process that merely has its writer's id: a zombie (exited,
/// not reaped) is gone, and so is a live process that started at another time (the id reused);
/// only the writer itself, or an older file's live namesake, counts as running.
#[cfg(target_os = "linux")]
#[test]
fn a_zombie_or_a_reused_pid_does_not_hide_a_recovery_file() {
    use ntori::editor::recovery::ProcessStamp;
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, pid: u32, process: Option<ProcessStamp>| {
        let file = RecoveryFile {
            format: RECOVERY_FORMAT.into(),
            pid,
            saved_at: 0,
            original: None,
            model: model().to_model(),
            process,
        };
        let path = dir.path().join(format!("recovery-{name}.json"));
        std::fs::write(&path, serde_json::to_string(&file).unwrap()).unwrap();
        path
    };
    // A child that exits at once and is not waited for stays a zombie.
    let mut zombie = Command::new("true").spawn().unwrap();
    let stat = format!("/proc/{}/stat", zombie.id());
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    while !std::fs::read_to_string(&stat)
        .unwrap()
        .rsplit(')')
        .next()
        .is_some_and(|rest| rest.trim_start().starts_with('Z'))
    {
        assert!(
            std::time::Instant::now() < deadline,
            "the child became a zombie"
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let mut sleeper = Command::new("sleep").arg("60").spawn().unwrap();
    let stamp = ProcessStamp::of(sleeper.id()).expect("/proc tells the stamp");
    let reused = ProcessStamp {
        start_ticks: stamp.start_ticks + 1,
        ..stamp.clone()
    };
    let earlier_boot = ProcessStamp {
        boot: "an-earlier-boot".into(),
        ..stamp.clone()
    };
    let zombie_file = write("zombie", zombie.id(), ProcessStamp::of(zombie.id()));
    let zombie_old = write("zombie-unstamped", zombie.id(), None);
    let reused_file = write("reused", sleeper.id(), Some(reused));
    let rebooted = write("rebooted", sleeper.id(), Some(earlier_boot));
    write("running", sleeper.id(), Some(stamp));
    write("running-unstamped", sleeper.id(), None);
    let mut found: Vec<PathBuf> = Recovery::new(dir.path())
        .orphans()
        .into_iter()
        .map(|o| o.path)
        .collect();
    found.sort();
    let mut expected = vec![zombie_file, zombie_old, reused_file, rebooted];
    expected.sort();
    sleeper.kill().unwrap();
    sleeper.wait().unwrap();
    zombie.wait().unwrap();
    assert_eq!(found, expected);
    // This editor's own autosave records its stamp, and is not an orphan to itself.
    let mut own = Recovery::new(dir.path());
    own.autosave(1, || model().to_model(), None, true).unwrap();
    let text = std::fs::read_to_string(own.own_file()).unwrap();
    let written: RecoveryFile = serde_json::from_str(&text).unwrap();
    assert_eq!(written.process, ProcessStamp::current());
    assert!(written.process.is_some());
    assert!(!own.orphans().iter().any(|o| o.path == own.own_file()));
}

/// The real window: `ntori edit` under Xvfb (winit, a wgpu surface on lavapipe), closing itself
/// after some frames with a picture of its viewport. Skipped where xvfb-run is missing.
#[test]
fn ntori_edit_runs_under_xvfb() {
    let has_xvfb = std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|d| d.join("xvfb-run").is_file()));
    if !has_xvfb {
        eprintln!("skipped: xvfb-run is not installed");
        return;
    }
    let _gpu = gpu_lock();
    let dir = tempfile::tempdir().unwrap();
    let model_path = dir.path().join("model.json");
    ntori::io::model_file::save(&model_path, model()).unwrap();
    let picture = artefact_dir().join("xvfb-window-viewport.png");
    let _ = std::fs::remove_file(&picture);
    let runtime = dir.path().join("runtime");
    std::fs::create_dir(&runtime).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    let output = std::process::Command::new("timeout")
        .args(["300", "xvfb-run", "-a", "-s", "-screen 0 1280x800x24"])
        .arg(env!("CARGO_BIN_EXE_ntori"))
        .arg("edit")
        .arg(&model_path)
        .args(["--exit-after-frames", "10", "--screenshot-on-exit"])
        .arg(&picture)
        .env("XDG_RUNTIME_DIR", &runtime)
        .env("XDG_STATE_HOME", dir.path().join("state"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "ntori edit failed: {stderr}");
    assert!(stderr.contains("10 frames"), "{stderr}");
    let png = std::fs::read(&picture).expect("the viewport's picture");
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    // The surface's blue covers a good part of the viewport.
    let blue = pixels[..info.buffer_size()]
        .chunks(4)
        .filter(|p| p[2] > 150 && p[2] > p[0] + 40)
        .count();
    assert!(
        blue * 10 > info.width as usize * info.height as usize,
        "{blue} surface pixels of {}×{}",
        info.width,
        info.height
    );
    println!("the window's viewport under Xvfb: {}", picture.display());
}

#[test]
fn export_and_screenshot_through_the_file_prompt() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let dir = tempfile::tempdir().unwrap();
    // File → Export mesh (Ctrl + E): the prompt, a path, the button; the export runs in the
    // background.
    let mesh_path = dir.path().join("surface.ply");
    harness.key_press_modifiers(Modifiers::COMMAND, Key::E);
    answer_file_prompt(&mut harness, &mesh_path, "Export");
    harness.run_steps(2);
    harness.state_mut().wait_for_job();
    harness.run();
    assert!(mesh_path.exists(), "{:?}", harness.state().messages());
    let (_, triangles) = ply_triangles(&mesh_path);
    let state = harness.state().state().unwrap();
    assert_eq!(triangles, state.mesh().triangle_count());
    // F12: a screenshot of the viewport.
    let png_path = dir.path().join("view.png");
    harness.key_press(Key::F12);
    answer_file_prompt(&mut harness, &png_path, "Save");
    harness.run();
    let png = std::fs::read(&png_path).expect("the screenshot was written");
    assert_eq!(&png[1..4], b"PNG");
}

/// Answers the in-window file prompt that the last key opened: `path`, then `button`.
fn answer_file_prompt(
    harness: &mut Harness<'static, EditorApp>,
    path: &std::path::Path,
    button: &str,
) {
    harness.run();
    harness
        .get_by_label("File:")
        .set_text_value_accesskit(path.to_str().unwrap());
    harness.run();
    harness.get_by_label(button).click();
}

/// The vertex and face counts of a PLY header.
fn ply_triangles(path: &std::path::Path) -> (usize, usize) {
    let bytes = std::fs::read(path).unwrap();
    let end = bytes.windows(10).position(|w| w == b"end_header").unwrap();
    let header = String::from_utf8_lossy(&bytes[..end]);
    let count = |what: &str| {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {what} ")))
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    (count("vertex"), count("face"))
}

#[test]
fn new_settings_refit_the_surface_and_undo_restores_it() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let before = harness.state().state().unwrap().surface().clone();
    // The side panel's grid sizes (every chart's, then the disk charts' apart), then Apply: a
    // refit in the background.
    harness
        .get_by_label("Grid per chart")
        .set_value_accesskit(12.0);
    harness.run();
    harness
        .get_by_label("Grid per disk chart")
        .set_value_accesskit(16.0);
    harness.run();
    harness.get_by_label("Apply").click();
    harness.run_steps(2);
    assert!(harness.state().busy());
    harness.state_mut().wait_for_job();
    harness.run();
    let state = harness.state().state().unwrap();
    assert_eq!(
        state.settings().grid,
        12,
        "{:?}",
        harness.state().messages()
    );
    assert_eq!(state.settings().disk_grid, Some(16));
    // The genus-2 model's inside and vertex disks at 16, its four edge squares at 12.
    assert_eq!(state.control().len(), 2 * 16 * 16 + 4 * 12 * 12);
    // The refitted surface stays close to the old one.
    let old = EditorState::new(before.clone(), Meshing::default()).unwrap();
    let worst = old
        .mesh()
        .tessellation
        .vertices
        .iter()
        .zip(old.mesh().positions())
        .map(|(&p, a)| (state.surface_point(p) - a).norm())
        .fold(0.0, f64::max);
    assert!(worst < 0.01 * old.size(), "moved by {worst}");
    assert!(state.is_modified());
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    harness.run();
    let state = harness.state().state().unwrap();
    assert_eq!(
        state.surface().to_model(),
        before.to_model(),
        "undo restores settings and control points"
    );
    // The panel shows the settings the surface has again: nothing to apply.
    let grid = |harness: &Harness<'static, EditorApp>| {
        use egui_kittest::kittest::NodeT as _;
        let node = harness.get_by_label("Grid per chart");
        node.accesskit_node().numeric_value()
    };
    assert_eq!(
        grid(&harness),
        Some(SplineSettings::default().grid as f64),
        "the grid field follows the undo"
    );
    assert!(harness.state().state().unwrap().settings().grid == SplineSettings::default().grid);
    harness.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    harness.run();
    assert_eq!(harness.state().state().unwrap().settings().grid, 12);
    assert_eq!(grid(&harness), Some(12.0), "and the redo");
}

/// Input is not lost however fast it comes: three Ctrl + Z in one frame undo three steps, a
/// Ctrl + Shift + Z between them redoes in its turn, and a Ctrl + click whose Ctrl is let go within
/// the same frame still pins.
#[test]
fn every_key_and_click_of_a_frame_counts_in_order() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let points: Vec<ChartPoint> = (0..4)
        .map(|k| {
            harness
                .state()
                .state()
                .unwrap()
                .mesh()
                .tessellation
                .vertices[40 * k + 7]
        })
        .collect();
    {
        let state = harness.state_mut().state_mut().unwrap();
        for &p in &points {
            state.add_pin(p);
        }
    }
    let key = |key, modifiers| Event::Key {
        key,
        physical_key: None,
        pressed: true,
        repeat: false,
        modifiers,
    };
    // kittest's `event` gives each queued event a frame of its own: these go into one frame's
    // input instead.
    let mut one_frame = Vec::new();
    for _ in 0..3 {
        one_frame.push(key(Key::Z, Modifiers::COMMAND));
    }
    in_one_frame(&mut harness, &mut one_frame);
    assert_eq!(
        harness.state().state().unwrap().pins(),
        &points[..1],
        "three undos"
    );
    // Undo, redo, redo, undo in one frame: in order, one pin more at the end than at the start.
    for (k, m) in [
        (Key::Z, Modifiers::COMMAND),
        (Key::Z, Modifiers::COMMAND | Modifiers::SHIFT),
        (Key::Y, Modifiers::COMMAND),
        (Key::Z, Modifiers::COMMAND),
        (Key::Y, Modifiers::COMMAND),
    ] {
        one_frame.push(key(k, m));
    }
    in_one_frame(&mut harness, &mut one_frame);
    assert_eq!(harness.state().state().unwrap().pins(), &points[..2]);
    // A quick Ctrl + click: Ctrl down, press, release and Ctrl up all within one frame.
    let (_, pixel) = visible_vertex(harness.state_mut(), [0.45, 0.55]);
    let pos = pos_of(harness.state(), pixel);
    harness.event(Event::PointerMoved(pos));
    harness.step();
    one_frame.push(Event::ModifiersChanged(Modifiers::COMMAND));
    for pressed in [true, false] {
        one_frame.push(Event::PointerButton {
            pos,
            button: PointerButton::Primary,
            pressed,
            modifiers: Modifiers::COMMAND,
        });
    }
    one_frame.push(Event::ModifiersChanged(Modifiers::NONE));
    in_one_frame(&mut harness, &mut one_frame);
    assert_eq!(
        harness.state().state().unwrap().pins().len(),
        3,
        "the quick Ctrl + click pinned"
    );
}

/// Runs one frame with all of `events` in its input, then until the app settles.
fn in_one_frame(harness: &mut Harness<'static, EditorApp>, events: &mut Vec<Event>) {
    harness.input_mut().events.append(events);
    harness.step();
    harness.run();
}

/// The side panel's tessellation: the quality one by default, t_e/t_r at the press of a radio
/// button (the mesh the size the scheme makes), and back; Remesh makes the quality one anew.
#[test]
fn the_panel_switches_between_the_quality_and_the_t_e_t_r_tessellation() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let state = harness.state().state().unwrap();
    assert_eq!(state.meshing(), Meshing::default());
    let quality_triangles = state.mesh().triangle_count();
    harness.get_by_label("t_e, t_r").click();
    harness.run();
    let state = harness.state().state().unwrap();
    assert_eq!(state.meshing(), Meshing::TeTr { te: 32, tr: 32 });
    assert_eq!(
        state.mesh().triangle_count() as u64,
        charts::Tessellation::expected_triangles(2, 32, 32)
    );
    harness.get_by_label("Quality").click();
    harness.run();
    let state = harness.state().state().unwrap();
    assert_eq!(state.meshing(), Meshing::default());
    assert_eq!(state.mesh().triangle_count(), quality_triangles);
    harness.get_by_label("Remesh").click();
    harness.run();
    assert_eq!(
        harness.state().state().unwrap().mesh().triangle_count(),
        quality_triangles,
        "the same surface remeshes the same"
    );
}

#[test]
fn a_new_model_of_another_genus_from_the_dialog() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    harness.key_press_modifiers(Modifiers::COMMAND, Key::N);
    harness.run();
    harness.get_by_label("Genus").set_value_accesskit(1.0);
    harness.run();
    harness.get_by_label("Create").click();
    harness.run_steps(2);
    harness.state_mut().wait_for_job();
    harness.run();
    let state = harness.state().state().unwrap();
    assert_eq!(state.genus(), 1, "{:?}", harness.state().messages());
    assert_eq!(state.path(), None);
    assert!(!state.is_modified());
    // The quality tessellation of the new torus: closed, χ = 0.
    assert_eq!(state.meshing(), Meshing::default());
    let triangles = &state.mesh().tessellation.triangles;
    let topology = mesh::HalfEdgeMesh::from_polygons(
        state.mesh().vertex_count(),
        triangles.iter().map(|t| &t[..]),
    )
    .unwrap()
    .topology();
    assert!(topology.closed && topology.manifold);
    assert_eq!(topology.euler_characteristic, 0);
}

/// File → Import mesh (Ctrl + I): the mesh is read, checked and fitted in the background as
/// `ntori fit` fits it, and becomes an untitled model; a mesh that cannot be fitted is said, and the
/// model on screen stays.
#[test]
fn an_imported_mesh_becomes_an_untitled_model() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let import = |harness: &mut Harness<'static, EditorApp>, path: &std::path::Path| {
        harness.key_press_modifiers(Modifiers::COMMAND, Key::I);
        answer_file_prompt(harness, path, "Import");
        harness.run_steps(2);
        harness.state_mut().wait_for_job();
        harness.run();
    };
    let dumbbell =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/meshes/dumbbell-genus-0.obj");
    import(&mut harness, &dumbbell);
    let messages = format!("{:?}", harness.state().messages());
    let state = harness.state().state().unwrap();
    assert_eq!(state.genus(), 0, "{messages}");
    assert_eq!(state.path(), None, "{messages}");
    assert!(!state.is_modified());
    assert_eq!(
        state.settings(),
        // The dumbbell's 642 vertices.
        embedding::mesh_fit::default_settings(0, 642).0,
        "{messages}"
    );
    assert!(
        messages.contains("imported") && messages.contains("genus 0"),
        "{messages}"
    );
    // The surface is the one `ntori fit` makes: it passes within 1% of the mesh's vertices.
    let mesh = ntori::io::import::read_mesh(&dumbbell).unwrap();
    let size = embedding::bounding_box(&mesh.positions);
    let diagonal = (size.1 - size.0).norm();
    let surface = state.surface().clone();
    let tessellation = surface.atlas().tessellate(24, 24).unwrap();
    let positions: Vec<[f64; 3]> = tessellation
        .vertices
        .iter()
        .map(|&p| surface.position(p).coords.into())
        .collect();
    let input: Vec<[f64; 3]> = mesh.positions.iter().map(|p| p.coords.into()).collect();
    let distance = mesh::spatial::hausdorff(
        mesh::spatial::MeshRef {
            positions: &input,
            triangles: &mesh.triangles,
        },
        mesh::spatial::MeshRef {
            positions: &positions,
            triangles: &tessellation.triangles,
        },
    )
    .unwrap();
    assert!(distance.symmetric < 0.01 * diagonal, "{distance:?}");
    // An open mesh: the error names the file and the problem; the dumbbell stays.
    let dir = tempfile::tempdir().unwrap();
    let open = dir.path().join("open.obj");
    std::fs::write(&open, "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n").unwrap();
    import(&mut harness, &open);
    let messages = format!("{:?}", harness.state().messages());
    assert!(
        messages.contains("open.obj") && messages.contains("not closed"),
        "{messages}"
    );
    assert_eq!(harness.state().state().unwrap().genus(), 0);
}

#[test]
fn every_style_and_a_control_net_drawn() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let dir = artefact_dir();
    harness.key_press(Key::C);
    harness.key_press(Key::C);
    harness.run();
    assert_eq!(
        harness.state().state().unwrap().control_chart,
        Some(charts::ChartId(1))
    );
    let mut pictures = Vec::new();
    for (key, name) in [
        (Key::Num1, "shaded"),
        (Key::Num2, "wireframe"),
        (Key::Num3, "charts"),
        (Key::Num4, "gaussian"),
        (Key::Num5, "mean"),
    ] {
        harness.key_press(key);
        harness.run();
        let image = harness.render().unwrap();
        let path = dir.join(format!("style-{name}.png"));
        image.save(&path).unwrap();
        println!("{name}: {}", path.display());
        pictures.push(harness.state().screenshot().unwrap().rgba);
    }
    for i in 0..pictures.len() {
        for j in 0..i {
            assert_ne!(pictures[i], pictures[j], "styles {i} and {j} look the same");
        }
    }
}

#[test]
fn a_changed_tessellation_keeps_picking_exact() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    harness
        .state_mut()
        .state_mut()
        .unwrap()
        .set_meshing(Meshing::TeTr { te: 9, tr: 5 })
        .unwrap();
    harness.run();
    let (k, pixel) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    let app = harness.state_mut();
    let vertex = app.state().unwrap().mesh().tessellation.vertices[k];
    let pick = app.state_mut().unwrap().pick(pixel).unwrap();
    assert!(same_point(app, pick.point, vertex) < 1e-9);
    let state = app.state().unwrap();
    assert_eq!(
        state.mesh().vertex_count() as u64,
        charts::Tessellation::expected_vertices(2, 9, 5)
    );
}

#[test]
fn the_influence_radius_widens_the_edit_and_keeps_the_constraints() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let (k, pixel) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    let (kp, _) = visible_vertex(harness.state_mut(), [0.56, 0.52]);
    let state = harness.state_mut().state_mut().unwrap();
    let (point, pin) = (
        state.mesh().tessellation.vertices[k],
        state.mesh().tessellation.vertices[kp],
    );
    state.add_pin(pin);
    let pinned = state.surface_point(pin);
    let size = state.size();
    let mut moved = Vec::new();
    for influence in [0.0, 0.25] {
        state.influence = influence;
        let before = state.control().to_vec();
        state.start_drag(point, Grab::Surface, pixel).unwrap();
        let target = state.surface_point(point) + Vector3::new(0.02, 0.03, 0.08) * size;
        state.drag_to_target(target).unwrap();
        state.release();
        assert!((state.surface_point(point) - target).norm() < 1e-6 * size);
        assert!((state.surface_point(pin) - pinned).norm() < 1e-9);
        moved.push(
            before
                .iter()
                .zip(state.control())
                .filter(|(a, b)| a != b)
                .count(),
        );
        state.undo().unwrap();
        assert_eq!(state.control(), &before[..]);
    }
    assert!(moved[1] > 2 * moved[0], "control points moved: {moved:?}");
}

/// With an influence radius the drag is a brush defined on the surface: the same surface point
/// picked in two charts gives the same edit (to 1e-9 of the model's size), for every falloff
/// profile, and the dragged point reaches its target.
#[test]
fn a_brush_edit_does_not_depend_on_the_chart_it_was_picked_in() {
    use embedding::brush::Falloff;
    let _gpu = gpu_lock();
    let mut harness = harness();
    let state = harness.state_mut().state_mut().unwrap();
    let size = state.size();
    // A vertex in an overlap, with its point in another chart.
    let (point, other) = state
        .mesh()
        .tessellation
        .vertices
        .iter()
        .step_by(7)
        .find_map(|&p| {
            let reps = state.atlas().locate(p).ok()?;
            let other = *reps.representations().iter().find(|q| q.chart != p.chart)?;
            Some((p, other))
        })
        .expect("a vertex in two charts");
    state.influence = 0.25;
    for falloff in [
        Falloff::Smooth,
        Falloff::Dome,
        Falloff::Sharp,
        Falloff::Constant,
    ] {
        state.falloff = falloff;
        let before = state.control().to_vec();
        let target = state.surface_point(point) + Vector3::new(0.03, -0.02, 0.06) * size;
        let mut edits = Vec::new();
        for picked in [point, other] {
            state.start_drag(picked, Grab::Surface, [0.0, 0.0]).unwrap();
            state.drag_to_target(target).unwrap();
            assert!((state.surface_point(picked) - target).norm() < 1e-6 * size);
            edits.push(state.control().to_vec());
            state.cancel_drag();
            assert_eq!(state.control(), &before[..]);
        }
        let worst = edits[0]
            .iter()
            .zip(&edits[1])
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-9 * size,
            "{falloff:?}: the edits differ by {worst:e}"
        );
        let moved = edits[0].iter().zip(&before).filter(|(a, b)| a != b).count();
        assert!(
            moved > 20,
            "{falloff:?}: a brush moves many control points ({moved})"
        );
    }
}

#[test]
fn escape_cancels_a_drag() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let before = harness.state().state().unwrap().control().to_vec();
    let (_, pixel) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    let start = pos_of(harness.state(), pixel);
    harness.hover_at(start);
    harness.step();
    harness.drag_at(start);
    harness.step();
    for i in 1..=4 {
        harness.hover_at(start + Vec2::new(0.0, -10.0 * i as f32));
        harness.step();
    }
    assert!(harness.state().state().unwrap().drag().is_some());
    assert_ne!(harness.state().state().unwrap().control(), &before[..]);
    harness.key_press(Key::Escape);
    harness.step();
    let state = harness.state().state().unwrap();
    assert!(state.drag().is_none());
    assert_eq!(state.control(), &before[..]);
    assert!(
        !state.history().can_undo(),
        "a cancelled drag leaves no history"
    );
}

#[test]
fn the_wheel_zooms_and_trackpad_fingers_orbit() {
    let _gpu = gpu_lock();
    let mut harness = harness();
    let centre = harness.state().viewport_rect().center();
    harness.hover_at(centre);
    harness.step();
    let before = harness.state().state().unwrap().camera;
    let wheel = |unit, source, delta| Event::MouseWheel {
        unit,
        delta,
        phase: egui::TouchPhase::Move,
        source,
        modifiers: Modifiers::NONE,
    };
    harness.event(wheel(
        egui::MouseWheelUnit::Line,
        egui::MouseWheelSource::Wheel,
        Vec2::new(0.0, 2.0),
    ));
    harness.step();
    let zoomed = harness.state().state().unwrap().camera;
    assert!(zoomed.distance < before.distance);
    assert_eq!(zoomed.azimuth, before.azimuth);
    harness.event(wheel(
        egui::MouseWheelUnit::Point,
        egui::MouseWheelSource::Trackpad,
        Vec2::new(30.0, 0.0),
    ));
    harness.step();
    let turned = harness.state().state().unwrap().camera;
    assert_ne!(turned.azimuth, zoomed.azimuth);
    assert_eq!(turned.distance, zoomed.distance);
}

// ------------------------------------------------------------------------------- brushes

/// The editor's state on the default model, without a window (brushes need no GPU).
fn brush_state() -> EditorState {
    EditorState::new(model().clone(), Meshing::default()).expect("the default model tessellates")
}

/// The volume the tessellation encloses (the divergence theorem over its triangles).
fn enclosed_volume(state: &EditorState) -> f64 {
    let p = state.mesh().positions();
    state
        .mesh()
        .tessellation
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| p[v as usize].coords);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum::<f64>()
        .abs()
}

/// The lowest z of the unit normals at the vertices within 2 R of `near` and above `at`'s height
/// less 0.2 R (the top face around a pulled point): below 0, the top face turned over there.
fn lowest_upward_normal(state: &EditorState, near: Point3, at: Point3, radius: f64) -> f64 {
    let mesh = state.mesh();
    mesh.positions()
        .iter()
        .zip(mesh.tangents())
        .filter(|(p, _)| (**p - near).norm() < 2.0 * radius && p.z > at.z - 0.2 * radius)
        .map(|(_, [u, v])| u.cross(v).normalize().z)
        .fold(f64::INFINITY, f64::min)
}

/// The surface point on the top face at (x, y): from the nearest tessellation vertex, a few
/// Gauss–Newton steps in its chart toward (x, y, top).
fn top_point_at(state: &EditorState, x: f64, y: f64) -> ChartPoint {
    let start = top_point_near(state, x, y);
    let top = state.surface_point(start).z;
    let target = Point3::new(x, y, top);
    let layout = state.layout();
    let mut p = start;
    for _ in 0..8 {
        let jet = layout.eval(state.control(), p);
        let (e, u, v) = (target - jet.pos, jet.du, jet.dv);
        let (uu, uv, vv) = (u.dot(&u), u.dot(&v), v.dot(&v));
        let det = uu * vv - uv * uv;
        let (a, b) = (u.dot(&e), v.dot(&e));
        let step = num_complex::Complex64::new((vv * a - uv * b) / det, (uu * b - uv * a) / det);
        p = ChartPoint::new(p.chart, p.coords + step);
    }
    p
}

/// The tessellation vertex on top of the default model (largest z) nearest to x on the line y = 0.
fn top_point(state: &EditorState, x: f64) -> ChartPoint {
    top_point_near(state, x, 0.0)
}

/// The tessellation vertex on top of the default model nearest to (x, y).
fn top_point_near(state: &EditorState, x: f64, y: f64) -> ChartPoint {
    let top = state
        .mesh()
        .positions()
        .iter()
        .map(|q| q.z)
        .fold(f64::MIN, f64::max);
    state.nearest_vertex(Point3::new(x, y, top))
}

/// Where the default (genus-2) plate's top face is widest: on the line x = 0 between its two
/// holes, halfway from the centre to the outer rim's band (0.8 from the holes' bands on the wide
/// bands, 1.25 from the outer one), so that a brush there works on a flat face and not on a rim.
fn widest_flat_y() -> f64 {
    let plate = embedding::holed::PlateLayout::new(2);
    0.5 * (plate.outer_radius - plate.band)
}

/// The largest distance between a point of the surface near `centre` (within 1.5 `radius` of it
/// or of its mirror image) mirrored by `signs`, and the surface: 0 on a mirror-symmetric surface.
fn asymmetry(state: &EditorState, centre: Point3, radius: f64, signs: Vector3) -> f64 {
    let layout = state.layout();
    let mirror = |q: &Point3| Point3::from(q.coords.component_mul(&signs));
    state
        .mesh()
        .positions()
        .iter()
        .filter(|q| {
            (*q - centre).norm() < 1.5 * radius || (mirror(q) - centre).norm() < 1.5 * radius
        })
        .step_by(3)
        .map(|q| {
            let mirrored = mirror(q);
            let start = state.nearest_vertex(mirrored);
            let image =
                embedding::brush::nearest_on_surface(&layout, state.control(), start, mirrored);
            (state.surface_point(image) - mirrored).norm()
        })
        .fold(0.0, f64::max)
}

/// Σ H² dA over the vertices within `radius` of `centre`: the bending energy there.
fn bending_energy(state: &mut EditorState, centre: Point3, radius: f64) -> f64 {
    // Over the viewport's vertices, not the brush's own samples: a measure the brush does not fit.
    let mesh = state.mesh();
    let areas = embedding::fit::vertex_areas(mesh.positions(), &mesh.tessellation.triangles);
    let layout = state.layout();
    (0..mesh.vertex_count())
        .filter(|&r| (mesh.positions()[r] - centre).norm() < radius)
        .map(|r| {
            let h = layout
                .eval(state.control(), mesh.tessellation.vertices[r])
                .mean_curvature();
            h * h * areas[r]
        })
        .sum()
}

/// The vertices within `radius` of `centre` on the side facing `facing`, weighted by the smooth
/// falloff: their RMS distance from their weighted least-squares plane.
fn distance_from_plane(state: &EditorState, centre: Point3, radius: f64, facing: Vector3) -> f64 {
    use embedding::brush::Falloff;
    let mesh = state.mesh();
    let near: Vec<(Vector3, f64)> = mesh
        .positions()
        .iter()
        .zip(mesh.tangents())
        .filter(|(_, [u, v])| u.cross(v).dot(&facing) > 0.0)
        .map(|(q, _)| (q.coords, Falloff::Smooth.at((q - centre).norm() / radius)))
        .filter(|(_, w)| *w > 0.0)
        .collect();
    let total: f64 = near.iter().map(|n| n.1).sum();
    let mean = near.iter().map(|(q, w)| q * *w).sum::<Vector3>() / total;
    let scatter = near
        .iter()
        .map(|(q, w)| (q - mean) * (q - mean).transpose() * *w)
        .fold(Vector3::zeros() * Vector3::zeros().transpose(), |a, b| {
            a + b
        });
    (scatter.symmetric_eigen().eigenvalues.min() / total).sqrt()
}

/// During a stroke no vertex the viewport shows lags the surface by as much as half a pixel
/// (measured on the screen, at the default view, zoomed out, and zoomed in during the stroke),
/// nor by more than the stroke's budget in model units (at least `UNSEEN` of the size, close up),
/// also after an undo and a switch of style in between; the stroke's end makes them exact again.
#[test]
fn a_stroke_keeps_its_vertices_within_half_a_pixel() {
    use embedding::brush::BrushKind;
    use ntori::editor::mesh::UNSEEN;
    use ntori::render::{CurvatureKind, Style};
    let mut state = brush_state();
    let size = state.size();
    let point = top_point(&state, 0.3 * size);
    let at = state.surface_point(point);
    state.influence = 0.15;
    let radius = state.radius();
    // The largest distance between a vertex as shown and where the control points put it, in
    // model units and in pixels (vertices in front of the eye and inside the viewport).
    let lag = |state: &EditorState| {
        let mesh = state.mesh();
        let (mut world, mut pixels) = (0.0f64, 0.0f64);
        for r in 0..mesh.vertex_count() {
            let (shown, truth) = (
                mesh.positions()[r],
                mesh.stencil().position(state.control(), r),
            );
            world = world.max((truth - shown).norm());
            let (a, depth) = state.camera.project(shown, state.viewport);
            let (b, _) = state.camera.project(truth, state.viewport);
            let inside = (0..2).all(|k| (0.0..=state.viewport[k]).contains(&a[k]));
            if depth > 0.0 && inside {
                pixels = pixels.max(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
            }
        }
        (world, pixels)
    };
    let (mut lagged, mut budgets) = (0.0f64, Vec::new());
    // At the default view; zoomed out; zoomed in by 3 after the third dab; close up.
    for (round, (kind, zoom, later)) in [
        (BrushKind::Inflate, 1.0, 1.0),
        (BrushKind::Smooth, 1.0, 1.0),
        (BrushKind::Smooth, 0.25, 1.0),
        (BrushKind::Inflate, 1.0, 3.0),
        (BrushKind::Smooth, 6.0, 1.0),
    ]
    .into_iter()
    .enumerate()
    {
        state.reset_view();
        state.camera.zoom(zoom);
        state.brush = kind;
        state.strength = 0.3;
        state.start_stroke(point).unwrap();
        for k in 1..=6 {
            if k == 4 {
                state.camera.zoom(later);
            }
            if round == 1 && k == 5 {
                // The dabs' bound on how near they brought a vertex says a third of the way to
                // the eye: the nearest vertex is found anew, and the budget stays.
                let stroke = state.stroke_mut().unwrap();
                stroke.approach = stroke.nearest / 3.0;
            }
            let next = state.nearest_vertex(at + Vector3::new(0.0, 0.3 * radius * k as f64, 0.0));
            state.stroke_at(next).unwrap();
            let unseen = state.stroke().unwrap().unseen;
            budgets.push(unseen / size);
            let (world, pixels) = lag(&state);
            lagged = lagged.max(pixels);
            assert!(
                unseen >= UNSEEN * state.size() && world <= unseen * (1.0 + 1e-6) + 1e-9 * size,
                "round {round}, dab {k}: a vertex lags by {:e} of the size, the budget {:e}",
                world / size,
                unseen / size
            );
            assert!(
                pixels <= 0.5,
                "round {round}, dab {k}: a vertex lags by {pixels} pixels"
            );
        }
        state.release();
        assert!(lag(&state).0 <= 1e-12 * size, "exact after the stroke");
        if round == 0 {
            state.undo().unwrap();
            state.set_style(Style::Curvature(CurvatureKind::Mean));
            state.set_style(Style::Shaded);
        }
    }
    println!("the largest lag during the strokes: {lagged:.3} pixels; budgets {budgets:?}");
    // Some vertices were left for later (else the test shows nothing), and the view sets the
    // budget: wider zoomed out, the least close up.
    assert!(lagged > 0.05, "the largest lag: {lagged} pixels");
    // Zoomed in during the fourth stroke, the budget shrank with the pixels (the vertices were
    // made exact first).
    assert!(budgets[12] > 2.0 * budgets[0], "{budgets:?}");
    assert!(
        budgets[6..12].iter().all(|&b| b >= budgets[6]),
        "{budgets:?}"
    );
    assert!(budgets[21] < 0.5 * budgets[20], "{budgets:?}");
    assert!((budgets[24] - UNSEEN).abs() < 0.02 * UNSEEN, "{budgets:?}");
}

/// Each brush changes the surface as it says, inside its radius only, and a stroke of several dabs
/// is one undo step: inflate raises the enclosed volume (deflate, a negative strength, lowers it),
/// smooth lowers the bending energy of a sharp bump, flatten brings the surface under it nearer to
/// its plane.
#[test]
fn each_brush_changes_the_surface_as_named() {
    use embedding::brush::{BrushKind, Falloff};
    let mut state = brush_state();
    let size = state.size();
    let original = state.control().to_vec();
    // On the widest flat face; the strokes run from there towards the plate's centre.
    let point = top_point_near(&state, 0.0, widest_flat_y());
    let at = state.surface_point(point);
    state.influence = 0.15;
    let radius = state.radius();
    let stroke = |state: &mut EditorState, kind: BrushKind, strength: f64| {
        state.brush = kind;
        state.strength = strength;
        let before = state.mesh().positions().to_vec();
        state.start_stroke(point).unwrap();
        // Three more dabs along a short line (each due: half the radius apart).
        for k in 1..=3 {
            let next = state.nearest_vertex(at - Vector3::new(0.0, 0.5 * radius * k as f64, 0.0));
            state.stroke_at(next).unwrap();
        }
        assert_eq!(state.stroke().unwrap().dabs, 4, "{kind:?}: four dabs");
        state.release();
        let moved: Vec<(f64, f64)> = before
            .iter()
            .zip(state.mesh().positions())
            .map(|(a, b)| (line_distance(*a, at, 1.5 * radius) / radius, (b - a).norm()))
            .collect();
        let most = moved.iter().map(|m| m.1).fold(0.0, f64::max);
        let beyond = |edge: f64| {
            moved
                .iter()
                .filter(|m| m.0 > edge)
                .map(|m| m.1)
                .fold(0.0, f64::max)
                / most
        };
        println!(
            "{kind:?} {strength}: moved {most:.3e}; beyond 1.2 R {:.3}, 1.6 R {:.3}, 2 R {:.3} of that",
            beyond(1.2),
            beyond(1.6),
            beyond(2.0)
        );
        assert!(most > 1e-3 * size, "{kind:?} moved the surface ({most:e})");

        // (Measured on the default model's widest flat face: at most 1.1% of the most beyond
        // 1.2 R and 0.0% beyond 2 R, for smooth; inflate 0.2% and 0.0%. Before brushes held the
        // control points with little weight inside the disc, inflate left a ring of 7.6% beyond
        // 1.2 R and smooth moved an edge chart's patch 2 R away by 8.3%.)
        assert!(
            beyond(1.2) <= 0.02 && beyond(2.0) <= 0.005,
            "{kind:?}: the surface moved beyond the brush ({:.3} of the most beyond 1.2 R, {:.3} \
             beyond 2 R)",
            beyond(1.2),
            beyond(2.0)
        );
    };
    let v0 = enclosed_volume(&state);
    stroke(&mut state, BrushKind::Inflate, 0.5);
    let inflated = enclosed_volume(&state);
    assert!(inflated > v0 * 1.001, "inflate: volume {v0} → {inflated}");
    state.undo().unwrap();
    assert_eq!(state.control(), &original[..], "a stroke is one undo step");
    stroke(&mut state, BrushKind::Inflate, -0.5);
    let deflated = enclosed_volume(&state);
    assert!(deflated < v0 * 0.999, "deflate: volume {v0} → {deflated}");
    state.undo().unwrap();

    // A sharp bump, then smooth over it.
    state.brush = BrushKind::Grab;
    state.falloff = Falloff::Sharp;
    state.influence = 0.08;
    state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
    state
        .drag_to_target(at + Vector3::new(0.0, 0.0, 0.04 * size))
        .unwrap();
    state.release();
    state.falloff = Falloff::Smooth;
    state.influence = 0.15;
    // The bump's bending energy: the energy under the brush above the model's own there.
    let e0 = bending_energy(&mut state, at, radius);
    state.undo().unwrap();
    let own = bending_energy(&mut state, at, radius);
    state.redo().unwrap();
    stroke(&mut state, BrushKind::Smooth, 1.0);
    let e1 = bending_energy(&mut state, at, radius);
    println!(
        "smooth: bending energy {e0:.3} → {e1:.3} ({own:.3} without the bump: {:.0}% of the \
         bump's removed)",
        100.0 * (e0 - e1) / (e0 - own)
    );
    assert!(
        e1 < e0 && e1 - own < 0.3 * (e0 - own),
        "smooth: bending energy {e0} → {e1} (the model's own {own})"
    );
    state.undo().unwrap();
    state.undo().unwrap();
    assert_eq!(state.control(), &original[..]);

    // Flatten over a bump.
    state.brush = BrushKind::Grab;
    state.falloff = Falloff::Sharp;
    state.influence = 0.08;
    state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
    state
        .drag_to_target(at + Vector3::new(0.0, 0.0, 0.03 * size))
        .unwrap();
    state.release();
    state.falloff = Falloff::Smooth;
    state.influence = 0.15;
    let up = Vector3::z();
    let d0 = distance_from_plane(&state, at, radius, up);
    state.brush = BrushKind::Flatten;
    state.strength = 1.0;
    state.start_stroke(point).unwrap();
    state.release();
    let d1 = distance_from_plane(&state, at, radius, up);
    println!("flatten: distance from the plane {d0:.4} → {d1:.4}");
    // (Measured: one dab takes 55% off. On the narrow strip between a hole's rim and the outer
    // one, where this test pointed before the rims' bands widened, it took 14 to 19%: the disc
    // reached down into the rims, where the spline cannot follow the plane.)
    assert!(
        d1 < 0.7 * d0,
        "flatten: distance from the plane {d0} → {d1}"
    );
}

/// Distance from `q` to the stroke's path: the segment from `at` along −y of length `length`.
fn line_distance(q: Point3, at: Point3, length: f64) -> f64 {
    let t = (at.y - q.y).clamp(0.0, length);
    (q - (at - Vector3::new(0.0, t, 0.0))).norm()
}

/// On `sphere` shown as `meshing`: a grab and each stroke brush with mirror symmetry in z leave it
/// symmetric to 1e-6 of its size.
fn symmetric_edits_stay_symmetric(sphere: embedding::Surface, meshing: Meshing) {
    use embedding::brush::{BrushKind, Symmetry};
    let mut state = EditorState::new(sphere, meshing).unwrap();
    let size = state.size();
    let flip = Vector3::new(1.0, 1.0, -1.0);
    let point = state.nearest_vertex(Point3::new(0.5, 0.3, 0.8));
    let at = state.surface_point(point);
    let before = asymmetry(&state, at, 0.3 * size, flip);
    println!("sphere: asymmetry in z {:e} of the size", before / size);
    state.symmetry = Symmetry {
        x: false,
        y: false,
        z: true,
    };
    let images = state.mirror_images(point);
    assert_eq!(images.len(), 1, "one image");
    let image = state.surface_point(images[0].0);
    assert!((image - Point3::from(at.coords.component_mul(&flip))).norm() < 1e-9 * size);
    state.influence = 0.2;
    state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
    let target = at + Vector3::new(0.1, -0.05, 0.2);
    state.drag_to_target(target).unwrap();
    state.release();
    let moved_image = state.surface_point(images[0].0);
    let expected = Point3::from(target.coords.component_mul(&flip));
    assert!(
        (moved_image - expected).norm() < 1e-9 * size,
        "the image reaches the mirrored target"
    );
    let grabbed = asymmetry(&state, at, 0.3 * size, flip);
    println!("after a symmetric grab: {:e}", grabbed / size);
    assert!(
        grabbed <= before + 1e-6 * size,
        "grab: asymmetry {grabbed:e}"
    );
    // Each stroke brush, from the symmetric sphere.
    state.undo().unwrap();
    for kind in [BrushKind::Inflate, BrushKind::Smooth, BrushKind::Flatten] {
        state.brush = kind;
        state.start_stroke(point).unwrap();
        state.release();
        let brushed = asymmetry(&state, at, 0.3 * size, flip);
        println!("after a symmetric {kind:?}: {:e}", brushed / size);
        assert!(
            brushed <= before + 1e-6 * size,
            "{kind:?}: asymmetry {brushed:e}"
        );
        state.undo().unwrap();
    }
    state.brush = BrushKind::Inflate;
    state.start_stroke(point).unwrap();
    state.release();
    let inflated = asymmetry(&state, at, 0.3 * size, flip);
    println!("after a symmetric inflate: {:e}", inflated / size);
    assert!(
        inflated <= before + 1e-6 * size,
        "inflate: asymmetry {inflated:e}"
    );
}

/// A grab brush pulled along the surface further than its radius can bend (0.8 R, where the
/// smooth profile's map x + Δ f(|x − c| / R) would fold past 0.58 R) drags a smooth bump along:
/// it plans anew every quarter of the radius, so no part of the top face under the brush turns
/// over (the rims of the holes nearby tilt the normals there: the lowest z is 0.30 before the
/// pull). One undo step, and Escape puts every control point back, however many plans the drag
/// made.
#[test]
fn a_long_grab_along_the_surface_does_not_fold_it() {
    let mut state = brush_state();
    let size = state.size();
    let original = state.control().to_vec();
    let point = top_point(&state, 0.3 * size);
    let at = state.surface_point(point);
    state.influence = 0.12;
    let radius = state.radius();
    let undo_steps = state.history().len();
    let facing_up = |state: &EditorState| lowest_upward_normal(state, at, at, radius);
    println!(
        "before: the normals near the point face up at least {:.3}",
        facing_up(&state)
    );
    for cancel in [false, true] {
        state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
        for k in 1..=8 {
            let to = at + Vector3::new(0.0, 0.1 * f64::from(k) * radius, 0.0);
            state.drag_to_target(to).unwrap();
        }
        let plans = state
            .drag()
            .and_then(|d| d.replan.as_ref())
            .map_or(0, |r| r.count);
        // Mid-drag, what the GPU is given: the vertices no plan holds now (the earlier plans'
        // among them) where the surface is, to f32; the current plan's follow its gains.
        let mesh = state.mesh();
        let shown = mesh
            .vertices()
            .iter()
            .zip(&mesh.tessellation.vertices)
            .filter(|(v, _)| v.flags == 0)
            .map(|(v, &p)| {
                (Point3::from(v.position.map(f64::from)) - state.surface_point(p)).norm()
            })
            .fold(0.0, f64::max);
        println!("mid-drag, the shown vertices no plan holds are within {shown:e} of the surface");
        assert!(
            shown < 1e-5 * size,
            "a shown vertex is {shown:e} off the surface"
        );
        if cancel {
            state.cancel_drag();
            assert_eq!(
                state.control(),
                &original[..],
                "Escape restores every control point"
            );
            let exact = EditorState::new(state.surface().clone(), Meshing::default()).unwrap();
            let off = state
                .mesh()
                .positions()
                .iter()
                .zip(exact.mesh().positions())
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            assert!(off < 1e-9 * size, "the vertices are back too: {off:e}");
            continue;
        }
        state.release();
        let lowest = facing_up(&state);
        println!(
            "after a pull of 0.8 R along the surface ({plans} plans after the first): {lowest:.3}"
        );
        assert!(plans >= 3, "the grab planned anew as it went: {plans}");
        // Without planning anew the lowest is -1.000: the bump's front folds right over.
        assert!(
            lowest > 0.0,
            "the top face turned over: a normal's z is {lowest:.3}"
        );
        let reached =
            (state.surface_point(point) - (at + Vector3::new(0.0, 0.8 * radius, 0.0))).norm();
        assert!(
            reached < 1e-6 * size,
            "the point reached the pointer: {reached:e} off"
        );
        assert_eq!(state.history().len(), undo_steps + 1, "one undo step");
        state.undo().unwrap();
        assert_eq!(
            state.control(),
            &original[..],
            "the undo restores every control point"
        );
    }
}

/// A grab brush that makes its plans in the background (as the editor's window does) ends where
/// one that makes each plan when due does, whenever each plan is put in place: waiting for every
/// plan after each event gives the same control points and the same GPU vertices, bit for bit;
/// not waiting (0.8 R along the surface), the drag still reaches the pointer without folding,
/// the release leaves every vertex exact and the mesh the editor's alone, and one undo step
/// takes it all back.
#[test]
fn a_grab_planning_in_the_background_ends_as_one_planning_when_due() {
    let mut due = brush_state();
    let mut waited = brush_state();
    waited.plan_in_background = true;
    let size = due.size();
    let original = due.control().to_vec();
    let point = top_point(&due, 0.3 * size);
    let at = due.surface_point(point);
    for state in [&mut due, &mut waited] {
        state.influence = 0.12;
        state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
    }
    let radius = due.radius();
    // Uneven steps, one of them well past where the last plan serves (that event waits).
    let steps = [0.1, 0.15, 0.3, 0.37, 0.45, 1.2, 1.25, 1.4];
    for (k, &s) in steps.iter().enumerate() {
        let to = at + Vector3::new(0.0, s * radius, 0.02 * k as f64 * radius);
        due.drag_to_target(to).unwrap();
        waited.drag_to_target(to).unwrap();
        waited.finish_plan();
        assert!(!waited.mesh().is_lent(), "the plan is in place");
        assert_eq!(due.control(), waited.control(), "event {k}: control points");
        assert!(
            due.mesh().vertices() == waited.mesh().vertices(),
            "event {k}: GPU vertices"
        );
        let plans = |s: &EditorState| s.drag().and_then(|d| d.replan.as_ref()).map(|r| r.count);
        assert_eq!(plans(&due), plans(&waited), "event {k}: plans");
    }
    let plans = due
        .drag()
        .and_then(|d| d.replan.as_ref())
        .map_or(0, |r| r.count);
    assert!(plans >= 4, "the grab planned anew as it went: {plans}");

    // Not waiting: plans are put in place whenever they are made.
    let mut free = brush_state();
    free.plan_in_background = true;
    free.influence = 0.12;
    free.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
    let end = at + Vector3::new(0.0, 0.8 * radius, 0.0);
    for k in 1..=32 {
        let to = at + Vector3::new(0.0, 0.025 * f64::from(k) * radius, 0.0);
        free.drag_to_target(to).unwrap();
    }
    let plans = free
        .drag()
        .and_then(|d| d.replan.as_ref())
        .map_or(0, |r| r.count);
    free.release();
    println!("not waiting: {plans} plans after the first were in place before the release");
    let mesh = free.mesh();
    assert!(!mesh.is_lent(), "the release waits for the plan");
    let mut exact = vec![Point3::origin(); mesh.vertex_count()];
    mesh.stencil().positions(free.control(), &mut exact);
    let off = mesh
        .positions()
        .iter()
        .zip(&exact)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(
        off <= 1e-12 * size,
        "a vertex is {off:e} off after the release"
    );
    let shown = mesh
        .vertices()
        .iter()
        .zip(&exact)
        .map(|(v, b)| (Point3::from(v.position.map(f64::from)) - b).norm())
        .fold(0.0, f64::max);
    assert!(shown < 1e-5 * size, "a GPU vertex is {shown:e} off");
    assert!(
        mesh.vertices().iter().all(|v| v.flags == 0),
        "no vertex follows a plan"
    );
    let reached = (free.surface_point(point) - end).norm();
    assert!(
        reached < 1e-6 * size,
        "the point reached the pointer: {reached:e} off"
    );
    let lowest = lowest_upward_normal(&free, end, at, radius);
    println!("planning in the background: the normals near the point face up at least {lowest:.3}");
    assert!(lowest > 0.0, "the top face turned over: {lowest:.3}");
    free.undo().unwrap();
    assert_eq!(free.control(), &original[..], "one undo step restores it");
}

/// With mirror symmetry the picked point's image, found on the surface, moves too, in the same
/// solve: on a mirror-symmetric model (the sphere is symmetric in z to 4e-16) the edited surface
/// stays symmetric to 1e-6 of its size, for a grab and for a stroke brush, whether the view shows
/// a symmetric tessellation or not; on the default genus-2
/// model (symmetric in x to 1.2e-3 of its size, the fit's error) both sides move alike.
#[test]
fn symmetry_mirrors_the_edit_in_one_solve() {
    use embedding::brush::{BrushKind, Symmetry};
    let sphere = initial_model(0, 32, SplineSettings::default(), FitSettings::default())
        .expect("the sphere fits")
        .surface;
    // On the t_e/t_r tessellation, which is itself symmetric, and on the quality one, which is
    // not (brushes sample the surface on their own, so the view's vertices do not matter).
    for meshing in [Meshing::TeTr { te: 32, tr: 32 }, Meshing::default()] {
        println!("sphere shown as {meshing:?}");
        symmetric_edits_stay_symmetric(sphere.clone(), meshing);
    }

    // The genus-2 model: the image side moves as much as the picked side.
    let mut state = brush_state();
    let size = state.size();
    let point = top_point(&state, 0.3 * size);
    state.symmetry = Symmetry {
        x: true,
        y: false,
        z: false,
    };
    state.influence = 0.12;
    state.brush = BrushKind::Inflate;
    let before = state.mesh().positions().to_vec();
    state.start_stroke(point).unwrap();
    state.release();
    let (mut left, mut right) = (0.0f64, 0.0f64);
    for (a, b) in before.iter().zip(state.mesh().positions()) {
        let d = (b - a).norm();
        if a.x > 0.0 {
            right = right.max(d)
        } else {
            left = left.max(d)
        }
    }
    println!("genus 2: moved {right:e} on the picked side, {left:e} on the other");
    assert!(right > 1e-3 * size && (left / right - 1.0).abs() < 0.05);
}

/// A grab near a mirror plane: the point and its image, close together, are neither pulled
/// apart across the plane by more than the brush's own field moves them there (an exact pull
/// fought the field and rippled the surface) nor together (pulled 0.5 R across from 0.06 R off
/// the X plane, the top face turned over): across, the point moves as the field does, towards
/// the plane at most half the way, and it follows the rest of the motion.
#[test]
fn a_grab_near_a_mirror_plane_moves_along_it_without_tearing() {
    use embedding::brush::Symmetry;
    let mut state = brush_state();
    let size = state.size();
    state.influence = 0.12;
    let radius = state.radius();
    state.symmetry = Symmetry {
        x: true,
        y: false,
        z: false,
    };
    let point = top_point(&state, 0.0);
    let at = state.surface_point(point);
    println!("the point is {:.2e} R off the X plane", at.x.abs() / radius);
    assert!(at.x.abs() < 0.1 * radius, "a point near the plane");
    let original = state.control().to_vec();
    for way in [-at.x.signum(), at.x.signum()] {
        let towards = way * at.x < 0.0;
        let pull = Vector3::new(way * 0.5 * radius, 0.2 * radius, 0.3 * radius);
        state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
        state.drag_to_target(at + pull).unwrap();
        state.release();
        let reached = state.surface_point(point);
        let across = (reached.x - at.x).abs();
        // Away: as the brush's field moves it, the two images' falloffs normalised.
        let f = embedding::brush::Falloff::Smooth.at(2.0 * at.x.abs() / radius);
        let allowed = if towards {
            0.5 * at.x.abs()
        } else {
            (1.0 - f) / (1.0 + f) * pull.x.abs()
        };
        println!(
            "pulled {} the plane: moved {across:.3e} across it (allowed {allowed:.3e}), {:.3} R along it",
            if towards { "towards" } else { "away from" },
            (reached - at).yz().norm() / radius
        );
        assert!(
            across <= allowed + 1e-9 * size,
            "{across:e} across the plane"
        );
        assert!(
            ((reached - at).yz() - pull.yz()).norm() < 1e-6 * size,
            "the rest reaches the pointer"
        );
        let lowest = lowest_upward_normal(&state, at, at, radius);
        println!("the normals near the point face up at least {lowest:.3}");
        assert!(lowest > 0.0, "the top face turned over: {lowest:.3}");
        state.undo().unwrap();
        assert_eq!(state.control(), &original[..]);
    }
}

/// A grab pulled straight up with X symmetry near the plane raises one smooth bump, as one brush
/// does: at 0.06, 0.12, 0.2 and 0.28 R off the plane (the point and its image nearly one, then
/// their discs overlapping less) the bump's largest principal curvature is within a quarter of a
/// grab's without symmetry at the same point. The bump is measured where the top face was flat
/// before the pull (|κ| under 0.05 / R), so the hole rims nearby do not count; the plane is
/// crossed on the plate's widest flat face. Measured (|κ| × R, symmetric against alone): 4.28 /
/// 4.35, 4.44 / 4.18, 4.53 / 4.13 and 4.47 / 4.23 at 0.06, 0.12, 0.2 and 0.28 R. (On the line
/// y = 0, where the holes' rims come within 0.3 of the plane, 0.28 R read 5.53 / 3.97: the
/// single bump's top lay on the rim, which the measure leaves out.) With the images' earlier
/// field Σ f² / Σ f (it dips between the images and leaves the picked point short of Δ, which the
/// edit's correction then made up in a spike) the same measure read 4.54 at 0.06 R and 16.95 at
/// 0.12 R.
#[test]
fn a_symmetric_grab_at_a_mirror_plane_raises_one_smooth_bump() {
    use embedding::brush::Symmetry;
    for off in [0.06, 0.12, 0.2, 0.28] {
        let bumps = [
            Symmetry::default(),
            Symmetry {
                x: true,
                y: false,
                z: false,
            },
        ]
        .map(|symmetry| {
            let mut state = brush_state();
            state.influence = 0.12;
            let radius = state.radius();
            state.symmetry = symmetry;
            let point = top_point_at(&state, off * radius, widest_flat_y());
            let at = state.surface_point(point);
            assert!((at.x - off * radius).abs() < 1e-3 * radius, "{at}");
            let curvature = |state: &EditorState, q: ChartPoint| {
                let (k1, k2) = state
                    .layout()
                    .eval(state.control(), q)
                    .principal_curvatures();
                k1.abs().max(k2.abs())
            };
            // The flat top face around the point and its image, before the pull.
            let mirror = Point3::new(-at.x, at.y, at.z);
            let flat: Vec<ChartPoint> = state
                .mesh()
                .positions()
                .iter()
                .zip(&state.mesh().tessellation.vertices)
                .filter(|(p, _)| (**p - at).norm().min((**p - mirror).norm()) < 1.5 * radius)
                .map(|(_, &q)| q)
                .filter(|&q| curvature(&state, q) < 0.05 / radius)
                .collect();
            state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
            state
                .drag_to_target(at + Vector3::new(0.0, 0.0, 0.75 * radius))
                .unwrap();
            state.release();
            flat.iter()
                .map(|&q| curvature(&state, q))
                .fold(0.0, f64::max)
                * radius
        });
        println!(
            "{off} R off the plane: the bump's largest principal curvature × R: {:.2} alone, \
             {:.2} with X symmetry",
            bumps[0], bumps[1]
        );
        assert!(
            bumps[1] < 1.25 * bumps[0],
            "{off} R off the plane: the symmetric bump is rough: {:.2} against {:.2}",
            bumps[1],
            bumps[0]
        );
    }
}

/// In the window: `]` and `[` scale the brush's radius, Shift + `]` and `[` change the strength
/// (Blender's keys); a stroke of each brush dragged across the surface is one undo step; the
/// radius is drawn as a ring on the surface under the cursor. Screenshots of each brush's result
/// (shaded, with the ring) are kept under the target directory.
#[test]
fn brush_keys_strokes_and_the_radius_ring() {
    use embedding::brush::BrushKind;
    let _gpu = gpu_lock();
    let mut harness = harness();
    harness.state_mut().state_mut().unwrap().influence = 0.1;
    harness.key_press(Key::CloseBracket);
    harness.run();
    let influence = harness.state().state().unwrap().influence;
    assert!(
        (influence - 0.11).abs() < 1e-12,
        "] grows the radius: {influence}"
    );
    harness.key_press(Key::OpenBracket);
    harness.key_press(Key::OpenBracket);
    harness.run();
    let influence = harness.state().state().unwrap().influence;
    assert!(
        (influence - 0.1 / 1.1).abs() < 1e-12,
        "[ shrinks it: {influence}"
    );
    harness.key_press_modifiers(Modifiers::SHIFT, Key::CloseBracket);
    harness.run();
    assert_eq!(harness.state().state().unwrap().strength, 0.55);
    harness.key_press_modifiers(Modifiers::SHIFT, Key::OpenBracket);
    harness.key_press_modifiers(Modifiers::SHIFT, Key::OpenBracket);
    harness.run();
    assert_eq!(harness.state().state().unwrap().strength, 0.45);

    // The ring: the same hover with and without a radius.
    let (_, pixel) = visible_vertex(harness.state_mut(), [0.5, 0.5]);
    let start = pos_of(harness.state(), pixel);
    let yellow = |harness: &mut Harness<'static, EditorApp>| {
        let image = harness.render().expect("the window renders");
        image
            .pixels()
            .filter(|p| p[0] > 200 && p[1] > 170 && p[2] < 120)
            .count()
    };
    harness.hover_at(start);
    harness.run();
    let with_ring = yellow(&mut harness);
    harness.state_mut().state_mut().unwrap().influence = 0.0;
    harness.hover_at(start + Vec2::new(1.0, 0.0));
    harness.run();
    let without = yellow(&mut harness);
    println!("yellow pixels: {with_ring} with the ring, {without} without");
    assert!(with_ring > without + 200, "the radius ring is drawn");

    for kind in [
        BrushKind::Grab,
        BrushKind::Inflate,
        BrushKind::Smooth,
        BrushKind::Flatten,
    ] {
        {
            let state = harness.state_mut().state_mut().unwrap();
            state.brush = kind;
            state.influence = 0.12;
            state.strength = 0.8;
        }
        let before = harness.state().state().unwrap().control().to_vec();
        let undo_steps = harness.state().state().unwrap().history().len();
        // Stroke brushes paint along the path; the grab pulls the point along it, mostly along
        // the surface (so it plans anew on the way rather than fold the surface).
        let path = Vec2::new(60.0, -30.0);
        harness.hover_at(start);
        harness.step();
        harness.drag_at(start);
        harness.step();
        for i in 1..=10 {
            harness.hover_at(start + path * (i as f32 / 10.0));
            harness.step();
        }
        harness.drop_at(start + path);
        harness.run();
        let state = harness.state().state().unwrap();
        assert_ne!(state.control(), &before[..], "{kind:?} changed the surface");
        assert_eq!(
            state.history().len(),
            undo_steps + 1,
            "{kind:?}: the stroke is one undo step"
        );
        let picture = artefact_dir().join(format!("brush-{}.png", kind.name()));
        harness.hover_at(start + path);
        harness.run();
        harness.render().unwrap().save(&picture).unwrap();
        println!("after a {} stroke: {}", kind.name(), picture.display());
        harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
        harness.run();
        assert_eq!(
            harness.state().state().unwrap().control(),
            &before[..],
            "{kind:?}: one Ctrl + Z undoes the stroke"
        );
    }
}
