//! One drag: the minimum-norm edit that moves a picked surface point to the cursor while the pins
//! stay, solved on every drag event, and the redraw of just the vertices it moves.
//!
//! Every event solves afresh from the control points the drag started with
//! ([`embedding::edit::solve`]: the dragged point's constraint and one per pin, at the pins'
//! positions when the drag began), so the result does not depend on how many events the pointer
//! sent. The solution is linear in the dragged point's displacement Δ: the change is ΔP_c = β_c Δ
//! for a fixed set of control points with fixed β (the constraint rows do not change during a
//! drag). So at the start the plan also collects, for each vertex those control points reach, its
//! position and tangents then and the gains g = Σ_c w_c β_c (and the same for the u and v
//! derivative weights): such a vertex is at p₀ + g Δ, its tangents likewise, a few multiply-adds
//! instead of its whole stencil row. These [`DragRow`]s go to the GPU once, at the start; each event
//! then only sends Δ, and the vertex shader moves the vertices (see `pulled.wgsl`).
//! [`DragPlan::move_vertices`] is the same on the CPU (the reference the tests compare with). When
//! the drag ends, the moved rows are recomputed exactly from the stencil.
//!
//! Pins that cannot interact with the drag — no control point of theirs can move, directly or through
//! another pin that shares control points with the moving ones — are left out of the system: their
//! control points do not move at all, so they stay exactly, and the drag reaches fewer vertices.
//!
//! The optional influence radius makes the drag a grab brush defined on the surface
//! ([`embedding::brush`]): control points first move by their share of Δ in the spline nearest to
//! "every surface point within the radius moves by Δ times the falloff of its model-space distance",
//! then the minimum-norm correction makes the dragged point and the pins exact again. The footprint
//! is then the radius in every chart, whichever chart the point was picked in.

use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use charts::ChartPoint;
use embedding::brush::BrushSamples;
use embedding::brush::{Falloff, Symmetry, grab_shares_mirrored};
use embedding::edit::{Constraint, solve};
use embedding::{
    ColumnIndex, ControlId, EmbeddingError, Layout, Point3, Stencil, Surface, Vector3,
};

use bytemuck::{Pod, Zeroable};

use super::mesh::{Lent, LiveMesh, ViewVertex};
use embedding::evaluate::parallel_chunks;

/// What a press in the viewport grabbed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Grab {
    /// A surface point (not pinned).
    Surface,
    /// The pin with this index.
    Pin(usize),
}

/// A drag in progress: the plan and where the pointer went down.
#[derive(Debug)]
pub struct Drag {
    pub plan: DragPlan,
    pub press_pixel: [f64; 2],
    pub grab: Grab,
    /// Where the dragged point was, and the control points, when the drag began (a drag may
    /// make several plans: see [`Replan`]).
    pub origin: Point3,
    pub origin_control: Vec<Point3>,
    /// A grab with mirror symmetry: how its displacement is held near the planes.
    pub mirror: Option<MirrorHold>,
    /// A grab brush's: how to plan anew as the point travels.
    pub replan: Option<Replan>,
    pub events: u32,
    /// Time spent in drag events (solve and vertex update), in total and the last one.
    pub busy: Duration,
    pub last: Duration,
}

/// How a grab with mirror symmetry holds its displacement near the planes, so that the point
/// moves as the brush's field moves it there and does not meet its images
/// ([`embedding::brush::Symmetry::limit_grab`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirrorHold {
    pub symmetry: Symmetry,
    /// The brush's radius (0: the paper's edit) and falloff.
    pub radius: f64,
    pub falloff: Falloff,
    /// Closer than this to a plane, a point is on it.
    pub tolerance: f64,
}

impl MirrorHold {
    /// Where the point grabbed at `origin` goes for a pointer at `target`.
    pub fn target(&self, origin: Point3, target: Point3) -> Point3 {
        let (radius, falloff, tolerance) = (self.radius, self.falloff, self.tolerance);
        let delta = target - origin;
        origin + (self.symmetry).limit_grab(origin, delta, radius, falloff, tolerance)
    }
}

