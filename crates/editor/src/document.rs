//! The document: the [`Graph`] being edited (the source of truth), its file, and every
//! edit the editor can make, each checked against the registry and recorded for undo.
//!
//! The canvas, the inspector and the tests all edit through these methods, so what the
//! UI can do and what the tests check is one code path. The canvas (egui-snarl) is only a
//! view rebuilt from this graph: the file keeps its node and edge order.

use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use lumagraph_graph::{Edge, ErrorKind, Graph, Node, ParamValue, Registry, Rgb, split_port_ref};
use lumagraph_render::NodeLibrary;

use crate::undo::History;

/// A graph being edited.
#[derive(Debug)]
pub struct Document {
    /// The graph: what is saved, compiled and previewed.
    pub graph: Graph,
    /// The file it was opened from or last saved to.
    pub path: Option<PathBuf>,
    /// The node kinds the graph is checked against.
    registry: Arc<Registry>,
    /// The kinds the program knows and how they run, under those the graph declares.
    library: Arc<NodeLibrary>,
    saved: Graph,
    history: History,
}

impl Default for Document {
    fn default() -> Self {
        Self::new(Graph::default(), None)
    }
}

/// Where a new node goes when none is given: right of the rightmost node.
const NODE_SPACING: f32 = 220.0;

impl Document {
    /// A document for `graph`, as if just opened from `path`, with the built-in kinds and
    /// those the graph declares (when they all compile; else the built-in ones, and the
    /// editor shows why).
    pub fn new(graph: Graph, path: Option<PathBuf>) -> Self {
        Self::with_library(
            graph,
            path,
            Arc::new(lumagraph_pathtrace::library::builtins().clone()),
        )
    }

    /// A document for `graph`, as if just opened from `path`, with the kinds of `library`
    /// and those the graph declares (when they all compile; else the library's, and the
    /// editor shows why).
    pub fn with_library(graph: Graph, path: Option<PathBuf>, library: Arc<NodeLibrary>) -> Self {
        let registry = library
            .registry_for(&graph)
            .unwrap_or_else(|_| library.registry().clone());
        Self {
            saved: graph.clone(),
            graph,
            path,
            registry: Arc::new(registry),
            library,
            history: History::default(),
        }
    }

    /// A document for `graph` checked against `registry`, run with the built-in
    /// implementations.
    pub fn with_registry(graph: Graph, path: Option<PathBuf>, registry: Arc<Registry>) -> Self {
        Self {
            registry,
            ..Self::new(graph, path)
        }
    }

    /// Whether the graph differs from the file.
    pub fn is_dirty(&self) -> bool {
        self.graph != self.saved || (self.path.is_none() && !self.graph.nodes.is_empty())
    }

    /// Marks the current graph as saved to `path`.
    pub fn mark_saved(&mut self, path: PathBuf) {
        self.saved = self.graph.clone();
        self.path = Some(path);
    }

    /// The folder relative input paths are resolved against.
    pub fn base_dir(&self) -> PathBuf {
        self.path
            .as_deref()
            .and_then(Path::parent)
            .map(Path::to_path_buf)
            .unwrap_or_default()
    }

    /// The node kinds the document is checked against.
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// The node library the document was opened with: the kinds the program knows (those
    /// the graph declares aside) and how they run.
    pub fn library(&self) -> &Arc<NodeLibrary> {
        &self.library
    }

    fn record(&mut self, key: Option<&str>) {
        self.history.record(&self.graph, key);
    }

    /// Ends a gesture (pointer released): the next slider or drag edit is a new undo step.
    pub fn end_gesture(&mut self) {
        self.history.end_gesture();
    }

    /// Undoes the last edit; returns whether there was one.
    pub fn undo(&mut self) -> bool {
        match self.history.undo(&self.graph) {
            Some(g) => {
                self.restore(g);
                true
            }
            None => false,
        }
    }

    /// Redoes the last undone edit; returns whether there was one.
    pub fn redo(&mut self) -> bool {
        match self.history.redo(&self.graph) {
            Some(g) => {
                self.restore(g);
                true
            }
            None => false,
        }
    }

