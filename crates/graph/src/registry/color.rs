//! Colour nodes: exposure, vignette and tone mapping.

use super::{
    COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, TONEMAP_OPERATORS, post_filter,
};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![exposure(), vignette(), tonemap()]
}

fn exposure() -> NodeKind {
    post_filter(
        "Exposure",
        Category::Color,
        "Scales linear color by 2^ev.",
        vec![ParamDef {
            name: "ev",
            ty: ParamType::Float {
                default: 0.0,
                min: -20.0,
                max: 20.0,
            },
            doc: "exposure in stops; +1 doubles the brightness",
        }],
        "post/exposure.wgsl",
    )
}

fn vignette() -> NodeKind {
    post_filter(
        "Vignette",
        Category::Color,
        "Darkens the image towards its corners, as a lens does: color × (1 − strength · s), \
         s rising smoothly from 0 at `radius` to 1 at `radius + softness`, distances in units \
         of half the image diagonal from its center.",
        vec![
            ParamDef {
                name: "strength",
                ty: ParamType::Float {
                    default: 0.5,
                    min: 0.0,
                    max: 1.0,
                },
                doc: "fraction of the light removed where the vignette is full",
            },
            ParamDef {
                name: "radius",
                ty: ParamType::Float {
                    default: 0.6,
                    min: 0.0,
                    max: 2.0,
                },
                doc: "where darkening starts, in half-diagonals from the center",
            },
            ParamDef {
                name: "softness",
                ty: ParamType::Float {
                    default: 0.6,
                    min: 0.001,
                    max: 2.0,
                },
                doc: "how far beyond `radius` it reaches full strength",
            },
        ],
        "post/vignette.wgsl",
    )
}

fn tonemap() -> NodeKind {
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
        renders_scene: false,
        shader: None,
    }
}