/// A grab brush moves the surface around the point by Δ times a falloff of the distance, and on
/// the surface the map x ↦ x + Δ f(|x − c| / R) folds once |Δ_t| · max |f′| / R reaches 1, Δ_t
/// the part of Δ along the surface (a pull along the normal raises a bump and never folds): a pull
/// along the surface of about half the radius. So a grab brush plans anew, from where the surface
/// then is, each time the point has travelled [`REPLAN`] of the radius along the surface since
/// the last plan: the region follows the pointer a step at a time, each step a map that cannot
/// fold, and a pull along the surface drags a smooth bump along instead of folding it. (Pulled
/// much further, about 1.4 R, the squeezed front does fold: each plan starts from the last one's
/// squeeze.)
#[derive(Debug)]
pub struct Replan {
    /// How far the point travels along the surface under one plan (model units).
    pub step: f64,
    pub pins: Vec<ChartPoint>,
    pub brush: (f64, Falloff),
    pub images: Vec<(ChartPoint, Vector3)>,
    /// Plans made after the first.
    pub count: u32,
    /// The vertices of the plans before the current one (increasing): their f64 positions and
    /// tangents are brought up to date at the release. (Lent to `job` while it runs.)
    pub settled: Vec<u32>,
    /// The next plan, being made on a thread of its own (see [`PlanJob`]).
    pub job: Option<PlanJob>,
}

/// A grab brush's plan carries the point this fraction of the radius (see [`Replan`]): the
/// smooth profile's steepest slope is 1.72, so one plan's map stretches the surface by at most
/// 1 − 0.43 and cannot fold it.
pub const REPLAN: f64 = 0.25;

/// While the next plan is made in the background ([`PlanJob`]), the last one serves the events
/// until the point has travelled this fraction of the radius from its start; then an event waits
/// for the plan. The smooth and sharp profiles' steepest slopes are 1.72 and 2, so the map still
/// keeps a fifth of the surface's length there.
pub const SERVE: f64 = 0.4;

/// The last finished drag: what moved where, and how long its events took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragStats {
    /// The dragged surface point, where it was, and where the last event asked it to go.
    pub point: ChartPoint,
    pub start: Point3,
    pub target: Point3,
    pub events: u32,
    pub mean: Duration,
    pub last: Duration,
    /// Vertices each event moved and control points it changed.
    pub vertices: usize,
    pub controls: usize,
}

/// A vertex a drag moves, as the GPU reads it: its position and tangents when the drag began, and
/// its gains per axis (position = base + g ⊙ Δ, S_u = u + g_u ⊙ Δ, S_v = v + g_v ⊙ Δ: with mirror
/// symmetry the images move by the mirrored Δ, so the three axes' gains differ). 72 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DragRow {
    pub base: [f32; 9],
    pub gain: [f32; 9],
}

/// Where a plan starts: the dragged point, its position and unit normal, and its mirror images
/// with their positions and the signs that mirror Δ for them.
struct Start {
    point: ChartPoint,
    position: Point3,
    normal: Vector3,
    images: Vec<(ChartPoint, Point3, Vector3)>,
}

impl Start {
    fn new(surface: &Surface, point: ChartPoint, images: &[(ChartPoint, Vector3)]) -> Start {
        let layout = &surface.layout();
        let control = surface.control_points();
        let start = layout.eval(control, point);
        Start {
            point,
            position: start.pos,
            normal: start.normal(),
            images: images
                .iter()
                .map(|&(p, signs)| (p, layout.eval(control, p).pos, signs))
                .collect(),
        }
    }

