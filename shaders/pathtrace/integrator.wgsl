// The integrator: a path's state, and one bounce of it (`path_step_from`, the one shading
// core of the megakernel and of host intersection's steps): emission found with its MIS
// weight, media, next-event estimation, BSDF sampling, Russian roulette.
// From its includer (pathtrace/pathtrace.wgsl): `frame`, the binding `lights` and
// `ray_count`.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/options.wgsl"
#import "pathtrace/sampler.wgsl"
#import "pathtrace/bsdf.wgsl"
#import "pathtrace/intersect.wgsl"
#import "pathtrace/alpha.wgsl"
#import "pathtrace/medium.wgsl"
#import "pathtrace/mis.wgsl"
#import "pathtrace/surface.wgsl"
#import "pathtrace/lights.wgsl"
#import "pathtrace/camera.wgsl"

const RR_START: u32 = 5u;

// The path being traced: `start_path` begins one, `path_step` takes it one bounce on.
var<private> path_ray: Ray;
var<private> path_throughput: vec3f;
var<private> path_radiance: vec3f;
// Solid-angle pdf of the BSDF sample that made `path_ray` (0: a mirror, interface or camera
// ray, which light sampling cannot produce), and where it left from (for MIS).
var<private> path_bsdf_pdf: f32;
var<private> path_prev_p: vec3f;
var<private> path_bounce: u32;
// The index-matched boundaries crossed so far.
var<private> path_crossings: u32;

// With HOST_RAYS: the shadow ray of the step's next-event estimate, which the host traces
// (from `shadow_near` to `shadow_far` along it), and what it adds to the path's radiance
// unless occluded.
var<private> shadow_pending: bool;
var<private> shadow_ray: Ray;
var<private> shadow_near: f32;
var<private> shadow_far: f32;
var<private> shadow_contribution: vec3f;

// Starts the path of the current sample (`sampler_init`) through `pixel`.
fn start_path(pixel: vec2u) {
    path_ray = camera_ray(pixel, sample_2d(PAIR_PIXEL));
    path_throughput = vec3f(1.0);
    path_radiance = vec3f(0.0);
    path_bsdf_pdf = 0.0;
    path_prev_p = path_ray.origin;
    path_bounce = 0u;
    path_crossings = 0u;
    // The triangle the current ray leaves (never hit again); camera rays leave none.
    leave_no_surface();
    // The medium the ray travels in: paths start in none.
    if HAS_MEDIA {
        medium_id = NO_MEDIUM;
    }
}

// Takes the path one bounce on; true once it ended (its radiance is `path_radiance`).
fn path_step() -> bool {
    return path_step_from(intersect_scene(path_ray), true);
}