    fn restore(&mut self, g: Graph) {
        // Keep the origin (base folder, error locations) of the current graph.
        let origin = self.graph.origin.take();
        self.graph = g;
        self.graph.origin = origin;
    }

    /// Whether undo / redo would do something.
    pub fn can_undo_redo(&self) -> (bool, bool) {
        (self.history.can_undo(), self.history.can_redo())
    }

    /// A node id not used yet, from `base` (`exposure`, `exposure_2`, ...).
    pub fn unique_id(&self, base: &str) -> String {
        let base: String = base
            .chars()
            .filter(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == '-')
            .collect::<String>()
            .to_lowercase();
        let base = if base.is_empty() { "node".into() } else { base };
        let taken: HashSet<&str> = self.graph.nodes.iter().map(|n| n.id.as_str()).collect();
        if !taken.contains(base.as_str()) {
            return base;
        }
        (2..)
            .map(|i| format!("{base}_{i}"))
            .find(|id| !taken.contains(id.as_str()))
            .unwrap_or(base)
    }

    /// Adds a node of `kind` with default params at `pos` (or right of the others).
    ///
    /// # Errors
    /// When the registry has no such kind.
    pub fn add_node(&mut self, kind: &str, pos: Option<(f32, f32)>) -> Result<String, String> {
        if self.registry().get(kind).is_none() {
            return Err(format!("unknown node kind \"{kind}\""));
        }
        let pos = pos.unwrap_or_else(|| {
            let x = self
                .graph
                .nodes
                .iter()
                .filter_map(|n| n.pos)
                .map(|p| p.0)
                .fold(None, |m: Option<f32>, x| Some(m.map_or(x, |m| m.max(x))));
            (x.map_or(0.0, |x| x + NODE_SPACING), 0.0)
        });
        self.record(None);
        let id = self.unique_id(kind);
        let mut node = Node::new(id.clone(), kind);
        node.pos = Some(pos);
        self.graph.nodes.push(node);
        Ok(id)
    }

    /// The types of port `port` (`"node.port"`): what an output produces, or what an
    /// input accepts; `None` when there is no such port.
    pub fn port_types(&self, port: &str, output: bool) -> Option<Vec<lumagraph_graph::PortType>> {
        let (node, name) = split_port_ref(port)?;
        let kind = self.registry().get(&self.graph.node(node)?.kind)?;
        if output {
            let o = kind.outputs.iter().find(|o| o.name == name)?;
            Some(vec![o.ty])
        } else {
            let i = kind.inputs.iter().find(|i| i.name == name)?;
            Some(i.accepts.to_vec())
        }
    }

    /// Adds a node of `kind` at `pos` wired to `port` (`"node.port"`): from an output
    /// `port` into the new node's first input that accepts its type, or from the new
    /// node's first output of a type an input `port` accepts (replacing the wire that
    /// input had). One undo step; returns the new node's id.
    ///
    /// # Errors
    /// When the kind has no port that fits, or the edge is refused (the compiler's words);
    /// the graph is then unchanged.
    pub fn add_wired(
        &mut self,
        kind: &str,
        pos: (f32, f32),
        port: &str,
        output: bool,
    ) -> Result<String, String> {
        let types = self
            .port_types(port, output)
            .ok_or_else(|| format!("no port {port}"))?;
        let k = self
            .registry()
            .get(kind)
            .cloned()
            .ok_or_else(|| format!("unknown node kind \"{kind}\""))?;
        let fit = crate::canvas::fitting_port(&k, &types, output)
            .ok_or_else(|| format!("{kind} has no port that fits {port}"))?;
        let before = self.graph.clone();
        let id = self.unique_id(kind);
        let mut node = Node::new(id.clone(), kind);
        node.pos = Some(pos);
        self.graph.nodes.push(node);
        let (from, to) = if output {
            (port.to_owned(), format!("{id}.{fit}"))
        } else {
            (format!("{id}.{fit}"), port.to_owned())
        };
        if let Some(why) = self.check_edge(&from, &to) {
            self.graph = before;
            return Err(why);
        }
        let edge = Edge::new(from, to.clone());
        if let Some(e) = self.graph.edges.iter_mut().find(|e| e.to == to) {
            *e = edge;
        } else {
            self.graph.edges.push(edge);
        }
        self.history.record(&before, None);
        Ok(id)
    }

