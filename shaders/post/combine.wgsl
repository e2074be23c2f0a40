// Combine: the red channels of `r`, `g`, `b` (and `a` when connected, else 1) as one image.
// A generic post filter (crates/render/src/nodes/post_filter.rs) with an optional input;
// the CPU reference is in tests/post/combine.rs.

@group(0) @binding(0) var input_r: texture_2d<f32>;
@group(0) @binding(1) var input_g: texture_2d<f32>;
@group(0) @binding(2) var input_b: texture_2d<f32>;
@group(0) @binding(3) var input_a: texture_2d<f32>;
@group(0) @binding(4) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var<uniform> params: Params;

struct Params {
    has_a: u32,
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    var a = 1.0;
    if params.has_a != 0u {
        a = textureLoad(input_a, id.xy, 0).r;
    }
    let r = textureLoad(input_r, id.xy, 0).r;
    let g = textureLoad(input_g, id.xy, 0).r;
    let b = textureLoad(input_b, id.xy, 0).r;
    textureStore(output, id.xy, vec4f(r, g, b, a));
}
