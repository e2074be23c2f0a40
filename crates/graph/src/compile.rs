//! Compilation: graph → validated, ordered, pruned plan with textures assigned.
//!
//! 1. Every node, param and edge is checked against the registry; all errors are
//!    collected, each located in the file and tied to its node.
//! 2. The edges must form a DAG (petgraph's topological sort; a cycle names its nodes).
//! 3. Only nodes from which an output (a sink, or a port the caller asks to keep) can be
//!    reached are kept: the rest is reported as left out and never executed.
//! 4. Each edge's data becomes a transient texture living from the pass that writes it to
//!    the last pass that reads it; textures whose lifetimes do not overlap and whose format
//!    and size agree share one allocation (greedy interval assignment).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::Arc;

use petgraph::algo::{tarjan_scc, toposort};
use petgraph::graph::{DiGraph, NodeIndex};

use crate::error::{ErrorKind, GraphError, GraphErrors, NodeId};
use crate::graph::{Graph, Node, split_port_ref};
use crate::plan::{LeftOut, Pass, Plan, Slot, TextureDesc, TextureId};
use crate::registry::{NodeKind, Registry};
use crate::types::{Extent, ParamValue};

/// A node's params after checking: every declared param present, in canonical form.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params(pub BTreeMap<String, ParamValue>);

impl Params {
    /// Whether the kind declares a param called `name`.
    pub fn has(&self, name: &str) -> bool {
        self.0.contains_key(name)
    }

    fn get(&self, name: &str) -> &ParamValue {
        self.0
            .get(name)
            .unwrap_or_else(|| panic!("param \"{name}\" is not declared by this node kind"))
    }

    /// A float param.
    pub fn float(&self, name: &str) -> f64 {
        self.get(name).as_f64().unwrap_or(f64::NAN)
    }

    /// An int param.
    pub fn int(&self, name: &str) -> i64 {
        match self.get(name) {
            ParamValue::Int(v) => *v,
            other => panic!("param \"{name}\" is {}, not int", other.type_name()),
        }
    }

    /// A bool param.
    pub fn bool(&self, name: &str) -> bool {
        matches!(self.get(name), ParamValue::Bool(true))
    }

    /// A string param (enum or path).
    pub fn str(&self, name: &str) -> &str {
        match self.get(name) {
            ParamValue::Str(v) => v,
            other => panic!("param \"{name}\" is {}, not string", other.type_name()),
        }
    }
}

/// Checks a node's params against its kind and fills in defaults.
///
/// # Errors
/// One error per unknown param or bad value.
pub fn resolve_params(node: &Node, kind: &NodeKind) -> Result<Params, Vec<(String, ErrorKind)>> {
    let mut errors = Vec::new();
    for name in node.params.keys() {
        if kind.param(name).is_none() {
            let known: Vec<_> = kind.params.iter().map(|p| p.name).collect();
            errors.push((
                name.clone(),
                ErrorKind::UnknownParam {
                    param: name.clone(),
                    kind: kind.name.to_owned(),
                    known: if known.is_empty() {
                        "none".into()
                    } else {
                        known.join(", ")
                    },
                },
            ));
        }
    }
    let mut params = BTreeMap::new();
    for def in &kind.params {
        let value = match node.params.get(def.name) {
            Some(v) => match def.ty.check(v) {
                Ok(v) => v,
                Err(message) => {
                    errors.push((
                        def.name.to_owned(),
                        ErrorKind::BadParam {
                            param: def.name.to_owned(),
                            message,
                        },
                    ));
                    continue;
                }
            },
            None => def.ty.default_value(),
        };
        params.insert(def.name.to_owned(), value);
    }
    if errors.is_empty() {
        Ok(Params(params))
    } else {
        Err(errors)
    }
}

/// What the compiler needs from outside the graph.
pub struct CompileOptions<'a> {
    /// The image size a source node (one with no inputs) of a kind produces with the
    /// params given, or why it cannot tell.
    pub source_extent: &'a dyn Fn(&NodeKind, &Params) -> Result<Extent, String>,
    /// Extra `"node.port"` outputs to keep alive to the end of the frame (live previews).
    pub keep: &'a [String],
}

