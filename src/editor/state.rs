//! The editor's state, apart from any drawing: the document (genus, spline settings, control points,
//! its file), the live mesh, the camera, picking, pins, the drag in progress and the history. The
//! egui code (`app.rs`) turns input into calls here; the tests drive the same calls.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use charts::{Atlas, ChartId, ChartPoint, ManifoldPoint};
use embedding::brush::{Brush, BrushKind, Falloff, Symmetry, nearest_on_surface};
use embedding::remesh::QualitySettings;
use embedding::{ControlId, EmbeddingError, Layout, Point3, SplineSettings, Surface, Vector3};

use super::camera::{OrbitCamera, to_point};
pub use super::drag::{Drag, DragStats, Grab};
use super::drag::{
    DragPlan, DragRow, MirrorHold, PlanFrom, PlanJob, REPLAN, Replan, SERVE, merge_sorted,
};
use super::history::{Change, History};
use super::mesh::{LAG_PIXELS, LiveMesh, UNSEEN};
use super::pick::Hit;
use super::stroke::{SHRINK, Stroke};
use crate::io::export::Meshing;
use crate::io::model_file::ModelFileError;
use crate::render::Style;

/// What can go wrong in the editor.
#[derive(Debug, thiserror::Error)]
pub enum EditorError {
    #[error(transparent)]
    Model(#[from] EmbeddingError),
    #[error(transparent)]
    Charts(#[from] charts::ChartsError),
    #[error(transparent)]
    File(#[from] ModelFileError),
    #[error(transparent)]
    Export(#[from] crate::io::export::ExportError),
    #[error(transparent)]
    Render(#[from] crate::render::RenderError),
    #[error(transparent)]
    Io(#[from] crate::io::atomic::FileError),
    #[error("t_e = {te}, t_r = {tr} is out of the editor's range (1 to {max} each)")]
    Tessellation { te: u32, tr: u32, max: u32 },
    #[error("{0}")]
    Other(String),
}

/// The largest t_e or t_r the editor offers (about 1.3 million vertices at genus 2).
pub const MAX_T: u32 = 256;
/// The smallest and largest brush radius the keys give, as fractions of the model's size.
pub const MIN_RADIUS: f64 = 0.01;
pub const MAX_RADIUS: f64 = 0.5;

/// The brush radius the editor starts with, as a fraction of the model's size, and a stroke
/// brush's radius when the radius has been turned off. Drags start as a brush with a smooth
/// falloff rather than the paper's edit (radius off), whose footprint is the control spacing: at
/// grid 16 a pointed peak, at grid 32 a narrow spike the view's tessellation shows as jagged.
pub const DEFAULT_STROKE_RADIUS: f64 = 0.15;

/// The t_e and t_r the panel offers first when switching to the t_e/t_r tessellation.
pub const DEFAULT_T: u32 = 32;

/// A picked surface point.
#[derive(Clone, Debug, PartialEq)]
pub struct Pick {
    /// The triangle the ray hit, the barycentric coordinates of the hit and the ray parameter.
    pub hit: Hit,
    /// The manifold point there: the barycentric combination of the triangle's corners in its home
    /// chart, with every chart that holds it.
    pub point: ChartPoint,
    pub manifold: ManifoldPoint,
    /// Where the ray met the triangle, and the exact surface point S(point).
    pub on_mesh: Point3,
    pub surface: Point3,
}

/// The editor's state (see the module documentation).
pub struct EditorState {
    /// The document's surface: validated once, when it was loaded, fitted or refitted.
    surface: Surface,
    mesh: LiveMesh,
    meshing: Meshing,
    pub camera: OrbitCamera,
    /// The viewport's size in physical pixels.
    pub viewport: [f64; 2],
    drag: Option<Drag>,
    history: History,
    path: Option<PathBuf>,
    saved_state: u64,
    /// The influence radius as a fraction of the model's size (0: off, the paper's edit).
    pub influence: f64,
    /// How the influence fades towards the radius.
    pub falloff: Falloff,
    /// What a press and drag does: grab (follow the pointer) or a stroke brush.
    pub brush: BrushKind,
    /// A stroke brush's strength (1: a full step per dab; negative: the opposite way).
    pub strength: f64,
    /// Mirror planes: a press acts on the picked point's mirror images too.
    pub symmetry: Symmetry,
    stroke: Option<Stroke>,
    /// Whose control points to show.
    pub control_chart: Option<ChartId>,
    pub last_drag: Option<DragStats>,
    /// A grab brush makes its next plan on a thread of its own while the last one goes on
    /// serving the events (see [`PlanJob`]): the editor's window does, so that no event waits
    /// for a plan. Off, each plan is made when it is due, so the result depends on the events
    /// alone, not on timing (`ntori sculpt`, tests).
    pub plan_in_background: bool,
}

impl EditorState {
    /// A state for `surface`, tessellated as `meshing` says, with the default view.
    pub fn new(surface: Surface, meshing: Meshing) -> Result<EditorState, EditorError> {
        check_meshing(meshing)?;
        let mesh = LiveMesh::new(&surface, meshing, Style::Shaded)?;
        let (centre, radius) = mesh.bounding_sphere();
        Ok(EditorState {
            camera: OrbitCamera::new(centre, radius),
            viewport: [800.0, 600.0],
            surface,
            mesh,
            meshing,
            drag: None,
            history: History::new(),
            path: None,
            saved_state: 0,
            influence: DEFAULT_STROKE_RADIUS,
            falloff: Falloff::Smooth,
            brush: BrushKind::Grab,
            strength: 0.5,
            symmetry: Symmetry::default(),
            stroke: None,
            control_chart: None,
            last_drag: None,
            plan_in_background: false,
        })
    }

    /// Opens a model file.
    pub fn open(path: &Path, meshing: Meshing) -> Result<EditorState, EditorError> {
        let surface = crate::io::model_file::load(path)?;
        let mut state = EditorState::new(surface, meshing)?;
        state.path = Some(path.to_owned());
        Ok(state)
    }

    /// Writes the model to `path` and makes it the document's file.
    pub fn save(&mut self, path: &Path) -> Result<(), EditorError> {
        crate::io::model_file::save(path, &self.surface)?;
        self.path = Some(path.to_owned());
        self.saved_state = self.history.state();
        Ok(())
    }

    /// The surface as it stands.
    pub fn surface(&self) -> &Surface {
        &self.surface
    }

    pub fn layout(&self) -> Layout<'_> {
        self.surface.layout()
    }

    pub fn atlas(&self) -> &Atlas {
        self.surface.atlas()
    }
    pub fn genus(&self) -> u32 {
        self.surface.genus()
    }
    pub fn settings(&self) -> SplineSettings {
        self.surface.settings()
    }
    pub fn control(&self) -> &[Point3] {
        self.surface.control_points()
    }
    pub fn mesh(&self) -> &LiveMesh {
        &self.mesh
    }
    pub fn mesh_mut(&mut self) -> &mut LiveMesh {
        self.finish_plan();
        &mut self.mesh
    }
    /// How the viewport's mesh is made (and an export from the editor).
    pub fn meshing(&self) -> Meshing {
        self.meshing
    }
    pub fn style(&self) -> Style {
        self.mesh.style()
    }
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }
    pub fn set_path(&mut self, path: Option<PathBuf>) {
        self.path = path;
    }
    pub fn history(&self) -> &History {
        &self.history
    }
    /// Unsaved changes?
    pub fn is_modified(&self) -> bool {
        self.history.state() != self.saved_state
    }
    /// Marks the document as changed since its file (e.g. recovered after a crash).
    pub fn mark_modified(&mut self) {
        self.saved_state = u64::MAX;
    }
    /// The pinned surface points (the document's: saved with it, and part of undo).
    pub fn pins(&self) -> &[ChartPoint] {
        self.surface.pins()
    }
    pub fn drag(&self) -> Option<&Drag> {
        self.drag.as_ref()
    }
    pub fn stroke(&self) -> Option<&Stroke> {
        self.stroke.as_ref()
    }
    /// The stroke in progress, to change (tests set its bounds).
    pub fn stroke_mut(&mut self) -> Option<&mut Stroke> {
        self.stroke.as_mut()
    }
    /// Whether a drag or a stroke is in progress.
    pub fn busy(&self) -> bool {
        self.drag.is_some() || self.stroke.is_some()
    }

    /// The model's size: the diagonal of the tessellation's bounding box.
    pub fn size(&self) -> f64 {
        self.mesh.size()
    }

    /// The exact surface point at a chart point.
    pub fn surface_point(&self, p: ChartPoint) -> Point3 {
        self.surface.eval(p).pos
    }

    // ------------------------------------------------------------------------------- display

    pub fn set_style(&mut self, style: Style) {
        self.finish_plan();
        if style != self.mesh.style() {
            self.mesh.set_style(&self.surface, style);
        }
    }

    /// Tessellates anew as `meshing` says (the view stays).
    pub fn set_meshing(&mut self, meshing: Meshing) -> Result<(), EditorError> {
        check_meshing(meshing)?;
        if meshing == self.meshing {
            return Ok(());
        }
        self.remesh(meshing)
    }

    /// Tessellates the surface as it stands anew (the quality tessellation follows its
    /// curvature as it was when made; after edits, a new one follows the new shape).
    pub fn remesh(&mut self, meshing: Meshing) -> Result<(), EditorError> {
        self.finish_plan();
        let mesh = LiveMesh::new(&self.surface, meshing, self.mesh.style())?;
        self.mesh = mesh;
        self.meshing = meshing;
        Ok(())
    }

    /// Centres the model and fits it in the view.
    pub fn frame(&mut self) {
        self.update_scene();
        self.camera.frame(self.viewport[0] / self.viewport[1]);
    }

    /// The default view of the model.
    pub fn reset_view(&mut self) {
        self.update_scene();
        self.camera.reset();
    }

    fn update_scene(&mut self) {
        let (centre, radius) = self.mesh.bounding_sphere();
        self.camera.set_scene(centre, radius);
    }

    // ------------------------------------------------------------------------------- picking

    /// The surface point under a pixel of the viewport, if any.
    pub fn pick(&mut self, pixel: [f64; 2]) -> Option<Pick> {
        if self.drag.is_some() {
            return None;
        }
        let ray = self.camera.ray(pixel, self.viewport);
        let hit = self.mesh.cast(&ray)?;
        let point = hit.chart_point(&self.mesh.tessellation);
        let manifold = self.surface.atlas().locate(point).ok()?;
        Some(Pick {
            hit,
            point,
            manifold,
            on_mesh: ray.at(hit.t),
            surface: self.surface_point(point),
        })
    }

    /// The pin drawn within `radius` pixels of `pixel` (nearest first), if any.
    pub fn pin_near(&self, pixel: [f64; 2], radius: f64) -> Option<usize> {
        self.pins()
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let (q, depth) = self.camera.project(self.surface_point(p), self.viewport);
                (i, (q[0] - pixel[0]).hypot(q[1] - pixel[1]), depth)
            })
            .filter(|&(_, d, depth)| d <= radius && depth > 0.0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _, _)| i)
    }

    /// Pins the surface point under `pixel`, or unpins the pin there. Returns whether anything
    /// changed.
    pub fn toggle_pin(&mut self, pixel: [f64; 2]) -> bool {
        if let Some(i) = self.pin_near(pixel, PIN_RADIUS_PX) {
            self.remove_pin(i);
            return true;
        }
        match self.pick(pixel) {
            Some(pick) => {
                self.add_pin(pick.point);
                true
            }
            None => false,
        }
    }

    /// Pins `point` (an undoable change).
    pub fn add_pin(&mut self, point: ChartPoint) {
        let mut pins = self.pins().to_vec();
        pins.push(point);
        self.change_pins("pin", pins);
    }
    /// Removes pin `i` (an undoable change).
    pub fn remove_pin(&mut self, i: usize) {
        if i < self.pins().len() {
            let mut pins = self.pins().to_vec();
            pins.remove(i);
            self.change_pins("unpin", pins);
        }
    }
    /// Removes every pin (one undoable change).
    pub fn clear_pins(&mut self) {
        if !self.pins().is_empty() {
            self.change_pins("clear pins", Vec::new());
        }
    }

    fn change_pins(&mut self, label: &str, after: Vec<ChartPoint>) {
        let before = self.pins().to_vec();
        // Picked points lie in their charts, and removing pins keeps the rest valid.
        if self.surface.set_pins(after.clone()).is_ok() {
            self.history.push(label, Change::Pins { before, after });
        }
    }

    // ------------------------------------------------------------------------------- dragging

    /// Starts a drag at `pixel`: grabs a pin drawn there, or else the surface point under it (with
    /// a stroke brush: starts a stroke there). Returns what was grabbed (None: nothing there, e.g.
    /// to orbit instead).
    pub fn press(&mut self, pixel: [f64; 2]) -> Result<Option<Grab>, EditorError> {
        if self.busy() {
            return Ok(None);
        }
        let (point, grab) = if let Some(i) = self.pin_near(pixel, PIN_RADIUS_PX) {
            (self.pins()[i], Grab::Pin(i))
        } else if let Some(pick) = self.pick(pixel) {
            (pick.point, Grab::Surface)
        } else {
            return Ok(None);
        };
        if grab == Grab::Surface && self.brush.is_stroke() {
            self.start_stroke(point)?;
        } else {
            self.start_drag(point, grab, pixel)?;
        }
        Ok(Some(grab))
    }

    /// Scales the brush's radius (as `[` and `]` do): from off, `]` turns it on at the smallest
    /// radius; it stays between [`MIN_RADIUS`] and [`MAX_RADIUS`] of the model's size.
    pub fn scale_radius(&mut self, factor: f64) {
        self.influence = if self.influence <= 0.0 {
            if factor > 1.0 { MIN_RADIUS } else { 0.0 }
        } else {
            (self.influence * factor).clamp(MIN_RADIUS, MAX_RADIUS)
        };
    }

    /// Changes the stroke brushes' strength (as Shift + `[` and `]` do), within −1 to 1.
    pub fn add_strength(&mut self, delta: f64) {
        self.strength = ((self.strength + delta) * 100.0).round() / 100.0;
        self.strength = self.strength.clamp(-1.0, 1.0);
    }

    /// The brush's radius in model units (0: no radius, the paper's edit).
    pub fn radius(&self) -> f64 {
        self.influence * self.size()
    }

    /// The mirror images of the surface point `point` under [`EditorState::symmetry`], found on
    /// the surface (the surface point nearest to the mirrored position), with the signs that
    /// mirror a displacement for each; images that fall on the point itself or on an earlier
    /// image (a point on a mirror plane) are left out.
    pub fn mirror_images(&self, point: ChartPoint) -> Vec<(ChartPoint, Vector3)> {
        let at = self.surface_point(point);
        let tolerance = 1e-6 * self.size();
        let mut images: Vec<(ChartPoint, Vector3)> = Vec::new();
        let mut seen = vec![at];
        for signs in self.symmetry.images().into_iter().skip(1) {
            let target = Point3::from(at.coords.component_mul(&signs));
            let start = self.nearest_vertex(target);
            let layout = self.layout();
            let image = nearest_on_surface(&layout, self.control(), start, target);
            let position = self.surface_point(image);
            if seen.iter().all(|s| (s - position).norm() > tolerance) {
                seen.push(position);
                images.push((image, signs));
            }
        }
        images
    }

    /// The tessellation vertex nearest to `p`, as a chart point.
    pub fn nearest_vertex(&self, p: Point3) -> ChartPoint {
        let k = self
            .mesh
            .positions()
            .iter()
            .map(|q| (q - p).norm_squared())
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(k, _)| k);
        self.mesh.tessellation.vertices[k]
    }

