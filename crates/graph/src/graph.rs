//! The graph model and its RON file format.
//!
//! A graph file is versioned and human-editable; nodes and edges keep the order they
//! are written in, and params are kept sorted, so load → save → load is an identity and
//! a saved file diffs cleanly. Saving writes a temporary file beside the target and
//! renames it over, so a failed save never leaves a half-written graph.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::custom::KindDecl;
use crate::error::{ErrorKind, GraphError, Pos};
use crate::group::{GroupDecl, Interface};
use crate::registry::Registry;
use crate::types::ParamValue;
use crate::working_space::WorkingSpace;

/// The newest graph file version this build reads and writes. Version 2 added node kinds
/// declared in the file (`kinds`), version 3 node groups (`groups`, `interface`), version
/// 4 the editor's frames, node colours and reroute points (`frames`, a node's `color`, an
/// edge's `via`), version 5 a working space other than Rec. 709 (`working_space`). A graph
/// is written
/// with the oldest version that holds it: without any of these, version 1, which every
/// build reads.
pub const VERSION: u32 = 5;

/// An sRGB colour the editor draws with: `(r, g, b)`, each 0 to 255.
pub type Rgb = (u8, u8, u8);

/// A node: an instance of a node kind with its params.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Node {
    /// Stable id, unique in the graph; edges name nodes by it.
    pub id: String,
    /// Name of the node kind in the registry.
    pub kind: String,
    /// Param values; params not listed take their defaults.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, ParamValue>,
    /// Position in the editor's canvas.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pos: Option<(f32, f32)>,
    /// The colour of its header in the editor (version 4; the compiler ignores it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Rgb>,
}

impl Node {
    /// A node of `kind` with default params.
    pub fn new(id: impl Into<String>, kind: impl Into<String>) -> Self {
        Self {
            id: id.into(),
            kind: kind.into(),
            params: BTreeMap::new(),
            pos: None,
            color: None,
        }
    }

    /// The same node with `param` set to `value`.
    #[must_use]
    pub fn with(mut self, param: &str, value: ParamValue) -> Self {
        self.params.insert(param.to_owned(), value);
        self
    }
}

/// An edge from an output port to an input port, each written `"node.port"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Edge {
    /// Output port, `"node.port"`.
    pub from: String,
    /// Input port, `"node.port"`.
    pub to: String,
    /// Reroute points the editor draws the wire through, in order from `from` (version 4;
    /// the compiler ignores them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub via: Vec<(f32, f32)>,
}

impl Edge {
    /// An edge between two `"node.port"` references.
    pub fn new(from: impl Into<String>, to: impl Into<String>) -> Self {
        Self {
            from: from.into(),
            to: to.into(),
            via: Vec::new(),
        }
    }
}

/// A frame in the editor: a labelled, coloured box drawn around some nodes, with a comment;
/// moving it moves them (version 4; the compiler ignores it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameDecl {
    /// Its title.
    pub label: String,
    /// Text shown in it, under the title.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub comment: String,
    /// Its colour (a default where none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<Rgb>,
    /// The ids of the nodes it holds; its box is drawn around them.
    pub nodes: Vec<String>,
}