    /// Puts node `id` into the wire `from` → `to`: `from` into its first input that takes
    /// `from`'s type, its first output of a type `to` accepts into `to`. One undo step.
    ///
    /// # Errors
    /// When the node has no such ports (naming the types), or an edge is refused; the
    /// graph is then unchanged.
    pub fn insert_on_edge(&mut self, from: &str, to: &str, id: &str) -> Result<(), String> {
        let kind = self
            .graph
            .node(id)
            .and_then(|n| self.registry().get(&n.kind))
            .cloned()
            .ok_or_else(|| format!("no node {id}"))?;
        let (out_types, in_types) = (
            self.port_types(from, true).unwrap_or_default(),
            self.port_types(to, false).unwrap_or_default(),
        );
        let input = crate::canvas::fitting_port(&kind, &out_types, true);
        let output = crate::canvas::fitting_port(&kind, &in_types, false);
        let (Some(input), Some(output)) = (input, output) else {
            let names = |t: &[lumagraph_graph::PortType]| {
                t.iter().map(|t| t.name()).collect::<Vec<_>>().join(" or ")
            };
            return Err(format!(
                "{id} ({}) does not go into the wire {from} -> {to}: it needs an input taking {} and an output {to} accepts ({})",
                kind.name,
                names(&out_types),
                names(&in_types)
            ));
        };
        let before = self.graph.clone();
        self.graph.edges.retain(|e| !(e.from == from && e.to == to));
        let (a, b) = (
            (from.to_owned(), format!("{id}.{input}")),
            (format!("{id}.{output}"), to.to_owned()),
        );
        for (f, t) in [&a, &b] {
            if let Some(why) = self.check_edge(f, t) {
                self.graph = before;
                return Err(why);
            }
            self.graph.edges.push(Edge::new(f.clone(), t.clone()));
        }
        self.history.record(&before, None);
        Ok(())
    }

    /// Why an edge `from` → `to` (each `"node.port"`) cannot be made, in the compiler's
    /// words; `None` when it can.
    pub fn check_edge(&self, from: &str, to: &str) -> Option<String> {
        let reg = self.registry();
        let (Some((fnode, fport)), Some((tnode, tport))) =
            (split_port_ref(from), split_port_ref(to))
        else {
            return Some(ErrorKind::BadPortRef(format!("{from} -> {to}")).to_string());
        };
        let kind_of = |id: &str| {
            self.graph
                .node(id)
                .and_then(|n| reg.get(&n.kind))
                .ok_or_else(|| format!("edge {from} -> {to}: no node \"{id}\" of a known kind"))
        };
        let (fk, tk) = match (kind_of(fnode), kind_of(tnode)) {
            (Ok(f), Ok(t)) => (f, t),
            (Err(e), _) | (_, Err(e)) => return Some(e),
        };
        let Some(out) = fk.output(fport) else {
            return Some(format!("{} has no output port \"{fport}\"", fk.name));
        };
        let Some(inp) = tk.input(tport) else {
            return Some(format!("{} has no input port \"{tport}\"", tk.name));
        };
        if !inp.accepts.contains(&out.ty) {
            let accepted: Vec<_> = inp.accepts.iter().map(|t| t.name()).collect();
            return Some(
                ErrorKind::IncompatibleTypes {
                    from: from.to_owned(),
                    to: to.to_owned(),
                    produced: out.ty.name().to_owned(),
                    accepted: accepted.join(" or "),
                }
                .to_string(),
            );
        }
        if fnode == tnode || self.reaches(tnode, fnode) {
            return Some(format!(
                "edge {from} -> {to}: it would make a cycle ({tnode} already feeds {fnode})"
            ));
        }
        None
    }

