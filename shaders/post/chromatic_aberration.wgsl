// Lateral chromatic aberration: red read at center + (p − center)(1 + strength), blue at
// (1 − strength), green in place, bilinear through the sampler (the CPU reference is in
// tests/post/effects.rs).
#import "post/resample.wgsl"

struct Params {
    strength: f32,
}

fn resample_pixel(pixel: vec2u, out_size: vec2u, in_size: vec2u) -> vec4f {
    let uv = (vec2f(pixel) + 0.5) / vec2f(out_size);
    let d = uv - 0.5;
    let r = textureSampleLevel(input, linear_clamp, 0.5 + d * (1.0 + params.strength), 0.0).r;
    let b = textureSampleLevel(input, linear_clamp, 0.5 + d * (1.0 - params.strength), 0.0).b;
    let c = textureLoad(input, pixel, 0);
    return vec4f(r, c.g, b, c.a);
}