/// Splits `"node.port"` at its last dot.
pub fn split_port_ref(r: &str) -> Option<(&str, &str)> {
    let (node, port) = r.rsplit_once('.')?;
    (!node.is_empty() && !port.is_empty()).then_some((node, port))
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GraphFile {
    version: u32,
    #[serde(default, skip_serializing_if = "Interface::is_empty")]
    interface: Interface,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    groups: Vec<GroupDecl>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    kinds: Vec<KindDecl>,
    nodes: Vec<Node>,
    #[serde(default)]
    edges: Vec<Edge>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    frames: Vec<FrameDecl>,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    working_space: String,
}

#[derive(Deserialize)]
struct VersionProbe {
    version: u32,
}

/// Where a graph was loaded from, kept to point errors at lines.
#[derive(Clone, Debug)]
pub struct Origin {
    /// The file.
    pub path: PathBuf,
    text: String,
}

impl Origin {
    /// The text the graph was read from.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The origin of a graph read from `path`, whose text was `text`.
    pub fn new(path: PathBuf, text: String) -> Self {
        Self { path, text }
    }

    fn pos_of_offset(&self, offset: usize) -> Pos {
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let col = before.rfind('\n').map_or(offset, |nl| offset - nl - 1) + 1;
        Pos { line, col }
    }

    fn node_offset(&self, id: &str) -> Option<usize> {
        let needle = format!("\"{id}\"");
        self.text
            .match_indices(&needle)
            .map(|(i, _)| i)
            .find(|&i| self.text[..i].trim_end().ends_with("id:"))
    }

    /// Where node `id` is declared.
    pub fn node_pos(&self, id: &str) -> Option<Pos> {
        self.node_offset(id).map(|o| self.pos_of_offset(o))
    }

    /// Where param `param` of node `id` is set, or else where the node is declared.
    pub fn param_pos(&self, id: &str, param: &str) -> Option<Pos> {
        let start = self.node_offset(id)?;
        let rest = &self.text[start..];
        let end = rest[1..].find("id:").map_or(rest.len(), |e| e + 1);
        let found = rest[..end].find(&format!("\"{param}\""));
        Some(self.pos_of_offset(start + found.unwrap_or(0)))
    }

    /// Where the declared kind called `name` is written (its `name:` field).
    pub fn kind_pos(&self, name: &str) -> Option<Pos> {
        let needle = format!("\"{name}\"");
        self.text
            .match_indices(&needle)
            .map(|(i, _)| i)
            .find(|&i| self.text[..i].trim_end().ends_with("name:"))
            .map(|o| self.pos_of_offset(o))
    }

    /// The file line of line 1 of `code`, a string written in the file, when its lines
    /// appear there as they are (a raw string); `None` when they do not (escapes).
    pub fn code_first_line(&self, code: &str) -> Option<usize> {
        let (index, line) = code
            .lines()
            .enumerate()
            .find(|(_, l)| !l.trim().is_empty())?;
        let found = self.text.find(line)?;
        // Every later line must follow in the file, too.
        let rest = &self.text[found..];
        let all_there = code
            .lines()
            .skip(index)
            .zip(rest.lines())
            .all(|(a, b)| a == b);
        all_there.then(|| self.pos_of_offset(found).line.saturating_sub(index).max(1))
    }

    /// Where the `index`-th edge is written.
    pub fn edge_pos(&self, index: usize) -> Option<Pos> {
        let edges = self.text.find("edges")?;
        let (o, _) = self.text[edges..].match_indices("from").nth(index)?;
        Some(self.pos_of_offset(edges + o))
    }
}

/// A render graph: nodes and the edges between their ports, and the node kinds the file
/// declares for them.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    /// What the graph shows when used as a node group (version 3).
    pub interface: Interface,
    /// Group kinds: graph files used as nodes (version 3), in file order.
    pub groups: Vec<GroupDecl>,
    /// Node kinds declared in the file (version 2), in file order.
    pub kinds: Vec<KindDecl>,
    /// Nodes, in file order.
    pub nodes: Vec<Node>,
    /// Edges, in file order.
    pub edges: Vec<Edge>,
    /// The editor's frames (version 4), in file order.
    pub frames: Vec<FrameDecl>,
    /// The colour space of its colour images (version 5 when not Rec. 709;
    /// [`crate::working_space`]).
    pub working_space: WorkingSpace,
    /// The file the graph was loaded from.
    pub origin: Option<Origin>,
}

impl PartialEq for Graph {
    fn eq(&self, other: &Self) -> bool {
        self.interface == other.interface
            && self.groups == other.groups
            && self.kinds == other.kinds
            && self.nodes == other.nodes
            && self.edges == other.edges
            && self.frames == other.frames
            && self.working_space == other.working_space
    }
}