    /// Whether data flows from node `a` to node `b` along edges.
    fn reaches(&self, a: &str, b: &str) -> bool {
        let mut stack = vec![a.to_owned()];
        let mut seen = HashSet::new();
        while let Some(n) = stack.pop() {
            if n == b {
                return true;
            }
            if !seen.insert(n.clone()) {
                continue;
            }
            for e in &self.graph.edges {
                if split_port_ref(&e.from).is_some_and(|(f, _)| f == n)
                    && let Some((t, _)) = split_port_ref(&e.to)
                {
                    stack.push(t.to_owned());
                }
            }
        }
        false
    }

    /// Connects output `from` to input `to` (each `"node.port"`), replacing the edge that
    /// fed `to` before.
    ///
    /// # Errors
    /// Why the edge is refused (incompatible types, a cycle, a missing port), in the same
    /// words as the compiler; the graph is unchanged then.
    pub fn connect(&mut self, from: &str, to: &str) -> Result<(), String> {
        if let Some(why) = self.check_edge(from, to) {
            return Err(why);
        }
        if self
            .graph
            .edges
            .iter()
            .any(|e| e.from == from && e.to == to)
        {
            return Ok(());
        }
        self.record(None);
        let edge = Edge::new(from, to);
        // Keep the file order: a replaced edge keeps its place.
        if let Some(e) = self.graph.edges.iter_mut().find(|e| e.to == to) {
            *e = edge;
        } else {
            self.graph.edges.push(edge);
        }
        Ok(())
    }

    /// Removes the edge `from` → `to`; returns whether there was one.
    pub fn disconnect(&mut self, from: &str, to: &str) -> bool {
        if !self
            .graph
            .edges
            .iter()
            .any(|e| e.from == from && e.to == to)
        {
            return false;
        }
        self.record(None);
        self.graph.edges.retain(|e| !(e.from == from && e.to == to));
        true
    }

    /// Removes every edge that starts or ends at `port` (`"node.port"`).
    pub fn disconnect_port(&mut self, port: &str) {
        if !self
            .graph
            .edges
            .iter()
            .any(|e| e.from == port || e.to == port)
        {
            return;
        }
        self.record(None);
        self.graph.edges.retain(|e| e.from != port && e.to != port);
    }

    /// Removes nodes and their edges.
    pub fn remove_nodes(&mut self, ids: &[String]) {
        if !self.graph.nodes.iter().any(|n| ids.contains(&n.id)) {
            return;
        }
        self.record(None);
        self.graph.nodes.retain(|n| !ids.contains(&n.id));
        for f in &mut self.graph.frames {
            f.nodes.retain(|n| !ids.contains(n));
        }
        self.graph.frames.retain(|f| !f.nodes.is_empty());
        let node_of = |r: &str| split_port_ref(r).map(|(n, _)| n.to_owned());
        self.graph.edges.retain(|e| {
            !node_of(&e.from).is_some_and(|n| ids.contains(&n))
                && !node_of(&e.to).is_some_and(|n| ids.contains(&n))
        });
    }

    /// Sets a param. Successive calls with the same node and param are one undo step
    /// until [`Self::end_gesture`] (one slider drag).
    pub fn set_param(&mut self, id: &str, param: &str, value: ParamValue) {
        let Some(node) = self.graph.node(id) else {
            return;
        };
        if node.params.get(param) == Some(&value) {
            return;
        }
        self.record(Some(&format!("param {id}.{param}")));
        if let Some(node) = self.graph.node_mut(id) {
            node.params.insert(param.to_owned(), value);
        }
    }

    /// Moves nodes; a drag is one undo step until [`Self::end_gesture`].
    pub fn move_nodes(&mut self, moves: &[(String, (f32, f32))]) {
        let changed = moves
            .iter()
            .any(|(id, p)| self.graph.node(id).is_some_and(|n| n.pos != Some(*p)));
        if !changed {
            return;
        }
        self.record(Some("move"));
        for (id, p) in moves {
            if let Some(n) = self.graph.node_mut(id) {
                n.pos = Some(*p);
            }
        }
    }

