// The function of the "Posterize" kind declared in custom_kinds.ron: each channel's
// display (sRGB-encoded) value rounded to `params.levels` steps, decoded back to linear.
#import "common/color.wgsl"

fn node(pixel: vec2u, size: vec2u) -> vec4f {
    let c = load_color(vec2i(pixel));
    let steps = f32(params.levels - 1);
    let display = round(srgb_encode(c.rgb) * steps) / steps;
    return vec4f(srgb_decode(display), c.a);
}