    /// Starts a drag of `point` (the pointer is at `pixel`).
    pub fn start_drag(
        &mut self,
        point: ChartPoint,
        grab: Grab,
        pixel: [f64; 2],
    ) -> Result<(), EditorError> {
        let pins: Vec<ChartPoint> = self
            .pins()
            .iter()
            .enumerate()
            .filter(|&(i, _)| grab != Grab::Pin(i))
            .map(|(_, &p)| p)
            .collect();
        // The samples and the model's size first: the radius is a fraction of the size as it is
        // now (a cancelled drag may have left the size of a surface it undid).
        if self.influence > 0.0 {
            self.mesh.refresh_brush_weights(&self.surface)?;
        }
        let brush = (self.influence > 0.0).then(|| (self.radius(), self.falloff));
        let images = match grab {
            Grab::Surface => self.mirror_images(point),
            Grab::Pin(_) => Vec::new(),
        };
        let plan = DragPlan::new(
            &self.surface,
            &mut self.mesh,
            point,
            &pins,
            brush,
            &images,
            &[],
        )?;
        let replan = match (grab, brush) {
            (Grab::Surface, Some(brush)) => Some(Replan {
                step: REPLAN * brush.0,
                pins,
                brush,
                images,
                count: 0,
                settled: Vec::new(),
                job: None,
            }),
            _ => None,
        };
        let mirror = (grab == Grab::Surface && !self.symmetry.is_empty()).then(|| MirrorHold {
            symmetry: self.symmetry,
            radius: brush.map_or(0.0, |b| b.0),
            falloff: self.falloff,
            tolerance: 1e-6 * self.size(),
        });
        self.drag = Some(Drag {
            origin: plan.start_position,
            mirror,
            origin_control: plan.start_control.clone(),
            plan,
            press_pixel: pixel,
            grab,
            replan,
            events: 0,
            busy: Duration::ZERO,
            last: Duration::ZERO,
        });
        Ok(())
    }

