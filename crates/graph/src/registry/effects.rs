//! Filter nodes: sharpening, lens and film effects.

use super::{Category, NodeKind, ParamDef, Reach, post_filter, post_node};
use crate::types::ParamValue;

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![
        blur(),
        sharpen(),
        bloom(),
        chromatic_aberration(),
        film_grain(),
    ]
}

fn blur() -> NodeKind {
    post_node(
        "Blur",
        Category::Filter,
        "Gaussian blur of standard deviation `sigma` pixels, separable: a horizontal pass \
         into a node-owned image, then a vertical one, each with the taps within \
         ceil(3 sigma) pixels, normalized, clamped to the edge. Cost grows with sigma: 6 \
         sigma + 1 taps per pixel and pass.",
        vec![ParamDef::float(
            "sigma",
            2.0,
            [0.3, 64.0],
            "standard deviation in pixels",
        )],
    )
    .with_example(&[("sigma", ParamValue::Float(3.0))])
    .with_reach(Reach::Within(three_sigma))
}

fn bloom() -> NodeKind {
    post_node(
        "Bloom",
        Category::Filter,
        "Energy-conserving multi-scale bloom (after Jimenez 2014): the image is halved \
         `levels` times with a [1 3 3 1]/8 filter per axis, then the levels are added back \
         from the smallest up, each upsampled bilinearly; the sum over the levels, divided \
         by their number, is the glow. out = (1 − intensity) × color + intensity × glow: \
         light is spread, never added (the image's mean is kept, up to the edges). The \
         pyramid's images are node-owned.",
        vec![
            ParamDef::float(
                "intensity",
                0.04,
                [0.0, 1.0],
                "fraction of the light spread into the glow",
            ),
            ParamDef::int(
                "levels",
                6,
                [1, 12],
                "how far the glow reaches: level i is 2^i pixels wide",
            ),
        ],
    )
    .with_example(&[("intensity", ParamValue::Float(0.3))])
    .with_reach(Reach::Image("its pyramid halves the whole image"))
}

fn sharpen() -> NodeKind {
    post_filter(
        "Sharpen",
        Category::Filter,
        "Unsharp mask: c + amount × (c − blur(c)), blur a Gaussian of `sigma` pixels \
         (taps within 3 sigma, clamped to the edge), negative results clipped to 0. Around \
         very bright HDR detail (a sun against the sky) the mask undershoots to black: a \
         dark ring; keep `amount` small there.",
        vec![
            ParamDef::float(
                "amount",
                0.5,
                [0.0, 10.0],
                "how much of the detail is added",
            ),
            ParamDef::float(
                "sigma",
                1.0,
                [0.3, 4.0],
                "the blur's standard deviation in pixels: the size of the detail sharpened",
            ),
        ],
        "post/sharpen.wgsl",
    )
    .with_example(&[("amount", ParamValue::Float(2.0))])
    .with_reach(Reach::Within(three_sigma))
}

fn chromatic_aberration() -> NodeKind {
    post_filter(
        "ChromaticAberration",
        Category::Filter,
        "Lateral chromatic aberration, as a lens with a different magnification per \
         wavelength: red is read at the image center + (p − center) × (1 + strength), blue \
         at × (1 − strength), green in place (bilinear, clamped to the edge), so fringes \
         grow towards the corners.",
        vec![ParamDef::float(
            "strength",
            0.005,
            [-0.1, 0.1],
            "relative magnification difference between green and red (and blue)",
        )],
        "post/chromatic_aberration.wgsl",
    )
    .with_example(&[("strength", ParamValue::Float(0.02))])
    .with_reach(Reach::Image(
        "it moves pixels by their distance from the image center",
    ))
}

fn film_grain() -> NodeKind {
    post_filter(
        "FilmGrain",
        Category::Filter,
        "Film grain: each pixel's color × (1 + intensity × n), n a standard normal number \
         drawn from a hash of the pixel and `seed` (the same for all channels), so the same \
         seed gives the same grain on every machine; negative results clipped to 0.",
        vec![
            ParamDef::float(
                "intensity",
                0.05,
                [0.0, 1.0],
                "standard deviation of the grain, relative to the color",
            ),
            ParamDef::int(
                "seed",
                0,
                [0, 1 << 30],
                "which grain: another seed, another pattern",
            ),
        ],
        "post/film_grain.wgsl",
    )
    .with_example(&[("intensity", ParamValue::Float(0.2))])
    .with_reach(Reach::Image(
        "its grain is keyed to the pixel's place in the image",
    ))
}

/// Pixels within ceil(3 `sigma`): a Gaussian's taps.
fn three_sigma(params: &crate::Params) -> u32 {
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "sigma is at most 64"
    )]
    let r = (3.0 * params.float("sigma")).ceil().max(0.0) as u32;
    r
}
