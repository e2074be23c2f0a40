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
              decoded from sRGB to linear; `colorspace` names another colour space (OpenColorIO). The image sets the size of everything downstream. \
              An EXR is read as compositors read it: its display window is the image (the \
              data window placed at its offset, transparent black around it), its colour is \
              converted from its `chromaticities` to Rec. 709, luminance/chroma images are \
              reconstructed, and any part or layer can be chosen (`lumagraph info FILE` lists \
              them): a colour layer comes out on `color`, a one-channel layer (a depth, a \
              matte, a luminance) on `scalar`, a two- to four-channel one (motion, normals) \
              on `vector`. The path may hold a frame number pattern (`####`, `%04d`, `$F4`): \
              a sequence, run by `lumagraph render --frames`, the editor's frame control \
              and Python's `render_frames`.",
        inputs: vec![],
        outputs: vec![
            OutputDef::new(
                "color",
                PortType::HdrColor,
                "a colour layer, linear Rec. 709 RGBA",
            ),
            OutputDef::new(
                "scalar",
                PortType::Scalar,
                "a one-channel layer (depth `Z`, a matte, luminance `Y`)",
            ),
            OutputDef::new(
                "vector",
                PortType::Vector,
                "a two- to four-channel layer that is not colour (motion `u v`, normals)",
            ),
        ],
        params: vec![
            ParamDef {
                name: "path",
                ty: ParamType::Path {
                    default: "image.exr",
                    extensions: &["exr", "hdr", "png", "jpg", "jpeg"],
                },
                doc: "image file, relative to the graph file's folder; `####` (or `%04d`, \
                      `$F4`) stands for the frame number",
            },
            ParamDef {
                name: "layer",
                ty: ParamType::Text { default: "" },
                doc: "EXR: the layer to read, by its name (`depth`, `forward`, \
                      `ViewLayer.Combined`, `Depth.Z`, a part's name); empty: the colour image",
            },
            ParamDef {
                name: "view",
                ty: ParamType::Text { default: "" },
                doc: "EXR: the view of a stereo or multi-view file (`left`, `right`); empty: \
                      the default view",
            },
            ParamDef {
                name: "colorspace",
                ty: ParamType::Text { default: "" },
                doc: "the colour space of the file's colour, converted into the working space \
                      on the GPU by OpenColorIO: a colour space (or alias, or role) of the \
                      config (`ACEScg`, `sRGB - Texture`, `Raw` for none); `file rules`: \
                      the config's file rules choose by the path; empty: the file says (EXR \
                      from its `chromaticities`, Rec. 709 without; PNG and JPEG sRGB; HDR \
                      linear Rec. 709). A named space takes the values as stored, ignoring \
                      the EXR's `chromaticities`",
            },
            super::color::ocio_config(),
        ],
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Image("it reads its file whole"),
    }
}
