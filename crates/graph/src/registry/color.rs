//! Colour nodes: exposure, vignette and tone mapping.

use super::{
    COLOR_TYPES, Category, InputDef, NodeKind, OutputDef, ParamDef, Reach, TONEMAP_OPERATORS,
    post_filter, post_node,
};
use crate::types::{ParamType, ParamValue, PortType};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![
        exposure(),
        // Their maths is Rec. 709's (luminance weights, the Planckian white in Rec. 709,
        // the tone curves' matrices): in an ACEScg graph their colour is converted around
        // them (`crate::working_space`).
        auto_exposure().with_rec709_maths(),
        white_balance().with_rec709_maths(),
        cdl().with_rec709_maths(),
        contrast(),
        hue_saturation(),
        lut(),
        vignette(),
        tonemap().with_rec709_maths(),
        color_space(),
        display_view(),
    ]
}

fn white_balance() -> NodeKind {
    post_filter(
        "WhiteBalance",
        Category::Color,
        "Adapts the image from the white of a light source to neutral: the white at \
         `temperature` on the Planckian locus, moved by `tint` along its isotherm, is \
         mapped to the locus's white at 6504 K with the Bradford chromatic adaptation (linear \
         Rec.709 primaries). The defaults change nothing; a lower temperature cools a warm \
         (tungsten-lit) image.",
        vec![
            ParamDef::float(
                "temperature",
                6504.0,
                [1000.0, 15000.0],
                "color temperature of the light the image is corrected for, in kelvin",
            ),
            ParamDef::float(
                "tint",
                0.0,
                [-1.0, 1.0],
                "shift of that white off the locus: + magenta, − green (±1 is 0.02 in CIE 1960 uv)",
            ),
        ],
        "post/white_balance.wgsl",
    )
    .with_example(&[("temperature", ParamValue::Float(4000.0))])
}

fn cdl() -> NodeKind {
    let slope = "ASC CDL slope (gain)";
    let offset = "ASC CDL offset (added after the slope)";
    let power = "ASC CDL power (applied after the offset, to values clipped at 0)";
    post_filter(
        "CDL",
        Category::Color,
        "ASC Color Decision List: out = max(in × slope + offset, 0)^power per channel, \
         then saturation around the Rec.709 luma. The defaults change nothing.",
        vec![
            ParamDef::float("slope_r", 1.0, [0.0, 100.0], slope),
            ParamDef::float("slope_g", 1.0, [0.0, 100.0], slope),
            ParamDef::float("slope_b", 1.0, [0.0, 100.0], slope),
            ParamDef::float("offset_r", 0.0, [-10.0, 10.0], offset),
            ParamDef::float("offset_g", 0.0, [-10.0, 10.0], offset),
            ParamDef::float("offset_b", 0.0, [-10.0, 10.0], offset),
            ParamDef::float("power_r", 1.0, [0.01, 10.0], power),
            ParamDef::float("power_g", 1.0, [0.01, 10.0], power),
            ParamDef::float("power_b", 1.0, [0.01, 10.0], power),
            ParamDef::float(
                "saturation",
                1.0,
                [0.0, 10.0],
                "ASC CDL saturation: 0 grey, 1 unchanged",
            ),
        ],
        "post/cdl.wgsl",
    )
    .with_example(&[
        ("slope_r", ParamValue::Float(1.2)),
        ("slope_b", ParamValue::Float(0.85)),
        ("power_g", ParamValue::Float(1.1)),
        ("saturation", ParamValue::Float(0.7)),
    ])
}

fn lut() -> NodeKind {
    NodeKind {
        params: vec![
            ParamDef {
                name: "path",
                ty: ParamType::Path {
                    default: "look.cube",
                    extensions: &["cube"],
                },
                doc: "the .cube file (LUT_3D_SIZE, optional DOMAIN_MIN/MAX or \
                      LUT_3D_INPUT_RANGE), relative to the graph file's folder",
            },
            ParamDef::choice(
                "interpolation",
                "tetrahedral",
                &[
                    ("trilinear", "the 8 entries around the value"),
                    (
                        "tetrahedral",
                        "the 4 entries of the cube's tetrahedron that holds the value \
                         (keeps greys grey)",
                    ),
                ],
                "how entries between the grid points are found",
            ),
        ],
        ..post_node(
            "LUT",
            Category::Color,
            "Applies a 3D colour lookup table from a .cube file (Adobe/Resolve format): each \
             pixel's rgb, mapped from the file's domain to the grid (clamped), is \
             interpolated between the grid's entries; alpha is kept. The values are looked \
             up as they are: a LUT made for display-referred input belongs where the \
             values are in its domain (e.g. after Exposure and a Math clamp). A bad file \
             is refused with its line number.",
            Vec::new(),
        )
    }
    .with_example(&[("path", ParamValue::Str("assets/luts/film.cube".into()))])
}

