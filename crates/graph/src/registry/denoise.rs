//! Denoising nodes.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, Reach};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![denoise(), regression(), oidn()]
}

/// What a denoiser's albedo guide takes: the G-buffer's, or an EXR layer read as colour.
pub(crate) const GUIDE_ALBEDO: &[PortType] = &[PortType::Albedo, PortType::HdrColor];
/// What a denoiser's normal guide takes: the G-buffer's, or an EXR layer read as a vector.
pub(crate) const GUIDE_NORMAL: &[PortType] = &[PortType::Normal, PortType::Vector];
/// What a denoiser's depth guide takes: the G-buffer's, or an EXR layer read as a scalar.
pub(crate) const GUIDE_DEPTH: &[PortType] = &[PortType::Depth, PortType::Scalar];

/// A denoiser's noisy colour input.
fn noisy_color() -> InputDef {
    InputDef::new(
        "color",
        COLOR_TYPES,
        "noisy linear color (e.g. Accumulate.color)",
    )
}

/// The inputs of a denoiser guided by the G-buffer: the noisy color, the first hit's
/// albedo, normal and depth, and optionally the variance of the color's mean (`variance`
/// says what the kind does with it).
fn guided_inputs(variance: &'static str) -> Vec<InputDef> {
    vec![
        noisy_color(),
        InputDef::new(
            "albedo",
            GUIDE_ALBEDO,
            "first-hit albedo (GBuffer or PathTrace, or an EXR layer); alpha 2 marks emitters",
        ),
        InputDef::new(
            "normal",
            GUIDE_NORMAL,
            "first-hit world-space normal (GBuffer, PathTrace, or an EXR layer)",
        ),
        InputDef::new(
            "depth",
            GUIDE_DEPTH,
            "first-hit distance along the camera ray (0: nothing hit); without it (a \
             render made elsewhere that has none) depth guides nothing",
        )
        .optional(),
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

/// OIDN 2's quality presets, as its API names them (`OIDN_QUALITY_*`).
const OIDN_QUALITIES: &[(&str, &str)] = &[
    ("default", "the library's choice (high on the CPU)"),
    ("high", "for final frames"),
    ("balanced", "faster, for interactive rendering"),
    ("fast", "fastest, for previews"),
];

fn oidn() -> NodeKind {
    NodeKind {
        name: "OIDN",
        category: Category::Denoise,
        doc: "Intel Open Image Denoise 2: its `RT` filter, a neural network trained on \
              path-traced images, run on the CPU. The images go to the host and back around \
              this node (the inputs are read back, the result uploaded); the result is kept \
              and uploaded again while the inputs and params do not change. The library is \
              loaded at run time: `bash scripts/setup.sh` fetches it, or \
              `LUMAGRAPH_OIDN_LIB` names a libOpenImageDenoise.so (2.x); without it the \
              node fails saying so.",
        inputs: vec![
            noisy_color(),
            InputDef::new(
                "albedo",
                GUIDE_ALBEDO,
                "first-hit albedo guide (GBuffer or PathTrace, or an EXR layer); rgb only",
            )
            .optional(),
            InputDef::new(
                "normal",
                GUIDE_NORMAL,
                "first-hit normal guide, world or camera space (needs `albedo` too: OIDN \
                 takes color, color + albedo, or color + albedo + normal)",
            )
            .optional(),
        ],
        outputs: vec![OutputDef::new(
            "color",
            PortType::HdrColor,
            "denoised linear color (alpha: the input's)",
        )],
        params: vec![
            ParamDef::choice(
                "quality",
                "high",
                OIDN_QUALITIES,
                "OIDN's quality preset (`quality`)",
            ),
            ParamDef {
                name: "prefilter",
                ty: ParamType::Bool { default: false },
                doc: "denoise the albedo and normal guides first, each with an RT filter of \
                      its own, then the color with them (OIDN's prefiltering, for noisy \
                      guides such as a path tracer's AOVs); off: the guides are taken as \
                      they are",
            },
            ParamDef {
                name: "clean_aux",
                ty: ParamType::Bool { default: true },
                doc: "tell OIDN the guides are noise-free (`cleanAux`): the G-buffer's are, \
                      and so are prefiltered ones; off: OIDN's own mode for noisy guides \
                      (a renderer's AOVs taken as they are)",
            },
            ParamDef {
                name: "hdr",
                ty: ParamType::Bool { default: true },
                doc: "the color is HDR, linear and unbounded (OIDN's `hdr`); off: in [0, 1]",
            },
        ],
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Image("its network reads far around each pixel"),
    }
}
