//! The editor's latencies at 10^5 and 10^6 vertices (genus 2, the default fitted model):
//!
//! - `drag_event`: one drag event as the editor runs it (`EditorState::drag_to_target`): the
//!   minimum-norm solve (the dragged point, and the pins that share control points with it) and the
//!   new control points; the vertices follow on the GPU from the displacement (see `drag.rs`);
//! - `frame_prepare_drag`: the CPU side of a frame during a drag: one event, the camera's uniforms,
//!   and whatever vertex ranges changed, copied out as the GPU upload would take them;
//! - `cpu_vertex_update`: what the vertex shader does per frame during a drag (every reached
//!   vertex's position and normal from the displacement), on the CPU, for comparison;
//! - `frame_prepare_full`: a frame's copy-out with every vertex uploaded (after a style change);
//! - `drag_start` and `drag_release`: what a press (planning the drag: gains of every reached
//!   vertex) and a release (recomputing the moved rows exactly from the stencil) cost, once per
//!   drag;
//! - `brush_start` and `brush_event`: the same with an influence radius of 15% (a grab brush:
//!   planning adds the least-squares shares of the falloff field);
//! - `brush_replan_event`: an event that carries the grabbed point a quarter of the radius or more
//!   along the surface, so the grab plans anew from there (see `editor::drag::Replan`), the plan
//!   made in the event (as `ntori sculpt` does);
//! - `brush_replan_background_{dispatch,job,install}`: the same with the plan made on a thread of
//!   its own, as the editor's window does (`editor::drag::PlanJob`): the event that starts it
//!   (the last plan serves it), the time until the plan is made (from that event's start), and
//!   the next event, which puts it in place;
//! - `stroke_step_inflate`, `_smooth`, `_flatten`: one step of a stroke (a dab: the brush's fit,
//!   the new control points and the vertices they reach, within the stroke's lag budget of the
//!   surface, here 0.4 pixel of a 1280×800 viewport at the default view) of a brush whose disc
//!   covers 5% of the surface's area; `stroke_step_smooth_close`: smooth zoomed in by 4, where
//!   the budget is its least, `UNSEEN` of the size;
//! - `mesh_open`: opening the model at that size (or changing the resolution): the tessellation,
//!   its f64 stencil (built on all cores) and column index, every vertex, the picking boxes;
//! - `pick_after_dab_inflate`, `_smooth`, `_flatten`: the pick under the pointer that comes
//!   before a stroke's next dab (the picking boxes are refitted once the dabs have moved vertices
//!   far enough out of them, otherwise grown).

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use embedding::fit::{default_resolution, default_settings, initial_model};
use embedding::{Surface, Vector3};
use ntori::editor::EditorState;
use ntori::editor::state::Grab;
use ntori::render::Style;

/// t_e = t_r = t for about 10^5 and 10^6 vertices at genus 2 (V ≈ 20 t²).
const SIZES: [(usize, u32); 2] = [(100_000, 71), (1_000_000, 224)];

/// `ntori new`'s genus-2 model, as the editor opens it.
fn model() -> Surface {
    let (spline, settings) = default_settings(2);
    let resolution = default_resolution(2).expect("genus 2's resolution");
    initial_model(2, resolution, spline, settings)
        .expect("the default model fits")
        .surface
}

/// A state at t, with two pins and the point to drag: three tessellation vertices spread over the
/// surface.
fn setup(model: &Surface, t: u32) -> (EditorState, charts::ChartPoint) {
    let meshing = ntori::io::export::Meshing::TeTr { te: t, tr: t };
    let mut state = EditorState::new(model.clone(), meshing).expect("the model opens");
    let n = state.mesh().vertex_count();
    let vertices = &state.mesh().tessellation.vertices;
    let (dragged, pins) = (vertices[n / 3], [vertices[n / 7], vertices[n / 2]]);
    for p in pins {
        state.add_pin(p);
    }
    (state, dragged)
}

/// Which part of a plan made in the background to time.
#[derive(Clone, Copy)]
enum Part {
    Dispatch,
    Job,
    Install,
}

