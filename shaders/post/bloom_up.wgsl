// Bloom's upsample-and-add (crates/render/src/nodes/bloom.rs): out = fine_weight × fine +
// coarse_weight × bilinear(coarse) at the fine pixel's center, the coarse image taken as
// half the fine one's resolution (coarse coordinate (x + 0.5) / 2 − 0.5, clamped to the
// edge) (the CPU reference is in tests/post/blur_bloom.rs).

struct Params {
    fine_weight: f32,
    coarse_weight: f32,
    pad0: f32,
    pad1: f32,
}

@group(0) @binding(0) var fine: texture_2d<f32>;
@group(0) @binding(1) var coarse: texture_2d<f32>;
@group(0) @binding(2) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let last = vec2i(textureDimensions(coarse)) - 1;
    let c = (vec2f(id.xy) + 0.5) * 0.5 - 0.5;
    let c0 = vec2i(floor(c));
    let f = c - floor(c);
    let p00 = textureLoad(coarse, clamp(c0, vec2i(0), last), 0);
    let p10 = textureLoad(coarse, clamp(c0 + vec2i(1, 0), vec2i(0), last), 0);
    let p01 = textureLoad(coarse, clamp(c0 + vec2i(0, 1), vec2i(0), last), 0);
    let p11 = textureLoad(coarse, clamp(c0 + vec2i(1, 1), vec2i(0), last), 0);
    let up = mix(mix(p00, p10, f.x), mix(p01, p11, f.x), f.y);
    let here = textureLoad(fine, id.xy, 0);
    textureStore(output, id.xy, params.fine_weight * here + params.coarse_weight * up);
}