impl std::fmt::Debug for CompileOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CompileOptions")
            .field("keep", &self.keep)
            .finish_non_exhaustive()
    }
}

struct Checked<'g> {
    kinds: Vec<Option<&'g Arc<NodeKind>>>,
    params: Vec<Params>,
    /// (consumer node, input port) → (producer node, output port).
    inputs: HashMap<(usize, &'g str), (usize, &'g str)>,
}

/// Validates and compiles a graph into a plan. Group nodes are flattened first
/// ([`crate::group::flatten`]): the plan names their inner nodes `group/inner`, and
/// [`Plan::aliases`] maps the group outputs (also those in `options.keep`) to inner ones.
///
/// # Errors
/// Every problem found, each naming its node and, for a graph loaded from a file, the line.
pub fn compile(
    graph: &Graph,
    registry: &Registry,
    options: &CompileOptions<'_>,
) -> Result<Plan, GraphErrors> {
    if crate::group::has_groups(graph, registry) {
        let flat = crate::group::flatten(graph, registry)?;
        let keep: Vec<String> = options
            .keep
            .iter()
            .map(|k| flat.resolve(k).to_owned())
            .collect();
        let mut plan = compile(
            &flat.graph,
            &flat.registry,
            &CompileOptions {
                keep: &keep,
                ..*options
            },
        )?;
        plan.aliases = flat.aliases;
        return Ok(plan);
    }
    let converted;
    let graph = if graph.working_space == crate::WorkingSpace::default() {
        graph
    } else {
        converted = crate::working_space::with_conversions(graph, registry);
        &converted
    };
    let mut errors = Vec::new();
    let checked = check(graph, registry, &mut errors);
    let n = graph.nodes.len();

    // Cycles.
    let mut dag = DiGraph::<usize, ()>::with_capacity(n, checked.inputs.len());
    let idx: Vec<NodeIndex> = (0..n).map(|i| dag.add_node(i)).collect();
    // In a fixed order (the map's is random), so the same graph always gives the same
    // pass order.
    let mut edges: Vec<(usize, &str, usize)> = checked
        .inputs
        .iter()
        .map(|(&(to, port), &(from, _))| (to, port, from))
        .collect();
    edges.sort_unstable();
    for (to, _, from) in edges {
        dag.update_edge(idx[from], idx[to], ());
    }
    let order = if let Ok(order) = toposort(&dag, None) {
        order.into_iter().map(|i| dag[i]).collect::<Vec<_>>()
    } else {
        for scc in tarjan_scc(&dag) {
            let cyclic = scc.len() > 1 || dag.contains_edge(scc[0], scc[0]);
            if cyclic {
                let mut ids: Vec<usize> = scc.iter().map(|&i| dag[i]).collect();
                ids.sort_unstable();
                let names: Vec<_> = ids
                    .iter()
                    .map(|&i| format!("\"{}\"", graph.nodes[i].id))
                    .collect();
                let e = GraphError::new(ErrorKind::Cycle(names.join(", ")))
                    .now_about(&graph.nodes[ids[0]].id);
                errors.push(graph.locate(e, None, None));
            }
        }
        return Err(GraphErrors(errors));
    };

    // Liveness: everything that reaches a sink or a kept port.
    let mut keep_nodes = HashSet::new();
    for k in options.keep {
        if let Some(i) =
            split_port_ref(k).and_then(|(node, _)| graph.nodes.iter().position(|n| n.id == node))
        {
            keep_nodes.insert(i);
        }
    }
    let sinks: Vec<usize> = (0..n)
        .filter(|&i| checked.kinds[i].is_some_and(|k| k.sink) || keep_nodes.contains(&i))
        .collect();
    if sinks.is_empty() && errors.is_empty() {
        let mut e = GraphError::new(ErrorKind::NoOutput);
        e.file = graph.origin.as_ref().map(|o| o.path.clone());
        errors.push(e);
    }
    let mut live = vec![false; n];
    let mut stack = sinks;
    while let Some(i) = stack.pop() {
        if std::mem::replace(&mut live[i], true) {
            continue;
        }
        stack.extend(
            checked
                .inputs
                .iter()
                .filter(|((to, _), _)| *to == i)
                .map(|(_, (from, _))| *from),
        );
    }

    // Live nodes need every input connected (reported only when the edges themselves
    // were fine, so one mistake does not give two errors).
    let edges_ok = errors.is_empty();
    for (i, node) in graph.nodes.iter().enumerate() {
        let Some(kind) = checked.kinds[i] else {
            continue;
        };
        if !live[i] || !edges_ok {
            continue;
        }
        for input in &kind.inputs {
            if !input.optional && !checked.inputs.contains_key(&(i, input.name)) {
                let e = GraphError::new(ErrorKind::UnconnectedInput {
                    port: input.name.to_owned(),
                })
                .now_about(&node.id);
                errors.push(graph.locate(e, None, None));
            }
        }
    }
    if !errors.is_empty() {
        return Err(GraphErrors(errors));
    }

    let order: Vec<usize> = order.into_iter().filter(|&i| live[i]).collect();
    let plan = build_plan(graph, &checked, &order, options, &mut errors);
    if errors.is_empty() {
        Ok(plan)
    } else {
        Err(GraphErrors(errors))
    }
}

