// Difference: the per-pixel error of `input` against `reference` (the metric's per-pixel
// term, averaged over rgb), as a log-scale heat map, and its sum over each 16×16 tile in
// `partial` (one f32 per workgroup, summed on the CPU in f64). The CPU reference is
// `render::cpu::difference_heat` and `render::metrics`.

@group(0) @binding(0) var input: texture_2d<f32>;
@group(0) @binding(1) var reference: texture_2d<f32>;
@group(0) @binding(2) var heat: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(3) var<storage, read_write> partial: array<f32>;
@group(0) @binding(4) var<uniform> params: Params;

struct Params {
    metric: u32,
    max_error: f32,
    decades: f32,
    groups_x: u32,
}

const METRIC_RELMSE: u32 = 0u;

var<workgroup> tile: array<f32, 256>;

// Inferno, sampled at 0, 1/4, 1/2, 3/4 and 1 (display-encoded), interpolated linearly.
fn inferno(t: f32) -> vec3f {
    let stops = array<vec3f, 5>(
        vec3f(0.0015, 0.0005, 0.0139),
        vec3f(0.2582, 0.0386, 0.4065),
        vec3f(0.5783, 0.1480, 0.4044),
        vec3f(0.8650, 0.3168, 0.2261),
        vec3f(0.9884, 0.9984, 0.6449),
    );
    let x = clamp(t, 0.0, 1.0) * 4.0;
    let i = min(u32(x), 3u);
    return mix(stops[i], stops[i + 1u], x - f32(i));
}

// The heat map's position of a per-pixel error: 1 at `max_error`, 0 `decades` powers of
// ten below it.
fn heat_position(e: f32) -> f32 {
    if e <= 0.0 {
        return 0.0;
    }
    return clamp(1.0 + log2(e / params.max_error) / (params.decades * log2(10.0)), 0.0, 1.0);
}

@compute @workgroup_size(16, 16)
fn main(
    @builtin(global_invocation_id) id: vec3u,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3u,
) {
    let size = textureDimensions(input);
    var e = 0.0;
    if id.x < size.x && id.y < size.y {
        let x = textureLoad(input, id.xy, 0).rgb;
        let r = textureLoad(reference, id.xy, 0).rgb;
        let d = (x - r) * (x - r);
        var terms = d;
        if params.metric == METRIC_RELMSE {
            terms = d / (r * r + 0.01);
        }
        e = (terms.r + terms.g + terms.b) / 3.0;
        textureStore(heat, id.xy, vec4f(inferno(heat_position(e)), 1.0));
    }
    tile[local] = e;
    workgroupBarrier();
    for (var stride = 128u; stride > 0u; stride = stride / 2u) {
        if local < stride {
            tile[local] = tile[local] + tile[local + stride];
        }
        workgroupBarrier();
    }
    if local == 0u {
        partial[group.y * params.groups_x + group.x] = tile[0];
    }
}
