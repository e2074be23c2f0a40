//! Undo and redo by snapshots of the whole [`Graph`].
//!
//! Graphs are small (tens of nodes), so a snapshot per edit is cheap and leaves no room
//! for an inverse operation that forgets a field. Consecutive edits that belong together
//! (one slider drag, one node drag) share a *coalescing key*: only the first of them takes
//! a snapshot, so one gesture is one undo step.

use lumagraph_graph::Graph;

/// How many steps are kept.
const LIMIT: usize = 200;

/// Snapshots before each edit (`undo`) and after each undo (`redo`).
#[derive(Debug, Default)]
pub struct History {
    undo: Vec<Graph>,
    redo: Vec<Graph>,
    coalesce: Option<String>,
}

impl History {
    /// Records `before`, the graph as it was before an edit. With a `key` equal to the
    /// previous edit's key, nothing is recorded: the edit extends the previous step.
    pub fn record(&mut self, before: &Graph, key: Option<&str>) {
        if key.is_some() && key == self.coalesce.as_deref() {
            return;
        }
        self.coalesce = key.map(str::to_owned);
        self.undo.push(before.clone());
        if self.undo.len() > LIMIT {
            self.undo.remove(0);
        }
        self.redo.clear();
    }

    /// Ends the current gesture: the next edit starts a new step even with the same key.
    pub fn end_gesture(&mut self) {
        self.coalesce = None;
    }

    /// Steps back: returns the graph to restore, given the current one.
    pub fn undo(&mut self, current: &Graph) -> Option<Graph> {
        let previous = self.undo.pop()?;
        self.redo.push(current.clone());
        self.coalesce = None;
        Some(previous)
    }

    /// Steps forward again after an undo.
    pub fn redo(&mut self, current: &Graph) -> Option<Graph> {
        let next = self.redo.pop()?;
        self.undo.push(current.clone());
        self.coalesce = None;
        Some(next)
    }

    /// Whether there is something to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is something to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Forgets everything (a new file was opened).
    pub fn clear(&mut self) {
        *self = Self::default();
    }
}
