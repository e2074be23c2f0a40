// The generic post filter's bindings and entry point for two inputs, per pixel
// (crates/render/src/nodes/post_filter.rs): the including shader declares `struct Params`
// (as for post/filter.wgsl) and
// `fn filter_pixels(a: vec4f, b: vec4f, pixel: vec2u, size: vec2u) -> vec4f`, the linear
// color of one output pixel from the two inputs' (in the kind's input order) at that pixel.

@group(0) @binding(0) var input_a: texture_2d<f32>;
@group(0) @binding(1) var input_b: texture_2d<f32>;
@group(0) @binding(2) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let a = textureLoad(input_a, id.xy, 0);
    let b = textureLoad(input_b, id.xy, 0);
    textureStore(output, id.xy, filter_pixels(a, b, id.xy, size));
}
