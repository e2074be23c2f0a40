// Light sampling: picking a light (alias table by power, with a uniform share), sampling
// a point on it or a direction to it (triangles, analytic shapes as their kind samples them
// (pathtrace/shapes/), lights without area as their kind does (pathtrace/lights/<kind>.wgsl,
// through the generated pathtrace/light_kinds.wgsl), the environment map), and the pdfs MIS
// needs.
// requires: var frame, var tri_texcoords (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/options.wgsl"
#import "pathtrace/shared.wgsl"
#import "pathtrace/integrator/sampler.wgsl"
#import "common/sampling.wgsl"
#import "pathtrace/lights/env.wgsl"
#import "pathtrace/scene_data.wgsl"
#import "pathtrace/textures.wgsl"
#import "pathtrace/integrator/surface.wgsl"
#import "pathtrace/shapes.wgsl"
#import "pathtrace/lights/sample.wgsl"
#import "pathtrace/light_kinds.wgsl"

fn env_map_on() -> bool {
    return HAS_ENV_MAP && frame.settings.env_kind == ENV_MAP;
}

// Probability that light sampling takes the environment map rather than an area light.
fn env_select_prob() -> f32 {
    if !env_map_on() {
        return 0.0;
    }
    return select(1.0, 0.5, HAS_LIGHTS && frame.header.num_lights > 0u);
}

// Probability that light sampling picks `l`: LIGHT_UNIFORM_SHARE uniformly, the rest by
// power (as `light_selection` in crates/scene/src/flatten.rs builds the alias table).

fn light_select_pdf(l: Light) -> f32 {
    let total = frame.header.total_light_power;
    let uniform = 1.0 / f32(frame.header.num_lights);
    let by_power = select(uniform, l.power / total, total > 0.0);
    return (1.0 - env_select_prob()) * mix(by_power, uniform, LIGHT_UNIFORM_SHARE);
}

// Solid-angle pdf of sampling the point `y` (normal `ny`) on light `l` from `x`.
fn light_pdf(l: Light, x: vec3f, y: vec3f, ny: vec3f) -> f32 {
    let d = y - x;
    let dist2 = dot(d, d);
    if (l.flags & LIGHT_SHAPE) != 0u {
        let pdf = shape_pdf(scene_shape(l.prim), x, y);
        return light_select_pdf(l) * pdf.x / pdf.y;
    }
    let cos_y = abs(dot(ny, d)) / sqrt(dist2);
    return light_select_pdf(l) * dist2 / (l.area * cos_y);
}

fn pick_light(u: f32) -> u32 {
    let n = frame.header.num_lights;
    let scaled = u * f32(n);
    let i = min(u32(scaled), n - 1u);
    let e = scene_light_alias(i);
    return select(e.other, i, scaled - f32(i) < e.prob);
}

// A light sample seen from `x`; `bounce` picks the point's random numbers (sampler.wgsl).
fn sample_light(x: vec3f, bounce: u32) -> LightSample {
    var out: LightSample;
    out.pdf = 0.0;
    out.delta = false;
    let l = scene_light(pick_light(rand()));
    let u = sample_2d_at(PAIR_LIGHT, bounce);
    if l.kind != 0u {
        out = punctual_sample(l, x);
        out.pdf *= light_select_pdf(l);
        return out;
    }
    if (l.flags & LIGHT_SHAPE) != 0u {
        let ss = shape_sample(scene_shape(l.prim), x, u, (l.flags & LIGHT_TWO_SIDED) != 0u);
        if ss.pdf.x <= 0.0 {
            return out;
        }
        out.wi = ss.wi;
        out.dist = ss.dist;
        out.radiance = l.emission;
        out.pdf = light_select_pdf(l) * ss.pdf.x / ss.pdf.y;
        out.margin = ss.margin;
        return out;
    }
    let b = sample_triangle(u);
    let y = l.p0 + b.x * l.e1 + b.y * l.e2;
    let ny = normalize(cross(l.e1, l.e2));
    let d = y - x;
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    let wi = d / dist;
    let cos_y = dot(ny, -wi);
    let two_sided = (l.flags & LIGHT_TWO_SIDED) != 0u;
    if !(cos_y > 0.0 || (two_sided && cos_y < 0.0)) {
        return out;
    }
    out.wi = wi;
    out.dist = dist;
    out.radiance = l.emission;
    if HAS_TEXTURES {
        // An emissive texture varies the emission over the triangle (selection goes by its
        // mean over the triangle: `GpuLight::power`).
        let m = scene_material(scene_tri_shading(l.prim).material);
        if tex_lo(m.tex_emissive_normal) != NO_TEX {
            out.radiance = textured_emission(m, tri_uv(tri_texcoords[l.prim], b.x, b.y));
        }
    }
    out.pdf = light_select_pdf(l) * dist2 / (l.area * abs(cos_y));
    let err = barycentric_err(l.p0, l.e1, l.e2, b.x, b.y);
    out.margin = dot(abs(ny), err) / abs(cos_y) + EDGE_ERR * dist;
    return out;
}

// A light sample for next-event estimation from `x`: the environment map with probability
// `p_env`, else an emitter.
fn sample_next_event(x: vec3f, bounce: u32, p_env: f32) -> LightSample {
    if rand() < p_env {
        let es = sample_env(rand(), rand2());
        return LightSample(es.wi, F32_MAX, es.radiance, es.pdf * p_env, 0.0, false);
    }
    return sample_light(x, bounce);
}