fn contrast() -> NodeKind {
    post_filter(
        "Contrast",
        Category::Color,
        "Contrast for linear HDR color: pivot × (c / pivot)^contrast per channel (negative \
         values clipped to 0), so the pivot stays put and ratios to it are raised to \
         `contrast`.",
        vec![
            ParamDef::float(
                "contrast",
                1.0,
                [0.1, 4.0],
                "1 unchanged; above 1 more contrast",
            ),
            ParamDef::float(
                "pivot",
                0.18,
                [1e-4, 100.0],
                "the value that stays (mid grey)",
            ),
        ],
        "post/contrast.wgsl",
    )
    .with_example(&[("contrast", ParamValue::Float(1.5))])
}

fn hue_saturation() -> NodeKind {
    post_filter(
        "HueSaturation",
        Category::Color,
        "Rotates hues by `hue` degrees around the grey axis, scales the distance from grey \
         (the mean of red, green and blue) by `saturation`, then the color by `value`; \
         negative results clipped to 0.",
        vec![
            ParamDef::float("hue", 0.0, [-180.0, 180.0], "hue rotation in degrees"),
            ParamDef::float("saturation", 1.0, [0.0, 10.0], "0 grey, 1 unchanged"),
            ParamDef::float("value", 1.0, [0.0, 100.0], "brightness factor"),
        ],
        "post/hue_saturation.wgsl",
    )
    .with_example(&[("hue", ParamValue::Float(90.0))])
}

fn exposure() -> NodeKind {
    post_filter(
        "Exposure",
        Category::Color,
        "Scales linear color by 2^ev.",
        vec![ParamDef {
            name: "ev",
            ty: ParamType::Float {
                default: 0.0,
                min: -20.0,
                max: 20.0,
            },
            doc: "exposure in stops; +1 doubles the brightness",
        }],
        "post/exposure.wgsl",
    )
    .with_example(&[("ev", ParamValue::Float(1.0))])
}

fn auto_exposure() -> NodeKind {
    post_node(
        "AutoExposure",
        Category::Color,
        "Exposes the image so its mean log luminance maps to `key`, as a camera's meter \
         does: a luminance histogram computed on the GPU (256 bins of log2 luminance over \
         [-24, 16] EV), the mean of its pixels between the `low` and `high` percentiles \
         (so a few bright lights or black borders do not pull it), clamped to \
         [`min_ev`, `max_ev`]. Over frames (the editor's live preview) the exposure moves \
         `adaptation` of the way to that target each frame; the first frame, and the first \
         after accumulation restarts, takes the target at once, so a headless render does \
         not depend on it. The exposure used is measured (`exposure_ev`).",
        vec![
            ParamDef::float(
                "key",
                0.18,
                [1e-4, 1e4],
                "the luminance the mean maps to (0.18: middle grey)",
            ),
            ParamDef::float(
                "low",
                0.1,
                [0.0, 1.0],
                "fraction of the pixels, darkest first, left out of the mean",
            ),
            ParamDef::float(
                "high",
                0.9,
                [0.0, 1.0],
                "fraction of the pixels, darkest first, up to which the mean runs (below \
                 `low`: `low`)",
            ),
            ParamDef::float(
                "min_ev",
                -10.0,
                [-30.0, 30.0],
                "the lowest exposure, in stops",
            ),
            ParamDef::float(
                "max_ev",
                10.0,
                [-30.0, 30.0],
                "the highest exposure, in stops (below `min_ev`: `min_ev`)",
            ),
            ParamDef::float(
                "adaptation",
                0.25,
                [0.0, 1.0],
                "fraction of the way to the target exposure taken each frame (1: at once)",
            ),
        ],
    )
    .with_example(&[("key", ParamValue::Float(0.5))])
    .with_reach(Reach::Image("it meters the whole image"))
}

fn vignette() -> NodeKind {
    post_filter(
        "Vignette",
        Category::Color,
        "Darkens the image towards its corners, as a lens does: color × (1 − strength · s), \
         s rising smoothly from 0 at `radius` to 1 at `radius + softness`, distances in units \
         of half the image diagonal from its center.",
        vec![
            ParamDef {
                name: "strength",
                ty: ParamType::Float {
                    default: 0.5,
                    min: 0.0,
                    max: 1.0,
                },
                doc: "fraction of the light removed where the vignette is full",
            },
            ParamDef {
                name: "radius",
                ty: ParamType::Float {
                    default: 0.6,
                    min: 0.0,
                    max: 2.0,
                },
                doc: "where darkening starts, in half-diagonals from the center",
            },
            ParamDef {
                name: "softness",
                ty: ParamType::Float {
                    default: 0.6,
                    min: 0.001,
                    max: 2.0,
                },
                doc: "how far beyond `radius` it reaches full strength",
            },
        ],
        "post/vignette.wgsl",
    )
    .with_reach(Reach::Image(
        "it darkens by the distance from the image center",
    ))
}