// `path_step` with the closest hit of `path_ray` given (`hit`); `may_miss` false where the
// caller knows the ray hit (a constant: the compiler leaves the miss's code out).
fn path_step_from(first_hit: Hit, may_miss: bool) -> bool {
    var ray = path_ray;
    var throughput = path_throughput;
    var radiance = path_radiance;
    var bsdf_pdf = path_bsdf_pdf;
    var prev_p = path_prev_p;
    var bounce = path_bounce;
    var crossings = path_crossings;
    let max_bounces = frame.settings.max_bounces;
    let has_lights = HAS_LIGHTS && frame.header.num_lights > 0u;
    var ended = false;
    // One pass: `break` leaves the bounce, `ended` says whether the path ends with it.
    loop {
        let hit = first_hit;
        ray_count += 1u;
        if HAS_MEDIA && medium_id != NO_MEDIUM {
            let m = scene_material(medium_id);
            let t_hit = select(F32_MAX, hit.t, hit.prim != NO_HIT);
            let sigma_t = m.sigma_a + m.sigma_s;
            if all(m.sigma_s == vec3f(0.0)) {
                // Absorption only: Beer-Lambert to the next surface.
                throughput *= exp(-sigma_t * t_hit);
            } else {
                // Free-flight distance by the extinction of a channel picked uniformly; the
                // pdf is the mean over the channels (one-sample MIS over the three).
                let c = min(u32(rand() * 3.0), 2u);
                let t = -log(1.0 - rand()) / sigma_t[c];
                if t < t_hit {
                    let tr = exp(-sigma_t * t);
                    let pdf = dot(sigma_t * tr, vec3f(1.0 / 3.0));
                    if !(pdf > 0.0) || bounce >= max_bounces {
                        ended = true;
                        break;
                    }
                    throughput *= m.sigma_s * tr / pdf;
                    let p = ray.origin + t * ray.dir;
                    radiance += throughput * medium_next_event(p, ray.dir, m.phase_g, bounce, has_lights);
                    let wi = hg_sample(ray.dir, m.phase_g, rand2());
                    bsdf_pdf = hg_eval(dot(ray.dir, wi), m.phase_g);
                    prev_p = p;
                    leave_no_surface();
                    ray = Ray(p, wi);
                    if bounce + 1u >= RR_START {
                        let q = min(max(throughput.x, max(throughput.y, throughput.z)), 0.95);
                        if rand() >= q {
                            ended = true;
                            break;
                        }
                        throughput /= q;
                    }
                    break;
                }
                // Through to the surface: the probability of no collision before it.
                let tr = exp(-sigma_t * t_hit);
                let p_pass = dot(tr, vec3f(1.0 / 3.0));
                if !(p_pass > 0.0) {
                    ended = true;
                    break;
                }
                throughput *= tr / p_pass;
            }
        }
        if may_miss && hit.prim == NO_HIT {
            // Camera rays see the environment only when it is shown as background.
            let visible = bounce > 0u || (frame.settings.env_flags & ENV_SHOW_BACKGROUND) != 0u;
            if HAS_ENVIRONMENT && visible && frame.settings.env_kind == ENV_CONSTANT {
                radiance += throughput * frame.settings.env_radiance;
            }
            if visible && env_map_on() {
                let e = env_eval(ray.dir);
                radiance += throughput * e.rgb * hit_weight(bsdf_pdf, e.a * env_select_prob());
            }
            ended = true;
            break;
        }
        let s = surface_at(ray, hit);
        // Rays leaving a surface start at the hit position itself and skip the primitive
        // left: a triangle ignores what is within the position's error (see `leave`), a
        // sphere is met again only by a ray going into it, at its far side.
        let on_sphere = is_sphere(hit.prim);
        skip_prim = hit.prim;
        var mat = scene_material(s.material);
        if HAS_TEXTURES {
            mat = textured_material(mat, s.uv, s.color);
        }
        if HAS_MEDIA && (mat.flags & MATERIAL_INDEX_MATCHED) != 0u {
            // No surface: the ray goes on into or out of the medium, and this is no
            // scattering event (not counted as a bounce; MIS keeps the last vertex's pdf).
            crossings += 1u;
            if crossings > MAX_CROSSINGS {
                ended = true;
                break;
            }
            medium_id = medium_after(s.material, mat, s.ng, ray.dir, medium_id);
            let side = select(-s.ng, s.ng, dot(s.ng, ray.dir) > 0.0);
            ray = Ray(leave(s, on_sphere, side, ray.dir), ray.dir);
            bounce -= 1u;
            break;
        }
        let front = dot(s.ng, ray.dir) < 0.0;
        let two_sided = (mat.flags & MATERIAL_TWO_SIDED) != 0u;
        let glass = HAS_GLASS && mat.transmission > 0.0 && mat.metallic < 1.0;

        // Emission seen along the ray, weighted against light sampling.
        if s.light != NO_LIGHT && (front || two_sided) {
            var w = 1.0;
            if bsdf_pdf > 0.0 {
                w = hit_weight(bsdf_pdf, light_pdf(scene_light(s.light), prev_p, s.p, s.ng));
            }
            radiance += throughput * mat.emission * w;
        }
        // One-sided opaque materials are black from behind; an interface has two sides.
        if !(front || two_sided || glass) || bounce >= max_bounces {
            ended = true;
            break;
        }
        // Shading frame: opaque surfaces face the ray; an interface keeps its orientation
        // so the BSDF knows which side is inside.
        let flip = !front && !glass;
        let ng = select(s.ng, -s.ng, flip);
        let frame_n = select(s.ns, -s.ns, flip);
        let basis = onb(frame_n);
        let to_local = transpose(basis);
        let wo = to_local * -ray.dir;

        // Next-event estimation through the non-delta lobes.
        let p_env = env_select_prob();
        // (BSDF sampling only: point, spot and directional lights, which no ray can hit.)
        if (has_lights || p_env > 0.0) && wo.z > 0.0 {
            let ls = sample_next_event(s.p, bounce, p_env);
            let wanted = ls.delta || frame.strategy != STRATEGY_BSDF;
            if wanted && ls.pdf > 0.0 && dot(ng, ls.wi) * select(-1.0, 1.0, front || flip) > 0.0 {
                let e = eval_bsdf(mat, wo, to_local * ls.wi);
                if e.pdf > 0.0 || any(e.f_cos > vec3f(0.0)) {
                    let shadow = Ray(leave(s, on_sphere, select(-ng, ng, dot(ng, ls.wi) > 0.0), ls.wi), ls.wi);
                    ray_count += 1u;
                    if HAS_MEDIA {
                        // Through the media on the way, across index-matched boundaries.
                        let start = medium_after(s.material, mat, s.ng, ls.wi, medium_id);
                        let tr = shadow_transmittance(shadow, ls.dist - ls.margin, start);
                        if any(tr > vec3f(0.0)) {
                            let w = select(light_weight(ls.pdf, e.pdf), 1.0, ls.delta);
                            radiance += throughput * e.f_cos * ls.radiance * tr * (w / ls.pdf);
                        }
                    } else {
                        let w = select(light_weight(ls.pdf, e.pdf), 1.0, ls.delta);
                        let contribution = throughput * e.f_cos * ls.radiance * (w / ls.pdf);
                        if HOST_RAYS {
                            // The host answers the shadow ray before the next step.
                            shadow_ray = shadow;
                            shadow_near = origin_slab;
                            shadow_far = ls.dist - ls.margin;
                            shadow_contribution = contribution;
                            shadow_pending = true;
                        } else if !occluded(shadow, ls.dist - ls.margin) {
                            radiance += contribution;
                        }
                    }
                }
            }
        }

        let u_lobe = rand();
        let u_dir = sample_2d_at(PAIR_BSDF, bounce);
        let bs = sample_bsdf(mat, wo, u_lobe, vec3f(u_dir, rand()));
        if !bs.valid {
            ended = true;
            break;
        }
        let wi = basis * bs.wi;
        if HAS_MEDIA {
            medium_id = medium_after(s.material, mat, s.ng, wi, medium_id);
        }
        // Leave from the side of the surface the new ray goes to.
        let side = select(-ng, ng, dot(ng, wi) > 0.0);
        throughput *= bs.weight;
        bsdf_pdf = bs.pdf;
        prev_p = s.p;
        ray = Ray(leave(s, on_sphere, side, wi), wi);

        // Russian roulette.
        if bounce + 1u >= RR_START {
            let q = min(max(throughput.x, max(throughput.y, throughput.z)), 0.95);
            if rand() >= q {
                ended = true;
                break;
            }
            throughput /= q;
        }
        break;
    }
    path_ray = ray;
    path_throughput = throughput;
    path_radiance = radiance;
    path_bsdf_pdf = bsdf_pdf;
    path_prev_p = prev_p;
    path_bounce = bounce + 1u;
    path_crossings = crossings;
    return ended;
}

// The radiance of one path through `pixel` for the current sample (`sampler_init`).
fn trace_path(pixel: vec2u) -> vec3f {
    start_path(pixel);
    loop {
        if path_step() {
            break;
        }
    }
    return path_radiance;
}
