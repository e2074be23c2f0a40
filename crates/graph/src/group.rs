//! Node groups: a graph file used as one node of another graph (version 3).
//!
//! The outer graph names the file in `groups: [(name: "Glow", file: "glow.ron")]` and uses
//! `Glow` as a node kind. The group file is an ordinary graph whose `interface` says what a
//! node of it shows: inputs that feed inner ports, outputs that come from an inner port,
//! params that set inner params (their type, range and default are the inner ones, the
//! default being what the group file sets).
//!
//! Groups do not survive compilation: [`flatten`] replaces every group node by its inner
//! nodes, named `group/inner`, with the edges rewired through the interface, so pruning
//! and texture sharing see one graph. The render crate loads group files (with the node
//! kinds they declare) into a [`Registry`] with [`Registry::add_group`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::custom::intern;
use crate::error::{ErrorKind, GraphError, GraphErrors};
use crate::graph::{Edge, Graph, Node, split_port_ref};
use crate::registry::Reach;
use crate::registry::{Category, InputDef, NodeKind, OutputDef, ParamDef, Registry, Shader};
use crate::types::{ParamType, ParamValue, PortType};

/// Groups nest at most this deep (a deeper chain is almost surely a mistake).
pub const MAX_DEPTH: usize = 16;

/// A group kind a graph file declares: the kind name its nodes use and the graph file
/// that implements it, relative to the declaring file's folder.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupDecl {
    /// Kind name nodes use (`kind: "Glow"`).
    pub name: String,
    /// The group's graph file.
    pub file: String,
}

/// An input or param a group exposes: the inner `"node.port"` or `"node.param"` it sets
/// (one or several).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Exposed {
    /// Name on the group node.
    pub name: String,
    /// Inner ports or params, `"node.port"`.
    pub to: Vec<String>,
    /// One line for docs and tooltips.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
}

/// An output a group exposes: the inner output it shows.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExposedOutput {
    /// Name on the group node.
    pub name: String,
    /// Inner output, `"node.port"`.
    pub from: String,
    /// One line for docs and tooltips.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
}

/// What a graph shows when it is used as a group.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interface {
    /// What the group does, for docs and tooltips.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub doc: String,
    /// Inputs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub inputs: Vec<Exposed>,
    /// Outputs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outputs: Vec<ExposedOutput>,
    /// Params.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub params: Vec<Exposed>,
}

impl Interface {
    /// Whether it exposes nothing (the graph is not meant as a group).
    pub fn is_empty(&self) -> bool {
        self.doc.is_empty()
            && self.inputs.is_empty()
            && self.outputs.is_empty()
            && self.params.is_empty()
    }
}

/// A group loaded for a registry: its graph and the kinds its nodes use.
#[derive(Clone, Debug)]
pub struct Group {
    /// Kind name.
    pub name: &'static str,
    /// Its graph, loaded from its file (relative paths in it are resolved against the
    /// file's folder).
    pub graph: Graph,
    /// The kinds its nodes use: the base kinds, those it declares, its own groups.
    pub registry: Registry,
}

impl Group {
    /// The group's file.
    pub fn file(&self) -> PathBuf {
        self.graph
            .origin
            .as_ref()
            .map_or_else(PathBuf::new, |o| o.path.clone())
    }

    /// The kind of inner node `node`.
    fn inner_kind(&self, node: &str) -> Result<&Arc<NodeKind>, String> {
        let n = self
            .graph
            .node(node)
            .ok_or_else(|| format!("the interface names node \"{node}\", not in the file"))?;
        self.registry
            .get(&n.kind)
            .ok_or_else(|| format!("node \"{node}\": unknown node kind \"{}\"", n.kind))
    }

