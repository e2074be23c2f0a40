//! Denoising nodes.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, Reach};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![denoise(), regression()]
}

/// The inputs of a denoiser guided by the G-buffer: the noisy color, the first hit's
/// albedo, normal and depth, and optionally the variance of the color's mean (`variance`
/// says what the kind does with it).
fn guided_inputs(variance: &'static str) -> Vec<InputDef> {
    vec![
        InputDef::new(
            "color",
            COLOR_TYPES,
            "noisy linear color (e.g. Accumulate.color)",
        ),
        InputDef::new(
            "albedo",
            &[PortType::Albedo],
            "first-hit albedo (GBuffer or PathTrace); alpha 2 marks emitters",
        ),
        InputDef::new(
            "normal",
            &[PortType::Normal],
            "first-hit world-space normal",
        ),
        InputDef::new(
            "depth",
            &[PortType::Depth],
            "first-hit distance along the camera ray (0: nothing hit)",
        ),
        InputDef::new("variance", &[PortType::Variance], variance).optional(),
    ]
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
        inputs: guided_inputs(
            "variance of the color's mean (Accumulate.variance); without it the luminance \
             tolerance is the fixed one, as with `variance_guided` off",
        ),
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

fn regression() -> NodeKind {
    NodeKind {
        name: "RegressionDenoise",
        category: Category::Denoise,
        doc: "Per-pixel first-order feature regression (after NFOR, Bitterli et al. 2016): \
              around each pixel, the color divided by the albedo is fitted by weighted least \
              squares as an affine function of the screen offset, the relative depth change, \
              the normal and the albedo over a (2 `radius` + 1)² window, and the fit at the pixel, times \
              the albedo, is the output. Diffuse light changes smoothly with the normal, so \
              curved surfaces are averaged where Denoise's normal edge-stop refuses to. \
              Pixels within one pixel of a light's edge, whose color mixes the light and \
              its surroundings, are passed through. Slower than Denoise; three images are \
              the memory it adds.",
        inputs: guided_inputs(
            "variance of the color's mean (Accumulate.variance), for the luminance weight; \
             without it that weight is off",
        ),
        outputs: vec![OutputDef::new(
            "color",
            PortType::HdrColor,
            "filtered linear color",
        )],
        params: vec![
            ParamDef::int(
                "radius",
                10,
                [1, 32],
                "window radius in pixels; the spatial weight is a Gaussian of σ = radius / 2",
            ),
            ParamDef::int(
                "stride",
                1,
                [1, 8],
                "distance between the window's taps (2 reads a quarter of the pixels)",
            ),
            ParamDef::float(
                "sigma_normal",
                0.5,
                [0.0, 10.0],
                "normal tolerance: weight exp(-(1 - n_p·n_q) / sigma_normal); the fit \
                 handles smooth normal changes, this only parts creases",
            ),
            ParamDef::float(
                "sigma_depth",
                0.05,
                [0.0, 10.0],
                "depth tolerance, relative to the pixel's depth, of a tap's distance from \
                 the pixel's tangent plane (parts silhouettes)",
            ),
            ParamDef::float(
                "sigma_color",
                3.0,
                [0.0, 1000.0],
                "luminance tolerance: a tap whose 5×5 mean luminance differs from the \
                 pixel's by more than the noise of the two means is weighted down, in units \
                 of that noise's standard deviation (needs `variance`; 0 = off)",
            ),
            ParamDef::float(
                "ridge",
                1e-3,
                [0.0, 1.0],
                "ridge term, relative to each feature's spread in the window",
            ),
        ],
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        // The window's taps, their 5×5 guide (2 more) and the light-boundary test of the
        // guide's pixels (1 more).
        reach: Reach::Within(|p| u32::try_from(p.int("radius")).unwrap_or(0) + 3),
    }
}
