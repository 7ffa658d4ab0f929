//! Stroke brushes (inflate, smooth, flatten): while the pointer moves over the surface, a dab at
//! the surface point under it whenever it has travelled a quarter of the radius since the last
//! one. Each dab fits the brush's displacement field by the spline nearest to it
//! ([`embedding::brush::dab`]) and re-evaluates exactly the vertices the moved control points reach.
//! The whole stroke is one undo step: the control points it moved, before and after.

use std::time::{Duration, Instant};

use embedding::brush::{Brush, dab};
use embedding::{ControlId, EmbeddingError, Point3, Surface, Vector3};

use super::mesh::LiveMesh;

/// Dabs are this far apart along a stroke, as a fraction of the radius.
pub const SPACING: f64 = 0.25;

/// A lag budget this much below the stroke's so far makes the vertices exact first (see
/// [`Stroke::set_unseen`]); one above it but still below is left as it was.
pub const SHRINK: f64 = 0.8;

/// A stroke in progress.
#[derive(Clone, Debug)]
pub struct Stroke {
    pub brush: Brush,
    /// Where each control point the stroke moved was when it started (indexed by control point).
    before: Vec<Option<Point3>>,
    /// Where the last dab was.
    last: Option<Point3>,
    pub dabs: u32,
    /// Time spent in dabs (fit, control points and vertices), in total and the last one.
    pub busy: Duration,
    pub last_dab: Duration,
    /// How many control points the last dab moved.
    pub last_moved: usize,
    /// How far (model units) a vertex may lag the surface (see [`LiveMesh::controls_moved`]).
    pub unseen: f64,
    /// The least depth a vertex had from the eye at `view`'s place, looking its way (none yet
    /// before the first dab).
    pub nearest: f64,
    pub view: Option<[glam::DVec3; 2]>,
    /// How far the dabs may have brought a vertex nearer since: a vertex moves by no more than
    /// the control points under it (its weights are positive and sum to 1), so by at most the
    /// largest motion of each dab, added up.
    pub approach: f64,
}

impl Stroke {
    /// A stroke with no lag budget yet: the first dab sets it (`EditorState::stroke_at`).
    pub fn new(brush: Brush, control_count: usize) -> Stroke {
        Stroke {
            unseen: 0.0,
            nearest: 0.0,
            view: None,
            approach: 0.0,
            brush,
            before: vec![None; control_count],
            last: None,
            dabs: 0,
            busy: Duration::ZERO,
            last_dab: Duration::ZERO,
            last_moved: 0,
        }
    }

    /// Whether the pointer at `at` is far enough from the last dab for the next.
    pub fn due(&self, at: Point3) -> bool {
        self.last
            .is_none_or(|last| (at - last).norm() >= SPACING * self.brush.radius)
    }

    /// One dab at `centres` (the point under the pointer first, then its mirror images with their
    /// signs): moves the control points and re-evaluates the vertices they reach. Returns how many
    /// control points moved.
    pub fn dab(
        &mut self,
        surface: &mut Surface,
        mesh: &mut LiveMesh,
        centres: &[(Point3, Vector3)],
    ) -> Result<usize, EmbeddingError> {
        let started = Instant::now();
        let moved = dab(&mesh.brush_samples(surface)?, self.brush, centres)?;
        let control = surface.control_points();
        let updates: Vec<(ControlId, Point3)> = moved
            .iter()
            .map(|&(c, d)| (c, control[c.index()] + d))
            .collect();
        for &(c, _) in &moved {
            self.before[c.index()].get_or_insert(control[c.index()]);
        }
        surface.set_control_points_at(updates.iter().copied())?;
        mesh.controls_moved(surface, &moved, self.unseen);
        self.approach += moved.iter().map(|m| m.1.norm()).fold(0.0, f64::max);
        self.last = centres.first().map(|c| c.0);
        self.dabs += 1;
        self.last_moved = moved.len();
        self.last_dab = started.elapsed();
        self.busy += self.last_dab;
        Ok(moved.len())
    }

    /// From now on the vertices may lag by `budget`. Where that is below [`SHRINK`] of the
    /// budget so far (the view came closer), the vertices the stroke moved are made exact first:
    /// no vertex lags by more than the budget over [`SHRINK`]. A larger one takes over at once
    /// (every lag is under the old).
    pub fn set_unseen(&mut self, budget: f64, surface: &Surface, mesh: &mut LiveMesh) {
        if budget < SHRINK * self.unseen {
            let moved: Vec<ControlId> = self.moved().map(|m| m.0).collect();
            mesh.controls_changed(surface, &moved);
        } else if budget < self.unseen {
            return;
        }
        self.unseen = budget;
    }

    /// The control points the stroke moved, with where they were before it.
    pub fn moved(&self) -> impl Iterator<Item = (ControlId, Point3)> + '_ {
        self.before
            .iter()
            .enumerate()
            .filter_map(|(c, p)| p.map(|p| (ControlId(c as u32), p)))
    }
}
