//! The node kinds the graph knows: their ports, params and docs.
//!
//! The registry is data, not code: the compiler, the CLI's `nodes` listing, the generated
//! docs and the editor's menus and inspector all read these declarations, so a kind is
//! described in exactly one place. The GPU implementation of each kind lives in the
//! render crate under the same name.

mod analysis;
mod color;
mod combine;
mod denoise;
mod effects;
mod input;
pub mod output;
mod render;
mod transform;

use std::sync::Arc;

use crate::compile::Params;
pub use crate::custom::Shader;
use crate::group::Group;
use crate::types::{Extent, ParamType, ParamValue, PortType};

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
    /// Nodes that combine images or do arithmetic on them.
    Combine,
    /// Nodes that filter an image spatially, or add lens and film effects.
    Filter,
    /// Nodes that resample an image to another size.
    Transform,
    /// Nodes that measure images: error against a reference.
    Analysis,
    /// Kinds declared in a graph file that name no other category.
    Custom,
    /// Graph files used as nodes (node groups).
    Group,
    /// Nodes that write results out of the graph.
    Output,
}

impl Category {
    /// Every category, in menu order.
    pub const ALL: [Self; 11] = [
        Self::Input,
        Self::Render,
        Self::Denoise,
        Self::Color,
        Self::Combine,
        Self::Filter,
        Self::Transform,
        Self::Analysis,
        Self::Custom,
        Self::Group,
        Self::Output,
    ];

    /// Display name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Input => "Input",
            Self::Render => "Render",
            Self::Denoise => "Denoise",
            Self::Color => "Color",
            Self::Combine => "Combine",
            Self::Filter => "Filter",
            Self::Transform => "Transform",
            Self::Analysis => "Analysis",
            Self::Custom => "Custom",
            Self::Group => "Group",
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
    /// Whether the node runs without it: an unconnected optional input is left out of the
    /// pass (and `plan` says so); every other input of a live node must be connected.
    pub optional: bool,
    /// Whether the node writes the image on this input, alone, to the file its `path` param
    /// names (`Output`'s `color`, see [`InputDef::image_file`]). A tiled render holds that
    /// image instead, pastes each tile's core into one whole image and writes the file
    /// once; it refuses a sink with no such input.
    pub image_file: bool,
    /// Whether the node's maths takes this colour input as scene-linear Rec. 709 (tone
    /// curves, Rec. 709 luminance weights): in a graph with another working space the
    /// compiler converts into Rec. 709 before it ([`crate::working_space`]).
    pub rec709: bool,
}

impl InputDef {
    /// A required input.
    pub const fn new(name: &'static str, accepts: &'static [PortType], doc: &'static str) -> Self {
        Self {
            name,
            accepts,
            doc,
            optional: false,
            image_file: false,
            rec709: false,
        }
    }

    /// The same input, taken as scene-linear Rec. 709 (see [`InputDef::rec709`]).
    #[must_use]
    pub const fn rec709(mut self) -> Self {
        self.rec709 = true;
        self
    }

    /// The same input, optional (see [`InputDef::optional`]).
    #[must_use]
    pub const fn optional(mut self) -> Self {
        self.optional = true;
        self
    }

    /// The same input, written by its sink as one image file (see
    /// [`InputDef::image_file`]); the kind must be a sink with a `path` param, and have
    /// one such input at most ([`Registry::add`] checks).
    #[must_use]
    pub const fn image_file(mut self) -> Self {
        self.image_file = true;
        self
    }
}

/// The size of the image an output port produces.
#[derive(Clone, Copy, Debug)]
pub enum OutputSize {
    /// The pass's size: its inputs' (which must agree), or for a source the size it tells.
    Input,
    /// The pass's size times `num / den` per axis, rounded up, at least one pixel (a
    /// half-resolution level is `{ num: 1, den: 2 }`).
    Scaled {
        /// Numerator.
        num: u32,
        /// Denominator (not 0).
        den: u32,
    },
    /// Worked out from the pass's size and the node's checked params; an `Err` is shown
    /// located at the node. The text says what the rule is, for the docs.
    Rule(fn(Extent, &Params) -> Result<Extent, String>, &'static str),
}

impl OutputSize {
    /// The output's size for a pass of size `input` with `params`.
    ///
    /// # Errors
    /// When the rule refuses the params (message for the user).
    pub fn extent(&self, input: Extent, params: &Params) -> Result<Extent, String> {
        match *self {
            Self::Input => Ok(input),
            Self::Scaled { num, den } => {
                let f = |v: u32| {
                    (u64::from(v) * u64::from(num))
                        .div_ceil(u64::from(den.max(1)))
                        .clamp(1, u64::from(u32::MAX))
                };
                #[expect(clippy::cast_possible_truncation, reason = "clamped to u32")]
                Ok(Extent::new(f(input.width) as u32, f(input.height) as u32))
            }
            Self::Rule(rule, _) => rule(input, params),
        }
    }

