// Path tracer megakernel: one invocation per pixel traces `samples_per_frame` paths and
// writes their mean radiance. Unidirectional path tracing with next-event estimation and
// multiple importance sampling (power heuristic) for emissive triangles and spheres and the
// environment map, next-event estimation alone for point, spot and directional lights,
// Russian roulette from the fifth bounce, the layered material of bsdf.wgsl (diffuse or
// rough diffuse base under GGX specular, metal, glass) and one-sided emitters (Mitsuba 3's
// conventions, so the references match). With HAS_MEDIA, homogeneous media
// inside closed shapes (medium.wgsl): Beer-Lambert absorption, or free-flight distance
// sampling with Henyey-Greenstein scattering, next-event estimation from medium points with
// MIS against phase sampling, and shadow rays through index-matched boundaries. Samples
// that are not finite never reach the output: they are dropped and counted in `stats[0]`.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/sampler.wgsl"
#import "common/sampling.wgsl"
#import "pathtrace/options.wgsl"
#import "pathtrace/bsdf.wgsl"
#import "pathtrace/env.wgsl"
#import "pathtrace/textures.wgsl"
// Constants shared with the Rust side, generated from crates/render/src/shared.rs.
#import "pathtrace/shared.wgsl"

struct Frame {
    settings: Settings,
    camera: Camera,
    header: SceneHeader,
    // Index of this frame's first sample in the pixel's sample sequence.
    sample_offset: u32,
    samples_per_frame: u32,
    // Size of the environment map (1x1 without one).
    env_width: u32,
    env_height: u32,
    // Largest channel value one sample may contribute (0: no clamp).
    firefly_clamp: f32,
    // SAMPLER_SOBOL or SAMPLER_INDEPENDENT (sampler.wgsl).
    sampler: u32,
    // STRATEGY_MIS, STRATEGY_LIGHT or STRATEGY_BSDF: how direct light is estimated.
    strategy: u32,
    // 1 or 2 Sobol replicates, alternating by frame (sampler.wgsl).
    replicates: u32,
    // The pixels this pass renders: left, top, width and height in the whole image (all of
    // it unless the render is tiled); the output holds them from (0, 0).
    window: vec4<u32>,
    // The samples of the frame this dispatch traces: `chunk_count` from `chunk_first`. On CPU
    // adapters a frame takes several dispatches (llvmpipe ends a dispatch's loops after 65 535
    // iterations in all); their sums are kept in `chunk_sums` and the last writes the mean.
    chunk_first: u32,
    chunk_count: u32,
    // CHUNK_FIRST | CHUNK_LAST.
    chunk_flags: u32,
    // With HOST_RAYS: WAVE_STEP or WAVE_FINISH (below); the first slot of the batch of
    // slots being traced, how many slots `wave`'s sections hold, and how many of the step's
    // listed slots `wave_misses` takes (`wave_hits` the rest).
    wave: u32,
    wave_base: u32,
    wave_capacity: u32,
    wave_split: u32,
    pad1: u32,
}

const CHUNK_FIRST: u32 = 1u;
const CHUNK_LAST: u32 = 2u;

const STRATEGY_MIS: u32 = 0u;
const STRATEGY_LIGHT: u32 = 1u;
const STRATEGY_BSDF: u32 = 2u;

// Weight of emission that a BSDF-sampled ray (solid-angle pdf `bsdf_pdf`, 0 after a mirror,
// an interface or from the camera) finds where light sampling has pdf `light_pdf`.
fn hit_weight(bsdf_pdf: f32, light_pdf: f32) -> f32 {
    if bsdf_pdf == 0.0 || frame.strategy == STRATEGY_BSDF {
        return 1.0;
    }
    return select(mis_power(bsdf_pdf, light_pdf), 0.0, frame.strategy == STRATEGY_LIGHT);
}

// Weight of a light sample of pdf `light_pdf` where BSDF sampling has pdf `bsdf_pdf`.
fn light_weight(light_pdf: f32, bsdf_pdf: f32) -> f32 {
    return select(mis_power(light_pdf, bsdf_pdf), 1.0, frame.strategy == STRATEGY_LIGHT);
}

