//! The selection: which nodes are selected, which port the preview shows, copy, paste
//! and delete.

use lumagraph_graph::{Graph, split_port_ref};

use super::Editor;

impl Editor {
    /// Selects nodes (as a click on the canvas would) and previews the first one.
    pub fn select(&mut self, ids: Vec<String>) {
        if let Some(first) = ids.first() {
            // Keep a port of this node chosen by clicking its pin; else its first output.
            let chosen_here = self
                .preview_port
                .as_deref()
                .and_then(split_port_ref)
                .is_some_and(|(n, _)| n == first);
            if !chosen_here {
                self.preview_port = self.port_for_node(first);
            }
        }
        self.selected_frame = None;
        self.selected = ids;
    }

    /// The port previewed for node `id`: its first output, or what feeds a sink.
    pub(super) fn port_for_node(&self, id: &str) -> Option<String> {
        let node = self.doc.graph.node(id)?;
        let kind = self.doc.registry().get(&node.kind)?;
        if let Some(o) = kind.outputs.first() {
            return Some(format!("{id}.{}", o.name));
        }
        let input = kind.inputs.first()?;
        let to = format!("{id}.{}", input.name);
        self.doc
            .graph
            .edges
            .iter()
            .find(|e| e.to == to)
            .map(|e| e.from.clone())
    }

    /// The port the preview shows: the chosen one if it still exists, else what feeds
    /// the first sink.
    pub fn effective_port(&self) -> Option<String> {
        let exists = |p: &str| {
            split_port_ref(p).is_some_and(|(n, port)| {
                self.doc
                    .graph
                    .node(n)
                    .and_then(|n| self.doc.registry().get(&n.kind))
                    .is_some_and(|k| k.output(port).is_some())
            })
        };
        if let Some(p) = self.preview_port.as_deref().filter(|p| exists(p)) {
            return Some(p.to_owned());
        }
        let reg = self.doc.registry();
        self.doc
            .graph
            .nodes
            .iter()
            .filter(|n| reg.get(&n.kind).is_some_and(|k| k.sink))
            .find_map(|n| self.port_for_node(&n.id))
    }

    /// Copies the selected nodes (and the edges between them) to the editor's clipboard;
    /// returns the copy as RON text for the system clipboard.
    pub fn copy_selection(&mut self) -> Option<String> {
        if self.selected.is_empty() {
            return None;
        }
        let clip = self.doc.copy(&self.selected);
        let text = clip.to_ron();
        self.clipboard = Some(clip);
        Some(text)
    }

    /// Pastes `text` when it is a graph, else the editor's clipboard; selects the copies.
    pub fn paste(&mut self, text: Option<&str>) {
        let clip = text
            .and_then(|t| Graph::from_ron(t).ok())
            .or_else(|| self.clipboard.clone());
        if let Some(clip) = clip {
            let ids = self.doc.paste(&clip, (40.0, 40.0));
            self.say(format!("pasted {}", ids.join(", ")), false);
            self.selected = ids;
        }
    }

    /// Duplicates the selected nodes (and the edges between them) beside themselves and
    /// selects the copies; the clipboard is left alone.
    pub fn duplicate_selection(&mut self) {
        if self.selected.is_empty() {
            return;
        }
        let clip = self.doc.copy(&self.selected);
        let ids = self.doc.paste(&clip, (40.0, 40.0));
        self.say(format!("duplicated as {}", ids.join(", ")), false);
        self.selected = ids;
    }

    /// Deletes the selected nodes.
    pub fn delete_selection(&mut self) {
        let ids = std::mem::take(&mut self.selected);
        self.doc.remove_nodes(&ids);
    }

    /// Puts the selected nodes in a new frame, selected; its label says what it holds until
    /// renamed.
    pub fn frame_selection(&mut self) {
        let label = format!("Frame {}", self.doc.graph.frames.len() + 1);
        if let Some(i) = self.doc.frame_nodes(&self.selected, &label) {
            self.select(Vec::new());
            self.selected_frame = Some(i);
        }
    }
}