    /// The input port `e` makes: the types all its inner ports accept, optional when they
    /// all are.
    fn exposed_input(&self, e: &Exposed) -> Result<InputDef, String> {
        if e.to.is_empty() {
            return Err(format!("input \"{}\" reaches no inner port", e.name));
        }
        let mut accepts: Option<Vec<PortType>> = None;
        let mut optional = true;
        for r in &e.to {
            let (node, port) = split_ref(r)?;
            let def = self.inner_kind(node)?.input(port).ok_or_else(|| {
                format!(
                    "input \"{}\": node \"{node}\" has no input \"{port}\"",
                    e.name
                )
            })?;
            if self.graph.edges.iter().any(|x| x.to == *r) {
                return Err(format!(
                    "input \"{}\": {r} is already connected inside the group",
                    e.name
                ));
            }
            optional &= def.optional;
            let a = accepts.get_or_insert_with(|| def.accepts.to_vec());
            a.retain(|t| def.accepts.contains(t));
        }
        let accepts = accepts.unwrap_or_default();
        if accepts.is_empty() {
            return Err(format!(
                "input \"{}\": its inner ports accept no type in common",
                e.name
            ));
        }
        let def = InputDef::new(
            intern(&e.name),
            crate::custom::intern_slice(accepts),
            intern(&e.doc),
        );
        Ok(if optional { def.optional() } else { def })
    }

    /// The param `p` makes: the type and range of its inner params (all of one type), the
    /// default what the group file sets on the first.
    fn exposed_param(&self, p: &Exposed) -> Result<ParamDef, String> {
        let mut ty: Option<ParamType> = None;
        for r in &p.to {
            let (node, param) = split_ref(r)?;
            let def = self.inner_kind(node)?.param(param).ok_or_else(|| {
                format!(
                    "param \"{}\": node \"{node}\" has no param \"{param}\"",
                    p.name
                )
            })?;
            let inner = self.graph.node(node).and_then(|n| n.params.get(param));
            let this = with_default(&def.ty, inner);
            match &ty {
                None => ty = Some(this),
                Some(t) if t.name() != this.name() => {
                    return Err(format!(
                        "param \"{}\": {r} is a {}, an earlier one a {}",
                        p.name,
                        this.name(),
                        t.name()
                    ));
                }
                Some(_) => {}
            }
        }
        let ty = ty.ok_or_else(|| format!("param \"{}\" reaches no inner param", p.name))?;
        Ok(ParamDef {
            name: intern(&p.name),
            ty,
            doc: intern(&p.doc),
        })
    }

    /// The node kind a group node is: ports and params from the interface, typed by the
    /// inner ports and params they reach.
    ///
    /// # Errors
    /// An interface entry naming a missing node, port or param, inputs whose inner ports
    /// accept no common type, params of different types, an inner input both exposed and
    /// connected inside, or a group that shows nothing (no output and no sink).
    pub fn kind(&self) -> Result<NodeKind, String> {
        let g = &self.graph;
        let iface = &g.interface;
        let inputs = iface
            .inputs
            .iter()
            .map(|e| self.exposed_input(e))
            .collect::<Result<Vec<_>, _>>()?;
        let mut outputs = Vec::new();
        for o in &iface.outputs {
            let (node, port) = split_ref(&o.from)?;
            let def = self.inner_kind(node)?.output(port).ok_or_else(|| {
                format!(
                    "output \"{}\": node \"{node}\" has no output \"{port}\"",
                    o.name
                )
            })?;
            outputs.push(OutputDef::new(intern(&o.name), def.ty, intern(&o.doc)));
        }
        let params = iface
            .params
            .iter()
            .map(|p| self.exposed_param(p))
            .collect::<Result<Vec<_>, _>>()?;
        let inner: Vec<&Arc<NodeKind>> = g
            .nodes
            .iter()
            .filter_map(|n| self.registry.get(&n.kind))
            .collect();
        let sink = inner.iter().any(|k| k.sink);
        if outputs.is_empty() && !sink {
            return Err(
                "the group exposes no output (`interface.outputs`) and writes no file".into(),
            );
        }
        Ok(NodeKind {
            name: self.name,
            category: Category::Group,
            doc: intern(if iface.doc.is_empty() {
                "A node group."
            } else {
                &iface.doc
            }),
            inputs,
            outputs,
            params,
            sink,
            history: inner.iter().any(|k| k.history),
            renders_scene: inner.iter().any(|k| k.renders_scene),
            shader: None,
            example: Vec::new(),
            reach: Reach::Pixel,
        })
    }
}