    /// A grab brush's shares of Δ per control point (none for the paper's edit), fitted over
    /// the brush samples `samples` gives.
    fn shares<'s>(
        &self,
        brush: Option<(f64, Falloff)>,
        samples: impl FnOnce() -> Result<BrushSamples<'s>, EmbeddingError>,
    ) -> Result<Vec<(ControlId, Vector3)>, EmbeddingError> {
        match brush {
            Some((radius, falloff)) if radius > 0.0 => {
                let centres: Vec<(Point3, Vector3)> =
                    std::iter::once((self.position, Vector3::new(1.0, 1.0, 1.0)))
                        .chain(self.images.iter().map(|&(_, at, signs)| (at, signs)))
                        .collect();
                grab_shares_mirrored(&samples()?, &centres, radius, falloff)
            }
            _ => Ok(Vec::new()),
        }
    }
}

/// What a plan reads of the live mesh (or of what it lent): the stencil and its columns, and
/// every vertex's f64 position and tangents.
pub(crate) struct PlanRows<'a> {
    pub stencil: &'a Stencil,
    pub columns: &'a ColumnIndex,
    pub positions: &'a [Point3],
    pub tangents: &'a [[Vector3; 2]],
}

/// A grab brush's next plan, made on a thread of its own while the last plan goes on serving the
/// events (a plan takes about 25 ms at 10⁵ vertices and 0.1 s at 10⁶: its rows' gains, the
/// brush's shares), so that no drag event waits for one. The live mesh lends it what it reads and
/// the vertices it writes (`LiveMesh::lend`): the thread brings the brush samples to where the
/// last plan moved the surface, writes the last plan's vertices as it left them, and makes the
/// plan from there.
#[derive(Debug)]
pub struct PlanJob {
    handle: JoinHandle<PlanDone>,
}

/// What a [`PlanJob`] hands back.
pub(crate) struct PlanDone {
    pub plan: Result<DragPlan, EmbeddingError>,
    pub lent: Lent,
    /// The settled vertices with the last plan's.
    pub settled: Vec<u32>,
    /// The vertices written (the last plan's and the new one's), to upload.
    pub written: Vec<u32>,
}

/// What the next plan is made from: the surface as the last plan left it at `via`, and the
/// grab's pins, brush and mirror images.
pub(crate) struct PlanFrom<'a> {
    pub surface: &'a Surface,
    pub via: Point3,
    pub pins: &'a [ChartPoint],
    pub brush: (f64, Falloff),
    pub images: &'a [(ChartPoint, Vector3)],
}

impl PlanJob {
    /// Starts making the plan that follows `last` from `from.via`; `settled` the vertices of
    /// the plans before `last` (taken for the job, and left as they are if it fails to start).
    /// Fails (before starting anything) if the last plan cannot reach `via` or the brush samples
    /// cannot be made.
    pub(crate) fn start(
        last: &DragPlan,
        from: PlanFrom<'_>,
        mesh: &mut LiveMesh,
        settled: &mut Vec<u32>,
    ) -> Result<PlanJob, EmbeddingError> {
        let mut surface = from.surface.clone();
        let delta = from.via - last.start_position;
        let (updates, _) = last.controls_at(&surface.layout(), delta)?;
        surface.set_control_points_at(updates)?;
        let mut lent = mesh.lend(&surface)?;
        // Lent to the job only now that nothing can fail.
        let settled = std::mem::take(settled);
        let (rows, moves, touched) = (
            Arc::clone(&last.rows),
            Arc::clone(&last.moves),
            last.touched.clone(),
        );
        let (point, pins, brush, images) = (
            last.point,
            from.pins.to_vec(),
            from.brush,
            from.images.to_vec(),
        );
        let handle = std::thread::Builder::new()
            .name("ntori grab plan".into())
            .spawn(move || {
                lent.samples.controls_moved(&surface, &touched);
                settle_rows(&rows, &moves, delta, &mut lent.vertices);
                let settled = merge_sorted(&settled, &rows);
                let plan = DragPlan::from_lent(
                    &surface, &mut lent, point, &pins, brush, &images, &settled,
                );
                let written = match &plan {
                    Ok(plan) => merge_sorted(&rows, &plan.rows),
                    Err(_) => rows.to_vec(),
                };
                PlanDone {
                    plan,
                    lent,
                    settled,
                    written,
                }
            })
            .expect("a thread for the grab's next plan");
        Ok(PlanJob { handle })
    }

