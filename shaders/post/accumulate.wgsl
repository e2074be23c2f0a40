// Accumulate: running mean of the input over frames, with Kahan-compensated f32 sums.
// History lives in two storage buffers owned by the node (it outlives a frame):
//   sum[i].rgb  running sum of the input,  sum[i].a  number of frames added (exact to 2^24);
//   comp[i].rgb Kahan compensation (the low-order bits the sum lost).
// Mirrored by `cpu::KahanMean`.
//
// Shader compilers may simplify `((s + y) - s) - y` to 0 (Mesa's NIR does, since naga marks no
// operation exact), which silently turns Kahan summation into a plain sum. Multiplying by
// `params.one` (1.0, but unknown to the compiler) keeps the compensation term alive.

struct Params {
    one: f32,
}

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<storage, read_write> sum: array<vec4f>;
@group(0) @binding(3) var<storage, read_write> comp: array<vec4f>;
@group(0) @binding(4) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(output);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let i = id.y * size.x + id.x;
    let x = textureLoad(input, id.xy, 0).rgb;
    var s = sum[i];
    let c = comp[i].rgb;
    let y = x - c;
    let t = (s.rgb + y) * params.one;
    comp[i] = vec4f((t - s.rgb) - y, 0.0);
    s = vec4f(t, s.a + 1.0);
    sum[i] = s;
    textureStore(output, id.xy, vec4f(s.rgb / s.a, 1.0));
}
