// Film grain: color × (1 + intensity × n), n standard normal from a hash of the pixel and
// the seed (Box-Muller on two PCG draws), the same for all channels; negative results
// clipped to 0 (the CPU reference is in tests/post/effects.rs).
#import "post/filter.wgsl"

struct Params {
    intensity: f32,
    seed: i32,
}

// PCG hash (Jarzynski and Olano 2020).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    let h = pcg(pixel.x + pcg(pixel.y + pcg(u32(params.seed))));
    // Two uniforms in (0, 1]: 24 bits each.
    let u1 = (f32(h >> 8u) + 1.0) / 16777216.0;
    let u2 = f32(pcg(h) >> 8u) / 16777216.0;
    let n = sqrt(-2.0 * log(u1)) * cos(6.28318530718 * u2);
    return vec4f(max(c.rgb * (1.0 + params.intensity * n), vec3f(0.0)), c.a);
}
