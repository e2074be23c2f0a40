// Split: each channel of `input` as a grey image (value in rgb, alpha 1). A generic post
// filter (crates/render/src/nodes/post_filter.rs) with four outputs and no params (so no param block); the CPU reference is
// in tests/post/combine.rs.

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var out_r: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var out_g: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var out_b: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var out_a: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(input);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let c = textureLoad(input, id.xy, 0);
    textureStore(out_r, id.xy, vec4f(vec3f(c.r), 1.0));
    textureStore(out_g, id.xy, vec4f(vec3f(c.g), 1.0));
    textureStore(out_b, id.xy, vec4f(vec3f(c.b), 1.0));
    textureStore(out_a, id.xy, vec4f(vec3f(c.a), 1.0));
}
