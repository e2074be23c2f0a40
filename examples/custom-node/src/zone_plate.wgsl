// ZonePlate: a circular zone plate around the image centre, 0.5 + 0.5 cos(π f r² / R), where
// R is half the image width. Its rings get finer with the distance r: the local frequency is
// f r / R cycles per pixel, `frequency` at R.

struct Params {
    frequency: f32,
}

@group(0) @binding(0) var out_color: texture_storage_2d<rgba32float, write>;
@group(0) @binding(1) var<uniform> params: Params;

const TAU: f32 = 6.283185307179586;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_color);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let centre = vec2f(size) * 0.5;
    let d = vec2f(id.xy) + 0.5 - centre;
    // The phase in cycles, f r² / (2R), reduced to [-0.5, 0.5) so the cosine's argument
    // stays in [-π, π) where GPUs bound its error: cos(2π(c + 0.5)) = -cos(2πc).
    let cycles = fract(params.frequency * dot(d, d) / (2.0 * centre.x)) - 0.5;
    let v = 0.5 - 0.5 * cos(TAU * cycles);
    textureStore(out_color, id.xy, vec4f(v, v, v, 1.0));
}