/// `"node.port"` split, or an error saying the interface entry is malformed.
fn split_ref(r: &str) -> Result<(&str, &str), String> {
    split_port_ref(r)
        .ok_or_else(|| format!("\"{r}\" in the interface is not of the form \"node.port\""))
}

/// `ty` with its default replaced by `value` when it is a valid one.
fn with_default(ty: &ParamType, value: Option<&ParamValue>) -> ParamType {
    let Some(value) = value.and_then(|v| ty.check(v).ok()) else {
        return ty.clone();
    };
    match (ty, value) {
        (ParamType::Float { min, max, .. }, ParamValue::Float(v)) => ParamType::Float {
            default: v,
            min: *min,
            max: *max,
        },
        (ParamType::Int { min, max, .. }, ParamValue::Int(v)) => ParamType::Int {
            default: v,
            min: *min,
            max: *max,
        },
        (ParamType::Bool { .. }, ParamValue::Bool(v)) => ParamType::Bool { default: v },
        (ParamType::Enum { options, .. }, ParamValue::Str(v)) => ParamType::Enum {
            default: intern(&v),
            options,
        },
        (ParamType::Path { extensions, .. }, ParamValue::Str(v)) => ParamType::Path {
            default: intern(&v),
            extensions,
        },
        (ParamType::Text { .. }, ParamValue::Str(v)) => ParamType::Text {
            default: intern(&v),
        },
        _ => ty.clone(),
    }
}

/// A graph with its groups flattened, and the kinds its nodes use.
#[derive(Clone, Debug)]
pub struct Flat {
    /// The graph: no group nodes; their inner nodes are named `group/inner`.
    pub graph: Graph,
    /// The outer registry with the kinds inner nodes use added.
    pub registry: Registry,
    /// Each group output `"node.port"` with the inner output it shows.
    pub aliases: Vec<(String, String)>,
}

impl Flat {
    /// The output `"node.port"` names in the flat graph (itself when not a group's).
    pub fn resolve<'a>(&'a self, port: &'a str) -> &'a str {
        self.aliases
            .iter()
            .find(|(a, _)| a == port)
            .map_or(port, |(_, b)| b.as_str())
    }
}

/// Whether `graph` has a node of a group kind of `registry`.
pub fn has_groups(graph: &Graph, registry: &Registry) -> bool {
    graph
        .nodes
        .iter()
        .any(|n| registry.group(&n.kind).is_some())
}

/// `graph` with every group node replaced by its inner nodes (see the module docs), and
/// `registry` with the kinds they use.
///
/// # Errors
/// Edges or params naming what a group does not expose; two different kinds of one
/// name (one in the outer graph, one in a group file).
pub fn flatten(graph: &Graph, registry: &Registry) -> Result<Flat, GraphErrors> {
    let mut errors = Vec::new();
    let expanded = expand(graph, registry, None, 0, &mut errors);
    let mut out_registry = registry.clone();
    for (kind, file) in &expanded.kinds {
        match out_registry.get(kind.name) {
            None => {
                out_registry
                    .add((**kind).clone())
                    .expect("the name is free and the kind was checked when it was added");
            }
            Some(k) if same_kind(k, kind) => {}
            Some(_) => errors.push(GraphError {
                file: Some(file.clone()),
                ..GraphError::new(ErrorKind::Source(format!(
                    "node kind \"{}\" of this group is another kind of that name in the graph \
                     using it; rename one",
                    kind.name
                )))
            }),
        }
    }
    if !errors.is_empty() {
        return Err(GraphErrors(errors));
    }
    let mut flat = graph.clone();
    flat.nodes = expanded.nodes;
    flat.edges = expanded.edges;
    Ok(Flat {
        graph: flat,
        registry: out_registry,
        aliases: expanded.outputs.into_iter().collect(),
    })
}