impl Graph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// Loads a graph file.
    ///
    /// # Errors
    /// When the file cannot be read or is not a valid graph file; the error names the file
    /// and the line and column.
    pub fn load(path: &Path) -> Result<Self, GraphError> {
        let text = read_text(path).map_err(|source| GraphError {
            file: Some(path.to_owned()),
            ..GraphError::new(ErrorKind::Io {
                action: "cannot read graph file",
                source,
            })
        })?;
        let mut graph = Self::from_ron(&text).map_err(|mut e| {
            e.file = Some(path.to_owned());
            e
        })?;
        graph.origin = Some(Origin {
            path: path.to_owned(),
            text,
        });
        Ok(graph)
    }

    /// Parses a graph from RON text.
    ///
    /// # Errors
    /// On a syntax error (with line and column) or an unsupported version.
    pub fn from_ron(text: &str) -> Result<Self, GraphError> {
        let syntax = |e: ron::error::SpannedError| GraphError {
            pos: Some(Pos {
                line: e.span.start.line,
                col: e.span.start.col,
            }),
            ..GraphError::new(ErrorKind::Syntax(e.code.to_string()))
        };
        let probe: VersionProbe = ron::from_str(text).map_err(syntax)?;
        if !(1..=VERSION).contains(&probe.version) {
            return Err(GraphError::new(ErrorKind::Version {
                found: probe.version,
                supported: VERSION,
            }));
        }
        let file: GraphFile = ron::from_str(text).map_err(syntax)?;
        if probe.version < 2 && !file.kinds.is_empty() {
            return Err(GraphError::new(ErrorKind::Source(
                "node kinds declared in the file (`kinds`) need `version: 2`".into(),
            )));
        }
        if probe.version < 3 && !(file.groups.is_empty() && file.interface.is_empty()) {
            return Err(GraphError::new(ErrorKind::Source(
                "node groups (`groups`, `interface`) need `version: 3`".into(),
            )));
        }
        let working_space = match file.working_space.as_str() {
            "" => WorkingSpace::default(),
            name => {
                if probe.version < 5 {
                    return Err(GraphError::new(ErrorKind::Source(
                        "a working space (`working_space`) needs `version: 5`".into(),
                    )));
                }
                WorkingSpace::parse(name).map_err(|e| GraphError::new(ErrorKind::Source(e)))?
            }
        };
        Ok(Self {
            interface: file.interface,
            groups: file.groups,
            kinds: file.kinds,
            nodes: file.nodes,
            edges: file.edges,
            frames: file.frames,
            working_space,
            origin: None,
        })
    }

    /// The graph as RON text, in the canonical layout `save` writes (one node and one
    /// edge per line), with the comments of the file it was loaded from where they belong
    /// (see [`crate::layout`]).
    pub fn to_ron(&self) -> String {
        let version = if self.working_space != WorkingSpace::default() {
            5
        } else if !self.frames.is_empty()
            || self.nodes.iter().any(|n| n.color.is_some())
            || self.edges.iter().any(|e| !e.via.is_empty())
        {
            4
        } else if !(self.groups.is_empty() && self.interface.is_empty()) {
            3
        } else if !self.kinds.is_empty() {
            2
        } else {
            1
        };
        crate::layout::write(self, version)
    }

    /// Writes the graph to `path` atomically: a temporary file in the same folder,
    /// renamed over the target, so the old file survives any failure.
    ///
    /// # Errors
    /// When the folder cannot be written.
    pub fn save(&self, path: &Path) -> Result<(), GraphError> {
        write_atomic(path, self.to_ron().as_bytes()).map_err(|source| GraphError {
            file: Some(path.to_owned()),
            ..GraphError::new(ErrorKind::Io {
                action: "cannot write graph file",
                source,
            })
        })
    }

    /// The folder relative input paths are resolved against: the graph file's folder,
    /// or the current folder for a graph not loaded from a file.
    pub fn base_dir(&self) -> PathBuf {
        self.origin
            .as_ref()
            .and_then(|o| o.path.parent().map(Path::to_path_buf))
            .unwrap_or_default()
    }

    /// The node with id `id`.
    pub fn node(&self, id: &str) -> Option<&Node> {
        self.nodes.iter().find(|n| n.id == id)
    }

    /// Removes the sinks (nodes of kinds that write out of the graph, as `registry` says)
    /// and the edges into them: the graph a preview or a measurement runs, writing no file.
    pub fn remove_sinks(&mut self, registry: &Registry) {
        let sinks: Vec<String> = self
            .nodes
            .iter()
            .filter(|n| registry.get(&n.kind).is_some_and(|k| k.sink))
            .map(|n| n.id.clone())
            .collect();
        self.nodes.retain(|n| !sinks.contains(&n.id));
        self.edges
            .retain(|e| split_port_ref(&e.to).is_none_or(|(n, _)| !sinks.iter().any(|s| s == n)));
    }

    /// The node with id `id`, mutably.
    pub fn node_mut(&mut self, id: &str) -> Option<&mut Node> {
        self.nodes.iter_mut().find(|n| n.id == id)
    }

    /// Sets a param from an override such as `tonemap.operator=agx` (the value in RON
    /// syntax, or a bare word for a string). The value is checked when the graph is compiled.
    ///
    /// # Errors
    /// When the override is malformed or names a missing node.
    pub fn apply_override(&mut self, assignment: &str) -> Result<(), GraphError> {
        let bad = |m: String| GraphError::new(ErrorKind::Source(m));
        let (target, value) = assignment
            .split_once('=')
            .ok_or_else(|| bad(format!("override \"{assignment}\" is not node.param=value")))?;
        let (node, param) = split_port_ref(target.trim())
            .ok_or_else(|| bad(format!("override \"{assignment}\" is not node.param=value")))?;
        let value =
            ParamValue::parse(value).map_err(|m| bad(format!("override \"{assignment}\": {m}")))?;
        let n = self
            .node_mut(node)
            .ok_or_else(|| bad(format!("override \"{assignment}\": no node \"{node}\"")))?;
        n.params.insert(param.to_owned(), value);
        Ok(())
    }

    /// Fills in file, line and column for an error found in this graph.
    pub fn locate(
        &self,
        mut e: GraphError,
        edge: Option<usize>,
        param: Option<&str>,
    ) -> GraphError {
        if let Some(origin) = &self.origin {
            e.file = Some(origin.path.clone());
            e.pos = match (edge, e.about.as_deref(), param) {
                (Some(i), _, _) => origin.edge_pos(i),
                (None, Some(node), Some(p)) => origin.param_pos(node, p),
                (None, Some(node), None) => origin.node_pos(node),
                _ => None,
            };
        }
        e
    }
}

/// The text of the regular file at `path`. A path a file names (a group file, a kind's
/// `.wgsl`, a LUT) may be a device or a pipe, which would be read without end: only
/// regular files (or links to them) are read.
///
/// # Errors
/// When `path` is not a regular file, or cannot be read as UTF-8 text.
pub fn read_text(path: &Path) -> std::io::Result<String> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::other(
            "not a regular file (a folder, a device or a pipe)",
        ));
    }
    std::fs::read_to_string(path)
}

// The one atomic file writer lives in a leaf crate that the scene crate shares.
pub use lumagraph_files::write_atomic;
