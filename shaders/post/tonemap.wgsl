// Tonemap: tone curve, then the sRGB transfer function, into an 8-bit texture.
#import "common/tonemap.wgsl"

struct Params {
    op: u32,
    white: f32,
}

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let c = textureLoad(input, id.xy, 0);
    let display = srgb_encode(tonemap(c.rgb, params.op, params.white));
    textureStore(output, id.xy, vec4f(display, clamp(c.a, 0.0, 1.0)));
}