@group(0) @binding(0) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(1) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> bvh_nodes: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> tri_positions: array<TriPositions>;
@group(0) @binding(4) var<storage, read> tri_shading: array<TriShading>;
@group(0) @binding(5) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(6) var<storage, read> materials: array<Material>;
@group(0) @binding(7) var<storage, read> lights: array<Light>;
@group(0) @binding(8) var<storage, read> light_alias: array<AliasEntry>;
@group(0) @binding(9) var<storage, read_write> stats: array<atomic<u32>>;
// First-hit AOVs (when WRITE_AOVS): albedo, world-space shading normal, distance.
@group(0) @binding(10) var out_albedo: texture_storage_2d<rgba32float, write>;
@group(0) @binding(11) var out_normal: texture_storage_2d<rgba32float, write>;
@group(0) @binding(12) var out_depth: texture_storage_2d<r32float, write>;
// GGX albedo tables for the material model (see bsdf.wgsl).
@group(0) @binding(13) var<storage, read> ggx_table: array<vec2f>;
// Environment map texels (rgb radiance, a = pixel probability) and their alias table.
@group(0) @binding(14) var<storage, read> env_texels: array<vec4f>;
@group(0) @binding(15) var<storage, read> env_alias: array<AliasEntry>;
// Texture coordinates and tangents per triangle, and where every texture is in the atlas
// (`textures`, binding 23; see textures.wgsl); one zeroed entry each (and a 1x1 atlas) when no
// material has a texture (HAS_TEXTURES off).
@group(0) @binding(16) var<storage, read> tri_texcoords: array<TriTexcoords>;
@group(0) @binding(17) var<storage, read> texture_descs: array<TexDesc>;
// Adaptive sampling (ADAPTIVE), per pixel of the window: the sums (rgb) and frame counts (a)
// of the even and of the odd frames, in that order, and whether `pathtrace/adaptive.wgsl`
// stopped the pixel (16-byte stand-ins otherwise).
@group(0) @binding(18) var<storage, read_write> adaptive_halves: array<vec4f>;
@group(0) @binding(19) var<storage, read> adaptive_stopped: array<u32>;
// The pixels still sampling this frame: their count, then each one's x | y << 16.
@group(0) @binding(20) var<storage, read> adaptive_active: array<u32>;
// Per pixel of the window: the sum of the frame's samples traced by its earlier dispatches.
@group(0) @binding(21) var<storage, read_write> chunk_sums: array<vec4f>;
// With HOST_RAYS, the paths in flight and the rays the host intersects (a 16-byte stand-in
// otherwise): see `wave_step`.
@group(0) @binding(22) var<storage, read_write> wave: array<vec4<u32>>;
// The texture atlas: every texture of the scene in the RGBA8 pages of one array texture.
@group(0) @binding(23) var textures: texture_2d_array<f32>;

#import "pathtrace/intersect.wgsl"
#import "pathtrace/scene_data.wgsl"
#import "pathtrace/alpha.wgsl"
#import "pathtrace/medium.wgsl"

const RR_START: u32 = 5u;

// Rays traced by this invocation (camera, extension and shadow rays), for the report.
var<private> ray_count: u32;

struct Surface {
    p: vec3f,
    // Geometric normal, front side (triangles: e1 x e2; spheres: outward).
    ng: vec3f,
    // Shading normal, front side.
    ns: vec3f,
    material: u32,
    light: u32,
    // Componentwise bound on the rounding error of `p` (triangles; 0 on spheres).
    err: vec3f,
    // Texture coordinates, set 0 in xy and set 1 in zw (HAS_TEXTURES; 0 on spheres).
    uv: vec4f,
    // Vertex colour (HAS_TEXTURES; white on spheres).
    color: vec4f,
}

// Rounding error bounds of a point computed as v0 + u e1 + v e2 in f32: a float step of each
// term (2^-23 relative) for the sum, plus 2^-20 of the edges for the error of the plane
// distance Moller-Trumbore computes against a neighbouring triangle. At 1e5 this is 1.5 float
// steps (0.012 units); at the origin of a unit-sized scene, about 4e-6.
const POSITION_ERR: f32 = 1.1920929e-7;
const EDGE_ERR: f32 = 9.536743e-7;

fn barycentric_err(v0: vec3f, e1: vec3f, e2: vec3f, u: f32, v: f32) -> vec3f {
    return POSITION_ERR * (abs(v0) + abs(u * e1) + abs(v * e2)) + EDGE_ERR * (abs(e1) + abs(e2));
}

// Whether `prim` (a hit's) is a sphere; a constant where the scene has one kind only.
fn is_sphere(prim: u32) -> bool {
    return HAS_SPHERES && (!HAS_TRIANGLES || (prim & PRIM_SPHERE) != 0u);
}