    /// Starts a stroke of the current (stroke) brush with a dab at `point`. A stroke brush needs a
    /// radius: without an influence radius it uses [`DEFAULT_STROKE_RADIUS`] of the model's size.
    pub fn start_stroke(&mut self, point: ChartPoint) -> Result<(), EditorError> {
        if self.busy() {
            return Ok(());
        }
        if self.influence <= 0.0 {
            self.influence = DEFAULT_STROKE_RADIUS;
        }
        let brush = Brush {
            kind: self.brush,
            radius: self.radius(),
            falloff: self.falloff,
            strength: self.strength,
        };
        self.mesh.refresh_brush_weights(&self.surface)?;
        self.stroke = Some(Stroke::new(brush, self.control().len()));
        self.stroke_at(point)
    }

    /// How far (model units) a vertex may lag the surface during a stroke when no vertex is
    /// nearer the eye than `nearest` (along the view direction): [`LAG_PIXELS`] of a pixel there
    /// ([`OrbitCamera::pixel_at`]), and never less than [`UNSEEN`] of the model's size. Far
    /// vertices lag more in model units, yet less on the screen.
    pub fn lag_budget(&self, nearest: f64) -> f64 {
        let pixel = self.camera.pixel_at(nearest, self.viewport);
        (LAG_PIXELS * pixel).max(UNSEEN * self.size())
    }

