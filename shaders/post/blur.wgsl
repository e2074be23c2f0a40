// One pass of the separable Gaussian blur (crates/render/src/nodes/blur.rs): along x or y,
// the taps within `radius` pixels weighted exp(−d²/2σ²), normalized, clamped to the edge
// (the CPU reference is in tests/post/blur_bloom.rs).

struct Params {
    sigma: f32,
    radius: i32,
    axis: u32,
    pad: u32,
}

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let step = select(vec2i(1, 0), vec2i(0, 1), params.axis == 1u);
    let last = vec2i(size) - 1;
    let k = -0.5 / (params.sigma * params.sigma);
    var sum = vec4f(0.0);
    var weight = 0.0;
    for (var d = -params.radius; d <= params.radius; d++) {
        let w = exp(k * f32(d * d));
        sum += w * textureLoad(input, clamp(vec2i(id.xy) + d * step, vec2i(0), last), 0);
        weight += w;
    }
    textureStore(output, id.xy, sum / weight);
}