fn surface_at(ray: Ray, hit: Hit) -> Surface {
    var s: Surface;
    s.p = ray.origin + hit.t * ray.dir;
    s.err = vec3f(0.0);
    s.uv = vec4f(0.0);
    s.color = vec4f(1.0);
    if is_sphere(hit.prim) {
        let sph = scene_sphere(hit.prim & ~PRIM_SPHERE);
        s.ng = normalize(s.p - sph.center);
        s.ns = s.ng;
        s.material = sph.material;
        s.light = sph.light;
    } else {
        let tri = scene_tri_positions(hit.prim);
        let sh = scene_tri_shading(hit.prim);
        // Position from the barycentrics: more accurate than origin + t * dir far away.
        s.p = tri.v0 + hit.u * tri.e1 + hit.v * tri.e2;
        s.err = barycentric_err(tri.v0, tri.e1, tri.e2, hit.u, hit.v);
        s.ng = normalize(cross(tri.e1, tri.e2));
        if (sh.flags & TRI_VERTEX_NORMALS) != 0u {
            let n = (1.0 - hit.u - hit.v) * sh.n0 + hit.u * sh.n1 + hit.v * sh.n2;
            s.ns = select(s.ng, normalize(n), dot(n, n) > 0.0);
        } else {
            s.ns = s.ng;
        }
        s.material = sh.material;
        s.light = sh.light;
        if HAS_TEXTURES {
            let tc = tri_texcoords[hit.prim];
            s.uv = tri_uv(tc, hit.u, hit.v);
            s.color = tri_color(tc, hit.u, hit.v);
            s.ns = normal_mapped(scene_material(sh.material), s.ns, s.ng, s.uv, tri_tangent(tc, hit.u, hit.v));
        }
    }
    return s;
}