    /// The stroke's pointer is over `point`: a dab there if it has moved far enough since the last.
    pub fn stroke_at(&mut self, point: ChartPoint) -> Result<(), EditorError> {
        let at = self.surface_point(point);
        if !self.stroke.as_ref().is_some_and(|s| s.due(at)) {
            return Ok(());
        }
        let centres: Vec<(Point3, Vector3)> = std::iter::once((at, Vector3::new(1.0, 1.0, 1.0)))
            .chain(
                self.mirror_images(point)
                    .into_iter()
                    .map(|(p, signs)| (self.surface_point(p), signs)),
            )
            .collect();
        // The budget for the view as it is now. At the first dab, where the view moved since
        // the last, or where the bound on how near the dabs brought a vertex would shrink it
        // (that would make the vertices exact), the nearest vertex anew: a pass over the
        // vertices, not one per dab.
        let view = [self.camera.eye(), self.camera.direction()];
        let stroke = self.stroke.as_ref().expect("a stroke in progress");
        let mut budget = self.lag_budget(stroke.nearest - stroke.approach);
        if stroke.view != Some(view) || budget < SHRINK * stroke.unseen {
            let nearest = self.camera.nearest_depth(self.mesh.positions());
            budget = self.lag_budget(nearest);
            let stroke = self.stroke.as_mut().expect("a stroke in progress");
            (stroke.nearest, stroke.view, stroke.approach) = (nearest, Some(view), 0.0);
        }
        let stroke = self.stroke.as_mut().expect("a stroke in progress");
        stroke.set_unseen(budget, &self.surface, &mut self.mesh);
        stroke.dab(&mut self.surface, &mut self.mesh, &centres)?;
        Ok(())
    }

