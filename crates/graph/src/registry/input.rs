//! Input nodes: images from files.

use super::{Category, NodeKind, OutputDef, ParamDef, Reach};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![image_input()]
}

fn image_input() -> NodeKind {
    NodeKind {
        name: "ImageInput",
        category: Category::Input,
        doc: "Reads an image file. EXR and Radiance .hdr are taken as linear; PNG and JPEG are \
              decoded from sRGB to linear. The image sets the size of everything downstream.",
        inputs: vec![],
        outputs: vec![OutputDef::new(
            "color",
            PortType::HdrColor,
            "the image, linear RGB",
        )],
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
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Image("it reads its file whole"),
    }
}