    pub fn is_finished(&self) -> bool {
        self.handle.is_finished()
    }

    /// Waits for the plan (a panic on its thread goes on here).
    pub(crate) fn join(self) -> PlanDone {
        self.handle
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    }
}

/// The union of two increasing lists of rows, increasing.
pub(crate) fn merge_sorted(a: &[u32], b: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let next = match (a.get(i), b.get(j)) {
            (Some(&x), Some(&y)) if x <= y => x,
            (_, Some(&y)) => y,
            (Some(&x), None) => x,
            (None, None) => unreachable!("one list has more"),
        };
        i += usize::from(a.get(i) == Some(&next));
        j += usize::from(b.get(j) == Some(&next));
        out.push(next);
    }
    out
}

static NEXT_PLAN: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// A drag in progress.
#[derive(Clone, Debug)]
pub struct DragPlan {
    /// The dragged surface point and where it was when the drag began.
    pub point: ChartPoint,
    pub start_position: Point3,
    /// The surface's unit normal there.
    pub start_normal: Vector3,
    /// The pins as constraints (targets: where they were when the drag began).
    pub pins: Vec<Constraint>,
    /// The control points when the drag began.
    pub start_control: Vec<Point3>,
    /// The dragged point's mirror images on the surface (symmetry), where they were when the
    /// drag began, and the signs that mirror Δ for them.
    pub images: Vec<(ChartPoint, Point3, Vector3)>,
    /// Influence: control point and its share of Δ per axis.
    soft: Vec<(ControlId, Vector3)>,
    /// Every control point an event may move (sorted), and how: ΔP_c = beta_c ⊙ Δ.
    pub touched: Vec<ControlId>,
    beta: Vec<Vector3>,
    /// The vertices those control points reach (sorted), and how they move (shared with the
    /// job that makes the next plan, which settles them).
    pub rows: Arc<Vec<u32>>,
    pub moves: Arc<Vec<DragRow>>,
    /// Names this plan (the GPU uploads a plan's rows once).
    pub id: u64,
    /// The displacement of the last event.
    pub displacement: Vector3,
    /// The least-squares residual of the last solve (0 unless constraints conflict).
    pub residual: f64,
}

impl DragPlan {
    /// Plans a drag of `point` with `pins` held, from the current control points; `brush` is the
    /// influence radius in model units and its falloff (None: the paper's edit); `images` are the
    /// point's mirror images on the surface with the signs that mirror a displacement for them;
    /// `settled` the vertices whose f64 positions in `mesh` are not up to date (a grab's earlier
    /// plans').
    pub fn new(
        surface: &Surface,
        mesh: &mut LiveMesh,
        point: ChartPoint,
        pins: &[ChartPoint],
        brush: Option<(f64, Falloff)>,
        images: &[(ChartPoint, Vector3)],
        settled: &[u32],
    ) -> Result<DragPlan, EmbeddingError> {
        let start = Start::new(surface, point, images);
        let soft = start.shares(brush, || mesh.brush_samples(surface))?;
        let plan = DragPlan::with_shares(surface, start, soft, pins, mesh.plan_rows(), settled)?;
        plan.hold(mesh.vertices_mut());
        mesh.mark_dirty(&plan.rows);
        Ok(plan)
    }

    /// [`DragPlan::new`] from what the live mesh lent (see [`PlanJob`]); the vertices' flags are
    /// written into the lent vertices.
    fn from_lent(
        surface: &Surface,
        lent: &mut Lent,
        point: ChartPoint,
        pins: &[ChartPoint],
        brush: (f64, Falloff),
        images: &[(ChartPoint, Vector3)],
        settled: &[u32],
    ) -> Result<DragPlan, EmbeddingError> {
        let start = Start::new(surface, point, images);
        let soft = start.shares(Some(brush), || Ok(lent.samples.view(surface)))?;
        let rows = PlanRows {
            stencil: &lent.stencil,
            columns: &lent.columns,
            positions: &lent.positions,
            tangents: &lent.tangents,
        };
        let plan = DragPlan::with_shares(surface, start, soft, pins, rows, settled)?;
        plan.hold(&mut lent.vertices);
        Ok(plan)
    }