    /// Ends the stroke: one undoable change, the control points it moved.
    pub fn end_stroke(&mut self) {
        let Some(stroke) = self.stroke.take() else {
            return;
        };
        let (indices, before): (Vec<ControlId>, Vec<Point3>) = stroke.moved().unzip();
        if indices.is_empty() {
            return;
        }
        // The dabs moved the vertices through the f32 stencil: exact again.
        self.mesh.controls_changed(&self.surface, &indices);
        let after = indices.iter().map(|c| self.control()[c.index()]).collect();
        self.history.push(
            stroke.brush.kind.name(),
            Change::Controls {
                indices,
                before,
                after,
            },
        );
    }

    /// Where a drag that pressed at `press` and is now at `pixel` wants its point: the start
    /// position moved by the pointer's motion in the plane through it facing the camera.
    pub fn drag_target(&self, anchor: Point3, press: [f64; 2], pixel: [f64; 2]) -> Point3 {
        let (a, b) = (
            self.camera.on_view_plane(press, self.viewport, anchor),
            self.camera.on_view_plane(pixel, self.viewport, anchor),
        );
        anchor + (b - a)
    }

    /// A drag event: the pointer is at `pixel`. Solves and moves the affected vertices (in a
    /// stroke: a dab at the surface point under the pointer, when it is due).
    pub fn drag_to(&mut self, pixel: [f64; 2]) -> Result<(), EditorError> {
        if self.stroke.is_some() {
            if let Some(pick) = self.pick(pixel) {
                self.stroke_at(pick.point)?;
            }
            return Ok(());
        }
        let Some(drag) = &self.drag else {
            return Ok(());
        };
        let target = self.drag_target(drag.origin, drag.press_pixel, pixel);
        self.drag_to_target(target)
    }

