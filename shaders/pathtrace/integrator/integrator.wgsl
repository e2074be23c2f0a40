// The integrator: a path's state, and one bounce of it (`path_step_from`, the one shading
// core of the megakernel and of host intersection's steps): emission found with its MIS
// weight, media, next-event estimation, BSDF sampling, Russian roulette.
// requires: var frame, var ray_count (integrator/pathtrace.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/options.wgsl"
#import "pathtrace/integrator/sampler.wgsl"
#import "pathtrace/bsdf/bsdf.wgsl"
#import "pathtrace/intersect.wgsl"
#import "pathtrace/intersect/alpha.wgsl"
#import "pathtrace/integrator/medium.wgsl"
#import "pathtrace/integrator/mis.wgsl"
#import "pathtrace/integrator/surface.wgsl"
#import "pathtrace/lights/lights.wgsl"
#import "pathtrace/integrator/camera.wgsl"

const RR_START: u32 = 5u;

// A path between bounces: `start_path` begins one, `path_step` takes it one bounce on.
struct PathState {
    ray: Ray,
    throughput: vec3f,
    radiance: vec3f,
    // Solid-angle pdf of the BSDF sample that made `ray` (0: a mirror, interface or camera
    // ray, which light sampling cannot produce), and where it left from (for MIS).
    bsdf_pdf: f32,
    prev_p: vec3f,
    bounce: u32,
    // The index-matched boundaries crossed so far.
    crossings: u32,
    // The ray's cone (HAS_TEXTURES; Akenine-Moller et al. 2021): its width at the ray's
    // origin (x) and its spread angle (y), which give texture lookups their footprint. A
    // camera ray's starts at width 0 with the pixel's spread (`pixel_spread`); at each
    // surface the width grows by spread x distance, and a BSDF sample adds to the spread the
    // angular radius of the solid angle 1 / pdf around its direction (`lobe_spread`): a
    // rough lobe scatters a ray's neighbours over about that; mirror, interface and glass
    // samples (pdf 0) add nothing. Curvature is not counted (surfaces are taken as locally
    // flat), nor is a scattering in a medium (the width stays that of the last surface).
    cone: vec2f,
}

// With WAVES: the shadow ray of the step's next-event estimate, which the host or the
// wavefront's `wave_trace` traces (from `near` to `far` along it; `n`, the normal of the
// plane it leaves, towards it: `origin_n` when it left), and what it adds to the path's
// radiance unless occluded.
struct HostShadow {
    pending: bool,
    ray: Ray,
    near: f32,
    far: f32,
    n: vec3f,
    contribution: vec3f,
}

// The path being traced, and its shadow ray for the host.
var<private> path: PathState;
var<private> host_shadow: HostShadow;

// What a part of a bounce leaves the path to: the bounce goes on (to the surface), the
// bounce is done (the next ray is set), or the path ends.
const BOUNCE_GOES_ON: u32 = 0u;
const BOUNCE_DONE: u32 = 1u;
const PATH_ENDS: u32 = 2u;

// Starts the path of the current sample (`sampler_init`) through `pixel`.
fn start_path(pixel: vec2u) {
    path.ray = camera_ray(pixel, sample_2d(PAIR_PIXEL));
    path.throughput = vec3f(1.0);
    path.radiance = vec3f(0.0);
    path.bsdf_pdf = 0.0;
    path.prev_p = path.ray.origin;
    path.bounce = 0u;
    path.crossings = 0u;
    path.cone = vec2f(0.0, pixel_spread());
    // The triangle the current ray leaves (never hit again); camera rays leave none.
    leave_no_surface();
    // The medium the ray travels in: paths start in none.
    if HAS_MEDIA {
        medium_id = NO_MEDIUM;
    }
}

// Takes the path one bounce on; true once it ended (its radiance is `path.radiance`).
fn path_step() -> bool {
    return path_step_from(intersect_scene(path.ray), true);
}

// `path_step` with the closest hit of `path.ray` given (`hit`); `may_miss` false where the
// caller knows the ray hit (a constant: the compiler leaves the miss's code out).
fn path_step_from(hit: Hit, may_miss: bool) -> bool {
    var p = path;
    let ended = bounce_path(&p, hit, may_miss) == PATH_ENDS;
    p.bounce += 1u;
    path = p;
    return ended;
}