impl Part {
    fn name(self) -> &'static str {
        match self {
            Part::Dispatch => "dispatch",
            Part::Job => "job",
            Part::Install => "install",
        }
    }
}

/// Starts a grab of `point` and returns where 0.3 R along the surface from it is, and the way.
fn start_sideways(
    state: &mut EditorState,
    point: charts::ChartPoint,
) -> (embedding::Point3, Vector3) {
    state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
    let plan = &state.drag().expect("a drag").plan;
    let side = plan
        .start_normal
        .cross(&Vector3::new(0.6, 0.8, 0.0))
        .normalize();
    (plan.start_position + side * (0.3 * state.radius()), side)
}

/// One grab brush that carries the point 0.3 R along the surface with its next plan made in the
/// background, then a little further: the time `part` took.
fn replan_in_background(
    state: &mut EditorState,
    point: charts::ChartPoint,
    part: Part,
) -> std::time::Duration {
    state.plan_in_background = true;
    let (to, side) = start_sideways(state, point);
    let started = std::time::Instant::now();
    state.drag_to_target(black_box(to)).unwrap();
    let dispatch = started.elapsed();
    let job = || {
        state
            .drag()
            .and_then(|d| d.replan.as_ref())
            .and_then(|r| r.job.as_ref())
            .is_some_and(|j| !j.is_finished())
    };
    while job() {
        std::thread::yield_now();
    }
    let made = started.elapsed();
    let started = std::time::Instant::now();
    state.drag_to_target(black_box(to + side * 1e-3)).unwrap();
    let install = started.elapsed();
    let plans = state
        .drag()
        .and_then(|d| d.replan.as_ref())
        .map(|r| r.count);
    assert_eq!(plans, Some(1), "the plan is in place");
    state.cancel_drag();
    state.plan_in_background = false;
    match part {
        Part::Dispatch => dispatch,
        Part::Job => made,
        Part::Install => install,
    }
}