    /// A drag event with an explicit target for the dragged point (with mirror symmetry, held
    /// near the planes: see [`MirrorHold`]).
    ///
    /// A grab brush plans anew each `step` of the way along the surface (see [`Replan`]): from
    /// the point `step` along, the last plan settles and the next is made from there. In the
    /// background ([`EditorState::plan_in_background`]) the last plan goes on serving the events
    /// until the next is made, or until the point has gone [`SERVE`] of the radius from its start
    /// (then the event waits for it).
    pub fn drag_to_target(&mut self, target: Point3) -> Result<(), EditorError> {
        let Some(drag) = &mut self.drag else {
            return Ok(());
        };
        let started = Instant::now();
        let target = drag
            .mirror
            .map_or(target, |m| m.target(drag.origin, target));
        while let Some(replan) = &mut drag.replan {
            let delta = target - drag.plan.start_position;
            let normal = drag.plan.start_normal;
            let along = (delta - normal * delta.dot(&normal)).norm();
            if let Some(job) = replan.job.take() {
                let wait = !self.plan_in_background || along > SERVE / REPLAN * replan.step;
                if !wait && !job.is_finished() {
                    replan.job = Some(job);
                    break;
                }
                install(drag, &mut self.surface, &mut self.mesh, job)?;
                continue;
            }
            // (No normal where the surface is degenerate: no plan anew.)
            if along <= replan.step || !along.is_finite() {
                break;
            }
            let via = drag.plan.start_position + delta * (replan.step / along);
            let from = PlanFrom {
                surface: &self.surface,
                via,
                pins: &replan.pins,
                brush: replan.brush,
                images: &replan.images,
            };
            let settled = &mut replan.settled;
            let job = PlanJob::start(&drag.plan, from, &mut self.mesh, settled)?;
            replan.job = Some(job);
        }
        drag.plan.drag_to(&mut self.surface, target)?;
        let took = started.elapsed();
        drag.events += 1;
        drag.busy += took;
        drag.last = took;
        Ok(())
    }

    /// Waits for a grab's next plan if one is being made, and puts it in place where the last
    /// event took the point: the mesh is the editor's alone again.
    pub fn finish_plan(&mut self) {
        let Some(drag) = &mut self.drag else {
            return;
        };
        let Some(job) = drag.replan.as_mut().and_then(|r| r.job.take()) else {
            return;
        };
        let target = drag.plan.start_position + drag.plan.displacement;
        let placed = install(drag, &mut self.surface, &mut self.mesh, job)
            .and_then(|()| Ok(drag.plan.drag_to(&mut self.surface, target).map(|_| ())?));
        if let Err(e) = placed {
            tracing::warn!("the grab's next plan could not be put in place: {e}");
        }
    }

    /// Waits for a grab's next plan if one is being made, and leaves it: the drag ends as the
    /// last plan shows it (what the user saw, not the next plan's take on the same target). The
    /// vertices the job wrote join the settled ones, to be made exact.
    fn drop_plan(&mut self) {
        let Some(drag) = &mut self.drag else {
            return;
        };
        let Some(replan) = drag.replan.as_mut() else {
            return;
        };
        let Some(job) = replan.job.take() else {
            return;
        };
        let done = job.join();
        self.mesh.give_back(done.lent, &done.written);
        replan.settled = merge_sorted(&done.settled, &done.written);
    }

    /// The drag as the GPU shows it: the plan's id, the vertices it moves and how, and the
    /// displacement of the last event.
    pub fn drag_display(&self) -> Option<(u64, &[DragRow], Vector3)> {
        self.drag
            .as_ref()
            .map(|d| (d.plan.id, &d.plan.moves[..], d.plan.displacement))
    }

    /// The live mesh and the drag as the GPU shows it, together (for uploading both).
    pub fn with_display<R>(
        &mut self,
        f: impl FnOnce(&mut LiveMesh, Option<(u64, &[DragRow], Vector3)>) -> R,
    ) -> R {
        let drag = self
            .drag
            .as_ref()
            .map(|d| (d.plan.id, &d.plan.moves[..], d.plan.displacement));
        f(&mut self.mesh, drag)
    }