// `path_step_from` for a ray that hit nothing, without the code of a surface's bounce (which
// a compiler would otherwise build for the host's step of misses, `wave_misses`, and throw
// away only after all the work: seconds on llvmpipe).
fn path_step_missed() -> bool {
    var p = path;
    var next = bounce_through(&p, Hit(NO_HIT, F32_MAX, 0.0, 0.0, NO_INSTANCE));
    if next == BOUNCE_GOES_ON {
        add_escaped(&p);
        next = PATH_ENDS;
    }
    p.bounce += 1u;
    path = p;
    return next == PATH_ENDS;
}

// The start of every bounce: the ray counted, and the medium it travels in, which may end the
// bounce (scattered, absorbed) before the ray reaches `hit`.
fn bounce_through(p: ptr<function, PathState>, hit: Hit) -> u32 {
    ray_count += 1u;
    if HAS_MEDIA && medium_id != NO_MEDIUM {
        return through_medium(p, hit, HAS_LIGHTS && frame.header.num_lights > 0u);
    }
    return BOUNCE_GOES_ON;
}

// One bounce of path `p`, whose ray's closest hit is `hit`: through the medium the ray
// travels in, then out of the scene, across an index-matched boundary, or at a surface
// (emission found, next-event estimation, the BSDF's next direction).
fn bounce_path(p: ptr<function, PathState>, hit: Hit, may_miss: bool) -> u32 {
    let through = bounce_through(p, hit);
    if through != BOUNCE_GOES_ON {
        return through;
    }
    let has_lights = HAS_LIGHTS && frame.header.num_lights > 0u;
    if may_miss && hit.prim == NO_HIT {
        add_escaped(p);
        return PATH_ENDS;
    }
    let s = surface_at((*p).ray, hit, (*p).cone);
    // Rays leaving a surface start at the hit position itself and skip the primitive
    // left: a triangle ignores what is within the position's error (see `leave`), a
    // closed shape (a sphere) is met again only by a ray going into it, at its far side.
    let on_shape = is_shape(hit.prim);
    skip_prim = hit.prim;
    skip_inst = hit.inst;
    var mat = scene_material(s.material);
    if HAS_TEXTURES {
        mat = textured_material(mat, s.uv, s.lod, s.color);
        // The cone's width at the surface, where the next ray leaves (see PathState).
        (*p).cone.x += (*p).cone.y * hit.t;
    }
    if HAS_MEDIA && (mat.flags & MATERIAL_INDEX_MATCHED) != 0u {
        return cross_boundary(p, s, mat, on_shape);
    }
    let front = dot(s.ng, (*p).ray.dir) < 0.0;
    let two_sided = (mat.flags & MATERIAL_TWO_SIDED) != 0u;
    let glass = HAS_GLASS && mat.transmission > 0.0 && mat.metallic < 1.0;

    // Emission seen along the ray, weighted against light sampling.
    if s.light != NO_LIGHT && (front || two_sided) {
        var w = 1.0;
        if (*p).bsdf_pdf > 0.0 {
            w = hit_weight((*p).bsdf_pdf, light_pdf(scene_light(s.light), (*p).prev_p, s.p, s.ng));
        }
        (*p).radiance += (*p).throughput * mat.emission * w;
    }
    // One-sided opaque materials are black from behind; an interface has two sides.
    if !(front || two_sided || glass) || (*p).bounce >= frame.settings.max_bounces {
        return PATH_ENDS;
    }
    // Shading frame: opaque surfaces face the ray; an interface keeps its orientation
    // so the BSDF knows which side is inside.
    let flip = !front && !glass;
    let ng = select(s.ng, -s.ng, flip);
    let frame_n = select(s.ns, -s.ns, flip);
    let basis = onb(frame_n);
    let to_local = transpose(basis);
    let wo = to_local * -(*p).ray.dir;
    coat_normal = vec3f(0.0, 0.0, 1.0);
    if HAS_COAT && any(s.coat_n != s.ns) {
        coat_normal = normalize(to_local * select(s.coat_n, -s.coat_n, flip));
    }
    if wo.z > 0.0 {
        next_event(p, s, mat, on_shape, ng, front || flip, to_local, wo, has_lights);
    }
    return scatter(p, s, mat, on_shape, ng, basis, wo);
}

