//! Output nodes: files written out of the graph.

use super::{ANY_IMAGE, Category, InputDef, NodeKind, ParamDef, Reach};
use crate::types::ParamType;

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![output()]
}

fn output() -> NodeKind {
    NodeKind {
        name: "Output",
        category: Category::Output,
        doc: "Writes its input to a file: PNG (8-bit sRGB) or EXR (32-bit float RGBA), chosen \
              by the extension. Linear input is sRGB-encoded (clipped) for PNG and written \
              as is to EXR; display-encoded input is written as is to both.",
        inputs: vec![InputDef::new("color", ANY_IMAGE, "image to write")],
        outputs: vec![],
        params: vec![ParamDef {
            name: "path",
            ty: ParamType::Path {
                default: "out.png",
                extensions: &["png", "exr"],
            },
            doc: "file to write, relative to the output folder (`--out`) and inside it",
        }],
        sink: true,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}
