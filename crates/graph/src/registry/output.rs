//! Output nodes: files written out of the graph: `Output` (one image, PNG or EXR) and
//! `MultiLayerOutput` (several images as the layers of one EXR).

use super::{ANY_IMAGE, Category, InputDef, NodeKind, ParamDef, Reach};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![output(), multi_layer_output()]
}

fn output() -> NodeKind {
    NodeKind {
        name: "Output",
        category: Category::Output,
        doc: "Writes its input to a file: PNG (8-bit sRGB) or EXR, chosen by the extension. \
              Linear input is sRGB-encoded (clipped) for PNG and written as is to EXR; \
              display-encoded input is written as is to both. An EXR is RGBA, or, when the \
              input was read from an EXR file (through nodes that pass their first input \
              on), the layer it was read as: its part name, view, channel names and \
              display window, and the header attributes that stay true (what does not is \
              named in a note); `data_window` and `type` choose the rest.",
        inputs: vec![InputDef::new("color", ANY_IMAGE, "image to write").image_file()],
        outputs: vec![],
        params: vec![
            ParamDef {
                name: "path",
                ty: ParamType::Path {
                    default: "out.png",
                    extensions: &["png", "exr"],
                },
                doc: "file to write, relative to the output folder (`--out`) and inside it",
            },
            ParamDef {
                name: "type",
                ty: ParamType::Enum {
                    default: "float",
                    options: OUTPUT_SAMPLE_TYPES,
                },
                doc: "EXR: the channels' sample type",
            },
            data_window_param(),
        ],
        sink: true,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}

/// The EXR compressions `MultiLayerOutput` offers (the footage crate's writer takes these
/// names).
pub const EXR_COMPRESSIONS: &[(&str, &str)] = &[
    (
        "zip",
        "lossless, 16 scan lines a block (Blender's and Nuke's default)",
    ),
    ("piz", "lossless wavelet, best for noisy renders"),
    ("zips", "lossless, one scan line a block"),
    ("rle", "lossless run-length, fast and weak"),
    (
        "pxr24",
        "floats rounded to 24 bits (lossy), halves lossless",
    ),
    ("none", "uncompressed"),
];

/// The sample types the EXR writers offer.
pub const SAMPLE_TYPES: &[(&str, &str)] = &[
    ("half", "16-bit float: colour, normals, albedo"),
    (
        "float",
        "32-bit float: depth, positions, anything needing more than 11 bits",
    ),
    (
        "source",
        "each channel as the file it was read from stores it (half, float or uint; float \
         where it was not read from a file)",
    ),
];

/// `Output`'s sample types: float first, its default.
const OUTPUT_SAMPLE_TYPES: &[(&str, &str)] = &[SAMPLE_TYPES[1], SAMPLE_TYPES[0], SAMPLE_TYPES[2]];

/// The data windows the EXR writers offer.
pub const DATA_WINDOWS: &[(&str, &str)] = &[
    ("display", "the display window: every pixel"),
    (
        "source",
        "the data window of the file the input was read from (pixels outside it are \
         dropped, and the node says how many were not empty)",
    ),
    (
        "auto",
        "the bounding box of the pixels that are not zero in every channel written (an \
         auto-crop, as Nuke's Write node makes)",
    ),
];

/// How `MultiLayerOutput` lays its layers out in parts.
pub const PARTS: &[(&str, &str)] = &[
    (
        "single",
        "every layer in one part, as Blender writes multi-layer EXR",
    ),
    (
        "per_layer",
        "one part a layer, named as the part it was read from or as the layer, as Nuke \
         writes multi-part EXR",
    ),
];

fn data_window_param() -> ParamDef {
    ParamDef {
        name: "data_window",
        ty: ParamType::Enum {
            default: "display",
            options: DATA_WINDOWS,
        },
        doc: "EXR: the data window written (the display window is the image's)",
    }
}

/// How many layers beside `color` a `MultiLayerOutput` takes.
pub const EXTRA_LAYERS: usize = 4;

/// The params of extra layer `i` (1-based): its name, its channels, its sample type.
pub const LAYER_PARAMS: [[&str; 3]; EXTRA_LAYERS] = [
    ["layer1_name", "layer1_channels", "layer1_type"],
    ["layer2_name", "layer2_channels", "layer2_type"],
    ["layer3_name", "layer3_channels", "layer3_type"],
    ["layer4_name", "layer4_channels", "layer4_type"],
];

/// The input ports of the extra layers.
pub const LAYER_INPUTS: [&str; EXTRA_LAYERS] = ["layer1", "layer2", "layer3", "layer4"];

/// The layer name and channels a `MultiLayerOutput` gives an input of type `ty` whose
/// params leave them empty: Blender's names for its passes, and the channels it writes
/// them with.
pub fn default_layer(ty: PortType, index: usize) -> (String, &'static str) {
    match ty {
        PortType::Albedo => ("DiffCol".into(), "R G B"),
        PortType::Normal => ("Normal".into(), "X Y Z"),
        PortType::Depth => ("Depth".into(), "Z"),
        PortType::Variance => ("Variance".into(), "R G B"),
        PortType::Vector => ("Vector".into(), "X Y Z W"),
        PortType::Scalar => (format!("Layer{index}"), "X"),
        _ => (format!("Layer{index}"), "R G B A"),
    }
}

fn multi_layer_output() -> NodeKind {
    let mut inputs = vec![InputDef::new(
        "color",
        ANY_IMAGE,
        "the main image: the root layer (`R G B A`), or the layer `color_name` names",
    )];
    inputs.extend(LAYER_INPUTS.iter().map(|name| {
        InputDef::new(
            name,
            ANY_IMAGE,
            "another layer of the file (params `layerN_name`, `_channels`, `_type`)",
        )
        .optional()
    }));
    let mut params = vec![
        ParamDef {
            name: "path",
            ty: ParamType::Path {
                default: "out.exr",
                extensions: &["exr"],
            },
            doc: "file to write, relative to the output folder (`--out`) and inside it; \
                  `####` stands for the frame number",
        },
        ParamDef {
            name: "compression",
            ty: ParamType::Enum {
                default: "zip",
                options: EXR_COMPRESSIONS,
            },
            doc: "the file's compression",
        },
        data_window_param(),
        ParamDef {
            name: "parts",
            ty: ParamType::Enum {
                default: "single",
                options: PARTS,
            },
            doc: "one part, or one part a layer (a multi-part file)",
        },
        ParamDef {
            name: "color_name",
            ty: ParamType::Text { default: "" },
            doc: "the main image's layer name; empty: the name it was read with from an EXR \
                  file, else the root layer (`R G B A`, what every reader shows first); e.g. \
                  `ViewLayer.Combined` as Blender names it",
        },
        ParamDef {
            name: "color_type",
            ty: ParamType::Enum {
                default: "half",
                options: SAMPLE_TYPES,
            },
            doc: "the main image's sample type",
        },
    ];
    for [name, channels, ty] in LAYER_PARAMS {
        params.push(ParamDef {
            name,
            ty: ParamType::Text { default: "" },
            doc: "the layer's name; empty: the name it was read with from an EXR file, else \
                  Blender's name for what is wired in (`DiffCol` for an albedo, `Normal`, \
                  `Depth`, `Vector`, else `LayerN`)",
        });
        params.push(ParamDef {
            name: channels,
            ty: ParamType::Text { default: "" },
            doc: "its channels, by name, separated by spaces (`u v`, `Z`); empty: the \
                  channels it was read with from an EXR file, else `R G B A` for colour, \
                  `R G B` for an albedo, `X Y Z` for a normal, `Z` for a depth, `X Y Z W` \
                  for a vector, `X` for a scalar; at most as many as the image has",
        });
        params.push(ParamDef {
            name: ty,
            ty: ParamType::Enum {
                default: "float",
                options: SAMPLE_TYPES,
            },
            doc: "its sample type",
        });
    }
    NodeKind {
        name: "MultiLayerOutput",
        category: Category::Output,
        doc: "Writes its inputs as the named layers of one EXR file, in one part (as \
              Blender's multi-layer EXR) or one part a layer (as Nuke's multi-part EXR): \
              `color` and up to four more inputs, each named by its params, else as it was \
              read from an EXR file (through nodes that pass their first input on), else \
              as Blender names its passes (`color` the root layer). Each layer half, float \
              or as read; the data window the display window, the source's or an \
              auto-crop; the source's display window and header attributes where they stay \
              true (what does not is named in a note); `chromaticities` Rec. 709. Linear \
              input is written as it is, display-encoded input too.",
        inputs,
        outputs: vec![],
        params,
        sink: true,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}