// The ray of path `p` through the medium it travels in, up to `hit`: Beer-Lambert
// absorption, or a free-flight distance that may scatter it before the surface (then
// next-event estimation from the medium point and a new direction by the phase function).
fn through_medium(p: ptr<function, PathState>, hit: Hit, has_lights: bool) -> u32 {
    let m = scene_material(medium_id);
    let t_hit = select(F32_MAX, hit.t, hit.prim != NO_HIT);
    let sigma_t = m.sigma_a + m.sigma_s;
    if all(m.sigma_s == vec3f(0.0)) {
        // Absorption only: Beer-Lambert to the next surface.
        (*p).throughput *= exp(-sigma_t * t_hit);
        return BOUNCE_GOES_ON;
    }
    // Free-flight distance by the extinction of a channel picked uniformly; the pdf is the
    // mean over the channels (one-sample MIS over the three).
    let c = min(u32(rand() * 3.0), 2u);
    let t = -log(1.0 - rand()) / sigma_t[c];
    if t < t_hit {
        let tr = exp(-sigma_t * t);
        let pdf = dot(sigma_t * tr, vec3f(1.0 / 3.0));
        if !(pdf > 0.0) || (*p).bounce >= frame.settings.max_bounces {
            return PATH_ENDS;
        }
        (*p).throughput *= m.sigma_s * tr / pdf;
        let dir = (*p).ray.dir;
        let x = (*p).ray.origin + t * dir;
        (*p).radiance += (*p).throughput * medium_next_event(x, dir, m.phase_g, (*p).bounce, has_lights);
        let wi = hg_sample(dir, m.phase_g, rand2());
        (*p).bsdf_pdf = hg_eval(dot(dir, wi), m.phase_g);
        (*p).prev_p = x;
        leave_no_surface();
        (*p).ray = Ray(x, wi);
        return select(PATH_ENDS, BOUNCE_DONE, survives_roulette(p));
    }
    // Through to the surface: the probability of no collision before it.
    let tr = exp(-sigma_t * t_hit);
    let p_pass = dot(tr, vec3f(1.0 / 3.0));
    if !(p_pass > 0.0) {
        return PATH_ENDS;
    }
    (*p).throughput *= tr / p_pass;
    return BOUNCE_GOES_ON;
}

// Light from outside the scene along the ray of path `p`, which left it: the environment,
// where it is seen (camera rays see it only when it is shown as background).
fn add_escaped(p: ptr<function, PathState>) {
    let visible = (*p).bounce > 0u || (frame.settings.env_flags & ENV_SHOW_BACKGROUND) != 0u;
    if HAS_ENVIRONMENT && visible && frame.settings.env_kind == ENV_CONSTANT {
        (*p).radiance += (*p).throughput * frame.settings.env_radiance;
    }
    if visible && env_map_on() {
        let e = env_eval((*p).ray.dir);
        (*p).radiance += (*p).throughput * e.rgb * hit_weight((*p).bsdf_pdf, e.a * env_select_prob());
    }
}

// An index-matched boundary `s`: no surface, the ray goes on into or out of the medium,
// and this is no scattering event (not counted as a bounce; MIS keeps the last vertex's
// pdf).
fn cross_boundary(p: ptr<function, PathState>, s: Surface, mat: Material, on_shape: bool) -> u32 {
    (*p).crossings += 1u;
    if (*p).crossings > MAX_CROSSINGS {
        return PATH_ENDS;
    }
    let dir = (*p).ray.dir;
    medium_id = medium_after(s.material, mat, s.ng, dir, medium_id);
    let side = select(-s.ng, s.ng, dot(s.ng, dir) > 0.0);
    (*p).ray = Ray(leave(s, on_shape, side, dir), dir);
    (*p).bounce -= 1u;
    return BOUNCE_DONE;
}

