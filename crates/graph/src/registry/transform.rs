//! Transform nodes: images resampled to another size.

use super::{Category, NodeKind, OutputSize, ParamDef, Reach, post_filter};
use crate::compile::Params;
use crate::types::{Extent, ParamValue};

pub(super) fn kinds() -> Vec<NodeKind> {
    vec![
        resize().with_reach(Reach::Image("it resamples the whole image")),
        crop().with_reach(Reach::Image("it cuts a rectangle out of the whole image")),
    ]
}

fn crop() -> NodeKind {
    let mut kind = post_filter(
        "Crop",
        Category::Transform,
        "Cuts out the rectangle of `width` × `height` pixels whose top-left corner is pixel \
         (`x`, `y`) of the input.",
        vec![
            ParamDef::int("x", 0, [0, MAX_SIDE], "left edge, in input pixels"),
            ParamDef::int("y", 0, [0, MAX_SIDE], "top edge, in input pixels"),
            ParamDef::int(
                "width",
                0,
                [0, MAX_SIDE],
                "width; 0: to the input's right edge",
            ),
            ParamDef::int(
                "height",
                0,
                [0, MAX_SIDE],
                "height; 0: to the input's bottom edge",
            ),
        ],
        "post/crop.wgsl",
    );
    kind.outputs[0].size = OutputSize::Rule(
        crop_extent,
        "`width` × `height` (0: to the input's edge); the rectangle must lie inside the input",
    );
    kind.with_example(&[
        ("x", ParamValue::Int(96)),
        ("y", ParamValue::Int(48)),
        ("width", ParamValue::Int(192)),
        ("height", ParamValue::Int(96)),
    ])
}

/// The output size of a Crop of an `input`-sized image.
fn crop_extent(input: Extent, params: &Params) -> Result<Extent, String> {
    let side = |name: &str| u32::try_from(params.int(name)).unwrap_or(u32::MAX);
    let (x, y) = (side("x"), side("y"));
    let (iw, ih) = (input.width, input.height);
    if x >= iw || y >= ih {
        return Err(format!("corner ({x}, {y}) is outside the {input} input"));
    }
    // 0: to the input's edge.
    let or_rest = |v: u32, rest: u32| if v == 0 { rest } else { v };
    let (w, h) = (
        or_rest(side("width"), iw - x),
        or_rest(side("height"), ih - y),
    );
    if u64::from(x) + u64::from(w) > u64::from(iw) || u64::from(y) + u64::from(h) > u64::from(ih) {
        return Err(format!(
            "{w}x{h} at ({x}, {y}) reaches past the {input} input"
        ));
    }
    Ok(Extent::new(w, h))
}

/// Largest side a resize may produce (the smallest `max_texture_dimension_2d` of the GPUs
/// lumagraph runs on).
const MAX_SIDE: i64 = 16384;

fn resize() -> NodeKind {
    let mut kind = post_filter(
        "Resize",
        Category::Transform,
        "Resamples the image to another size. `kernel` `bilinear` takes the 4 texels around each \
         output pixel's center with the GPU's filtering sampler (fine up to 2× down; smaller \
         scales alias); `lanczos3` weighs the texels within 3 input pixels (3 output pixels \
         when shrinking, so no aliasing) by the Lanczos-3 kernel, normalized, and clips the \
         negative values its lobes can give to 0; it shrinks by at most 32× per node.",
        vec![
            ParamDef::int(
                "width",
                0,
                [0, MAX_SIDE],
                "output width in pixels; 0: from `height` keeping the aspect ratio, or from \
                 `scale` when both are 0",
            ),
            ParamDef::int(
                "height",
                0,
                [0, MAX_SIDE],
                "output height in pixels; 0: from `width` keeping the aspect ratio, or from \
                 `scale` when both are 0",
            ),
            ParamDef::float(
                "scale",
                0.5,
                [0.01, 16.0],
                "size factor on both axes, used when `width` and `height` are 0",
            ),
            ParamDef::choice(
                "kernel",
                "lanczos3",
                &[
                    ("bilinear", "4 texels through the filtering sampler"),
                    ("lanczos3", "Lanczos-3, widened when shrinking"),
                ],
                "resampling kernel",
            ),
        ],
        "post/resize.wgsl",
    );
    kind.outputs[0].size = OutputSize::Rule(
        resize_extent,
        "`width` × `height`; one of them 0 keeps the input's aspect ratio; both 0: the \
         input's size × `scale`, rounded, at least 1 pixel",
    );
    kind
}

/// The most a `lanczos3` Resize shrinks an axis. Each output pixel sums the input texels
/// within 3 output pixels, (6 × shrink)² of them, in one shader invocation: at 32× that is
/// 192 × 193 loop iterations. Far beyond, llvmpipe (Mesa's CPU driver) ends the loops
/// silently after 65 535 iterations in all (a 100× shrink came out 40× too dark), and a GPU
/// spends 360 000 texel reads on each pixel.
pub const MAX_LANCZOS_SHRINK: f64 = 32.0;

/// The output size of a Resize of an `input`-sized image.
fn resize_extent(input: Extent, params: &Params) -> Result<Extent, String> {
    let (w, h) = (params.int("width"), params.int("height"));
    let (iw, ih) = (f64::from(input.width), f64::from(input.height));
    let (w, h) = match (w, h) {
        (0, 0) => {
            let s = params.float("scale");
            ((iw * s).round(), (ih * s).round())
        }
        #[expect(clippy::cast_precision_loss, reason = "at most MAX_SIDE")]
        (0, h) => ((iw * h as f64 / ih).round(), h as f64),
        #[expect(clippy::cast_precision_loss, reason = "at most MAX_SIDE")]
        (w, 0) => (w as f64, (ih * w as f64 / iw).round()),
        #[expect(clippy::cast_precision_loss, reason = "at most MAX_SIDE")]
        (w, h) => (w as f64, h as f64),
    };
    #[expect(clippy::cast_precision_loss, reason = "a small constant")]
    let max = MAX_SIDE as f64;
    if w > max || h > max {
        return Err(format!("{w}x{h} pixels: a side is more than {MAX_SIDE}"));
    }
    let shrink = (iw / w.max(1.0)).max(ih / h.max(1.0));
    if params.str("kernel") == "lanczos3" && shrink > MAX_LANCZOS_SHRINK {
        return Err(format!(
            "{}x{} to {}x{} pixels shrinks {shrink:.1}×: lanczos3 shrinks by at most \
             {MAX_LANCZOS_SHRINK}× in one Resize (chain Resize nodes, or use bilinear)",
            input.width,
            input.height,
            w.max(1.0),
            h.max(1.0)
        ));
    }
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "in 1..=MAX_SIDE"
    )]
    Ok(Extent::new(w.max(1.0) as u32, h.max(1.0) as u32))
}
