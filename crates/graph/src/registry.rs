//! The node kinds the graph knows: their ports, params and docs.
//!
//! The registry is data, not code: the compiler, the CLI's `nodes` listing, the generated
//! docs and the editor's menus and inspector all read these declarations, so a kind is
//! described in exactly one place. The GPU implementation of each kind lives in the
//! render crate under the same name.

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

fn builtin_kinds() -> Vec<NodeKind> {
    vec![
        NodeKind {
            name: "ImageInput",
            category: Category::Input,
            doc: "Reads an image file. EXR and Radiance .hdr are taken as linear; PNG and JPEG are \
                  decoded from sRGB to linear. The image sets the size of everything downstream.",
            inputs: &[],
            outputs: &[OutputDef {
                name: "color",
                ty: PortType::HdrColor,
                doc: "the image, linear RGB",
            }],
            params: vec![ParamDef {
                name: "path",
                ty: ParamType::Path {
                    default: "image.exr",
                    extensions: &["exr", "hdr", "png", "jpg", "jpeg"],
                },
                doc: "image file, relative to the graph file's folder",
            }],
            sink: false,
            history: false,
        },
        NodeKind {
            name: "PathTrace",
            category: Category::Render,
            doc: "Path traces the scene (`--scene`) on the GPU: BVH traversal in WGSL, next-event \
                  estimation with multiple importance sampling, Russian roulette. Each frame adds \
                  `samples_per_frame` samples per pixel and outputs their mean; feed it to \
                  Accumulate for a progressive render. Image size, bounces and seed come from \
                  the scene.",
            inputs: &[],
            outputs: &[
                OutputDef {
                    name: "color",
                    ty: PortType::HdrColor,
                    doc: "this frame's radiance estimate",
                },
                OutputDef {
                    name: "albedo",
                    ty: PortType::Albedo,
                    doc: "base color at the first hit through the pixel center; alpha 2 on emitters, 1 \
                          elsewhere (0 on a miss)",
                },
                OutputDef {
                    name: "normal",
                    ty: PortType::Normal,
                    doc: "world-space shading normal at that hit (0 on a miss)",
                },
                OutputDef {
                    name: "depth",
                    ty: PortType::Depth,
                    doc: "distance from the camera to that hit (0 on a miss)",
                },
            ],
            params: vec![
                ParamDef {
                    name: "samples_per_frame",
                    ty: ParamType::Int {
                        default: 4,
                        min: 1,
                        max: 4096,
                    },
                    doc: "samples per pixel in one frame (one dispatch)",
                },
                ParamDef {
                    name: "firefly_clamp",
                    ty: ParamType::Float {
                        default: 0.0,
                        min: 0.0,
                        max: 1e9,
                    },
                    doc: "largest channel value one sample may contribute; 0 is off (on is biased, and the render report says so)",
                },
                ParamDef {
                    name: "env_sampling",
                    ty: ParamType::Enum {
                        default: "importance",
                        options: &[
                            (
                                "importance",
                                "environment map pixels drawn by luminance x solid angle",
                            ),
                            ("uniform", "uniform directions (a baseline for comparisons)"),
                        ],
                    },
                    doc: "how light sampling draws directions from an environment map",
                },
                ParamDef {
                    name: "sampler",
                    ty: ParamType::Enum {
                        default: "sobol",
                        options: &[
                            (
                                "sobol",
                                "Owen-scrambled Sobol points for the pixel, lens, and first-hit \
                                 light and BSDF samples; the other dimensions independent",
                            ),
                            (
                                "independent",
                                "every dimension from a PCG hash stream (a baseline for \
                                 comparisons)",
                            ),
                        ],
                    },
                    doc: "how the random numbers of a path are drawn (docs/pathtracer.md)",
                },
                ParamDef {
                    name: "strategy",
                    ty: ParamType::Enum {
                        default: "mis",
                        options: &[
                            (
                                "mis",
                                "light sampling and BSDF sampling, weighted by the power \
                                 heuristic",
                            ),
                            (
                                "light",
                                "light sampling only: emitters a BSDF-sampled ray hits count \
                                 only after mirrors and interfaces (a check, noisy on glossy \
                                 surfaces)",
                            ),
                            (
                                "bsdf",
                                "BSDF sampling only: emitters count when hit; shadow rays only \
                                 to point, spot and directional lights, which no ray can hit \
                                 (a check, noisy for small lights)",
                            ),
                        ],
                    },
                    doc: "how direct light is estimated; every strategy converges to the same \
                          image (docs/pathtracer.md)",
                },
            ],
            sink: false,
            history: false,
        },
        NodeKind {
            name: "Accumulate",
            category: Category::Render,
            doc: "Running mean of its input over frames (progressive rendering). Sums are kept in \
                  f32 with Kahan compensation, so millions of frames do not drift. Restarts when \
                  the scene, the camera or anything upstream changes. Also estimates the \
                  variance of the mean (for Denoise) when its `variance` output is read.",
            inputs: &[InputDef {
                name: "color",
                accepts: COLOR_TYPES,
                doc: "this frame's estimate",
            }],
            outputs: &[
                OutputDef {
                    name: "color",
                    ty: PortType::HdrColor,
                    doc: "mean of all frames so far",
                },
                OutputDef {
                    name: "variance",
                    ty: PortType::Variance,
                    doc: "variance of that mean per pixel (rgb per channel, alpha of the \
                          luminance), from a Welford second moment over frames; after a single \
                          frame, estimated over the pixel's 3×3 neighborhood (luminance: from the median \
                          absolute deviation)",
                },
            ],
            params: vec![],
            sink: false,
            history: true,
        },
        NodeKind {
            name: "GBuffer",
            category: Category::Render,
            doc: "Rasterizes the scene (`--scene`) from the path tracer's camera: triangles with \
                  their shading normals, spheres tessellated and then intersected exactly per \
                  pixel. Writes what the path tracer's first hit through the pixel center sees, \
                  without tracing a ray; the guides of Denoise. Image size from the scene.",
            inputs: &[],
            outputs: &[
                OutputDef {
                    name: "albedo",
                    ty: PortType::Albedo,
                    doc: "material base color; alpha 2 on emitters, 1 elsewhere (0 where nothing is \
                          hit)",
                },
                OutputDef {
                    name: "normal",
                    ty: PortType::Normal,
                    doc: "world-space shading normal, interpolated vertex normals where the \
                          triangle has them (0 where nothing is hit)",
                },
                OutputDef {
                    name: "depth",
                    ty: PortType::Depth,
                    doc: "distance from the camera along the ray through the pixel center \
                          (0 where nothing is hit)",
                },
            ],
            params: vec![ParamDef {
                name: "sphere_segments",
                ty: ParamType::Int {
                    default: 48,
                    min: 8,
                    max: 512,
                },
                doc: "segments around a sphere's tessellation (the silhouette is exact anyway: \
                      each fragment intersects the true sphere)",
            }],
            sink: false,
            history: false,
        },
        NodeKind {
            name: "Denoise",
            category: Category::Render,
            doc: "Edge-avoiding à-trous wavelet filter (Dammertz et al. 2010, with SVGF's \
                  weights): `iterations` passes of the 5×5 B3-spline kernel with holes of \
                  1, 2, 4, 8, 16… pixels. Color is divided by the albedo before filtering and \
                  multiplied back after; each tap is weighted by luminance (scaled by the \
                  pixel's standard deviation when `variance_guided`), normal and depth \
                  differences. Two ping-pong images are the only memory it adds.",
            inputs: &[
                InputDef {
                    name: "color",
                    accepts: COLOR_TYPES,
                    doc: "noisy linear color (e.g. Accumulate.color)",
                },
                InputDef {
                    name: "albedo",
                    accepts: &[PortType::Albedo],
                    doc: "first-hit albedo (GBuffer or PathTrace)",
                },
                InputDef {
                    name: "normal",
                    accepts: &[PortType::Normal],
                    doc: "first-hit world-space normal",
                },
                InputDef {
                    name: "depth",
                    accepts: &[PortType::Depth],
                    doc: "first-hit distance along the camera ray",
                },
                InputDef {
                    name: "variance",
                    accepts: &[PortType::Variance],
                    doc: "variance of the color's mean (Accumulate.variance); read only when \
                          `variance_guided` is on, but always connected",
                },
            ],
            outputs: &[OutputDef {
                name: "color",
                ty: PortType::HdrColor,
                doc: "filtered linear color",
            }],
            params: vec![
                ParamDef {
                    name: "iterations",
                    ty: ParamType::Int {
                        default: 5,
                        min: 1,
                        max: 8,
                    },
                    doc: "à-trous passes; pass i spaces the kernel's taps 2^i pixels apart",
                },
                ParamDef {
                    name: "sigma_color",
                    ty: ParamType::Float {
                        default: 4.0,
                        min: 0.0,
                        max: 1000.0,
                    },
                    doc: "luminance tolerance: in standard deviations when variance-guided, \
                          else in units of luminance, halved every pass (0 = stop at any \
                          difference)",
                },
                ParamDef {
                    name: "sigma_normal",
                    ty: ParamType::Float {
                        default: 0.02,
                        min: 0.0,
                        max: 10.0,
                    },
                    doc: "normal tolerance: weight exp(-(1 - n_p·n_q) / sigma_normal)",
                },
                ParamDef {
                    name: "sigma_depth",
                    ty: ParamType::Float {
                        default: 0.5,
                        min: 0.0,
                        max: 1000.0,
                    },
                    doc: "depth tolerance, in multiples of the depth change the local gradient \
                          predicts over the tap's offset",
                },
                ParamDef {
                    name: "variance_guided",
                    ty: ParamType::Bool { default: true },
                    doc: "scale the luminance tolerance by the per-pixel standard deviation \
                          (SVGF); off: a fixed tolerance halved every pass (Dammertz)",
                },
            ],
            sink: false,
            history: false,
        },
        NodeKind {
            name: "Exposure",
            category: Category::Color,
            doc: "Scales linear color by 2^ev.",
            inputs: &[InputDef {
                name: "color",
                accepts: COLOR_TYPES,
                doc: "linear color",
            }],
            outputs: &[OutputDef {
                name: "color",
                ty: PortType::HdrColor,
                doc: "color × 2^ev",
            }],
            params: vec![ParamDef {
                name: "ev",
                ty: ParamType::Float {
                    default: 0.0,
                    min: -20.0,
                    max: 20.0,
                },
                doc: "exposure in stops; +1 doubles the brightness",
            }],
            sink: false,
            history: false,
        },
        NodeKind {
            name: "Tonemap",
            category: Category::Color,
            doc: "Maps linear scene color to display color with a tone curve, then applies the \
                  sRGB transfer function.",
            inputs: &[InputDef {
                name: "color",
                accepts: COLOR_TYPES,
                doc: "linear color",
            }],
            outputs: &[OutputDef {
                name: "color",
                ty: PortType::LdrColor,
                doc: "display-encoded color",
            }],
            params: vec![
                ParamDef {
                    name: "operator",
                    ty: ParamType::Enum {
                        default: "aces",
                        options: TONEMAP_OPERATORS,
                    },
                    doc: "tone curve",
                },
                ParamDef {
                    name: "white",
                    ty: ParamType::Float {
                        default: 4.0,
                        min: 1e-3,
                        max: 1e6,
                    },
                    doc: "luminance mapped to white by `reinhard` (other operators ignore it)",
                },
            ],
            sink: false,
            history: false,
        },
        NodeKind {
            name: "Output",
            category: Category::Output,
            doc: "Writes its input to a file: PNG (8-bit sRGB) or EXR (32-bit float RGBA), chosen \
                  by the extension. Linear input is sRGB-encoded (clipped) for PNG and written \
                  as is to EXR; display-encoded input is written as is to both.",
            inputs: &[InputDef {
                name: "color",
                accepts: ANY_IMAGE,
                doc: "image to write",
            }],
            outputs: &[],
            params: vec![ParamDef {
                name: "path",
                ty: ParamType::Path {
                    default: "out.png",
                    extensions: &["png", "exr"],
                },
                doc: "file to write, relative to the output folder (`--out`)",
            }],
            sink: true,
            history: false,
        },
    ]
}