    /// Ends the drag (or the stroke): the moved vertices are recomputed exactly and the change
    /// joins the history.
    pub fn release(&mut self) {
        self.end_stroke();
        self.drop_plan();
        let Some(drag) = self.drag.take() else {
            return;
        };
        let plan = drag.plan;
        let moved = changed_since(self.control(), &drag.origin_control);
        let settled = drag.replan.map(|r| r.settled).unwrap_or_default();
        self.mesh
            .rows_changed(&self.surface, &merge_sorted(&settled, &plan.rows));
        self.last_drag = Some(DragStats {
            point: plan.point,
            start: drag.origin,
            target: plan.start_position + plan.displacement,
            events: drag.events,
            mean: drag.busy / drag.events.max(1),
            last: drag.last,
            vertices: plan.rows.len(),
            controls: plan.touched.len(),
        });
        if moved.is_empty() {
            return;
        }
        let label = match drag.grab {
            Grab::Surface => "drag",
            Grab::Pin(_) => "drag pin",
        };
        self.history.push(
            label,
            Change::Controls {
                before: moved
                    .iter()
                    .map(|&c| drag.origin_control[c.index()])
                    .collect(),
                after: moved.iter().map(|&c| self.control()[c.index()]).collect(),
                indices: moved,
            },
        );
    }

    /// Abandons the drag (or the stroke): the control points go back to where they were.
    pub fn cancel_drag(&mut self) {
        self.drop_plan();
        if let Some(stroke) = self.stroke.take() {
            let (indices, before): (Vec<ControlId>, Vec<Point3>) = stroke.moved().unzip();
            // The starting control points were valid, so restoring them cannot fail.
            if self
                .surface
                .set_control_points_at(indices.iter().copied().zip(before))
                .is_ok()
            {
                self.mesh.controls_changed(&self.surface, &indices);
            }
        }
        let Some(drag) = self.drag.take() else {
            return;
        };
        let moved = changed_since(self.control(), &drag.origin_control);
        let restored = moved.iter().map(|&c| (c, drag.origin_control[c.index()]));
        // The starting control points were valid, so restoring them cannot fail.
        if self.surface.set_control_points_at(restored).is_ok() {
            // Every vertex the moved points reach, the last plan's (drawn from its gains) and the
            // earlier plans' (written from theirs).
            let settled = drag.replan.map(|r| r.settled).unwrap_or_default();
            let rows = merge_sorted(&self.mesh.rows_of_controls(&moved), &drag.plan.rows);
            self.mesh
                .rows_changed(&self.surface, &merge_sorted(&rows, &settled));
        }
    }

    // ------------------------------------------------------------------------------- history

    pub fn can_undo(&self) -> bool {
        !self.busy() && self.history.can_undo()
    }
    pub fn can_redo(&self) -> bool {
        !self.busy() && self.history.can_redo()
    }

    /// Reverts the last change. Returns its label.
    pub fn undo(&mut self) -> Result<Option<String>, EditorError> {
        if self.busy() {
            return Ok(None);
        }
        let Some(entry) = self.history.undo() else {
            return Ok(None);
        };
        let (label, change) = (entry.label.clone(), entry.change.clone());
        self.apply(&change, false)?;
        Ok(Some(label))
    }

    /// Applies the last undone change again. Returns its label.
    pub fn redo(&mut self) -> Result<Option<String>, EditorError> {
        if self.busy() {
            return Ok(None);
        }
        let Some(entry) = self.history.redo() else {
            return Ok(None);
        };
        let (label, change) = (entry.label.clone(), entry.change.clone());
        self.apply(&change, true)?;
        Ok(Some(label))
    }

    fn apply(&mut self, change: &Change, forward: bool) -> Result<(), EditorError> {
        match change {
            Change::Controls {
                indices,
                before,
                after,
            } => {
                let values = if forward { after } else { before };
                let updates = indices.iter().copied().zip(values.iter().copied());
                self.surface.set_control_points_at(updates)?;
                self.mesh.controls_changed(&self.surface, indices);
            }
            Change::Settings { before, after } => {
                let (settings, control) = if forward { after } else { before };
                self.replace_control(*settings, control.clone())?;
            }
            Change::Pins { before, after } => {
                let pins = if forward { after } else { before };
                self.surface.set_pins(pins.clone())?;
            }
        }
        Ok(())
    }

