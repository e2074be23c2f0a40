//! Render nodes: the path tracer, progressive accumulation and the G-buffer.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, Reach};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![path_trace(), accumulate(), gbuffer()]
}

fn path_trace() -> NodeKind {
    NodeKind {
        name: "PathTrace",
        category: Category::Render,
        doc: "Path traces the scene (`--scene`) on the GPU: BVH traversal in WGSL, next-event \
          estimation with multiple importance sampling, Russian roulette. Each frame adds \
          `samples_per_frame` samples per pixel and outputs their mean; feed it to \
          Accumulate for a progressive render. Image size, bounces and seed come from \
          the scene.",
        inputs: vec![],
        outputs: vec![
            OutputDef::new(
                "color",
                PortType::HdrColor,
                "this frame's radiance estimate",
            ),
            OutputDef::new(
                "albedo",
                PortType::Albedo,
                "base color at the first hit through the pixel center; alpha 2 on emitters, 1 \
                  elsewhere (0 on a miss)",
            ),
            OutputDef::new(
                "normal",
                PortType::Normal,
                "world-space shading normal at that hit (0 on a miss)",
            ),
            OutputDef::new(
                "depth",
                PortType::Depth,
                "distance from the camera to that hit (0 on a miss)",
            ),
        ],
        params: vec![
            ParamDef {
                name: "samples_per_frame",
                ty: ParamType::Int {
                    default: 4,
                    min: 1,
                    max: 4096,
                },
                doc: "samples per pixel in one frame (one dispatch)",
            },
            ParamDef {
                name: "firefly_clamp",
                ty: ParamType::Float {
                    default: 0.0,
                    min: 0.0,
                    max: 1e9,
                },
                doc: "largest channel value one sample may contribute; 0 is off (on is biased, and the render report says so)",
            },
            ParamDef {
                name: "env_sampling",
                ty: ParamType::Enum {
                    default: "importance",
                    options: &[
                        (
                            "importance",
                            "environment map pixels drawn by luminance x solid angle",
                        ),
                        ("uniform", "uniform directions (a baseline for comparisons)"),
                    ],
                },
                doc: "how light sampling draws directions from an environment map",
            },
            ParamDef {
                name: "sampler",
                ty: ParamType::Enum {
                    default: "sobol",
                    options: &[
                        (
                            "sobol",
                            "Owen-scrambled Sobol points for the pixel, lens, and first-hit \
                         light and BSDF samples; the other dimensions independent",
                        ),
                        (
                            "independent",
                            "every dimension from a PCG hash stream (a baseline for \
                         comparisons)",
                        ),
                    ],
                },
                doc: "how the random numbers of a path are drawn (docs/pathtracer.md)",
            },
            ParamDef {
                name: "strategy",
                ty: ParamType::Enum {
                    default: "mis",
                    options: &[
                        (
                            "mis",
                            "light sampling and BSDF sampling, weighted by the power \
                         heuristic",
                        ),
                        (
                            "light",
                            "light sampling only: emitters a BSDF-sampled ray hits count \
                         only after mirrors and interfaces (a check, noisy on glossy \
                         surfaces)",
                        ),
                        (
                            "bsdf",
                            "BSDF sampling only: emitters count when hit; shadow rays only \
                         to point, spot and directional lights, which no ray can hit \
                         (a check, noisy for small lights)",
                        ),
                    ],
                },
                doc: "how direct light is estimated; every strategy converges to the same \
                  image (docs/pathtracer.md)",
            },
            ParamDef {
                name: "replicates",
                ty: ParamType::Int {
                    default: 1,
                    min: 1,
                    max: 2,
                },
                doc: "independent Sobol replicates: 1, one sequence per pixel (least noise); \
                  2, frames alternate between two, so the mean of the even and that of the \
                  odd frames are independent and Accumulate's `variance_estimate: halves` \
                  is right (raw relMSE a few percent higher; docs/denoise.md)",
            },
        ],
        sink: false,
        history: false,
        renders_scene: true,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}

fn accumulate() -> NodeKind {
    NodeKind {
        name: "Accumulate",
        category: Category::Render,
        doc: "Running mean of its input over frames (progressive rendering). Sums are kept in \
          f32 with Kahan compensation, so millions of frames do not drift. Restarts when \
          the scene, the camera or anything upstream changes. Also estimates the \
          variance of the mean (for Denoise) when its `variance` output is read.",
        inputs: vec![InputDef::new("color", COLOR_TYPES, "this frame's estimate")],
        outputs: vec![
            OutputDef::new("color", PortType::HdrColor, "mean of all frames so far"),
            OutputDef::new(
                "variance",
                PortType::Variance,
                "variance of that mean per pixel (rgb per channel, alpha of the \
                  luminance), as `variance_estimate` says; after a single frame, estimated \
                  over the pixel's 3×3 neighborhood (luminance: from the median absolute \
                  deviation)",
            ),
        ],
        params: vec![ParamDef {
            name: "variance_estimate",
            ty: ParamType::Enum {
                default: "frames",
                options: &[
                    (
                        "frames",
                        "from the spread of the frames (Welford): right for independent \
                         frames; overstates the variance of Sobol-stratified ones \
                         (1.5–3.7× at 4–16 spp)",
                    ),
                    (
                        "halves",
                        "from the difference of the means of the even and the odd frames: \
                         right when those are independent, as with PathTrace's \
                         `replicates: 2` or the independent sampler (with one Sobol \
                         replicate it overstates far more); one degree of freedom per pixel",
                    ),
                ],
            },
            doc: "how the `variance` output is estimated",
        }],
        sink: false,
        history: true,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        // Its variance after one frame is taken over the 3×3 neighborhood.
        reach: Reach::Within(|_| 1),
    }
}

fn gbuffer() -> NodeKind {
    NodeKind {
        name: "GBuffer",
        category: Category::Render,
        doc: "Rasterizes the scene (`--scene`) from the path tracer's camera: triangles with \
          their shading normals, spheres tessellated and then intersected exactly per \
          pixel. Writes what the path tracer's first hit through the pixel center sees, \
          without tracing a ray; the guides of Denoise. Image size from the scene.",
        inputs: vec![],
        outputs: vec![
            OutputDef::new(
                "albedo",
                PortType::Albedo,
                "material base color; alpha 2 on emitters, 1 elsewhere (0 where nothing is \
                  hit)",
            ),
            OutputDef::new(
                "normal",
                PortType::Normal,
                "world-space shading normal, interpolated vertex normals where the \
                  triangle has them (0 where nothing is hit)",
            ),
            OutputDef::new(
                "depth",
                PortType::Depth,
                "distance from the camera along the ray through the pixel center \
                  (0 where nothing is hit)",
            ),
        ],
        params: vec![ParamDef {
            name: "sphere_segments",
            ty: ParamType::Int {
                default: 48,
                min: 8,
                max: 512,
            },
            doc: "segments around a sphere's tessellation (the silhouette is exact anyway: \
              each fragment intersects the true sphere)",
        }],
        sink: false,
        history: false,
        renders_scene: true,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}