fn drag(c: &mut Criterion) {
    let model = model();
    let mut group = c.benchmark_group("editor");
    group.sample_size(20);
    for (n, t) in SIZES {
        let (mut state, point) = setup(&model, t);
        let start = state.surface_point(point);
        let size = state.size();
        state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
        let rows = state.drag().map_or(0, |d| d.plan.rows.len());
        let controls = state.drag().map_or(0, |d| d.plan.touched.len());
        println!(
            "editor at {} vertices: a drag event moves {rows} vertices through {controls} control points",
            state.mesh().vertex_count()
        );
        let mut step = 0u32;
        let mut target = move || {
            step = step.wrapping_add(1);
            let s = f64::from(step % 100) / 100.0;
            start + Vector3::new(0.05 * s, -0.03 * s, 0.04 * s) * size
        };
        group.bench_function(BenchmarkId::new("drag_event", n), |b| {
            b.iter(|| state.drag_to_target(black_box(target())).unwrap())
        });
        group.bench_function(BenchmarkId::new("frame_prepare_drag", n), |b| {
            let mut staging: Vec<u8> = Vec::new();
            b.iter(|| {
                state.drag_to_target(target()).unwrap();
                let uniforms = state.camera.uniforms(state.style(), [1280, 800]);
                staging.clear();
                let bytes = state
                    .mesh_mut()
                    .upload(false, |_, data| staging.extend_from_slice(data));
                black_box((uniforms, bytes, staging.len()))
            })
        });
        group.bench_function(BenchmarkId::new("drag_release", n), |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                for _ in 0..iters {
                    if state.drag().is_none() {
                        state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
                    }
                    state.drag_to_target(target()).unwrap();
                    let started = std::time::Instant::now();
                    state.release();
                    total += started.elapsed();
                }
                total
            })
        });
        state.release();
        group.bench_function(BenchmarkId::new("drag_start", n), |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                for _ in 0..iters {
                    let started = std::time::Instant::now();
                    state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
                    total += started.elapsed();
                    state.cancel_drag();
                }
                total
            })
        });
        // What the vertex shader does per frame during a drag, done on the CPU instead: every
        // reached vertex's position and normal from the displacement.
        state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
        let mut vertices = state.mesh().vertices().to_vec();
        let plan = state.drag().unwrap().plan.clone();
        group.bench_function(BenchmarkId::new("cpu_vertex_update", n), |b| {
            b.iter(|| plan.move_vertices(black_box(target() - start), &mut vertices))
        });
        state.cancel_drag();
        // The grab brush (influence radius 15% of the model's size): planning it (the least-squares
        // shares) and one event.
        state.influence = 0.15;
        group.bench_function(BenchmarkId::new("brush_start", n), |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                for _ in 0..iters {
                    let started = std::time::Instant::now();
                    state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
                    total += started.elapsed();
                    state.cancel_drag();
                }
                total
            })
        });
        state.start_drag(point, Grab::Surface, [0.0, 0.0]).unwrap();
        println!(
            "a brush of 15% moves {} control points and reaches {} vertices",
            state.drag().map_or(0, |d| d.plan.touched.len()),
            state.drag().map_or(0, |d| d.plan.rows.len())
        );
        group.bench_function(BenchmarkId::new("brush_event", n), |b| {
            b.iter(|| state.drag_to_target(black_box(target())).unwrap())
        });
        state.cancel_drag();
        // An event that carries the point 0.3 R along the surface: the grab plans anew once.
        group.bench_function(BenchmarkId::new("brush_replan_event", n), |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                for _ in 0..iters {
                    let (to, _) = start_sideways(&mut state, point);
                    let started = std::time::Instant::now();
                    state.drag_to_target(black_box(to)).unwrap();
                    total += started.elapsed();
                    assert_eq!(
                        state
                            .drag()
                            .and_then(|d| d.replan.as_ref())
                            .map(|r| r.count),
                        Some(1)
                    );
                    state.cancel_drag();
                }
                total
            })
        });
        for part in [Part::Dispatch, Part::Job, Part::Install] {
            let name = format!("brush_replan_background_{}", part.name());
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter_custom(|iters| {
                    (0..iters)
                        .map(|_| replan_in_background(&mut state, point, part))
                        .sum()
                })
            });
        }
        // The drags above left their releases in the surface: strokes start from the model.
        let (mut fresh, point) = setup(&model, t);
        stroke_steps(&mut group, &mut fresh, point, n);
        state.influence = 0.0;
        group.bench_function(BenchmarkId::new("frame_prepare_full", n), |b| {
            let mut staging: Vec<u8> = Vec::new();
            b.iter(|| {
                // Every vertex dirty, as after a style change: the copy out is what is measured.
                state.mesh_mut().mark_all_dirty();
                let uniforms = state.camera.uniforms(Style::Shaded, [1280, 800]);
                staging.clear();
                let bytes = state
                    .mesh_mut()
                    .upload(false, |_, data| staging.extend_from_slice(data));
                black_box((uniforms, bytes, staging.len()))
            })
        });
    }
    group.finish();
}

