// Homogeneous participating media for the path tracer (HAS_MEDIA): the medium a path is
// in, Henyey-Greenstein phase sampling, and the transmittance of shadow rays, which cross
// index-matched boundaries. A medium fills the inside of the shapes of a material with
// MATERIAL_MEDIUM (its sigma_a, sigma_s and phase_g); the path enters it when it leaves
// such a surface towards its back (refracted through glass, or crossing an index-matched
// boundary, MATERIAL_INDEX_MATCHED) and leaves it through its front. One medium at a time:
// the scene loader refuses media that overlap (so none is nested in another), and paths
// start outside every medium (the camera must not be in one).
// Also next-event estimation from a point in a medium (`medium_next_event`).
// requires: var frame, var ray_count (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/intersect.wgsl"
#import "pathtrace/scene_data.wgsl"
#import "pathtrace/integrator/surface.wgsl"
#import "pathtrace/lights/lights.wgsl"
#import "pathtrace/integrator/mis.wgsl"

// `medium_id` when the path is in no medium.
const NO_MEDIUM: u32 = 0xffffffffu;
// Most index-matched boundaries one ray segment or shadow ray crosses (a bound against
// paths caught between surfaces by rounding).
const MAX_CROSSINGS: u32 = 64u;

// The material whose medium the current ray travels in, or NO_MEDIUM.
var<private> medium_id: u32 = NO_MEDIUM;

// The medium a ray leaving a surface of material `id` towards `dir` travels in: a medium
// boundary's inside is behind it; any other surface leaves the path where it was.
fn medium_after(id: u32, m: Material, ng: vec3f, dir: vec3f, current: u32) -> u32 {
    if (m.flags & MATERIAL_MEDIUM) == 0u {
        return current;
    }
    return select(NO_MEDIUM, id, dot(dir, ng) < 0.0);
}

// The Henyey-Greenstein phase function for the cosine between the direction of travel
// before and after scattering (g > 0 scatters forward), per steradian.
fn hg_eval(cos_t: f32, g: f32) -> f32 {
    let d = 1.0 + g * g - 2.0 * g * cos_t;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(max(d, 1e-12)));
}

// A direction of travel after scattering, from `dir`, sampled exactly by the phase
// function (its weight, value over pdf, is 1).
fn hg_sample(dir: vec3f, g: f32, u: vec2f) -> vec3f {
    var cos_t = 1.0 - 2.0 * u.x;
    if abs(g) >= 1e-3 {
        let sq = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        cos_t = clamp((1.0 + g * g - sq * sq) / (2.0 * g), -1.0, 1.0);
    }
    let sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    let phi = TWO_PI * u.y;
    return normalize(onb(dir) * vec3f(sin_t * cos(phi), sin_t * sin(phi), cos_t));
}

// Transmittance along a shadow ray from its origin (in `medium`) to `t_max`: Beer-Lambert
// through the media it travels in, across index-matched boundaries; 0 when anything else is
// in the way. The ray's origin state (`skip_prim`, `origin_*`) is the caller's, as for
// `occluded`; `skip_prim` and `skip_inst` are restored on return. The caller counts the first ray.
fn shadow_transmittance(shadow: Ray, t_max: f32, medium: u32) -> vec3f {
    let saved_skip = skip_prim;
    let saved_inst = skip_inst;
    var ray = shadow;
    var left = t_max;
    var current = medium;
    var tr = vec3f(1.0);
    var crossings = 0u;
    loop {
        let hit = intersect_scene_within(ray, left);
        let t = select(left, hit.t, hit.prim != NO_HIT);
        if current != NO_MEDIUM {
            let m = scene_material(current);
            tr *= exp(-(m.sigma_a + m.sigma_s) * t);
        }
        if hit.prim == NO_HIT {
            break;
        }
        let s = surface_at(ray, hit, vec2f(0.0));
        let m = scene_material(s.material);
        crossings += 1u;
        if (m.flags & MATERIAL_INDEX_MATCHED) == 0u || crossings > MAX_CROSSINGS {
            tr = vec3f(0.0);
            break;
        }
        current = medium_after(s.material, m, s.ng, ray.dir, current);
        skip_prim = hit.prim;
        skip_inst = hit.inst;
        let side = select(-s.ng, s.ng, dot(s.ng, ray.dir) > 0.0);
        ray = Ray(leave(s, is_shape(hit.prim), side, ray.dir), ray.dir);
        left -= t;
        ray_count += 1u;
    }
    skip_prim = saved_skip;
    skip_inst = saved_inst;
    return tr;
}

// Light reaching medium point `p` (a ray travelling along `dir` scattered there, phase
// asymmetry `g`) by next-event estimation, over the scattering coefficient: phase function
// times radiance times transmittance over the light sample's pdf, MIS-weighted against
// phase sampling.
fn medium_next_event(p: vec3f, dir: vec3f, g: f32, bounce: u32, has_lights: bool) -> vec3f {
    let p_env = env_select_prob();
    if !(has_lights || p_env > 0.0) {
        return vec3f(0.0);
    }
    let ls = sample_next_event(p, bounce, p_env);
    if !(ls.pdf > 0.0) || !(ls.delta || frame.strategy != STRATEGY_BSDF) {
        return vec3f(0.0);
    }
    let phase = hg_eval(dot(dir, ls.wi), g);
    leave_no_surface();
    ray_count += 1u;
    let tr = shadow_transmittance(Ray(p, ls.wi), ls.dist - ls.margin, medium_id);
    let w = select(light_weight(ls.pdf, phase), 1.0, ls.delta);
    return phase * ls.radiance * tr * (w / ls.pdf);
}