// Next-event estimation at surface point `s` through the BSDF's non-delta lobes (`wo` in
// the shading frame `to_local`; `ng` the geometric normal on the side the ray came from,
// `toward_ng` whether lit directions lie on its side): a light sample, MIS-weighted against
// BSDF sampling, and its shadow ray, traced here (through the media on the way) or, with
// WAVES, left for the host or `wave_trace` in `host_shadow`. Point, spot and directional lights,
// which no ray can hit, are sampled so even with BSDF sampling only.
fn next_event(
    p: ptr<function, PathState>,
    s: Surface,
    mat: Material,
    on_shape: bool,
    ng: vec3f,
    toward_ng: bool,
    to_local: mat3x3f,
    wo: vec3f,
    has_lights: bool,
) {
    let p_env = env_select_prob();
    if !(has_lights || p_env > 0.0) {
        return;
    }
    let ls = sample_next_event(s.p, (*p).bounce, p_env);
    let wanted = ls.delta || frame.strategy != STRATEGY_BSDF;
    if !(wanted && ls.pdf > 0.0 && dot(ng, ls.wi) * select(-1.0, 1.0, toward_ng) > 0.0) {
        return;
    }
    let e = eval_bsdf(mat, wo, to_local * ls.wi);
    if !(e.pdf > 0.0 || any(e.f_cos > vec3f(0.0))) {
        return;
    }
    let shadow = Ray(leave(s, on_shape, select(-ng, ng, dot(ng, ls.wi) > 0.0), ls.wi), ls.wi);
    ray_count += 1u;
    let w = select(light_weight(ls.pdf, e.pdf), 1.0, ls.delta);
    if HAS_MEDIA {
        // Through the media on the way, across index-matched boundaries.
        let start = medium_after(s.material, mat, s.ng, ls.wi, medium_id);
        let tr = shadow_transmittance(shadow, ls.dist - ls.margin, start);
        if any(tr > vec3f(0.0)) {
            (*p).radiance += (*p).throughput * e.f_cos * ls.radiance * tr * (w / ls.pdf);
        }
        return;
    }
    let contribution = (*p).throughput * e.f_cos * ls.radiance * (w / ls.pdf);
    if WAVES {
        // The host or `wave_trace` answers the shadow ray before the next step.
        host_shadow.ray = shadow;
        host_shadow.near = origin_slab;
        host_shadow.n = origin_n;
        host_shadow.far = ls.dist - ls.margin;
        host_shadow.contribution = contribution;
        host_shadow.pending = true;
    } else if !occluded(shadow, ls.dist - ls.margin) {
        (*p).radiance += contribution;
    }
}

// The next direction of path `p` at surface point `s`, sampled from the BSDF (`wo` and the
// sample in the shading frame `basis`), the ray leaving from the side it goes to, and
// Russian roulette.
fn scatter(
    p: ptr<function, PathState>,
    s: Surface,
    mat: Material,
    on_shape: bool,
    ng: vec3f,
    basis: mat3x3f,
    wo: vec3f,
) -> u32 {
    let u_lobe = rand();
    let u_dir = sample_2d_at(PAIR_BSDF, (*p).bounce);
    let bs = sample_bsdf(mat, wo, u_lobe, vec3f(u_dir, rand()));
    if !bs.valid {
        return PATH_ENDS;
    }
    let wi = basis * bs.wi;
    if HAS_MEDIA {
        medium_id = medium_after(s.material, mat, s.ng, wi, medium_id);
    }
    let side = select(-ng, ng, dot(ng, wi) > 0.0);
    if HAS_TEXTURES {
        (*p).cone.y += lobe_spread(bs.pdf);
    }
    (*p).throughput *= bs.weight;
    (*p).bsdf_pdf = bs.pdf;
    (*p).prev_p = s.p;
    (*p).ray = Ray(leave(s, on_shape, side, wi), wi);
    return select(PATH_ENDS, BOUNCE_DONE, survives_roulette(p));
}

// What a BSDF sample of solid-angle pdf `pdf` adds to its ray cone's spread angle: the
// half-angle of a cone of solid angle 1 / pdf (about sqrt(1 / (pi pdf)) radians), at most 1
// radian (a diffuse sample's); 0 for a delta sample (pdf 0).
fn lobe_spread(pdf: f32) -> f32 {
    if !(pdf > 0.0) {
        return 0.0;
    }
    return min(inverseSqrt(PI * pdf), 1.0);
}

// Russian roulette from bounce RR_START on: whether path `p` goes on, its throughput then
// divided by the probability it did.
fn survives_roulette(p: ptr<function, PathState>) -> bool {
    if (*p).bounce + 1u >= RR_START {
        let q = min(max((*p).throughput.x, max((*p).throughput.y, (*p).throughput.z)), 0.95);
        if rand() >= q {
            return false;
        }
        (*p).throughput /= q;
    }
    return true;
}

// The radiance of one path through `pixel` for the current sample (`sampler_init`).
fn trace_path(pixel: vec2u) -> vec3f {
    start_path(pixel);
    loop {
        if path_step() {
            break;
        }
    }
    return path.radiance;
}
