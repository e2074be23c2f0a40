//! The node kinds the graph knows: their ports, params and docs.
//!
//! The registry is data, not code: the compiler, the CLI's `nodes` listing, the generated
//! docs and the editor's menus and inspector all read these declarations, so a kind is
//! described in exactly one place. The GPU implementation of each kind lives in the
//! render crate under the same name.

mod color;
mod denoise;
mod input;
mod output;
mod render;

use std::sync::LazyLock;

use crate::types::{ParamType, PortType};

/// Where a node kind sits in menus and docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Category {
    /// Nodes that produce images from files or scenes.
    Input,
    /// Nodes that render or accumulate samples over frames.
    Render,
    /// Nodes that remove noise from renders.
    Denoise,
    /// Nodes that change colors of an image.
    Color,
    /// Nodes that write results out of the graph.
    Output,
}

impl Category {
    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Input => "Input",
            Self::Render => "Render",
            Self::Denoise => "Denoise",
            Self::Color => "Color",
            Self::Output => "Output",
        }
    }
}

/// An input port of a node kind.
#[derive(Clone, Debug)]
pub struct InputDef {
    /// Port name, unique among the kind's inputs.
    pub name: &'static str,
    /// The port types it accepts.
    pub accepts: &'static [PortType],
    /// One-line description.
    pub doc: &'static str,
}

/// An output port of a node kind.
#[derive(Clone, Debug)]
pub struct OutputDef {
    /// Port name, unique among the kind's outputs.
    pub name: &'static str,
    /// What it produces.
    pub ty: PortType,
    /// One-line description.
    pub doc: &'static str,
}

/// A parameter of a node kind.
#[derive(Clone, Debug)]
pub struct ParamDef {
    /// Parameter name, unique within the kind.
    pub name: &'static str,
    /// Type, default and range.
    pub ty: ParamType,
    /// One-line description.
    pub doc: &'static str,
}

/// A kind of node: what it reads, writes and is configured with.
#[derive(Clone, Debug)]
pub struct NodeKind {
    /// Name used in graph files (`kind: "Tonemap"`).
    pub name: &'static str,
    /// Menu and docs grouping.
    pub category: Category,
    /// One-paragraph description.
    pub doc: &'static str,
    /// Input ports; every one must be connected.
    pub inputs: &'static [InputDef],
    /// Output ports.
    pub outputs: &'static [OutputDef],
    /// Parameters.
    pub params: Vec<ParamDef>,
    /// Whether the node is a sink: it writes results out of the graph, and the nodes
    /// that feed no sink are pruned.
    pub sink: bool,
    /// Whether the node keeps history across frames (progressive accumulation): it and
    /// everything upstream of it run every frame; nodes downstream only need the last one.
    pub history: bool,
    /// Whether the node renders the scene given with `--scene`: it needs one, and its
    /// images are the scene's size.
    pub renders_scene: bool,
    /// A post filter run by the generic implementation: this WGSL file (under `shaders/`)
    /// reads input `color`, writes output `color`, and gets the params in declaration order
    /// in its `Params` struct, member names as the params' (float → `f32`, int → `i32`,
    /// bool and enum option index → `u32`). `None`: the kind has an implementation of its
    /// own in the render crate.
    pub shader: Option<&'static str>,
}

impl NodeKind {
    /// The input port called `name`.
    pub fn input(&self, name: &str) -> Option<&InputDef> {
        self.inputs.iter().find(|p| p.name == name)
    }

    /// The output port called `name`.
    pub fn output(&self, name: &str) -> Option<&OutputDef> {
        self.outputs.iter().find(|p| p.name == name)
    }

    /// The parameter called `name`.
    pub fn param(&self, name: &str) -> Option<&ParamDef> {
        self.params.iter().find(|p| p.name == name)
    }

    /// Whether the node has no inputs and so sets the image size itself.
    pub fn is_source(&self) -> bool {
        self.inputs.is_empty()
    }
}

/// A set of node kinds.
#[derive(Debug)]
pub struct Registry {
    kinds: Vec<NodeKind>,
}

impl Registry {
    /// The kinds built into lumagraph.
    pub fn builtin() -> &'static Self {
        static BUILTIN: LazyLock<Registry> = LazyLock::new(|| Registry {
            kinds: builtin_kinds(),
        });
        &BUILTIN
    }

    /// The kind called `name`.
    pub fn get(&self, name: &str) -> Option<&NodeKind> {
        self.kinds.iter().find(|k| k.name == name)
    }

    /// Every kind, in registry order (grouped by category).
    pub fn kinds(&self) -> &[NodeKind] {
        &self.kinds
    }
}

const COLOR_TYPES: &[PortType] = &[PortType::HdrColor];
const ANY_IMAGE: &[PortType] = &[
    PortType::HdrColor,
    PortType::LdrColor,
    PortType::Albedo,
    PortType::Normal,
    PortType::Depth,
    PortType::Variance,
];

/// The param of a progressive source: how many samples per pixel each frame adds. A pass
/// with it is where a render's samples come from (the CLI divides `--spp` by it).
pub const SAMPLES_PER_FRAME: &str = "samples_per_frame";

/// Tone-mapping operators, shared by the registry and the implementations.
pub const TONEMAP_OPERATORS: &[(&str, &str)] = &[
    ("clamp", "linear, clipped to [0, 1]"),
    (
        "reinhard",
        "extended Reinhard on luminance, `white` maps to 1",
    ),
    ("aces", "ACES filmic curve (Hill's RRT+ODT fit)"),
    ("agx", "AgX base (Sobotka), polynomial fit of the sigmoid"),
    (
        "pbr_neutral",
        "Khronos PBR Neutral: keeps base colors, compresses highlights",
    ),
];

/// A post filter on the generic implementation ([`NodeKind::shader`]): linear colour in on
/// `color`, HDR colour out on `color`, with `params` packed for `shader`.
pub(crate) fn post_filter(
    name: &'static str,
    category: Category,
    doc: &'static str,
    params: Vec<ParamDef>,
    shader: &'static str,
) -> NodeKind {
    NodeKind {
        name,
        category,
        doc,
        inputs: &[InputDef {
            name: "color",
            accepts: COLOR_TYPES,
            doc: "linear color",
        }],
        outputs: &[OutputDef {
            name: "color",
            ty: PortType::HdrColor,
            doc: "the filtered linear color",
        }],
        params,
        sink: false,
        history: false,
        renders_scene: false,
        shader: Some(shader),
    }
}

fn builtin_kinds() -> Vec<NodeKind> {
    [
        input::kinds(),
        render::kinds(),
        denoise::kinds(),
        color::kinds(),
        output::kinds(),
    ]
    .concat()
}