    /// New spline settings with their control points (e.g. from [`refit`](super::jobs::refit())): an undoable change.
    pub fn set_settings(
        &mut self,
        settings: SplineSettings,
        control: Vec<Point3>,
    ) -> Result<(), EditorError> {
        // A drag or stroke in progress (a refit can finish during one) ends first, as if released:
        // its control points are the old settings'.
        self.release();
        let before = (self.settings(), self.control().to_vec());
        self.replace_control(settings, control.clone())?;
        self.history.push(
            format!(
                "settings: degree {}, C^{}, {}",
                settings.degree,
                settings.continuity,
                settings.grid_text()
            ),
            Change::Settings {
                before,
                after: (settings, control),
            },
        );
        Ok(())
    }

    fn replace_control(
        &mut self,
        settings: SplineSettings,
        control: Vec<Point3>,
    ) -> Result<(), EditorError> {
        self.finish_plan();
        let mut surface = Surface::new(self.surface.shared_atlas(), settings, control)?;
        // Pins are surface points, whatever the spline settings.
        surface.set_pins(self.pins().to_vec())?;
        let mesh = LiveMesh::new(&surface, self.meshing, self.mesh.style())?;
        self.surface = surface;
        self.mesh = mesh;
        if let Some(c) = self.control_chart
            && c.index() >= self.atlas().charts().len()
        {
            self.control_chart = None;
        }
        Ok(())
    }

    /// The control points of one chart, as a g × g net (g its grid; row j, column i at j·g + i).
    pub fn control_net(&self, chart: ChartId) -> &[Point3] {
        let grids = self.layout().grids();
        let (start, g) = (grids.offset(chart), grids.grid(chart));
        let control = self.control();
        &control[start.min(control.len())..(start + g * g).min(control.len())]
    }

    /// Where a viewport pixel's ray meets the surface, as text for the status bar.
    pub fn describe(&self, pick: &Pick) -> String {
        let p = pick.point;
        format!(
            "chart {} at ({:.4}, {:.4}), S = ({:.4}, {:.4}, {:.4})",
            p.chart.0, p.coords.re, p.coords.im, pick.surface.x, pick.surface.y, pick.surface.z
        )
    }

    /// The camera's eye, in model coordinates.
    pub fn eye(&self) -> Point3 {
        to_point(self.camera.eye())
    }
}

/// How close (in pixels) a press must be to a pin to grab it.
pub const PIN_RADIUS_PX: f64 = 7.0;

/// Puts a grab's next plan in place (made by `job` from the point `via` of the last plan's way):
/// the mesh takes back what it lent, with the vertices the job wrote, and the control points the
/// last plan moved beyond `via` go back there, where the new plan starts. If the plan failed, the
/// last one goes on (its vertices follow it again) and the error is returned.
fn install(
    drag: &mut Drag,
    surface: &mut Surface,
    mesh: &mut LiveMesh,
    job: PlanJob,
) -> Result<(), EditorError> {
    let done = job.join();
    mesh.give_back(done.lent, &done.written);
    let replan = drag.replan.as_mut().expect("a grab brush plans anew");
    replan.settled = done.settled;
    let plan = match done.plan {
        Ok(plan) => plan,
        Err(e) => {
            drag.plan.hold(mesh.vertices_mut());
            mesh.mark_dirty(&drag.plan.rows);
            return Err(e.into());
        }
    };
    let back = drag
        .plan
        .touched
        .iter()
        .map(|&c| (c, plan.start_control[c.index()]));
    surface.set_control_points_at(back)?;
    drag.plan = plan;
    replan.count += 1;
    Ok(())
}

/// The control points that differ from `origin`, in order.
fn changed_since(control: &[Point3], origin: &[Point3]) -> Vec<ControlId> {
    (0..control.len())
        .filter(|&c| control[c] != origin[c])
        .map(|c| ControlId(c as u32))
        .collect()
}

fn check_meshing(meshing: Meshing) -> Result<(), EditorError> {
    match meshing {
        Meshing::TeTr { te, tr } if !(1..=MAX_T).contains(&te) || !(1..=MAX_T).contains(&tr) => {
            Err(EditorError::Tessellation { te, tr, max: MAX_T })
        }
        Meshing::Quality { tolerance } | Meshing::Quads { tolerance } => {
            QualitySettings::with_tolerance(tolerance).check()?;
            Ok(())
        }
        Meshing::TeTr { .. } => Ok(()),
    }
}
