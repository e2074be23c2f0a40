//! Analysis nodes: images measured against a reference.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, Reach, post_node};
use crate::types::{ParamValue, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![difference()]
}

fn difference() -> NodeKind {
    NodeKind {
        inputs: vec![
            InputDef::new("color", COLOR_TYPES, "the linear image measured"),
            InputDef::new(
                "reference",
                COLOR_TYPES,
                "the linear reference, of the same size (an ImageInput reads one from a file)",
            ),
        ],
        outputs: vec![OutputDef::new(
            "heat",
            PortType::LdrColor,
            "the per-pixel error as a heat map (inferno colours: black none, yellow \
             `max_error` or more)",
        )],
        params: vec![
            ParamDef::choice(
                "metric",
                "relmse",
                &[
                    (
                        "relmse",
                        "mean over pixels and rgb of (x − ref)² / (ref² + 0.01)",
                    ),
                    ("rmse", "root of the mean over pixels and rgb of (x − ref)²"),
                ],
                "the error measured (and mapped per pixel, before any root)",
            ),
            ParamDef::float(
                "max_error",
                1.0,
                [1e-12, 1e12],
                "per-pixel error shown at the top of the heat map",
            ),
            ParamDef::int(
                "decades",
                4,
                [1, 12],
                "powers of ten the heat map spans below `max_error` (log scale)",
            ),
        ],
        ..post_node(
            "Difference",
            Category::Analysis,
            "Measures an image against a reference (a file through an ImageInput, or another \
             node's output): the metric over the whole image (printed by `lumagraph \
             render`, shown in the editor beside the preview) and a heat map of the \
             per-pixel error on a log scale. The node runs when its heat map is used: \
             connect it to an Output, or preview it in the editor.",
            Vec::new(),
        )
    }
    .with_example(&[("max_error", ParamValue::Float(10.0))])
    .with_reach(Reach::Image("it measures the whole image"))
}
