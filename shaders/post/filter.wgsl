// The generic post filter's bindings and entry point (crates/render/src/nodes/post_filter.rs):
// the including shader declares `struct Params` (the node's params by name, in order: f32
// for floats, i32 for ints, u32 for bools and enum option indices) and
// `fn filter_pixel(color: vec4f, pixel: vec2u, size: vec2u) -> vec4f`, the linear color of one
// output pixel from the input's at the same pixel.

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    textureStore(output, id.xy, filter_pixel(textureLoad(input, id.xy, 0), id.xy, size));
}
