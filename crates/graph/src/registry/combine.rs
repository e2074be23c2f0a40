//! Combine nodes: two images blended, arithmetic on one, channels split and combined.

use super::{
    ANY_IMAGE, COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, post_filter,
};
use crate::types::{ParamValue, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![mix(), math(), split(), combine()]
}

fn split() -> NodeKind {
    let mut kind = post_filter(
        "Split",
        Category::Combine,
        "Splits an image into its four channels, each a grey image (the channel's value in \
         red, green and blue; alpha 1), to be changed on its own and put back with Combine. \
         Depth images hold their value in red.",
        Vec::new(),
        "post/split.wgsl",
    );
    kind.inputs = vec![InputDef::new("color", ANY_IMAGE, "the image split")];
    kind.outputs = ["r", "g", "b", "a"]
        .into_iter()
        .zip([
            "red, as a grey image",
            "green, as a grey image",
            "blue, as a grey image",
            "alpha, as a grey image",
        ])
        .map(|(name, doc)| OutputDef::new(name, PortType::HdrColor, doc))
        .collect();
    kind
}

fn combine() -> NodeKind {
    let mut kind = post_filter(
        "Combine",
        Category::Combine,
        "Makes an image from four: the red channel of `r`, `g` and `b` becomes its red, green \
         and blue, and that of `a` its alpha (1 when `a` is not connected). The inverse of \
         Split; the red channel is the value of Split's grey images and of a depth.",
        Vec::new(),
        "post/combine.wgsl",
    );
    kind.inputs = vec![
        InputDef::new("r", ANY_IMAGE, "red: this image's red channel"),
        InputDef::new("g", ANY_IMAGE, "green: this image's red channel"),
        InputDef::new("b", ANY_IMAGE, "blue: this image's red channel"),
        InputDef::new("a", ANY_IMAGE, "alpha: this image's red channel (else 1)").optional(),
    ];
    kind.outputs = vec![OutputDef::new(
        "color",
        PortType::HdrColor,
        "the combined image",
    )];
    kind
}

fn mix() -> NodeKind {
    let mut kind = post_filter(
        "Mix",
        Category::Combine,
        "Blends `b` over `a` with a blend mode, then mixes that with `a` by `factor`: \
         lerp(a, blend(a, b), factor) per channel; alpha from `a`. Screen and overlay are \
         the [0, 1] formulas applied as they are: on HDR values above 1 they go negative \
         (tone map first, or use `add` for glows).",
        vec![
            ParamDef::choice(
                "mode",
                "mix",
                &[
                    ("mix", "b"),
                    ("add", "a + b"),
                    ("multiply", "a × b"),
                    ("screen", "1 − (1 − a)(1 − b)"),
                    ("overlay", "2ab where a < 0.5, else 1 − 2(1 − a)(1 − b)"),
                    ("difference", "|a − b|"),
                    ("subtract", "a − b"),
                ],
                "blend mode",
            ),
            ParamDef::float("factor", 0.5, [0.0, 1.0], "0: a alone; 1: the blend alone"),
        ],
        "post/mix.wgsl",
    );
    kind.inputs = vec![
        InputDef::new("a", COLOR_TYPES, "the base image"),
        InputDef::new("b", COLOR_TYPES, "the image blended over it (same size)"),
    ];
    kind.with_example(&[
        ("mode", ParamValue::Str("multiply".into())),
        ("factor", ParamValue::Float(1.0)),
    ])
}

fn math() -> NodeKind {
    post_filter(
        "Math",
        Category::Combine,
        "One arithmetic operation with `value` on each of red, green and blue; alpha is kept.",
        vec![
            ParamDef::choice(
                "operation",
                "multiply",
                &[
                    ("add", "c + value"),
                    ("multiply", "c × value"),
                    ("power", "max(c, 0)^value"),
                    ("minimum", "min(c, value)"),
                    ("maximum", "max(c, value)"),
                    ("clamp", "c clamped to [0, value]"),
                ],
                "the operation",
            ),
            ParamDef::float("value", 1.0, [-1e6, 1e6], "the operand"),
        ],
        "post/math.wgsl",
    )
    .with_example(&[
        ("operation", ParamValue::Str("power".into())),
        ("value", ParamValue::Float(2.0)),
    ])
}