    /// Adds a reroute point at `pos` (graph units) to the wire `from` → `to`, as its
    /// `index`th point; one undo step. The edge (its ports and types) stays as it is.
    pub fn add_reroute(&mut self, from: &str, to: &str, index: usize, pos: (f32, f32)) {
        let Some(i) = self.edge_index(from, to) else {
            return;
        };
        self.record(None);
        let via = &mut self.graph.edges[i].via;
        via.insert(index.min(via.len()), pos);
    }

    /// Moves reroute point `index` of the wire `from` → `to` to `pos`; a drag is one undo
    /// step until [`Self::end_gesture`].
    pub fn move_reroute(&mut self, from: &str, to: &str, index: usize, pos: (f32, f32)) {
        let Some(i) = self.edge_index(from, to) else {
            return;
        };
        if self.graph.edges[i].via.get(index).is_none_or(|p| *p == pos) {
            return;
        }
        self.record(Some("move"));
        self.graph.edges[i].via[index] = pos;
    }

    /// Removes reroute point `index` of the wire `from` → `to`; one undo step.
    pub fn remove_reroute(&mut self, from: &str, to: &str, index: usize) {
        let Some(i) = self.edge_index(from, to) else {
            return;
        };
        if index < self.graph.edges[i].via.len() {
            self.record(None);
            self.graph.edges[i].via.remove(index);
        }
    }

    fn edge_index(&self, from: &str, to: &str) -> Option<usize> {
        self.graph
            .edges
            .iter()
            .position(|e| e.from == from && e.to == to)
    }

    /// Puts the nodes `ids` in a new frame called `label` (leaving any frame they were
    /// in; a frame left empty goes); one undo step. Returns the frame's index, `None` when
    /// no id names a node.
    pub fn frame_nodes(&mut self, ids: &[String], label: &str) -> Option<usize> {
        let ids: Vec<String> = ids
            .iter()
            .filter(|id| self.graph.node(id).is_some())
            .cloned()
            .collect();
        if ids.is_empty() {
            return None;
        }
        self.record(None);
        for f in &mut self.graph.frames {
            f.nodes.retain(|n| !ids.contains(n));
        }
        self.graph.frames.retain(|f| !f.nodes.is_empty());
        self.graph.frames.push(lumagraph_graph::FrameDecl {
            label: label.to_owned(),
            comment: String::new(),
            color: None,
            nodes: ids,
        });
        Some(self.graph.frames.len() - 1)
    }

    /// Sets frame `index`'s label, comment and colour; successive edits of one frame are
    /// one undo step until [`Self::end_gesture`] (typing, a colour drag).
    pub fn set_frame(&mut self, index: usize, label: &str, comment: &str, color: Option<Rgb>) {
        let Some(f) = self.graph.frames.get(index) else {
            return;
        };
        if f.label == label && f.comment == comment && f.color == color {
            return;
        }
        self.record(Some(&format!("frame {index}")));
        if let Some(f) = self.graph.frames.get_mut(index) {
            label.clone_into(&mut f.label);
            comment.clone_into(&mut f.comment);
            f.color = color;
        }
    }

    /// Removes frame `index` (its nodes stay); one undo step.
    pub fn remove_frame(&mut self, index: usize) {
        if index < self.graph.frames.len() {
            self.record(None);
            self.graph.frames.remove(index);
        }
    }

    /// Moves frame `index` by `delta` (graph units): every node in it moves; a drag is one
    /// undo step until [`Self::end_gesture`].
    pub fn move_frame(&mut self, index: usize, delta: (f32, f32)) {
        let Some(f) = self.graph.frames.get(index) else {
            return;
        };
        let moves: Vec<(String, (f32, f32))> = f
            .nodes
            .iter()
            .filter_map(|id| {
                let (x, y) = self.graph.node(id)?.pos?;
                Some((id.clone(), (x + delta.0, y + delta.1)))
            })
            .collect();
        self.move_nodes(&moves);
    }

