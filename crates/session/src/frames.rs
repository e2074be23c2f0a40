//! Frame sequences in graphs: the params that hold a frame-number pattern (`####`, `%04d`,
//! `$F4`: [`lumagraph_footage::sequence`]) or, for numbers, a frame expression
//! (`"0.25 * frame"`: [`lumagraph_graph::expr`]), and the graph at a given frame.
//!
//! The command line (`render --frames`), the session ([`crate::Session::set_frame`],
//! the Python package's `render_frames`) and the editor's frame control all substitute
//! frames through [`FrameParams`], so a sequence means the same everywhere.

use std::path::PathBuf;

use lumagraph_footage::sequence;
use lumagraph_graph::{Graph, ParamType, ParamValue, Registry, expr};

/// One param whose value holds a frame pattern.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Patterned {
    /// The node's id.
    pub node: String,
    /// The param's name.
    pub param: String,
    /// The value as written, pattern and all.
    pub template: String,
    /// Whether it names a file the graph reads (a path param of a node that is no sink).
    pub input_file: bool,
    /// Whether it is a number param written as a frame expression
    /// ([`lumagraph_graph::expr`]), not a text with a frame-number pattern.
    pub expression: bool,
}

/// Every frame-numbered param of a graph.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameParams {
    /// The params, in node order.
    pub params: Vec<Patterned>,
    /// Sinks whose file param holds no pattern (each frame would overwrite the last):
    /// `(kind, node, param, value)`.
    pub fixed_outputs: Vec<(String, String, String, String)>,
}

impl FrameParams {
    /// The frame-numbered params of `graph`, whose kinds `registry` holds (a node of an
    /// unknown kind is passed over: compiling the graph names it).
    pub fn of(graph: &Graph, registry: &Registry) -> Self {
        let mut out = Self::default();
        for node in &graph.nodes {
            let Some(kind) = registry.get(&node.kind) else {
                continue;
            };
            for def in &kind.params {
                let Some(ParamValue::Str(value)) = node.params.get(def.name) else {
                    if kind.sink && matches!(def.ty, ParamType::Path { .. }) {
                        out.fixed_outputs.push((
                            kind.name.to_owned(),
                            node.id.clone(),
                            def.name.to_owned(),
                            def.ty.default_value().to_string(),
                        ));
                    }
                    continue;
                };
                let is_path = matches!(def.ty, ParamType::Path { .. });
                let is_number = matches!(def.ty, ParamType::Float { .. } | ParamType::Int { .. });
                if is_number {
                    if expr::uses_frame(value) {
                        out.params.push(Patterned {
                            node: node.id.clone(),
                            param: def.name.to_owned(),
                            template: value.clone(),
                            input_file: false,
                            expression: true,
                        });
                    }
                } else if sequence::has_pattern(value) {
                    out.params.push(Patterned {
                        node: node.id.clone(),
                        param: def.name.to_owned(),
                        template: value.clone(),
                        input_file: is_path && !kind.sink,
                        expression: false,
                    });
                } else if kind.sink && is_path {
                    out.fixed_outputs.push((
                        kind.name.to_owned(),
                        node.id.clone(),
                        def.name.to_owned(),
                        format!("{value:?}"),
                    ));
                }
            }
        }
        out
    }

    /// Whether no param holds a pattern.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// Why `graph` (`name` in messages) cannot be rendered as a sequence, if it cannot: no
    /// param holds a pattern, or an output's file would be the same for every frame.
    pub fn check_sequence(&self, name: &str) -> Result<(), String> {
        if let Some((kind, node, param, value)) = self.fixed_outputs.first() {
            return Err(format!(
                "{kind} {node:?} writes {value} for every frame, each over the last: put a \
                 frame pattern in its {param} (`####`, `%04d` or `$F4`, e.g. \"f.####.exr\")"
            ));
        }
        if self.is_empty() {
            return Err(format!(
                "no param of {name} holds a frame pattern (`####`, `%04d`, `$F4`) or a frame \
                 expression (`\"0.25 * frame\"` in a number), so every \
                 frame would be the same image"
            ));
        }
        Ok(())
    }

    /// `node.param = "template"` for each param, for messages.
    pub fn describe(&self) -> String {
        let items: Vec<String> = self
            .params
            .iter()
            .map(|p| format!("{}.{} = {:?}", p.node, p.param, p.template))
            .collect();
        items.join(", ")
    }

    /// `graph` (the one these params were found in) with frame `frame`'s values.
    pub fn at(&self, graph: &Graph, frame: i64) -> Graph {
        let mut g = graph.clone();
        for p in &self.params {
            if let Some(node) = g.nodes.iter_mut().find(|n| n.id == p.node) {
                let value = if p.expression {
                    expr::substitute(&p.template, frame)
                } else {
                    sequence::substitute(&p.template, frame)
                };
                node.params.insert(p.param.clone(), ParamValue::Str(value));
            }
        }
        g
    }

    /// The files frame `frame` reads, relative paths resolved against `graph`'s folder.
    pub fn inputs_at(&self, graph: &Graph, frame: i64) -> Vec<PathBuf> {
        self.params
            .iter()
            .filter(|p| p.input_file)
            .map(|p| {
                graph
                    .base_dir()
                    .join(sequence::substitute(&p.template, frame))
            })
            .collect()
    }

    /// The first file frame `frame` reads that is missing.
    pub fn missing_at(&self, graph: &Graph, frame: i64) -> Option<PathBuf> {
        self.inputs_at(graph, frame)
            .into_iter()
            .find(|p| !p.is_file())
    }
}