    /// How the size is chosen, in words (docs); `None` for [`OutputSize::Input`].
    pub fn describe(&self) -> Option<String> {
        match *self {
            Self::Input => None,
            Self::Scaled { num, den } => Some(format!("{num}/{den} of the input size")),
            Self::Rule(_, doc) => Some(doc.to_owned()),
        }
    }
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
    /// Its image size.
    pub size: OutputSize,
    /// Whether this colour output is scene-linear Rec. 709 whatever the graph's working
    /// space (the path tracer renders in Rec. 709): in a graph with another working space
    /// the compiler converts it ([`crate::working_space`]).
    pub rec709: bool,
}

impl OutputDef {
    /// An output of the pass's size.
    pub const fn new(name: &'static str, ty: PortType, doc: &'static str) -> Self {
        Self {
            name,
            ty,
            doc,
            size: OutputSize::Input,
            rec709: false,
        }
    }

    /// The same output, in scene-linear Rec. 709 (see [`OutputDef::rec709`]).
    #[must_use]
    pub const fn rec709(mut self) -> Self {
        self.rec709 = true;
        self
    }

    /// The same output, sized by `size`.
    #[must_use]
    pub const fn sized(mut self, size: OutputSize) -> Self {
        self.size = size;
        self
    }
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

impl ParamDef {
    /// A float param in `[min, max]`.
    pub const fn float(
        name: &'static str,
        default: f64,
        [min, max]: [f64; 2],
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            ty: ParamType::Float { default, min, max },
            doc,
        }
    }

    /// An int param in `[min, max]`.
    pub const fn int(
        name: &'static str,
        default: i64,
        [min, max]: [i64; 2],
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            ty: ParamType::Int { default, min, max },
            doc,
        }
    }

    /// An enum param: one of `options` (name, description).
    pub const fn choice(
        name: &'static str,
        default: &'static str,
        options: &'static [(&'static str, &'static str)],
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            ty: ParamType::Enum { default, options },
            doc,
        }
    }
}

