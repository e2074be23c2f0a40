// The generic post filter's bindings and entry point for filters that read around a pixel
// with a filtering sampler or change the image's size (crates/render/src/nodes/post_filter.rs):
// the including shader declares `struct Params` (as for post/filter.wgsl) and
// `fn resample_pixel(pixel: vec2u, out_size: vec2u, in_size: vec2u) -> vec4f`, the linear
// color of one output pixel; it may read `input` with `textureLoad` or with
// `textureSampleLevel(input, linear_clamp, uv, 0.0)` (bilinear, clamped to the edge).
// The pass runs over the output's size.

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var linear_clamp: sampler;
@group(0) @binding(2) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    textureStore(output, id.xy, resample_pixel(id.xy, size, textureDimensions(input)));
}
