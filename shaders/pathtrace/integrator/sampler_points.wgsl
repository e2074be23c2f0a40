// The path tracer's sampler, evaluated for a buffer of queries, so tests can check it:
// mode 0: x = sobol_owen(index = a, dimension = b, seed = c);
// mode 1: the 2D point of pair d for pixel a, sample b, seed c (sample_2d, Sobol sampler,
// one replicate).
#import "pathtrace/integrator/sampler.wgsl"

struct Params {
    count: u32,
    mode: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> queries: array<vec4u>;
@group(0) @binding(2) var<storage, read_write> points: array<vec2f>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.y * 65535u * 64u + id.x;
    if i >= params.count {
        return;
    }
    let q = queries[i];
    if params.mode == 0u {
        points[i] = vec2f(sobol_owen(q.x, q.y, q.z), 0.0);
    } else {
        sampler_init(q.x, q.y, q.z, SAMPLER_SOBOL, 1u, 1u);
        points[i] = sample_2d(q.w);
    }
}