    /// The plan for a start and the brush's shares: the pins that interact, the minimum-norm
    /// change per unit displacement, the rows it reaches and their gains.
    fn with_shares(
        surface: &Surface,
        start: Start,
        soft: Vec<(ControlId, Vector3)>,
        pins: &[ChartPoint],
        mesh: PlanRows<'_>,
        settled: &[u32],
    ) -> Result<DragPlan, EmbeddingError> {
        let layout = &surface.layout();
        let control = surface.control_points();
        let Start {
            point,
            position: start_position,
            normal: start_normal,
            images,
        } = start;
        // The pins that interact with the drag: grow the set of control points that may move.
        let mut moving = vec![false; control.len()];
        let mut row = Vec::new();
        for p in std::iter::once(point).chain(images.iter().map(|i| i.0)) {
            layout.weights(p, &mut row);
            for w in &row {
                moving[w.control as usize] = true;
            }
        }
        for s in &soft {
            moving[s.0.index()] = true;
        }
        let supports: Vec<Vec<u32>> = pins
            .iter()
            .map(|&p| {
                row.clear();
                layout.weights(p, &mut row);
                row.iter().map(|w| w.control).collect()
            })
            .collect();
        let mut active = vec![false; pins.len()];
        loop {
            let mut grew = false;
            for (i, support) in supports.iter().enumerate() {
                if !active[i] && support.iter().any(|&c| moving[c as usize]) {
                    active[i] = true;
                    grew = true;
                    for &c in support {
                        moving[c as usize] = true;
                    }
                }
            }
            if !grew {
                break;
            }
        }
        let pins: Vec<Constraint> = pins
            .iter()
            .zip(&active)
            .filter(|&(_, &a)| a)
            .map(|(&p, _)| Constraint {
                point: p,
                target: layout.eval(control, p).pos,
            })
            .collect();
        let mut plan = DragPlan {
            point,
            start_position,
            start_normal,
            pins,
            start_control: control.to_vec(),
            images,
            soft,
            touched: Vec::new(),
            beta: Vec::new(),
            rows: Arc::default(),
            moves: Arc::default(),
            id: NEXT_PLAN.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            displacement: Vector3::zeros(),
            residual: 0.0,
        };
        // β by linearity, per axis (the images' constraints mirror Δ, each axis on its own): the
        // change for a displacement of 1 along every axis.
        let (moved, _) = plan.solve(layout, Vector3::new(1.0, 1.0, 1.0))?;
        let mut touched: Vec<(ControlId, Vector3)> = moved;
        touched.sort_unstable_by_key(|t| t.0);
        plan.touched = touched.iter().map(|t| t.0).collect();
        plan.beta = touched.iter().map(|t| t.1).collect();
        // The rows reached, in increasing order.
        let rows = mesh
            .stencil
            .rows_of_controls(mesh.columns, plan.touched.iter().map(|c| c.index()));
        // Each reached row's gains from its own stencil row (streamed, in parallel), with β looked up
        // by control point.
        let mut beta = vec![Vector3::zeros(); control.len()];
        for (&c, &b) in plan.touched.iter().zip(&plan.beta) {
            beta[c.index()] = b;
        }
        // The rows' positions and tangents: the mesh's, except for the vertices of a grab's
        // earlier plans (`settled`: their f64 copies wait for the release), which come from the
        // stencil rows streamed here anyway.
        let mut stale = Vec::new();
        if !settled.is_empty() {
            stale = vec![0u64; mesh.positions.len().div_ceil(64)];
            for &r in settled {
                stale[r as usize / 64] |= 1 << (r % 64);
            }
        }
        let is_stale = |r: u32| {
            stale
                .get(r as usize / 64)
                .is_some_and(|w| w & (1 << (r % 64)) != 0)
        };
        let (stencil, positions, tangents) = (mesh.stencil, mesh.positions, mesh.tangents);
        let mut moves = vec![DragRow::default(); rows.len()];
        parallel_chunks(&rows, &mut moves, |rows, out| {
            for (o, &r) in out.iter_mut().zip(rows) {
                let stale = is_stale(r);
                let (mut g, mut base) = ([0.0f64; 9], [Vector3::zeros(); 3]);
                for (c, w) in stencil.row(r as usize) {
                    if stale {
                        for a in 0..3 {
                            base[a] += control[c as usize].coords * w[a];
                        }
                    }
                    let b = beta[c as usize];
                    if b != Vector3::zeros() {
                        for a in 0..3 {
                            for axis in 0..3 {
                                g[3 * a + axis] += w[a] * b[axis];
                            }
                        }
                    }
                }
                if !stale {
                    let [u, v] = tangents[r as usize];
                    base = [positions[r as usize].coords, u, v];
                }
                let [p, u, v] = base;
                *o = DragRow {
                    base: [p.x, p.y, p.z, u.x, u.y, u.z, v.x, v.y, v.z].map(|x| x as f32),
                    gain: g.map(|x| x as f32),
                };
            }
        });
        plan.rows = Arc::new(rows);
        plan.moves = Arc::new(moves);
        Ok(plan)
    }

