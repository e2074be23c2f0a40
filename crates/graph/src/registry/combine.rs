//! Combine nodes: two images blended, arithmetic on one.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, ParamDef, post_filter};
use crate::types::ParamValue;

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![mix(), math()]
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