/// Whether two kinds of one name are the same: built-in (or added in Rust) kinds are one
/// per name; kinds declared in files are the same when their shaders are.
fn same_kind(a: &Arc<NodeKind>, b: &Arc<NodeKind>) -> bool {
    match (&a.shader, &b.shader) {
        (Some(Shader::Generated(x)), Some(Shader::Generated(y))) => x.text == y.text,
        (Some(Shader::Generated(_)), _) | (_, Some(Shader::Generated(_))) => false,
        _ => true,
    }
}

#[derive(Default)]
struct Expanded {
    nodes: Vec<Node>,
    edges: Vec<Edge>,
    /// Kinds of inner nodes, with the file of the group they come from.
    kinds: Vec<(Arc<NodeKind>, PathBuf)>,
    /// Group input `"node.port"` → the inner inputs it feeds.
    inputs: HashMap<String, Vec<String>>,
    /// Group output `"node.port"` → the inner output.
    outputs: HashMap<String, String>,
    /// Group param `"node.param"` → the inner params it sets.
    params: HashMap<String, Vec<String>>,
}

/// The nodes and edges of `graph` with its group nodes expanded. `base` is the folder of
/// a group file: relative path params of its (non-sink) nodes are made relative to it.
fn expand(
    graph: &Graph,
    registry: &Registry,
    base: Option<&Path>,
    depth: usize,
    errors: &mut Vec<GraphError>,
) -> Expanded {
    let mut out = Expanded::default();
    let file = graph
        .origin
        .as_ref()
        .map(|o| o.path.clone())
        .unwrap_or_default();
    for node in &graph.nodes {
        if let Some(group) = registry.group(&node.kind) {
            if depth >= MAX_DEPTH {
                let e = GraphError::new(ErrorKind::Source(format!(
                    "groups nest deeper than {MAX_DEPTH}"
                )));
                errors.push(graph.locate(e.now_about(&node.id), None, None));
            } else {
                expand_group(graph, node, group, depth, &mut out, errors);
            }
            continue;
        }
        let mut n = node.clone();
        if let Some(kind) = registry.get(&node.kind) {
            if let Some(base) = base {
                rebase_paths(&mut n, kind, base);
            }
            if !out.kinds.iter().any(|(k, _)| Arc::ptr_eq(k, kind)) {
                out.kinds.push((kind.clone(), file.clone()));
            }
        }
        out.nodes.push(n);
    }
    rewire(graph, registry, &mut out, errors);
    out
}