    /// Tells the GPU copy which vertices follow the drag (flags: the row's index + 1).
    pub(crate) fn hold(&self, vertices: &mut [ViewVertex]) {
        for (k, &r) in self.rows.iter().enumerate() {
            vertices[r as usize].flags = k as u32 + 1;
        }
    }

    /// The minimum-norm change for displacement `delta` of the dragged point: (control point,
    /// change) for every control point that moves, and the residual.
    fn solve(
        &self,
        layout: &Layout,
        delta: Vector3,
    ) -> Result<(Vec<(ControlId, Vector3)>, f64), EmbeddingError> {
        let mut start = std::borrow::Cow::Borrowed(&self.start_control);
        if !self.soft.is_empty() {
            let shifted = start.to_mut();
            for &(c, f) in &self.soft {
                shifted[c.index()] += delta.component_mul(&f);
            }
        }
        let mut constraints = Vec::with_capacity(1 + self.images.len() + self.pins.len());
        constraints.push(Constraint {
            point: self.point,
            target: self.start_position + delta,
        });
        constraints.extend(self.images.iter().map(|&(point, at, signs)| Constraint {
            point,
            target: at + delta.component_mul(&signs),
        }));
        constraints.extend_from_slice(&self.pins);
        let edit = solve(layout, &start, &constraints)?;
        let mut moved: Vec<(ControlId, Vector3)> = self
            .soft
            .iter()
            .map(|&(c, f)| (c, delta.component_mul(&f)))
            .collect();
        moved.extend(
            edit.controls
                .iter()
                .copied()
                .zip(edit.deltas.iter().copied()),
        );
        // Merge a control point that is both soft and corrected.
        moved.sort_unstable_by_key(|m| m.0);
        let mut merged: Vec<(ControlId, Vector3)> = Vec::with_capacity(moved.len());
        for (c, d) in moved {
            match merged.last_mut() {
                Some(last) if last.0 == c => last.1 += d,
                _ => merged.push((c, d)),
            }
        }
        Ok((merged, edit.residual))
    }

    /// One drag event: the dragged point's new target. Solves and writes the new control points
    /// into `control` (start + change, for the touched ones); the vertices follow on the GPU from
    /// [`DragPlan::displacement`]. Returns the residual.
    pub fn drag_to(
        &mut self,
        surface: &mut Surface,
        target: Point3,
    ) -> Result<f64, EmbeddingError> {
        let delta = target - self.start_position;
        let (updates, residual) = self.controls_at(&surface.layout(), delta)?;
        surface.set_control_points_at(updates)?;
        self.displacement = delta;
        self.residual = residual;
        Ok(residual)
    }

