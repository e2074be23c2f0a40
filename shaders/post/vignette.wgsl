// Vignette: color × (1 − strength · smoothstep(radius, radius + softness, d)), d the distance
// of the pixel center from the image center in half-diagonals (the CPU reference is in
// tests/post/vignette.rs).
#import "post/filter.wgsl"

struct Params {
    strength: f32,
    radius: f32,
    softness: f32,
}

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    let half = 0.5 * vec2f(size);
    let d = length(vec2f(pixel) + 0.5 - half) / length(half);
    let s = smoothstep(params.radius, params.radius + params.softness, d);
    return vec4f(c.rgb * (1.0 - params.strength * s), c.a);
}