    /// Sets the colour of node `id`'s header (`None`: the default); one undo step per node
    /// until [`Self::end_gesture`].
    pub fn set_node_color(&mut self, id: &str, color: Option<Rgb>) {
        if self.graph.node(id).is_none_or(|n| n.color == color) {
            return;
        }
        self.record(Some(&format!("color {id}")));
        if let Some(n) = self.graph.node_mut(id) {
            n.color = color;
        }
    }

    /// Sets the graph's working space (the colour space of its colour images); one undo
    /// step.
    pub fn set_working_space(&mut self, space: lumagraph_graph::WorkingSpace) {
        if self.graph.working_space == space {
            return;
        }
        self.record(None);
        self.graph.working_space = space;
    }

    /// The nodes `ids` and the edges between them, as a graph (for the clipboard).
    pub fn copy(&self, ids: &[String]) -> Graph {
        let mut g = Graph::new();
        g.nodes = self
            .graph
            .nodes
            .iter()
            .filter(|n| ids.contains(&n.id))
            .cloned()
            .collect();
        let inside = |r: &str| split_port_ref(r).is_some_and(|(n, _)| ids.iter().any(|i| i == n));
        g.edges = self
            .graph
            .edges
            .iter()
            .filter(|e| inside(&e.from) && inside(&e.to))
            .cloned()
            .collect();
        g
    }

    /// Pastes a copied graph, renaming ids that are taken and offsetting positions by
    /// `offset`; returns the new ids.
    pub fn paste(&mut self, clip: &Graph, offset: (f32, f32)) -> Vec<String> {
        if clip.nodes.is_empty() {
            return Vec::new();
        }
        self.record(None);
        let mut renamed = BTreeMap::new();
        let mut new_ids = Vec::new();
        for n in &clip.nodes {
            let id = self.unique_id(&n.id);
            let mut node = n.clone();
            node.id.clone_from(&id);
            node.pos = Some(n.pos.map_or(offset, |p| (p.0 + offset.0, p.1 + offset.1)));
            self.graph.nodes.push(node);
            renamed.insert(n.id.clone(), id.clone());
            new_ids.push(id);
        }
        let rename = |r: &str| {
            let (n, p) = split_port_ref(r)?;
            Some(format!("{}.{p}", renamed.get(n)?))
        };
        for e in &clip.edges {
            if let (Some(from), Some(to)) = (rename(&e.from), rename(&e.to)) {
                // Reroute points move with the nodes.
                let mut edge = Edge::new(from, to);
                edge.via = e
                    .via
                    .iter()
                    .map(|p| (p.0 + offset.0, p.1 + offset.1))
                    .collect();
                self.graph.edges.push(edge);
            }
        }
        new_ids
    }

    /// `graph` with this document's file as its origin when it has none, so the files it
    /// names are found beside the document's.
    pub fn with_origin(&self, graph: &Graph) -> Graph {
        let mut g = graph.clone();
        if g.origin.is_none()
            && let Some(p) = &self.path
        {
            g.origin = Some(lumagraph_graph::Origin::new(p.clone(), String::new()));
        }
        g
    }

    /// Replaces the graph by `graph` (one undo step) checked against `registry`.
    pub fn set_graph(&mut self, graph: Graph, registry: Arc<Registry>) {
        self.record(None);
        let origin = self.graph.origin.take();
        self.graph = graph;
        self.graph.origin = origin;
        self.registry = registry;
    }

    /// Checks the graph against `registry` from now on (the kinds were read again).
    pub fn set_registry(&mut self, registry: Arc<Registry>) {
        self.registry = registry;
    }

    /// Reads the kinds the graph declares and its group files again (a group file was
    /// edited); keeps the registry, and returns why, when they do not load.
    ///
    /// # Errors
    /// The loading errors, one a line.
    pub fn reload_registry(&mut self) -> Result<(), String> {
        let registry = self
            .library
            .registry_for(&self.with_origin(&self.graph))
            .map_err(|e| e.to_string())?;
        self.registry = Arc::new(registry);
        Ok(())
    }

    /// Replaces the whole graph (for example a file opened in place), clearing history.
    pub fn replace(&mut self, graph: Graph, path: Option<PathBuf>) {
        *self = Self::with_library(graph, path, Arc::clone(&self.library));
    }
}
