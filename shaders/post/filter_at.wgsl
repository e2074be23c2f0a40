// The generic post filter's bindings and entry point for filters that move pixels
// (crates/render/src/nodes/post_filter.rs): the including shader declares `struct Params`
// (as for post/filter.wgsl) and `fn source_pixel(pixel: vec2u) -> vec2u`, the input pixel
// the output pixel copies. The pass runs over the output's size.

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let last = textureDimensions(input) - 1u;
    textureStore(output, id.xy, textureLoad(input, min(source_pixel(id.xy), last), 0));
}