struct LightSample {
    // Unit direction from the shading point to the light.
    wi: vec3f,
    dist: f32,
    radiance: vec3f,
    // Solid-angle pdf, light selection included; 0 when the sample is invalid.
    pdf: f32,
    // How far the shadow ray stops short of `dist`, so that it does not reach the light (or
    // what is coplanar with it): the sampled point's error off the light's plane over the
    // cosine there, and a relative term for the error of t.
    margin: f32,
    // A point, spot or directional light: `pdf` is only its selection probability, and no
    // BSDF-sampled ray can reach it (no MIS).
    delta: bool,
}

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
    if (l.flags & LIGHT_SPHERE) != 0u {
        let r = l.e1.x;
        let s = min(1.0, r * r / dot(l.p0 - x, l.p0 - x));
        let cone = one_minus_sqrt_one_minus(s);
        return light_select_pdf(l) / (TWO_PI * cone);
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
    if (l.flags & LIGHT_DELTA) != 0u {
        out.delta = true;
        out.pdf = light_select_pdf(l);
        if (l.flags & LIGHT_DIRECTIONAL) != 0u {
            out.wi = -l.e1;
            out.dist = F32_MAX;
            out.radiance = l.emission;
            out.margin = 0.0;
            return out;
        }
        let d = l.p0 - x;
        let dist2 = dot(d, d);
        let dist = sqrt(dist2);
        out.wi = d / dist;
        out.dist = dist;
        out.margin = EDGE_ERR * dist;
        var falloff = 1.0;
        if (l.flags & LIGHT_SPOT) != 0u {
            // Full within the beam width e2.y, linear in angle to 0 at the cutoff e2.x.
            let theta = acos(clamp(dot(-out.wi, l.e1), -1.0, 1.0));
            falloff = clamp((l.e2.x - theta) / max(l.e2.x - l.e2.y, 1e-12), 0.0, 1.0);
        }
        out.radiance = l.emission * (falloff / dist2);
        return out;
    }
    if (l.flags & LIGHT_SPHERE) != 0u {
        // Uniform direction in the cone the sphere subtends.
        let r = l.e1.x;
        let to_c = l.p0 - x;
        let d2 = dot(to_c, to_c);
        if d2 <= r * r {
            return out;
        }
        let d = sqrt(d2);
        let cone = one_minus_sqrt_one_minus(r * r / d2);
        let cos_t = 1.0 - u.x * cone;
        let sin_t = sqrt(max(0.0, (1.0 - cos_t) * (1.0 + cos_t)));
        let phi = TWO_PI * u.y;
        let axis = to_c / d;
        let wi = normalize(onb(axis) * vec3f(sin_t * cos(phi), sin_t * sin(phi), cos_t));
        // Distance to the near intersection with the sphere.
        let b = dot(to_c, wi);
        let h = to_c - b * wi;
        let dist = b - sqrt(max(0.0, r * r - dot(h, h)));
        out.wi = wi;
        out.dist = dist;
        out.radiance = l.emission;
        out.pdf = light_select_pdf(l) / (TWO_PI * cone);
        out.margin = 1e-4 * dist;
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

// The pinhole ray through image position `u` within `pixel`.
fn pinhole_ray(pixel: vec2u, u: vec2f) -> Ray {
    let cam = frame.camera;
    let size = vec2f(f32(frame.settings.width), f32(frame.settings.height));
    let xy = (vec2f(pixel) + u) / size;
    let dir = cam.forward + (2.0 * xy.x - 1.0) * cam.tan_half_fov * cam.aspect * cam.right
        - (2.0 * xy.y - 1.0) * cam.tan_half_fov * cam.up;
    return Ray(cam.position, normalize(dir));
}

fn camera_ray(pixel: vec2u, u: vec2f) -> Ray {
    let cam = frame.camera;
    var ray = pinhole_ray(pixel, u);
    if cam.aperture_radius > 0.0 {
        let lens = cam.aperture_radius * sample_disk(sample_2d(PAIR_LENS));
        let focus = cam.position + ray.dir * (cam.focus_distance / dot(ray.dir, cam.forward));
        ray.origin = cam.position + lens.x * cam.right + lens.y * cam.up;
        ray.dir = normalize(focus - ray.origin);
    }
    return ray;
}

// For a ray that leaves no surface (a camera ray, a ray from a point in a medium): no
// primitive skipped, no origin error.
fn leave_no_surface() {
    skip_prim = NO_HIT;
    origin_n = vec3f(0.0);
    origin_err = vec3f(0.0);
    origin_off = 0.0;
    origin_slab = 0.0;
}

// The origin of a ray leaving `s` towards the side `n` faces, and its error for the
// intersection routines (`origin_n`, `origin_err`, `origin_off`, `origin_slab`,
// `skip_inward`). Rays start at the hit itself, never offset (`skip_prim`).
fn leave(s: Surface, on_sphere: bool, n: vec3f, dir: vec3f) -> vec3f {
    if on_sphere {
        origin_n = vec3f(0.0);
        origin_err = vec3f(0.0);
        origin_off = 0.0;
        origin_slab = 0.0;
        skip_inward = dot(dir, s.ng) < 0.0;
        return s.p;
    }
    // The front of the plane left is the side the ray goes to.
    origin_n = n;
    origin_err = s.err;
    origin_off = dot(abs(n), s.err);
    origin_slab = origin_off / abs(dot(n, dir));
    return s.p;
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

// The row of 8×8 tiles that workgroup row `row` of `rows` traces: rows a stride apart, the
// stride near rows / golden ratio and prime to `rows` (so every row is traced once). llvmpipe
// splits a dispatch into one contiguous range of workgroups per thread; in image order, a
// thread given the sky would idle while another traces the ground.
fn spread_row(row: u32, rows: u32) -> u32 {
    var stride = max(u32(f32(rows) * 0.618034), 1u);
    loop {
        var a = stride;
        var b = rows;
        while b != 0u {
            let r = a % b;
            a = b;
            b = r;
        }
        if a == 1u {
            break;
        }
        stride += 1u;
    }
    return (row * stride) % rows;
}

@compute @workgroup_size(8, 8)
fn main(
    @builtin(workgroup_id) group: vec3u,
    @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_id) local: vec3u,
    @builtin(local_invocation_index) lane: u32,
) {
    // The tile this workgroup traces: the workgroup's own, or with SPREAD_WORKGROUPS (CPU
    // adapters) the rows of tiles spread over the image, which is the same work in another
    // order (the images are bit-identical).
    var tile = group.xy;
    if SPREAD_WORKGROUPS {
        tile.y = spread_row(group.y, groups.y);
    }
    let id = tile * 8u + local.xy;
    var at = id;
    var trace = true;
    if ADAPTIVE {
        // A pixel adaptive sampling stopped takes no samples and outputs alpha 0. The pixels
        // still sampling are traced by the first invocations, in the order the adaptive pass
        // listed them (workgroup by workgroup), so whole workgroups at the end idle.
        if all(id < frame.window.zw) && adaptive_stopped[id.y * frame.window.z + id.x] != 0u {
            textureStore(output, id, vec4f(0.0));
        }
        let k = (tile.y * groups.x + tile.x) * 64u + lane;
        trace = k < adaptive_active[0];
        if trace {
            let packed = adaptive_active[1u + k];
            at = vec2u(packed & 0xffffu, packed >> 16u);
        }
    }
    if HOST_RAYS {
        if frame.wave == WAVE_FINISH {
            let slot = id.y * frame.window.z + id.x;
            if all(id < frame.window.zw) {
                let n = f32(max(frame.samples_per_frame, 1u));
                textureStore(output, id, vec4f(chunk_sums[slot].xyz / n, 1.0));
            }
            first_hit_aovs(id);
            return;
        }
        // The steps are the entry points below.
        return;
    }
    if trace {
        trace_pixel(at);
    }
    first_hit_aovs(id);
}

// Adds a path's radiance `l` to `sum`, clamped (`firefly_clamp`), or counts it in `dropped`
// when it is not finite.
fn add_sample(radiance: vec3f, sum: ptr<function, vec3f>, dropped: ptr<function, u32>) {
    var l = radiance;
    if frame.firefly_clamp > 0.0 {
        let peak = max(l.x, max(l.y, l.z));
        l *= select(1.0, frame.firefly_clamp / peak, peak > frame.firefly_clamp);
    }
    if all_finite(l) {
        *sum += l;
    } else {
        *dropped += 1u;
    }
}

// Traces the pixel `at` of the window (`samples_per_frame` paths) and writes their mean.
fn trace_pixel(at: vec2u) {
    let w = frame.settings.width;
    let h = frame.settings.height;
    // The pixel of the whole image: tiles sample and trace exactly as the whole image does.
    let pixel = at + frame.window.xy;
    if any(at >= frame.window.zw) || pixel.x >= w || pixel.y >= h {
        return;
    }
    let pixel_index = pixel.y * w + pixel.x;
    var sum = vec3f(0.0);
    var dropped = 0u;
    ray_count = 0u;
    let n = frame.samples_per_frame;
    let first = frame.chunk_first;
    let end = first + frame.chunk_count;
    if REGENERATE_PATHS {
        // One loop over the bounces of all the samples: a lane whose path ended starts its
        // next sample at once instead of idling until the longest path of its SIMD vector
        // ends (the same samples, traced and summed in the same order).
        var i = first;
        if i < end {
            sampler_init(pixel_index, frame.sample_offset + i, frame.settings.seed, frame.sampler, n, frame.replicates);
            start_path(pixel);
            loop {
                if path_step() {
                    add_sample(path_radiance, &sum, &dropped);
                    i++;
                    if i >= end {
                        break;
                    }
                    sampler_init(pixel_index, frame.sample_offset + i, frame.settings.seed, frame.sampler, n, frame.replicates);
                    start_path(pixel);
                }
            }
        }
    } else {
        for (var i = first; i < end; i++) {
            sampler_init(pixel_index, frame.sample_offset + i, frame.settings.seed, frame.sampler, n, frame.replicates);
            add_sample(trace_path(pixel), &sum, &dropped);
        }
    }
    if dropped > 0u {
        atomicAdd(&stats[0], dropped);
    }
    // 64-bit ray count in two words: carry into the high word when the low one wraps.
    let before = atomicAdd(&stats[1], ray_count);
    if before > 0xffffffffu - ray_count {
        atomicAdd(&stats[2], 1u);
    }
    let slot = at.y * frame.window.z + at.x;
    if (frame.chunk_flags & CHUNK_FIRST) == 0u {
        sum += chunk_sums[slot].xyz;
    }
    if (frame.chunk_flags & CHUNK_LAST) == 0u {
        chunk_sums[slot] = vec4f(sum, 0.0);
        return;
    }
    let mean = sum / f32(max(n, 1u));
    textureStore(output, at, vec4f(mean, 1.0));
    if ADAPTIVE {
        // Frames alternate two replicates: the even ones make one half, the odd the other.
        let odd = ((frame.sample_offset / max(n, 1u)) & 1u) == 1u;
        let i = 2u * (at.y * frame.window.z + at.x) + select(0u, 1u, odd);
        adaptive_halves[i] += vec4f(mean, 1.0);
        atomicAdd(&stats[3], n);
    }
}

// First hit through the center of the window's pixel `at`: what a raster G-buffer sees.
fn first_hit_aovs(at: vec2u) {
    let pixel = at + frame.window.xy;
    if any(at >= frame.window.zw) || pixel.x >= frame.settings.width || pixel.y >= frame.settings.height {
        return;
    }
    if WRITE_AOVS {
        // First hit through the pixel center: what a raster G-buffer sees.
        let ray = pinhole_ray(pixel, vec2f(0.5));
        leave_no_surface();
        let hit = intersect_scene(ray);
        var albedo = vec3f(0.0);
        var normal = vec3f(0.0);
        var depth = 0.0;
        // As GBuffer: alpha 2 on emitters, 1 on other surfaces, 0 where nothing is hit (Denoise
        // never mixes emitters with the rest).
        var flag = 0.0;
        if hit.prim != NO_HIT {
            let s = surface_at(ray, hit);
            var m = scene_material(s.material);
            flag = select(1.0, 2.0, any(m.emission > vec3f(0.0)));
            if HAS_TEXTURES {
                m = textured_material(m, s.uv, s.color);
            }
            albedo = m.base_color;
            normal = s.ns;
            depth = hit.t;
        }
        textureStore(out_albedo, at, vec4f(albedo, flag));
        textureStore(out_normal, at, vec4f(normal, 1.0));
        textureStore(out_depth, at, vec4f(depth, 0.0, 0.0, 0.0));
    }
}

// Host intersection (HOST_RAYS). The paths of a frame are traced in steps: each dispatch
// takes every pixel's path one bounce on, as `path_step` does, from the closest hit the host
// found for its ray, and writes the rays the host is to trace next (the path's next ray and
// the step's shadow ray); the host intersects them and dispatches again, until every pixel
// has traced its `chunk_count` samples. A slot per pixel of the window (y * width + x),
// traced in batches of at most `wave_slots()` (S) from `frame.wave_base`; `wave` has
// sections of S entries each. The first holds each slot's path in flight;
// the others hold the step's slots in the step's order (the lane's slots at the first
// step, then those the host lists, those with a ray out), the j-th of the step at j:
//   [0, 3S)     the path in flight, what every step moves: 3 vec4 per slot (`save_slot`)
//   [3S, 7S)    the rest of it: 4 vec4 per slot
//   [7S, 10S)   the rays the step wrote, which leave from one point: 3 vec4 (origin, the
//               next ray's t_near, < 0: no next ray, -2: none, but list the slot for the
//               next step all the same; its direction, the shadow ray's
//               t_near; the shadow ray's direction and t_far, < 0: no shadow ray)
//   [10S, 11S)  the host's closest hit of the ray the step reads: t, u, v (bits) and the
//               primitive; t's sign bit set when the slot's shadow ray was occluded
//   [11S, ...)  the step's slots: their count, then each one, a u32 each (`wave_list_at`)
// The random numbers, their order and the arithmetic are `trace_pixel`'s; only the hits are
// the host's. The host counts the rays (`ray_count` is not kept).
const WAVE_STEP: u32 = 1u;
// Writes the pixels' means from `chunk_sums` (and the AOVs): recorded with the graph.
const WAVE_FINISH: u32 = 2u;

// Slot flags: a shadow ray is out; the path ended (its last shadow ray still out); the
// pixel traced all its samples.
const SLOT_SHADOW: u32 = 1u;
const SLOT_ENDED: u32 = 2u;
const SLOT_DONE: u32 = 4u;
// Where the flags sit in the word that holds the bounce (the plan keeps bounces below 2^24).
const SLOT_FLAGS_SHIFT: u32 = 24u;
const SLOT_BOUNCE_MASK: u32 = 0xffffffu;

fn wave_slots() -> u32 {
    return frame.wave_capacity;
}

// Host intersection's records in `wave`, declared once: their Rust twins
// (`shared::WaveRays`, `embree::HostHit`) are checked field by field against these by the
// param-block layout test. Per slot of a batch: `WAVE_HOT_VEC4S` + `WAVE_COLD_VEC4S` vec4 of
// path state, then the sections (see crates/render/src/shared.rs) of `WaveRays` the kernel
// writes, `WaveHit` the host writes, and the list of slots to step.
struct WaveRays {
    origin: vec3f,
    next_near: f32,
    next_dir: vec3f,
    shadow_near: f32,
    shadow_dir: vec3f,
    shadow_far: f32,
}

struct WaveHit {
    t: f32,
    u: f32,
    v: f32,
    prim: u32,
}

// A slot's path state: `WAVE_HOT_VEC4S` (3) vec4 from `b` that every step moves (direction, BSDF pdf;
// throughput, random state; radiance, bounce and slot flags in its top 8 bits), kept apart
// from the rest so that a step's loads and stores stream through 48 bytes per slot;
// `WAVE_COLD_VEC4S` (4) vec4 from `c`: [0] the previous vertex and crossings, only for scenes with emitters or media
// (no origin: host intersection hits only triangles, whose points come from the
// barycentrics); [1] the shadow ray's contribution and the Sobol index, only while a shadow
// ray is out or the first hit is next; [2] the pixel's sum and the Sobol seed, [3] the
// sample index and the dropped samples, only when a path ends or starts. (llvmpipe loads
// and stores a buffer word lane by lane, and a step touches every slot's state: the fewer
// words and cache lines a step moves, the faster it runs.)
fn save_slot(b: u32, c: u32, flags: u32, moved: bool, i: u32, sum: vec3f, dropped: u32) {
    wave[b] = vec4u(bitcast<vec3u>(path_ray.dir), bitcast<u32>(path_bsdf_pdf));
    wave[b + 1u] = vec4u(bitcast<vec3u>(path_throughput), rng_state);
    wave[b + 2u] = vec4u(bitcast<vec3u>(path_radiance), path_bounce | (flags << SLOT_FLAGS_SHIFT));
    if HAS_LIGHTS || HAS_MEDIA {
        wave[c] = vec4u(bitcast<vec3u>(path_prev_p), path_crossings);
    }
    if shadow_pending || path_bounce == 0u {
        wave[c + 1u] = vec4u(bitcast<vec3u>(shadow_contribution), sampler_index);
    }
    if moved {
        wave[c + 2u] = vec4u(bitcast<vec3u>(sum), sampler_seed);
        wave[c + 3u].x = i;
        wave[c + 3u].y = dropped;
    }
}

// The u32 at position `i` from the vec4 at `at` of `wave`.
fn wave_word(at: u32, i: u32) -> u32 {
    return wave[at + i / 4u][i % 4u];
}

// Where the host's list of the slots to step starts: their count, then each one.
fn wave_list_at() -> u32 {
    return WAVE_LIST_AT * wave_slots();
}

// One step of the paths of window slot `slot`, the `j`-th of the step (see above).
fn wave_step(slot: u32, j: u32, kind: u32) {
    let at = vec2u(slot % frame.window.z, slot / frame.window.z);
    let w = frame.settings.width;
    let h = frame.settings.height;
    let pixel = at + frame.window.xy;
    let n = frame.samples_per_frame;
    let slots = wave_slots();
    let pixel_index = pixel.y * w + pixel.x;
    let end = frame.chunk_first + frame.chunk_count;
    var flags = 0u;
    var i = frame.chunk_first;
    var sum = vec3f(0.0);
    var dropped = 0u;
    // Whether the sum or the sample moved on (a path ended): [6] and [7] are saved.
    var moved = true;
    shadow_pending = false;
    shadow_contribution = vec3f(0.0);
    // The slot's state: what every step moves, then the rest (see `save_slot`).
    let b = WAVE_HOT_VEC4S * (slot - frame.wave_base);
    let c = WAVE_HOT_VEC4S * slots + WAVE_COLD_VEC4S * (slot - frame.wave_base);
    if kind == WAVE_KIND_START {
        sampler_init(pixel_index, frame.sample_offset + i, frame.settings.seed, frame.sampler, n, frame.replicates);
        start_path(pixel);
    } else {
        moved = false;
        let s0 = wave[b];
        let s1 = wave[b + 1u];
        let s2 = wave[b + 2u];
        // No origin: a hit's point comes from its triangle's barycentrics.
        path_ray = Ray(vec3f(0.0), bitcast<vec3f>(s0.xyz));
        path_bsdf_pdf = bitcast<f32>(s0.w);
        path_throughput = bitcast<vec3f>(s1.xyz);
        rng_state = s1.w;
        path_radiance = bitcast<vec3f>(s2.xyz);
        path_bounce = s2.w & SLOT_BOUNCE_MASK;
        flags = s2.w >> SLOT_FLAGS_SHIFT;
        if HAS_LIGHTS || HAS_MEDIA {
            let s3 = wave[c];
            path_prev_p = bitcast<vec3f>(s3.xyz);
            path_crossings = s3.w;
        }
        sampler_sobol = frame.sampler == SAMPLER_SOBOL;
        // The `WaveHit` of this slot's ray; the sign bit of its `t` answers the shadow ray.
        let hv = wave[WAVE_HITS_AT * slots + j];
        let shadow_out = (flags & SLOT_SHADOW) != 0u;
        if shadow_out || path_bounce == 0u {
            let s4 = wave[c + 1u];
            sampler_index = s4.w;
            if shadow_out && (hv.x >> 31u) == 0u {
                path_radiance += bitcast<vec3f>(s4.xyz);
            }
        }
        if path_bounce == 0u {
            sampler_seed = wave[c + 2u].w;
        }
        var ended = (flags & SLOT_ENDED) != 0u;
        flags = 0u;
        if !ended {
            if kind == WAVE_KIND_MISS {
                ended = path_step_from(Hit(NO_HIT, F32_MAX, 0.0, 0.0), true);
            } else {
                let t = bitcast<f32>(hv.x & 0x7fffffffu);
                ended = path_step_from(Hit(hv.w, t, bitcast<f32>(hv.y), bitcast<f32>(hv.z)), false);
            }
        }
        if ended && (shadow_pending || kind == WAVE_KIND_HIT) {
            // The path's last shadow ray is still to be answered; or the path ended at a
            // surface, and the next step's `wave_misses` adds its sample and starts the next
            // one (so `wave_hits` carries none of that code).
            flags = SLOT_ENDED;
        } else if ended {
            moved = true;
            let s5 = wave[c + 2u];
            sum = bitcast<vec3f>(s5.xyz);
            sampler_seed = s5.w;
            i = wave[c + 3u].x;
            dropped = wave[c + 3u].y;
            add_sample(path_radiance, &sum, &dropped);
            i++;
            if i >= end {
                flags = SLOT_DONE;
                chunk_sums[slot] = vec4f(sum, 0.0);
                if dropped > 0u {
                    atomicAdd(&stats[0], dropped);
                }
            } else {
                sampler_init(pixel_index, frame.sample_offset + i, frame.settings.seed, frame.sampler, n, frame.replicates);
                start_path(pixel);
            }
        }
    }
    // The slot's `WaveRays`, written word by word (fewer stores where a ray is absent). The
    // rays leave from one point (`leave`): the next ray's origin is the shadow ray's.
    let r = WAVE_RAYS_AT * slots + WAVE_RAYS_VEC4S * j;
    let next = flags == 0u;
    if next || shadow_pending {
        let origin = select(shadow_ray.origin, path_ray.origin, next);
        // Within `origin_slab` of its origin a hit is the origin's own error (see `leave`).
        wave[r] = vec4u(bitcast<vec3u>(origin), bitcast<u32>(select(WAVE_NO_RAY, origin_slab, next)));
    } else {
        // No ray; WAVE_FINISH_ME asks the host to list the slot all the same (an ended path
        // to finish).
        wave[r].w = bitcast<u32>(select(WAVE_NO_RAY, WAVE_FINISH_ME, flags == SLOT_ENDED));
    }
    if next {
        // A shadow ray ending before it starts is still a ray (never occluded), not none.
        wave[r + 1u] = vec4u(bitcast<vec3u>(path_ray.dir), bitcast<u32>(shadow_near));
    } else if shadow_pending {
        wave[r + 1u].w = bitcast<u32>(shadow_near);
    }
    if shadow_pending {
        wave[r + 2u] = vec4u(bitcast<vec3u>(shadow_ray.dir), bitcast<u32>(max(shadow_far, 0.0)));
        flags |= SLOT_SHADOW;
    } else {
        wave[r + 2u].w = bitcast<u32>(WAVE_NO_RAY);
    }
    save_slot(b, c, flags, moved, i, sum, dropped);
}

// The steps of host intersection, one entry point per kind of step, each compiled on its
// own: llvmpipe runs the code behind every `if`, taken or not, so a step that started paths,
// shaded misses and shaded hits in one kernel paid for all three at every slot. The host
// lists a step's slots whose ray missed (or that only await a shadow ray) first, then those
// whose ray hit (`frame.wave_split` of them first), and dispatches `wave_misses` over the
// first and `wave_hits` over the others; `wave_start` starts the batch's first paths.
const WAVE_KIND_START: u32 = 0u;
const WAVE_KIND_MISS: u32 = 1u;
const WAVE_KIND_HIT: u32 = 2u;

// A 1D dispatch: each invocation takes the listed slots of its kind one `threads` apart:
// llvmpipe pays a fixed cost per invocation, as much as a step of a path when the kernel is
// this large, so an invocation per slot would pay it for every step.
fn wave_run(kind: u32, group: u32, groups: u32, lane: u32) {
    let threads = groups * 64u;
    let count = wave_word(wave_list_at(), 0u);
    let first = select(0u, frame.wave_split, kind == WAVE_KIND_HIT);
    let end = select(count, min(frame.wave_split, count), kind == WAVE_KIND_MISS);
    for (var j = first + group * 64u + lane; j < end; j += threads) {
        wave_step(wave_word(wave_list_at(), 1u + j), j, kind);
    }
}

@compute @workgroup_size(8, 8)
fn wave_start(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u, @builtin(local_invocation_index) lane: u32) {
    if HOST_RAYS {
        wave_run(WAVE_KIND_START, group.x, groups.x, lane);
    }
}

@compute @workgroup_size(8, 8)
fn wave_misses(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u, @builtin(local_invocation_index) lane: u32) {
    if HOST_RAYS {
        wave_run(WAVE_KIND_MISS, group.x, groups.x, lane);
    }
}

@compute @workgroup_size(8, 8)
fn wave_hits(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u, @builtin(local_invocation_index) lane: u32) {
    if HOST_RAYS {
        wave_run(WAVE_KIND_HIT, group.x, groups.x, lane);
    }
}
