//! A graph's working space: the colour space its colour images are in, and the
//! conversions the compiler puts in where a node works in another one.
//!
//! Scene-linear Rec. 709 is the default, and what every node of lumagraph was written for.
//! A graph may choose ACEScg instead (`working_space: "ACEScg"` in its file), as Blender
//! and Nuke let a project choose its scene-linear space. Then files are read into ACEScg
//! (`ImageInput`), the OpenColorIO nodes convert from and to ACEScg, and outputs are
//! tagged with ACEScg's primaries; the ports that stay Rec. 709 (the path tracer's and the
//! G-buffer's colour outputs, the inputs of nodes whose maths is Rec. 709's: tone curves,
//! luminance weights, white balance; [`crate::registry::InputDef::rec709`]) are joined to
//! the rest through `ColorSpace` nodes the compiler adds, named `NODE_PORT_to_acescg` and
//! `NODE_PORT_to_rec709`, which `lumagraph plan` lists. A graph in Rec. 709 gets none.

use std::fmt;

use crate::graph::{Edge, Graph, Node, split_port_ref};
use crate::registry::Registry;
use crate::types::{ParamValue, PortType};

/// The OpenColorIO config the added conversions use: OpenColorIO's CG config (ACES 2.0),
/// built in, so that they do not depend on `$OCIO` (the colour crate's default config).
pub const CONVERSION_CONFIG: &str = "ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5";

/// The colour space of a graph's colour images.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WorkingSpace {
    /// Scene-linear Rec. 709 (sRGB primaries, D65): the default.
    #[default]
    Rec709,
    /// ACEScg (AP1 primaries, the ACES white point), linear.
    AcesCg,
}

impl WorkingSpace {
    /// Every working space, default first.
    pub const ALL: [Self; 2] = [Self::Rec709, Self::AcesCg];

    /// The name a graph file uses.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rec709 => "Linear Rec.709",
            Self::AcesCg => "ACEScg",
        }
    }

    /// The space named `name` (as [`WorkingSpace::name`], or an alias: `rec709`,
    /// `lin_rec709`, `acescg`, `lin_ap1`; any case).
    ///
    /// # Errors
    /// An unknown name: the message lists the names.
    pub fn parse(name: &str) -> Result<Self, String> {
        let n = name.trim().to_ascii_lowercase();
        match n.as_str() {
            "linear rec.709" | "rec709" | "rec.709" | "lin_rec709" | "linear rec.709 (srgb)" => {
                Ok(Self::Rec709)
            }
            "acescg" | "lin_ap1" | "aces - acescg" => Ok(Self::AcesCg),
            _ => Err(format!(
                "unknown working space {name:?}: \"Linear Rec.709\" (the default) or \"ACEScg\""
            )),
        }
    }

    /// Its names in OpenColorIO configs (the CG and studio configs, ACES 1.x, Blender's),
    /// in the order they are looked for.
    pub const fn ocio_names(self) -> &'static [&'static str] {
        match self {
            Self::Rec709 => &[
                "Linear Rec.709 (sRGB)",
                "lin_rec709_srgb",
                "lin_rec709",
                "Utility - Linear - sRGB",
                "Utility - Linear - Rec.709",
                "Linear Rec.709",
                "Linear",
            ],
            Self::AcesCg => &["ACEScg", "lin_ap1", "ACES - ACEScg", "Linear ACEScg"],
        }
    }

    /// Its primaries and white as an EXR `chromaticities` attribute holds them: red,
    /// green, blue, white (x, y).
    pub fn chromaticities(self) -> [f32; 8] {
        match self {
            Self::Rec709 => [0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290],
            Self::AcesCg => [0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767],
        }
    }
}

impl fmt::Display for WorkingSpace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `graph` with a `ColorSpace` node on every colour edge between a Rec. 709 port and a
/// port in the working space (none when the graph's working space is Rec. 709). One
/// conversion per output and direction, shared by the inputs it feeds.
pub fn with_conversions(graph: &Graph, registry: &Registry) -> Graph {
    let space = graph.working_space;
    let mut out = graph.clone();
    if space == WorkingSpace::Rec709 {
        return out;
    }
    let is_rec709_output = |node: &str, port: &str| {
        graph
            .node(node)
            .and_then(|n| registry.get(&n.kind))
            .and_then(|k| k.outputs.iter().find(|o| o.name == port).cloned())
            .map(|o| (o.ty == PortType::HdrColor, o.rec709))
    };
    let is_rec709_input = |node: &str, port: &str| {
        graph
            .node(node)
            .and_then(|n| registry.get(&n.kind))
            .and_then(|k| k.inputs.iter().find(|i| i.name == port).cloned())
            .map(|i| i.rec709)
    };
    let mut added: Vec<(String, String)> = Vec::new();
    for edge in &mut out.edges {
        let (Some((from_node, from_port)), Some((to_node, to_port))) =
            (split_port_ref(&edge.from), split_port_ref(&edge.to))
        else {
            continue;
        };
        let (Some((true, from_709)), Some(to_709)) = (
            is_rec709_output(from_node, from_port),
            is_rec709_input(to_node, to_port),
        ) else {
            continue;
        };
        if from_709 == to_709 {
            continue;
        }
        let target = if to_709 { "rec709" } else { "acescg" };
        let base = format!("{from_node}_{from_port}_to_{target}");
        let id = unique_id(graph, &base);
        if !added.iter().any(|(i, _)| *i == id) {
            let (from, to) = if to_709 {
                (space.ocio_names()[0], WorkingSpace::Rec709.ocio_names()[0])
            } else {
                (WorkingSpace::Rec709.ocio_names()[0], space.ocio_names()[0])
            };
            added.push((id.clone(), edge.from.clone()));
            out.nodes.push(
                Node::new(&id, "ColorSpace")
                    .with("config", ParamValue::Str(CONVERSION_CONFIG.into()))
                    .with("from", ParamValue::Str(from.into()))
                    .with("to", ParamValue::Str(to.into())),
            );
        }
        edge.from = format!("{id}.color");
    }
    for (id, from) in added {
        out.edges.push(Edge::new(from, format!("{id}.color")));
    }
    out
}

/// `base`, or `base_2`, `base_3`… where a node of the graph already has the id.
fn unique_id(graph: &Graph, base: &str) -> String {
    let mut id = base.to_owned();
    let mut n = 2;
    while graph.node(&id).is_some() {
        id = format!("{base}_{n}");
        n += 1;
    }
    id
}
