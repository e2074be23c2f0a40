// The path tracer's BSDF (bsdf.wgsl) on its own, for statistical tests of every lobe:
// mode 0 samples it `count` times for one material and outgoing direction (random numbers
//        from a PCG stream per sample): out[2i] = (wi, pdf), out[2i+1] = (weight, valid);
// mode 1 evaluates it at the directions `dirs[i].xyz`: out[2i] = (f * cos, pdf), and the
//        same with wo and wi swapped (reciprocity): out[2i+1] = (f * cos, pdf).
// All in the shading frame (normal +z); wo points away from the surface.
#import "pathtrace/scene_types.wgsl"
#import "common/rng.wgsl"
#import "pathtrace/options.wgsl"

struct Params {
    wo: vec3f,
    count: u32,
    mode: u32,
    seed: u32,
    pad0: u32,
    pad1: u32,
    // The clear coat's normal in the shading frame (`coat_normal`).
    coat_n: vec3f,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> material: array<Material>;
@group(0) @binding(2) var<storage, read> ggx_table: array<vec2f>;
@group(0) @binding(3) var<storage, read> dirs: array<vec4f>;
@group(0) @binding(4) var<storage, read_write> out: array<vec4f>;

#import "pathtrace/bsdf/bsdf.wgsl"

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.y * 65535u * 64u + id.x;
    if i >= params.count {
        return;
    }
    let m = material[0];
    coat_normal = params.coat_n;
    if params.mode == 0u {
        rng_init(i, 0u, params.seed);
        let u_lobe = rand();
        let u = vec3f(rand2(), rand());
        let s = sample_bsdf(m, params.wo, u_lobe, u);
        out[2u * i] = vec4f(s.wi, s.pdf);
        out[2u * i + 1u] = vec4f(s.weight, select(0.0, 1.0, s.valid));
    } else {
        let wi = dirs[i].xyz;
        let e = eval_bsdf(m, params.wo, wi);
        out[2u * i] = vec4f(e.f_cos, e.pdf);
        let r = eval_bsdf(m, wi, params.wo);
        out[2u * i + 1u] = vec4f(r.f_cos, r.pdf);
    }
}
