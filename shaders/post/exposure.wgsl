// Exposure: color × 2^ev (the scale is computed on the CPU).

struct Params {
    scale: f32,
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
    let c = textureLoad(input, id.xy, 0);
    textureStore(output, id.xy, vec4f(c.rgb * params.scale, c.a));
}
