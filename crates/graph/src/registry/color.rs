//! Colour nodes: exposure and tone mapping.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, TONEMAP_OPERATORS};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![exposure(), tonemap()]
}

fn exposure() -> NodeKind {
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
        renders_scene: false,
    }
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
    }
}