/// How far from an output pixel a node reads its inputs: what a tiled render must render
/// around each tile (its apron) for the tile to come out as in the whole image.
#[derive(Clone, Copy, Debug)]
pub enum Reach {
    /// Each output pixel reads the inputs at the same pixel only; a node that renders the
    /// scene renders its pixels of the whole image.
    Pixel,
    /// Each output pixel reads the inputs within this many pixels (from the params).
    Within(fn(&crate::Params) -> u32),
    /// It reads the whole image, or the pixel's place in it: it cannot run tile by tile
    /// (the reason).
    Image(&'static str),
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
    /// Input ports; every one that is not optional must be connected.
    pub inputs: Vec<InputDef>,
    /// Output ports.
    pub outputs: Vec<OutputDef>,
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
    /// binds one texture per input and one storage texture per output, in declaration
    /// order, and gets the params in declaration order in its `Params` struct, member names
    /// as the params' (float → `f32`, int → `i32`, bool and enum option index → `u32`),
    /// then `has_<input>: u32` per optional input. `None`: the kind has an implementation
    /// of its own in the render crate.
    pub shader: Option<Shader>,
    /// Params that show what the node does, for the gallery (`lumagraph gallery`); empty:
    /// its defaults (which for a grading node change nothing).
    pub example: Vec<(&'static str, ParamValue)>,
    /// How far it reads around a pixel, for tiled renders.
    pub reach: Reach,
}

impl NodeKind {
    /// The same kind with how far it reads around a pixel.
    #[must_use]
    pub fn with_reach(mut self, reach: Reach) -> Self {
        self.reach = reach;
        self
    }

    /// The same kind, whose maths takes its colour as scene-linear Rec. 709 (tone curves,
    /// Rec. 709 luminance weights): every colour input and output marked
    /// [`InputDef::rec709`] / [`OutputDef::rec709`].
    #[must_use]
    pub fn with_rec709_maths(mut self) -> Self {
        for input in &mut self.inputs {
            if input.accepts.contains(&PortType::HdrColor) {
                input.rec709 = true;
            }
        }
        for output in &mut self.outputs {
            if output.ty == PortType::HdrColor {
                output.rec709 = true;
            }
        }
        self
    }

    /// The same kind with `example` params for the gallery.
    #[must_use]
    pub fn with_example(mut self, example: &[(&'static str, ParamValue)]) -> Self {
        self.example = example.to_vec();
        self
    }

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

    /// The input a sink writes, alone, as the image file its `path` param names
    /// ([`InputDef::image_file`]); `None` for a kind that writes no such file.
    pub fn image_file_input(&self) -> Option<&InputDef> {
        self.inputs.iter().find(|p| p.image_file)
    }

    /// Why the kind's [`InputDef::image_file`] marks do not hold, if they do not.
    fn check_image_file(&self) -> Result<(), String> {
        let marked = self.inputs.iter().filter(|p| p.image_file).count();
        let has_path = self
            .param("path")
            .is_some_and(|p| matches!(p.ty, ParamType::Path { .. }));
        if marked == 0 || (marked == 1 && self.sink && has_path) {
            return Ok(());
        }
        Err(format!(
            "node kind \"{}\" marks {marked} input(s) as written to an image file: at most \
             one, and only on a sink with a `path` param",
            self.name
        ))
    }
}

/// A set of node kinds: the built-in ones and any added at run time. It is an ordinary
/// value, passed to whatever needs to look kinds up (the compiler, the docs, the editor);
/// a compiled [`Pass`](crate::Pass) holds its kind, so executing a plan needs no registry.
#[derive(Clone, Debug, Default)]
pub struct Registry {
    kinds: Vec<Arc<NodeKind>>,
    /// The graphs of the group kinds among `kinds`.
    groups: Vec<Arc<Group>>,
}

impl Registry {
    /// The kinds built into lumagraph.
    pub fn with_builtins() -> Self {
        Self {
            kinds: builtin_kinds().into_iter().map(Arc::new).collect(),
            groups: Vec::new(),
        }
    }

    /// Adds a kind.
    ///
    /// # Errors
    /// When a kind of that name is already registered, or the kind repeats a port or
    /// param name.
    pub fn add(&mut self, kind: NodeKind) -> Result<(), String> {
        if self.get(kind.name).is_some() {
            return Err(format!(
                "a node kind called \"{}\" is already registered",
                kind.name
            ));
        }
        let mut names: Vec<(&str, &str)> = kind
            .inputs
            .iter()
            .map(|p| ("input", p.name))
            .chain(kind.outputs.iter().map(|p| ("output", p.name)))
            .chain(kind.params.iter().map(|p| ("param", p.name)))
            .collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!(
                "node kind \"{}\" declares {} \"{}\" twice",
                kind.name, w[0].0, w[0].1
            ));
        }
        kind.check_image_file()?;
        self.kinds.push(Arc::new(kind));
        Ok(())
    }

    /// Adds a group kind: its node kind made from its interface ([`Group::kind`]).
    ///
    /// # Errors
    /// As [`Registry::add`] and [`Group::kind`].
    pub fn add_group(&mut self, group: Group) -> Result<(), String> {
        self.add(group.kind()?)?;
        self.groups.push(Arc::new(group));
        Ok(())
    }

    /// Adds a group kind, or replaces the one of that name (its file was edited).
    ///
    /// # Errors
    /// As [`Registry::add_group`]; the registry is unchanged then.
    pub fn set_group(&mut self, group: Group) -> Result<(), String> {
        let kind = group.kind()?;
        let name = group.name;
        self.kinds.retain(|k| k.name != name);
        self.groups.retain(|g| g.name != name);
        self.add(kind)?;
        self.groups.push(Arc::new(group));
        Ok(())
    }

    /// The group of the group kind called `name`.
    pub fn group(&self, name: &str) -> Option<&Arc<Group>> {
        self.groups.iter().find(|g| g.name == name)
    }

    /// The kind called `name`.
    pub fn get(&self, name: &str) -> Option<&Arc<NodeKind>> {
        self.kinds.iter().find(|k| k.name == name)
    }

    /// Every kind, in registry order (built-ins grouped by category, then those added).
    pub fn kinds(&self) -> &[Arc<NodeKind>] {
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
    PortType::Scalar,
    PortType::Vector,
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
        shader: Some(Shader::File(shader)),
        ..post_node(name, category, doc, params)
    }
}

/// A post node of the same ports with an implementation of its own (several passes,
/// node-owned images) in the render crate.
pub(crate) fn post_node(
    name: &'static str,
    category: Category,
    doc: &'static str,
    params: Vec<ParamDef>,
) -> NodeKind {
    NodeKind {
        name,
        category,
        doc,
        inputs: vec![InputDef::new("color", COLOR_TYPES, "linear color")],
        outputs: vec![OutputDef::new(
            "color",
            PortType::HdrColor,
            "the filtered linear color",
        )],
        params,
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}

fn builtin_kinds() -> Vec<NodeKind> {
    [
        input::kinds(),
        render::kinds(),
        denoise::kinds(),
        color::kinds(),
        combine::kinds(),
        effects::kinds(),
        transform::kinds(),
        analysis::kinds(),
        output::kinds(),
    ]
    .concat()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Output` declares the input it writes alone as an image file, `MultiLayerOutput`
    /// (several images in one file) none; a mark where no such file is written is refused.
    #[test]
    fn image_file_inputs_are_declared_and_checked() {
        let r = Registry::with_builtins();
        let input = |k: &str| r.get(k).unwrap().image_file_input().map(|i| i.name);
        assert_eq!(input("Output"), Some("color"));
        assert_eq!(input("MultiLayerOutput"), None);
        for kind in r.kinds() {
            assert_eq!(kind.check_image_file(), Ok(()), "{}", kind.name);
        }
        let mut marked = post_node("Marked", Category::Color, "a test kind", Vec::new());
        marked.inputs[0] = marked.inputs[0].clone().image_file();
        let e = Registry::default().add(marked).unwrap_err();
        assert!(
            e.starts_with("node kind \"Marked\" marks 1 input(s)"),
            "{e}"
        );
    }
}
