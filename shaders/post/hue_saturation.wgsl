// Hue, saturation, value: the color rotated by `hue` degrees around the grey axis,
// its distance from grey (the mean of r, g, b) scaled by `saturation`, the result scaled
// by `value`; negative channels clipped to 0 (the CPU reference is in tests/post/grade.rs).
#import "post/filter.wgsl"

struct Params {
    hue: f32,
    saturation: f32,
    value: f32,
}

fn filter_pixel(c: vec4f, pixel: vec2u, size: vec2u) -> vec4f {
    let grey = (c.r + c.g + c.b) / 3.0;
    let d = c.rgb - grey;
    // Rodrigues' rotation around k = (1, 1, 1)/√3; d ⟂ k, so no k(k·d) term.
    let k = vec3f(0.57735027);
    let a = radians(params.hue);
    let r = d * cos(a) + cross(k, d) * sin(a);
    let rgb = params.value * (grey + params.saturation * r);
    return vec4f(max(rgb, vec3f(0.0)), c.a);
}
