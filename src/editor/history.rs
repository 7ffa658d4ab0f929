//! Undo and redo. A drag stores only the control points it moved, before and after (exact copies, so
//! undo restores them bit for bit); a change of spline settings stores both whole models, a change of
//! pins both lists.

use embedding::charts::ChartPoint;
use embedding::{ControlId, Point3, SplineSettings};

/// One undoable change.
#[derive(Clone, Debug, PartialEq)]
pub enum Change {
    /// Some control points moved.
    Controls {
        indices: Vec<ControlId>,
        before: Vec<Point3>,
        after: Vec<Point3>,
    },
    /// The spline settings changed, and with them every control point.
    Settings {
        before: (SplineSettings, Vec<Point3>),
        after: (SplineSettings, Vec<Point3>),
    },
    /// Pins were added or removed.
    Pins {
        before: Vec<ChartPoint>,
        after: Vec<ChartPoint>,
    },
}

impl Change {
    fn bytes(&self) -> usize {
        match self {
            Change::Controls { indices, .. } => indices.len() * (4 + 48),
            Change::Settings { before, after } => (before.1.len() + after.1.len()) * 24,
            Change::Pins { before, after } => (before.len() + after.len()) * 24,
        }
    }
}

/// A labelled change with an id (the document's state after it).
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    pub label: String,
    pub change: Change,
    pub id: u64,
}

/// The undo and redo stacks. The document's state is named by the id of the last change applied
/// (0 before any), so "modified" is a comparison with the id that was saved.
#[derive(Clone, Debug, Default)]
pub struct History {
    undo: Vec<Entry>,
    redo: Vec<Entry>,
    next_id: u64,
    /// At most this many bytes of changes are kept; the oldest go first.
    pub budget: usize,
}

/// 256 MiB of undo.
const DEFAULT_BUDGET: usize = 256 << 20;

impl History {
    pub fn new() -> History {
        History {
            budget: DEFAULT_BUDGET,
            next_id: 1,
            ..History::default()
        }
    }

    /// Records a change just made; the redo stack is dropped.
    pub fn push(&mut self, label: impl Into<String>, change: Change) {
        self.redo.clear();
        let id = self.next_id;
        self.next_id += 1;
        self.undo.push(Entry {
            label: label.into(),
            change,
            id,
        });
        let mut total: usize = self.undo.iter().map(|e| e.change.bytes()).sum();
        while total > self.budget && self.undo.len() > 1 {
            total -= self.undo.remove(0).change.bytes();
        }
    }

    /// The change to revert, moved to the redo stack.
    pub fn undo(&mut self) -> Option<&Entry> {
        let e = self.undo.pop()?;
        self.redo.push(e);
        self.redo.last()
    }

    /// The change to apply again, moved back to the undo stack.
    pub fn redo(&mut self) -> Option<&Entry> {
        let e = self.redo.pop()?;
        self.undo.push(e);
        self.undo.last()
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|e| e.label.as_str())
    }
    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|e| e.label.as_str())
    }

    /// The id of the document's current state.
    pub fn state(&self) -> u64 {
        self.undo.last().map_or(0, |e| e.id)
    }

    pub fn len(&self) -> usize {
        self.undo.len()
    }
    pub fn is_empty(&self) -> bool {
        self.undo.is_empty()
    }
}
