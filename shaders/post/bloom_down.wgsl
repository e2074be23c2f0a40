// Bloom's downsampling (crates/render/src/nodes/bloom.rs): output pixel (x, y) is the
// [1 3 3 1]/8 ⊗ [1 3 3 1]/8 average of input pixels 2x−1 … 2x+2 (and in y), clamped to the
// edge (the CPU reference is in tests/post/blur_bloom.rs).

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let w = array<f32, 4>(0.125, 0.375, 0.375, 0.125);
    let last = vec2i(textureDimensions(input)) - 1;
    let origin = 2 * vec2i(id.xy) - 1;
    var sum = vec4f(0.0);
    for (var j = 0; j < 4; j++) {
        var row = vec4f(0.0);
        for (var i = 0; i < 4; i++) {
            row += w[i] * textureLoad(input, clamp(origin + vec2i(i, j), vec2i(0), last), 0);
        }
        sum += w[j] * row;
    }
    textureStore(output, id.xy, sum);
}