fn check<'g>(
    graph: &'g Graph,
    registry: &'g Registry,
    errors: &mut Vec<GraphError>,
) -> Checked<'g> {
    let (kinds, params) = check_nodes(graph, registry, errors);
    let inputs = check_edges(graph, &kinds, errors);
    Checked {
        kinds,
        params,
        inputs,
    }
}

/// Each node's kind (`None` when unknown) and checked params, reporting bad ids, unknown
/// kinds and bad params.
fn check_nodes<'g>(
    graph: &'g Graph,
    registry: &'g Registry,
    errors: &mut Vec<GraphError>,
) -> (Vec<Option<&'g Arc<NodeKind>>>, Vec<Params>) {
    let mut seen = HashSet::new();
    let mut kinds = Vec::with_capacity(graph.nodes.len());
    let mut params = Vec::with_capacity(graph.nodes.len());
    for node in &graph.nodes {
        let err = |kind: ErrorKind, param: Option<&str>| {
            graph.locate(GraphError::new(kind).now_about(&node.id), None, param)
        };
        if node.id.is_empty()
            || !node
                .id
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '/')
        {
            errors.push(err(ErrorKind::InvalidId(node.id.clone()), None));
        }
        if !seen.insert(node.id.as_str()) {
            errors.push(err(ErrorKind::DuplicateId(node.id.clone()), None));
        }
        let kind = registry.get(&node.kind);
        match kind {
            None => {
                let known: Vec<_> = registry.kinds().iter().map(|k| k.name).collect();
                errors.push(err(
                    ErrorKind::UnknownKind {
                        kind: node.kind.clone(),
                        known: known.join(", "),
                    },
                    None,
                ));
                params.push(Params::default());
            }
            Some(kind) => match resolve_params(node, kind) {
                Ok(p) => params.push(p),
                Err(es) => {
                    errors.extend(es.into_iter().map(|(p, k)| err(k, Some(&p))));
                    params.push(Params::default());
                }
            },
        }
        kinds.push(kind);
    }
    (kinds, params)
}