    /// The touched control points for displacement `delta` (start + change), and the residual.
    fn controls_at(
        &self,
        layout: &Layout,
        delta: Vector3,
    ) -> Result<(Vec<(ControlId, Point3)>, f64), EmbeddingError> {
        let (moved, residual) = self.solve(layout, delta)?;
        let mut updates: Vec<(ControlId, Point3)> = self
            .touched
            .iter()
            .map(|&c| (c, self.start_control[c.index()]))
            .collect();
        for (c, d) in moved {
            updates.push((c, self.start_control[c.index()] + d));
        }
        Ok((updates, residual))
    }

    /// Ends this plan's hold on its vertices as its last event left them: their GPU copies
    /// written (no longer following the drag) and marked for upload. Their f64 positions and
    /// tangents are not: [`LiveMesh::rows_changed`] with [`DragPlan::rows`] brings them up to date.
    pub fn settle(&self, mesh: &mut LiveMesh) {
        settle_rows(
            &self.rows,
            &self.moves,
            self.displacement,
            mesh.vertices_mut(),
        );
        mesh.mark_dirty(&self.rows);
    }

    /// The vertices' positions and normals for displacement `delta`, written into a vertex array on
    /// the CPU: what the vertex shader does (sorted rows, so the array splits into disjoint pieces,
    /// one per thread).
    pub fn move_vertices(&self, delta: Vector3, vertices: &mut [ViewVertex]) {
        move_rows(&self.rows, &self.moves, delta, vertices);
    }
}

/// Writes a plan's rows at displacement `delta` into the vertices and lets go of them (flags 0).
fn settle_rows(rows: &[u32], moves: &[DragRow], delta: Vector3, vertices: &mut [ViewVertex]) {
    move_rows(rows, moves, delta, vertices);
    for &r in rows {
        vertices[r as usize].flags = 0;
    }
}

/// What the vertex shader does with a plan's rows (`moves`, one per row) for displacement `delta`.
fn move_rows(rows: &[u32], moves: &[DragRow], delta: Vector3, vertices: &mut [ViewVertex]) {
    {
        let d = [delta.x as f32, delta.y as f32, delta.z as f32];
        let work = |first: usize, rows: &[u32], out: &mut [ViewVertex], offset: usize| {
            for (k, &r) in (first..).zip(rows) {
                let DragRow { base: b, gain: g } = &moves[k];
                let p = [b[0] + g[0] * d[0], b[1] + g[1] * d[1], b[2] + g[2] * d[2]];
                let u = [b[3] + g[3] * d[0], b[4] + g[4] * d[1], b[5] + g[5] * d[2]];
                let v = [b[6] + g[6] * d[0], b[7] + g[7] * d[1], b[8] + g[8] * d[2]];
                let n = [
                    u[1] * v[2] - u[2] * v[1],
                    u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0],
                ];
                let inv = 1.0 / (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                let vertex = &mut out[r as usize - offset];
                vertex.position = p;
                vertex.normal = n.map(|x| x * inv);
            }
        };
        split_by_rows(rows, vertices, work);
    }
}

/// Splits sorted rows into per-thread chunks and the vertex array at the chunk borders, so each
/// thread writes its own piece: `work(index of the chunk's first row, rows, piece, piece offset)`.
fn split_by_rows(
    rows: &[u32],
    vertices: &mut [ViewVertex],
    work: impl Fn(usize, &[u32], &mut [ViewVertex], usize) + Sync,
) {
    const MIN_PER_THREAD: usize = 16_384;
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(rows.len().div_ceil(MIN_PER_THREAD))
        .max(1);
    if threads == 1 {
        work(0, rows, vertices, 0);
        return;
    }
    let per = rows.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let mut rest = vertices;
        let mut offset = 0usize;
        for (i, chunk) in rows.chunks(per).enumerate() {
            let end = chunk.last().map_or(offset, |&r| r as usize + 1);
            let (mine, tail) = std::mem::take(&mut rest).split_at_mut(end - offset);
            rest = tail;
            let work = &work;
            let start = offset;
            scope.spawn(move || work(i * per, chunk, mine, start));
            offset = end;
        }
    });
}
