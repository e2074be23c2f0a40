// Sharpen: unsharp mask c + amount × (c − G_sigma * c), the Gaussian's taps within
// ceil(3 sigma) pixels, clamped to the edge, normalized; negative results clipped to 0
// (the CPU reference is in tests/post/effects.rs).
#import "post/resample.wgsl"

struct Params {
    amount: f32,
    sigma: f32,
}

fn resample_pixel(pixel: vec2u, out_size: vec2u, in_size: vec2u) -> vec4f {
    let r = i32(ceil(3.0 * params.sigma));
    let last = vec2i(in_size) - 1;
    let p = vec2i(pixel);
    let k = -0.5 / (params.sigma * params.sigma);
    var sum = vec4f(0.0);
    var weight = 0.0;
    for (var dy = -r; dy <= r; dy++) {
        for (var dx = -r; dx <= r; dx++) {
            let w = exp(k * f32(dx * dx + dy * dy));
            sum += w * textureLoad(input, clamp(p + vec2i(dx, dy), vec2i(0), last), 0);
            weight += w;
        }
    }
    let c = textureLoad(input, p, 0);
    let s = c + params.amount * (c - sum / weight);
    return vec4f(max(s.rgb, vec3f(0.0)), c.a);
}