/// The input each edge connects, as (node, input port) → (node, output port), reporting
/// bad port references, missing nodes and ports, incompatible types and two edges into one
/// input.
fn check_edges<'g>(
    graph: &'g Graph,
    kinds: &[Option<&'g Arc<NodeKind>>],
    errors: &mut Vec<GraphError>,
) -> HashMap<(usize, &'g str), (usize, &'g str)> {
    let index: HashMap<&str, usize> = graph
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (n.id.as_str(), i))
        .collect();
    let mut inputs: HashMap<(usize, &str), (usize, &str)> = HashMap::new();
    for (e_i, edge) in graph.edges.iter().enumerate() {
        let mut fail = |kind: ErrorKind, node: Option<&str>| {
            let mut e = GraphError::new(kind);
            e.about = node.map(NodeId::from);
            errors.push(graph.locate(e, Some(e_i), None));
        };
        let (Some((from_node, from_port)), Some((to_node, to_port))) =
            (split_port_ref(&edge.from), split_port_ref(&edge.to))
        else {
            let bad = if split_port_ref(&edge.from).is_none() {
                &edge.from
            } else {
                &edge.to
            };
            fail(ErrorKind::BadPortRef(bad.clone()), None);
            continue;
        };
        let ends = [(from_node, "output"), (to_node, "input")];
        let mut resolved = [None, None];
        for (slot, (node, direction)) in ends.into_iter().enumerate() {
            let Some(&i) = index.get(node) else {
                fail(
                    ErrorKind::MissingNode {
                        from: edge.from.clone(),
                        to: edge.to.clone(),
                        node: node.to_owned(),
                    },
                    None,
                );
                continue;
            };
            let Some(kind) = kinds[i] else { continue }; // already reported as unknown kind
            let port = if slot == 0 { from_port } else { to_port };
            let has = if slot == 0 {
                kind.output(port).is_some()
            } else {
                kind.input(port).is_some()
            };
            if !has {
                let known: Vec<&str> = if slot == 0 {
                    kind.outputs.iter().map(|p| p.name).collect()
                } else {
                    kind.inputs.iter().map(|p| p.name).collect()
                };
                fail(
                    ErrorKind::MissingPort {
                        from: edge.from.clone(),
                        to: edge.to.clone(),
                        kind: kind.name.to_owned(),
                        direction,
                        port: port.to_owned(),
                        known: if known.is_empty() {
                            "none".into()
                        } else {
                            known.join(", ")
                        },
                    },
                    Some(node),
                );
                continue;
            }
            resolved[slot] = Some((i, kind));
        }
        let [Some((fi, fk)), Some((ti, tk))] = resolved else {
            continue;
        };
        let (Some(out), Some(inp)) = (fk.output(from_port), tk.input(to_port)) else {
            continue;
        };
        if !inp.accepts.contains(&out.ty) {
            let accepted: Vec<_> = inp.accepts.iter().map(|t| t.name()).collect();
            fail(
                ErrorKind::IncompatibleTypes {
                    from: edge.from.clone(),
                    to: edge.to.clone(),
                    produced: out.ty.name().to_owned(),
                    accepted: accepted.join(" or "),
                },
                Some(to_node),
            );
            continue;
        }
        if let Some(&(pi, pport)) = inputs.get(&(ti, inp.name)) {
            fail(
                ErrorKind::TwoEdgesIntoInput {
                    to: edge.to.clone(),
                    first: format!("{}.{pport}", graph.nodes[pi].id),
                    second: edge.from.clone(),
                },
                Some(to_node),
            );
            continue;
        }
        inputs.insert((ti, inp.name), (fi, out.name));
    }
    inputs
}

