//! Making a node group from selected nodes: the nodes move to a graph file of their own,
//! and one node of the new group kind takes their place, wired as they were.
//!
//! What the group shows is worked out from the edges that cross the selection: every
//! output outside that reads from inside becomes a group input (one per outside output,
//! feeding every inner port it fed), every inside output read outside becomes a group
//! output, and every param the nodes set explicitly becomes a group param named
//! `node_param`, its default the value set (so the graph renders as before).

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use lumagraph_graph::group::{Exposed, ExposedOutput, GroupDecl};
use lumagraph_graph::{Edge, Node, split_port_ref};

use crate::document::Document;

/// A name free among `taken`: `base`, else `base_2`, `base_3`, ...
fn free_name(base: &str, taken: &[String]) -> String {
    if !taken.iter().any(|t| t == base) {
        return base.to_owned();
    }
    (2..)
        .map(|i| format!("{base}_{i}"))
        .find(|n| !taken.contains(n))
        .unwrap_or_else(|| base.to_owned())
}

impl Document {
    /// Moves the nodes `ids` into a new group file `file` (written now) and replaces them
    /// by one node of the group kind `name`, declared in this graph; returns the new
    /// node's id. One undo step (the group file stays).
    ///
    /// # Errors
    /// No nodes, a graph not saved yet (the group's file is named relative to it), a kind
    /// name that is taken or not letters, digits and `_`, a file that cannot be written,
    /// or a group the registry refuses.
    pub fn group_nodes(
        &mut self,
        ids: &[String],
        name: &str,
        file: &Path,
    ) -> Result<String, String> {
        let ids: Vec<String> = self
            .graph
            .nodes
            .iter()
            .filter(|n| ids.contains(&n.id))
            .map(|n| n.id.clone())
            .collect();
        if ids.is_empty() {
            return Err("select the nodes to group first".into());
        }
        let base = self
            .path
            .as_deref()
            .ok_or("save the graph first: its group's file is named relative to it")?
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(format!(
                "group name \"{name}\" must be letters, digits and _"
            ));
        }
        if self.registry().get(name).is_some() {
            return Err(format!("a node kind called \"{name}\" exists already"));
        }
        let inside = |r: &str| split_port_ref(r).is_some_and(|(n, _)| ids.iter().any(|i| i == n));

        let mut group = self.copy(&ids);
        // The kinds and groups the moved nodes use come along.
        let used = |kind: &str| group.nodes.iter().any(|n| n.kind == kind);
        group.kinds = self
            .graph
            .kinds
            .iter()
            .filter(|k| used(&k.name))
            .cloned()
            .collect();
        group.groups = self
            .graph
            .groups
            .iter()
            .filter(|g| used(&g.name))
            .cloned()
            .collect();
        let (inputs, outputs) = boundary(&self.graph, &inside);
        group.interface.inputs = inputs.values().cloned().collect();
        group.interface.outputs = outputs.values().cloned().collect();
        group.interface.params = group
            .nodes
            .iter()
            .flat_map(|n| {
                n.params.keys().map(move |p| Exposed {
                    name: format!("{}_{p}", n.id.replace('-', "_")),
                    to: vec![format!("{}.{p}", n.id)],
                    doc: String::new(),
                })
            })
            .collect();
        crate::files::save(self.registry(), &group, &base, file).map_err(|e| e.to_string())?;

        // The group kind, declared with its file relative to this graph.
        let decl_file = GroupDecl {
            name: name.to_owned(),
            file: crate::files::relative_path(file, &base),
        };

        let mut next = self.graph.clone();
        next.groups.push(decl_file);
        let registry = self
            .library()
            .registry_for(&self.with_origin(&next))
            .map_err(|e| e.to_string())?;

        let positions: Vec<(f32, f32)> = next
            .nodes
            .iter()
            .filter(|n| ids.contains(&n.id))
            .filter_map(|n| n.pos)
            .collect();
        #[expect(clippy::cast_precision_loss, reason = "a handful of nodes")]
        let pos = (!positions.is_empty()).then(|| {
            let k = positions.len() as f32;
            (
                positions.iter().map(|p| p.0).sum::<f32>() / k,
                positions.iter().map(|p| p.1).sum::<f32>() / k,
            )
        });
        next.nodes.retain(|n| !ids.contains(&n.id));
        let id = {
            let taken: Vec<String> = next.nodes.iter().map(|n| n.id.clone()).collect();
            free_name(&name.to_lowercase(), &taken)
        };
        let mut node = Node::new(id.clone(), name);
        node.pos = pos;
        next.nodes.push(node);
        let mut edges = Vec::new();
        for e in &next.edges {
            match (inside(&e.from), inside(&e.to)) {
                (false, false) => edges.push(e.clone()),
                (true, true) => {}
                (false, true) => {
                    let input = &inputs[&e.from];
                    let edge = Edge::new(e.from.clone(), format!("{id}.{}", input.name));
                    if !edges.contains(&edge) {
                        edges.push(edge);
                    }
                }
                (true, false) => {
                    let output = &outputs[&e.from];
                    edges.push(Edge::new(format!("{id}.{}", output.name), e.to.clone()));
                }
            }
        }
        next.edges = edges;
        self.set_graph(next, Arc::new(registry));
        Ok(id)
    }
}

/// The group inputs and outputs the edges crossing a selection make (`inside` tells
/// whether a `"node.port"` is in it), keyed by the output each edge starts at.
fn boundary(
    graph: &lumagraph_graph::Graph,
    inside: &dyn Fn(&str) -> bool,
) -> (BTreeMap<String, Exposed>, BTreeMap<String, ExposedOutput>) {
    // Inputs: one per outside output read inside.
    let mut inputs: BTreeMap<String, Exposed> = BTreeMap::new();
    let mut taken: Vec<String> = Vec::new();
    for e in &graph.edges {
        if inside(&e.to) && !inside(&e.from) {
            let entry = inputs.entry(e.from.clone()).or_insert_with(|| {
                let port = split_port_ref(&e.to).map_or("input", |(_, p)| p);
                let name = free_name(port, &taken);
                taken.push(name.clone());
                Exposed {
                    name,
                    to: Vec::new(),
                    doc: String::new(),
                }
            });
            entry.to.push(e.to.clone());
        }
    }
    // Outputs: one per inside output read outside.
    let mut outputs: BTreeMap<String, ExposedOutput> = BTreeMap::new();
    let mut taken: Vec<String> = Vec::new();
    for e in &graph.edges {
        if inside(&e.from) && !inside(&e.to) {
            outputs.entry(e.from.clone()).or_insert_with(|| {
                let port = split_port_ref(&e.from).map_or("output", |(_, p)| p);
                let name = free_name(port, &taken);
                taken.push(name.clone());
                ExposedOutput {
                    name,
                    from: e.from.clone(),
                    doc: String::new(),
                }
            });
        }
    }
    (inputs, outputs)
}