fn tonemap() -> NodeKind {
    NodeKind {
        name: "Tonemap",
        category: Category::Color,
        doc: "Maps linear scene color to display color with a tone curve, then applies the \
          sRGB transfer function.",
        inputs: vec![InputDef::new("color", COLOR_TYPES, "linear color")],
        outputs: vec![OutputDef::new(
            "color",
            PortType::LdrColor,
            "display-encoded color",
        )],
        params: vec![
            ParamDef {
                name: "operator",
                ty: ParamType::Enum {
                    default: "aces",
                    options: TONEMAP_OPERATORS,
                },
                doc: "tone curve",
            },
            ParamDef {
                name: "white",
                ty: ParamType::Float {
                    default: 4.0,
                    min: 1e-3,
                    max: 1e6,
                },
                doc: "luminance mapped to white by `reinhard` (other operators ignore it)",
            },
        ],
        sink: false,
        history: false,
        renders_scene: false,
        shader: None,
        example: Vec::new(),
        reach: Reach::Pixel,
    }
}

/// The `config` param of the OpenColorIO nodes (and `ImageInput`'s).
pub(super) fn ocio_config() -> ParamDef {
    ParamDef {
        name: "config",
        ty: ParamType::Text { default: "" },
        doc: "the OpenColorIO config: empty for the one the `OCIO` environment variable \
              names, else OpenColorIO's CG config with ACES 2.0 \
              (`ocio://cg-config-v4.0.0_aces-v2.0_ocio-v2.5`); `ocio://NAME` for a built-in one \
              (`ocio://studio-config-latest`); `blender` for Blender 4.2's (AgX, Filmic; \
              unpacked by the set-up, or `LUMAGRAPH_BLENDER_OCIO`); or a `config.ocio` \
              file, relative to the graph file's folder",
    }
}

fn color_space() -> NodeKind {
    let mut kind = post_node(
        "ColorSpace",
        Category::Color,
        "Converts colour between two colour spaces of an OpenColorIO config (any to any: \
         ACEScg, ACES2065-1, sRGB encoded, Display P3, a camera's log…), on the GPU with \
         the shader OpenColorIO generates for the conversion. lumagraph's images are \
         scene-linear Rec. 709 (the config's `Linear Rec.709 (sRGB)`), the default of both \
         ends. `lumagraph color` lists a config's colour spaces, displays and views.",
        vec![
            ocio_config(),
            ParamDef {
                name: "from",
                ty: ParamType::Text { default: "" },
                doc: "the colour space the input is in (a name, alias or role of the \
                      config); empty: the working space, scene-linear Rec. 709",
            },
            ParamDef {
                name: "to",
                ty: ParamType::Text { default: "" },
                doc: "the colour space to convert to; empty: the working space",
            },
        ],
    );
    kind.example = vec![("from", ParamValue::Str("ACEScg".into()))];
    kind.outputs[0].doc = "the colour in `to`";
    kind
}

fn display_view() -> NodeKind {
    let mut kind = post_node(
        "DisplayView",
        Category::Color,
        "Renders scene-linear colour for a display through an OpenColorIO view, as \
         Blender's and Nuke's viewers do: `sRGB - Display` with `ACES 2.0 - SDR 100 nits \
         (Rec.709)`, `Un-tone-mapped`, a config's AgX or Filmic, with its looks. The \
         output is display-encoded, ready for a PNG. On the GPU with OpenColorIO's shader.",
        vec![
            ocio_config(),
            ParamDef {
                name: "display",
                ty: ParamType::Text { default: "" },
                doc: "the display (`sRGB - Display`, `Display P3 - Display`…); empty: the \
                      config's default display",
            },
            ParamDef {
                name: "view",
                ty: ParamType::Text { default: "" },
                doc: "the view of that display; empty: the display's default view",
            },
            ParamDef {
                name: "looks",
                ty: ParamType::Text { default: "" },
                doc: "looks to apply (OpenColorIO's syntax: `+look, -other`); empty: the \
                      view's own",
            },
            ParamDef {
                name: "from",
                ty: ParamType::Text { default: "" },
                doc: "the colour space the input is in; empty: the working space, \
                      scene-linear Rec. 709",
            },
        ],
    );
    kind.outputs = vec![OutputDef::new(
        "color",
        PortType::LdrColor,
        "display-encoded colour for `display`",
    )];
    kind
}
