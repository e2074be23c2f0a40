//! Filter nodes: sharpening, lens and film effects.

use super::{Category, NodeKind, ParamDef, post_filter};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![sharpen(), chromatic_aberration(), film_grain()]
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
}
