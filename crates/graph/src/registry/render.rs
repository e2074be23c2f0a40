//! Render nodes: the path tracer, progressive accumulation and the G-buffer.

use super::{COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, Reach};
use crate::types::{ParamType, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![path_trace(), accumulate(), gbuffer(), temporal_reuse()]
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
            )
            .rec709(),
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
            OutputDef::new(
                "samples",
                PortType::HdrColor,
                "where adaptive sampling put its samples: rgb the share of the frames so far \
                  that sampled the pixel (1 everywhere without `adaptive_error`), alpha its \
                  samples per pixel",
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
            sampler_param(),
            replicates_param(),
            adaptive_error_param(),
            adaptive_min_spp_param(),
            intersector_param(),
            schedule_param(),
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
        ],
        sink: false,
        history: false,
        renders_scene: true,
        shader: None,
        example: Vec::new(),
        // Adaptive sampling stops a pixel by the error over its 5×5 neighborhood.
        reach: Reach::Within(|p| {
            if p.float("adaptive_error") > 0.0 {
                2
            } else {
                0
            }
        }),
    }
}

/// `PathTrace`'s `adaptive_error` param.
fn adaptive_error_param() -> ParamDef {
    ParamDef {
        name: "adaptive_error",
        ty: ParamType::Float {
            default: 0.0,
            min: 0.0,
            max: 10.0,
        },
        doc: "adaptive sampling: a pixel stops taking samples once the relative error \
          of its mean, estimated from two independent halves of its frames and \
          pooled over its 5×5 neighborhood, is below this (per channel, the standard \
          deviation of the mean over √(mean² + 0.01), the weight relMSE gives it: 0.02 \
          stops pixels near a relMSE of 4e-4); 0 is off. On, the \
          frames alternate two Sobol replicates (as `replicates: 2`) and skipped \
          pixels output alpha 0, which Accumulate does not add (docs/pathtracer.md)",
    }
}

/// `PathTrace`'s `intersector` param.
fn intersector_param() -> ParamDef {
    ParamDef {
        name: "intersector",
        ty: ParamType::Enum {
            default: "auto",
            options: &[
                (
                    "auto",
                    "the scene and the adapter decide (or `lumagraph render --intersector`)",
                ),
                (
                    "inline",
                    "every primitive tested in code written for the scene (at most 64)",
                ),
                (
                    "host",
                    "Embree on the host's threads (CPU adapters, triangle scenes)",
                ),
                ("binary", "the binary BVH in WGSL (traces everything)"),
                ("wide", "the 8-wide BVH in WGSL (flat scenes)"),
                (
                    "rays",
                    "the device's ray queries (devices that have them, flat scenes)",
                ),
            ],
        },
        doc: "how rays find what they hit; when not `auto` it wins over `--intersector`, and one \
          that cannot trace the scene on this adapter stops the render with the reason (the \
          support matrix in docs/pathtracer.md). Images are the same whichever traces",
    }
}

/// `PathTrace`'s `schedule` param.
fn schedule_param() -> ParamDef {
    ParamDef {
        name: "schedule",
        ty: ParamType::Enum {
            default: "auto",
            options: &[
                (
                    "auto",
                    "the scene and the adapter decide (or `lumagraph render --schedule`)",
                ),
                ("megakernel", "one invocation traces a pixel's whole paths"),
                (
                    "wavefront",
                    "the paths taken one bounce at a time by small kernels (triangle scenes \
                     without media or adaptive sampling, through a WGSL BVH or ray queries)",
                ),
            ],
        },
        doc: "how the path tracer's work is laid out on the device; when not `auto` it wins \
          over `--schedule`, and a wavefront that cannot take the scene stops the render \
          with the reason",
    }
}

/// `PathTrace`'s `adaptive_min_spp` param.
fn adaptive_min_spp_param() -> ParamDef {
    ParamDef {
        name: "adaptive_min_spp",
        ty: ParamType::Int {
            default: 16,
            min: 2,
            max: 1 << 20,
        },
        doc: "samples every pixel takes before adaptive sampling may stop it",
    }
}

/// `PathTrace`'s `sampler` param.
fn sampler_param() -> ParamDef {
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
    }
}

/// `PathTrace`'s `replicates` param.
fn replicates_param() -> ParamDef {
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
          their shading normals, analytic shapes drawn as hulls and then intersected exactly per \
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
            doc: "segments around an analytic shape's hull, a sphere's or a disk's (the \
              silhouette is exact anyway: each fragment intersects the shape itself)",
        }],
        sink: false,
        history: false,
        renders_scene: true,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}

fn temporal_reuse() -> NodeKind {
    NodeKind {
        name: "TemporalReuse",
        category: Category::Render,
        doc: "Keeps a progressive render's samples across camera moves (the editor's \
          preview). Reads Accumulate's mean and the depth (normal, albedo) of the first hit \
          through each pixel center. When the camera moves, the image it last wrote is \
          reprojected into the new view: each pixel's first hit is looked up in the old \
          image, bilinear over the taps whose depth, normal and emitter flag agree and that \
          are not on the border of a surface with an emitter or the background; pixels that \
          were hidden or off screen get no history. The output is the mean of the new \
          frames and that history, weighted by their frame counts, the history's weight \
          capped at `history_frames`, so it fades as new frames arrive. Without a move it \
          passes Accumulate's mean through unchanged.",
        inputs: vec![
            InputDef::new(
                "color",
                &[PortType::HdrColor],
                "Accumulate's mean since the camera last moved",
            ),
            InputDef::new(
                "depth",
                &[PortType::Depth],
                "distance to the first hit through the pixel center (GBuffer or PathTrace)",
            ),
            InputDef::new(
                "normal",
                &[PortType::Normal],
                "shading normal there; when connected, taps whose normals differ by more \
                  than `normal_angle` are dropped too",
            )
            .optional(),
            InputDef::new(
                "albedo",
                &[PortType::Albedo],
                "albedo there, alpha 2 on emitters; when connected, a tap is dropped unless \
                  it is an emitter exactly when the new hit is one (a light set in a ceiling \
                  does not bleed into it)",
            )
            .optional(),
        ],
        outputs: vec![
            OutputDef::new(
                "color",
                PortType::HdrColor,
                "the new frames blended with the reprojected history",
            ),
            OutputDef::new(
                "weight",
                PortType::HdrColor,
                "per pixel: the history's weight in frames (r), the new frames (g) and their \
                  sum (b); r is 0 where the history was dropped",
            ),
        ],
        params: vec![
            ParamDef::int(
                "history_frames",
                64,
                [0, 1 << 20],
                "most frames of reprojected history a pixel keeps (0: no reuse)",
            ),
            ParamDef::float(
                "depth_tolerance",
                0.02,
                [0.0, 1.0],
                "largest relative difference between a tap's depth and the distance the old \
                  camera would see the new hit at",
            ),
            ParamDef::float(
                "normal_angle",
                25.0,
                [0.0, 180.0],
                "largest angle in degrees between a tap's normal and the new one",
            ),
        ],
        sink: false,
        history: true,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Image("the history it reprojects may come from anywhere in the image"),
    }
}