/// One step of each stroke brush, its disc covering 5% of the surface's area: dabs alternate
/// between two surface points 0.4 R apart, so every step is due.
fn stroke_steps(
    group: &mut criterion::BenchmarkGroup<criterion::measurement::WallTime>,
    state: &mut EditorState,
    point: charts::ChartPoint,
    n: usize,
) {
    use embedding::brush::BrushKind;
    let mesh = state.mesh();
    let area: f64 = embedding::fit::vertex_areas(mesh.positions(), &mesh.tessellation.triangles)
        .iter()
        .sum();
    let radius = (0.05 * area / std::f64::consts::PI).sqrt();
    state.influence = radius / state.size();
    let at = state.surface_point(point);
    // A vertex 0.3 to 0.5 R away, facing the same way (not across a thin part).
    let mesh = state.mesh();
    let normal = |k: usize| {
        let [u, v] = mesh.tangents()[k];
        u.cross(&v).normalize()
    };
    let here = mesh
        .tessellation
        .vertices
        .iter()
        .position(|p| *p == point)
        .expect("the point is a vertex");
    let other = (0..mesh.vertex_count())
        .find(|&k| {
            let d = (mesh.positions()[k] - at).norm();
            (0.3 * radius..0.5 * radius).contains(&d) && normal(k).dot(&normal(here)) > 0.9
        })
        .map(|k| mesh.tessellation.vertices[k])
        .expect("a vertex near the point");
    // The editor's default window, at the default view; then close up, where the vertices' lag
    // budget is its least (`UNSEEN` of the size, not half a pixel).
    state.viewport = [1280.0, 800.0];
    for (kind, zoom, view) in [
        (BrushKind::Inflate, 1.0, ""),
        (BrushKind::Smooth, 1.0, ""),
        (BrushKind::Flatten, 1.0, ""),
        (BrushKind::Smooth, 4.0, "_close"),
    ] {
        state.reset_view();
        state.camera.zoom(zoom);
        state.brush = kind;
        state.strength = 0.2;
        println!(
            "a {} brush of radius {radius:.3} (5% of the area {area:.2}) at {n} vertices",
            kind.name()
        );
        let (mut flip, mut dabs, mut moved) = (false, 0u32, 0usize);
        group.bench_function(
            BenchmarkId::new(format!("stroke_step_{}{view}", kind.name()), n),
            |b| {
                b.iter_custom(|iters| {
                    let mut total = std::time::Duration::ZERO;
                    for _ in 0..iters {
                        let (at, _) = next_dab(state, [point, other], &mut flip);
                        let started = std::time::Instant::now();
                        state.stroke_at(black_box(at)).unwrap();
                        total += started.elapsed();
                        dabs += 1;
                        moved += state.stroke().map_or(0, |s| s.last_moved);
                    }
                    total
                })
            },
        );
        // The editor picks the surface point under the pointer before every dab: after a dab the
        // ray meets the picking boxes grown by how far the dabs moved the vertices, or refitted
        // once that is 1% of the size.
        let name = format!("pick_after_dab_{}", kind.name());
        if view.is_empty() {
            let centre = [state.viewport[0] / 2.0, state.viewport[1] / 2.0];
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter_custom(|iters| {
                    let mut total = std::time::Duration::ZERO;
                    for _ in 0..iters {
                        let (at, restarted) = next_dab(state, [point, other], &mut flip);
                        if restarted {
                            // The restart's undo moved vertices by any amount: a refit, untimed.
                            state.pick(centre);
                        }
                        state.stroke_at(at).unwrap();
                        let started = std::time::Instant::now();
                        black_box(state.pick(black_box(centre)));
                        total += started.elapsed();
                    }
                    total
                })
            });
        }
        if dabs > 0 {
            println!(
                "{}: {dabs} dabs, {:.0} control points moved on average",
                kind.name(),
                moved as f64 / f64::from(dabs)
            );
        }
        state.cancel_drag();
    }
    state.brush = BrushKind::Grab;
}

/// The point of a stroke's next dab, alternating between `points` (so every dab is due), and
/// whether the stroke was begun anew for it: every `STROKE` dabs (untimed, its changes undone), so
/// the surface stays near the model (hundreds of inflate dabs in one place would blow it up, and
/// the brush would then cover a small part of it).
fn next_dab(
    state: &mut EditorState,
    points: [charts::ChartPoint; 2],
    flip: &mut bool,
) -> (charts::ChartPoint, bool) {
    const STROKE: u32 = 8;
    let restart = state.stroke().is_none_or(|s| s.dabs >= STROKE);
    if restart {
        state.cancel_drag();
        state.start_stroke(points[0]).unwrap();
        *flip = false;
    }
    *flip = !*flip;
    (points[usize::from(*flip)], restart)
}

/// Opening the model at each size (or changing the resolution): tessellating, the f64 stencil and
/// its column index, every vertex evaluated, and the picking boxes.
fn open(c: &mut Criterion) {
    let model = model();
    let mut group = c.benchmark_group("editor");
    group.sample_size(10);
    for (n, t) in SIZES {
        let meshing = ntori::io::export::Meshing::TeTr { te: t, tr: t };
        group.bench_function(BenchmarkId::new("mesh_open", n), |b| {
            b.iter(|| {
                ntori::editor::mesh::LiveMesh::new(&model, meshing, Style::Shaded)
                    .unwrap()
                    .vertex_count()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, drag, open);
criterion_main!(benches);