#[expect(
    clippy::too_many_lines,
    reason = "one walk over the live nodes; split up, its state would be threaded through"
)]
fn build_plan(
    graph: &Graph,
    checked: &Checked<'_>,
    order: &[usize],
    options: &CompileOptions<'_>,
    errors: &mut Vec<GraphError>,
) -> Plan {
    let position: HashMap<usize, usize> = order.iter().enumerate().map(|(p, &i)| (i, p)).collect();
    let mut textures: Vec<TextureDesc> = Vec::new();
    let mut texture_of: HashMap<(usize, &str), TextureId> = HashMap::new();
    // Textures of unknown size (a source that could not tell, and what is computed from
    // it) are not compared, so that one error is reported.
    let mut size_unknown: HashSet<TextureId> = HashSet::new();
    let mut passes = Vec::with_capacity(order.len());
    let mut left_out = Vec::new();

    for (p, &i) in order.iter().enumerate() {
        let node = &graph.nodes[i];
        let kind = checked.kinds[i].expect("live nodes have known kinds");
        let params = checked.params[i].clone();
        let located = |m: String, param: Option<&str>| {
            graph.locate(
                GraphError::new(ErrorKind::Source(m)).now_about(&node.id),
                None,
                param,
            )
        };
        let mut inputs = Vec::new();
        let mut extent = None;
        let mut unknown = false;
        for input in &kind.inputs {
            let Some(&(from, port)) = checked.inputs.get(&(i, input.name)) else {
                left_out.push(LeftOut {
                    what: format!("input {}.{}", node.id, input.name),
                    reason: "optional, not connected".into(),
                });
                continue;
            };
            let t = texture_of[&(from, port)];
            textures[t.0].last = textures[t.0].last.max(p);
            inputs.push((input.name, t));
            let e = textures[t.0].extent;
            unknown |= size_unknown.contains(&t);
            match extent {
                _ if size_unknown.contains(&t) => {}
                None => extent = Some(e),
                Some(prev) if prev != e => {
                    let m = format!(
                        "inputs differ in size: {prev} and {e} (input \"{}\")",
                        input.name
                    );
                    errors.push(located(m, None));
                }
                Some(_) => {}
            }
        }
        let extent = extent.unwrap_or_else(|| {
            let sized = if unknown {
                Ok(Extent::new(1, 1))
            } else {
                (options.source_extent)(kind, &params)
            };
            sized.unwrap_or_else(|m| {
                errors.push(located(m, Some("path")));
                unknown = true;
                Extent::new(1, 1)
            })
        });

        let mut outputs = Vec::new();
        for output in &kind.outputs {
            let name = format!("{}.{}", node.id, output.name);
            let consumed = checked.inputs.iter().any(|((to, _), (from, port))| {
                *from == i && *port == output.name && position.contains_key(to)
            });
            let kept = options.keep.contains(&name);
            if !consumed && !kept {
                left_out.push(LeftOut {
                    what: format!("texture {name}"),
                    reason: "nothing reads it".into(),
                });
                continue;
            }
            let size = match output.size.extent(extent, &params) {
                Ok(e) => e,
                Err(_) if unknown => extent,
                Err(m) => {
                    errors.push(located(format!("output \"{}\": {m}", output.name), None));
                    extent
                }
            };
            let id = TextureId(textures.len());
            textures.push(TextureDesc {
                id,
                name,
                ty: output.ty,
                format: output.ty.format(),
                extent: size,
                first: p,
                last: if kept { order.len() } else { p },
                slot: 0,
            });
            texture_of.insert((i, output.name), id);
            if unknown {
                size_unknown.insert(id);
            }
            outputs.push((output.name, id));
        }
        passes.push(Pass {
            node: node.id.clone(),
            kind: Arc::clone(kind),
            params,
            inputs,
            outputs,
            extent,
        });
    }

    for (i, node) in graph.nodes.iter().enumerate() {
        if position.contains_key(&i) {
            continue;
        }
        let kind = checked.kinds[i].map_or("?", |k| k.name);
        left_out.push(LeftOut {
            what: format!("node \"{}\" ({kind})", node.id),
            reason: "feeds no output".into(),
        });
    }

    let slots = assign_slots(&mut textures);
    Plan {
        passes,
        textures,
        slots,
        left_out,
        aliases: Vec::new(),
        working_space: graph.working_space,
    }
}

/// Greedy interval assignment: each texture, in order of first use, takes the first slot of
/// its format and size that is free before the texture is written; otherwise a new slot.
fn assign_slots(textures: &mut [TextureDesc]) -> Vec<Slot> {
    let mut slots: Vec<Slot> = Vec::new();
    let mut busy_until: Vec<usize> = Vec::new();
    for t in textures.iter_mut() {
        let free = slots.iter().zip(&busy_until).position(|(s, &until)| {
            s.format == t.format && s.extent == t.extent && until < t.first
        });
        let s = free.unwrap_or_else(|| {
            slots.push(Slot {
                format: t.format,
                extent: t.extent,
                textures: Vec::new(),
            });
            busy_until.push(0);
            slots.len() - 1
        });
        slots[s].textures.push(t.id);
        busy_until[s] = t.last;
        t.slot = s;
    }
    slots
}