/// Adds to `out` the inner nodes and edges of group node `node` of `graph`, its ports and
/// params mapped to theirs, and its params set on them.
fn expand_group(
    graph: &Graph,
    node: &Node,
    group: &Group,
    depth: usize,
    out: &mut Expanded,
    errors: &mut Vec<GraphError>,
) {
    let group_base = group.graph.base_dir();
    let inner = expand(
        &group.graph,
        &group.registry,
        Some(&group_base),
        depth + 1,
        errors,
    );
    let prefix = |r: &str| format!("{}/{r}", node.id);
    let mut nodes: Vec<Node> = inner
        .nodes
        .into_iter()
        .map(|mut n| {
            n.id = prefix(&n.id);
            n.pos = None;
            n
        })
        .collect();
    let iface = &group.graph.interface;
    // Inner refs through nested groups, then prefixed.
    let through = |map: &HashMap<String, Vec<String>>, r: &str| -> Vec<String> {
        map.get(r)
            .cloned()
            .unwrap_or_else(|| vec![r.to_owned()])
            .iter()
            .map(|r| prefix(r))
            .collect()
    };
    for e in &iface.inputs {
        let targets = e.to.iter().flat_map(|r| through(&inner.inputs, r));
        out.inputs
            .insert(format!("{}.{}", node.id, e.name), targets.collect());
    }
    for o in &iface.outputs {
        let from = inner.outputs.get(&o.from).unwrap_or(&o.from);
        out.outputs
            .insert(format!("{}.{}", node.id, o.name), prefix(from));
    }
    for p in &iface.params {
        let targets = p.to.iter().flat_map(|r| through(&inner.params, r));
        out.params
            .insert(format!("{}.{}", node.id, p.name), targets.collect());
    }
    for (name, value) in &node.params {
        let Some(targets) = out.params.get(&format!("{}.{name}", node.id)) else {
            let known: Vec<&str> = iface.params.iter().map(|p| p.name.as_str()).collect();
            let e = GraphError::new(ErrorKind::UnknownParam {
                param: name.clone(),
                kind: node.kind.clone(),
                known: if known.is_empty() {
                    "none".into()
                } else {
                    known.join(", ")
                },
            });
            errors.push(graph.locate(e.now_about(&node.id), None, Some(name)));
            continue;
        };
        for (id, param) in targets.iter().filter_map(|t| split_port_ref(t)) {
            if let Some(n) = nodes.iter_mut().find(|n| n.id == id) {
                n.params.insert(param.to_owned(), value.clone());
            }
        }
    }
    out.nodes.append(&mut nodes);
    out.edges.extend(
        inner
            .edges
            .into_iter()
            .map(|e| Edge::new(prefix(&e.from), prefix(&e.to))),
    );
    out.kinds.extend(inner.kinds);
}

/// Adds `graph`'s own edges to `out`, those at group nodes moved to the inner ports.
fn rewire(graph: &Graph, registry: &Registry, out: &mut Expanded, errors: &mut Vec<GraphError>) {
    for (i, e) in graph.edges.iter().enumerate() {
        // `Some(exposed)` for a port of a group node.
        let group_port = |r: &str, input: bool| {
            let (node, port) = split_port_ref(r)?;
            let iface = &registry.group(&graph.node(node)?.kind)?.graph.interface;
            Some(if input {
                iface.inputs.iter().any(|x| x.name == port)
            } else {
                iface.outputs.iter().any(|x| x.name == port)
            })
        };
        let refuse = |r: &str, what: &str| {
            let (node, port) = split_port_ref(r).unwrap_or_default();
            let e = GraphError::new(ErrorKind::Source(format!(
                "edge {} -> {}: the group node \"{node}\" has no {what} \"{port}\"",
                e.from, e.to
            )));
            graph.locate(e.now_about(node), Some(i), None)
        };
        let from = match group_port(&e.from, false) {
            Some(true) => out.outputs[&e.from].clone(),
            Some(false) => {
                errors.push(refuse(&e.from, "output"));
                continue;
            }
            None => e.from.clone(),
        };
        let to = match group_port(&e.to, true) {
            Some(true) => out.inputs[&e.to].clone(),
            Some(false) => {
                errors.push(refuse(&e.to, "input"));
                continue;
            }
            None => vec![e.to.clone()],
        };
        out.edges
            .extend(to.into_iter().map(|t| Edge::new(from.clone(), t)));
    }
}

/// Makes the relative file params of `node` (of `kind`, not a sink: a sink's paths are
/// relative to the output folder) relative to `base`.
fn rebase_paths(node: &mut Node, kind: &NodeKind, base: &Path) {
    if kind.sink {
        return;
    }
    for def in &kind.params {
        if let ParamType::Path { .. } = def.ty
            && let Some(ParamValue::Str(v)) = node.params.get_mut(def.name)
            && !v.is_empty()
            && Path::new(v.as_str()).is_relative()
        {
            *v = base.join(v.as_str()).to_string_lossy().into_owned();
        }
    }
}
