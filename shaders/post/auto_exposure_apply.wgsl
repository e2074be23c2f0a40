// AutoExposure, pass 3: color × 2^ev with the exposure pass 2 left in `state`; alpha kept.
struct State {
    ev: f32,
    valid: u32,
}

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<storage, read> state: State;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let c = textureLoad(input, id.xy, 0);
    textureStore(output, id.xy, vec4f(c.rgb * exp2(state.ev), c.a));
}
