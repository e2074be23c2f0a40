//! Denoising nodes.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, Reach};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![denoise()]
}

fn denoise() -> NodeKind {
    NodeKind {
        name: "Denoise",
        category: Category::Denoise,
        doc: "Edge-avoiding à-trous wavelet filter (Dammertz et al. 2010, with SVGF's \
              weights): `iterations` passes of the 5×5 B3-spline kernel with holes of \
              1, 2, 4, 8, 16… pixels. Color is divided by the albedo before filtering and \
              multiplied back after; each tap is weighted by luminance (scaled by the \
              pixel's standard deviation when `variance_guided`), normal and depth \
              differences. Two ping-pong images are the only memory it adds.",
        inputs: vec![
            InputDef::new(
                "color",
                COLOR_TYPES,
                "noisy linear color (e.g. Accumulate.color)",
            ),
            InputDef::new(
                "albedo",
                &[PortType::Albedo],
                "first-hit albedo (GBuffer or PathTrace)",
            ),
            InputDef::new(
                "normal",
                &[PortType::Normal],
                "first-hit world-space normal",
            ),
            InputDef::new(
                "depth",
                &[PortType::Depth],
                "first-hit distance along the camera ray",
            ),
            InputDef::new(
                "variance",
                &[PortType::Variance],
                "variance of the color's mean (Accumulate.variance); without it the \
                 luminance tolerance is the fixed one, as with `variance_guided` off",
            )
            .optional(),
        ],
        outputs: vec![OutputDef::new(
            "color",
            PortType::HdrColor,
            "filtered linear color",
        )],
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
                      (SVGF) when `variance` is connected; off: a fixed tolerance halved \
                      every pass (Dammertz)",
            },
        ],
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        // Pass i reads 2 × 2^i pixels away (its 5×5 kernel's taps `step` apart).
        reach: Reach::Within(|p| {
            let n = u32::try_from(p.int("iterations")).unwrap_or(0).min(16);
            2 * ((1 << n) - 1)
        }),
    }
}
