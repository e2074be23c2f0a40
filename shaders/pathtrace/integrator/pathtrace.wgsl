// Path tracer megakernel: one invocation per pixel traces `samples_per_frame` paths and
// writes their mean radiance. Unidirectional path tracing with next-event estimation and
// multiple importance sampling (power heuristic) for emissive triangles and shapes and the
// environment map, next-event estimation alone for point, spot and directional lights,
// Russian roulette from the fifth bounce, the layered material of bsdf.wgsl (diffuse or
// rough diffuse base under GGX specular, metal, glass) and one-sided emitters (Mitsuba 3's
// conventions, so the references match). With HAS_MEDIA, homogeneous media
// inside closed shapes (medium.wgsl): Beer-Lambert absorption, or free-flight distance
// sampling with Henyey-Greenstein scattering, next-event estimation from medium points with
// MIS against phase sampling, and shadow rays through index-matched boundaries. Samples
// that are not finite never reach the output: they are dropped and counted in `stats[0]`.
//
// The parts, each in its file: integrator.wgsl (a path's state and one bounce of it),
// surface.wgsl (the surface point of a hit, robust ray origins), lights.wgsl (light
// selection and sampling), mis.wgsl (MIS weights), camera.wgsl, bsdf.wgsl (the layered
// material), medium.wgsl, env.wgsl, textures.wgsl, alpha.wgsl, and the intersector behind
// intersect.wgsl (its contract in contract.wgsl; the specialization replaces the file).
// wave.wgsl holds the steps of host intersection and of the wavefront. This file: the frame's uniform block, the
// bindings, the entry point and the loop over a pixel's samples.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/integrator/sampler.wgsl"
#import "common/sampling.wgsl"
#import "pathtrace/options.wgsl"
#import "pathtrace/bsdf/bsdf.wgsl"
#import "pathtrace/lights/env.wgsl"
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
    // With WAVES: WAVE_STEP or WAVE_FINISH (pathtrace/shared.wgsl); the first slot of the batch of
    // slots being traced, how many slots `wave`'s sections hold, and how many of the step's
    // listed slots `wave_misses` takes (`wave_hits` the rest); with WAVEFRONT, which of the
    // two lists is the step's.
    wave: u32,
    wave_base: u32,
    wave_capacity: u32,
    wave_split: u32,
    wave_list: u32,
}

// `Frame::chunk_flags`: CHUNK_FIRST, CHUNK_LAST (pathtrace/shared.wgsl, generated).

@group(0) @binding(0) var output: texture_storage_2d<rgba32float, write>;
@group(0) @binding(1) var<uniform> frame: Frame;
@group(0) @binding(2) var<storage, read> bvh_nodes: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> tri_positions: array<TriPositions>;
@group(0) @binding(4) var<storage, read> tri_shading: array<TriShading>;
@group(0) @binding(5) var<storage, read> shapes: array<Shape>;
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
// of the even and of the odd frames, in that order, and whether `pathtrace/integrator/adaptive.wgsl`
// stopped the pixel (16-byte stand-ins otherwise).
@group(0) @binding(18) var<storage, read_write> adaptive_halves: array<vec4f>;
@group(0) @binding(19) var<storage, read> adaptive_stopped: array<u32>;
// The pixels still sampling this frame: their count, then each one's x | y << 16.
@group(0) @binding(20) var<storage, read> adaptive_active: array<u32>;
// Per pixel of the window: the sum of the frame's samples traced by its earlier dispatches.
@group(0) @binding(21) var<storage, read_write> chunk_sums: array<vec4f>;
// With WAVES, the paths in flight and the rays the host or `wave_trace` intersects (a
// 16-byte stand-in otherwise): see `wave_start`, `wave_misses` and `wave_hits` in
// pathtrace/integrator/wave.wgsl.
@group(0) @binding(22) var<storage, read_write> wave: array<vec4<u32>>;
// The texture atlas: every texture of the scene in the RGBA8 pages of one array texture.
@group(0) @binding(23) var textures: texture_2d_array<f32>;

#import "pathtrace/intersect.wgsl"
#import "pathtrace/scene_data.wgsl"
#import "pathtrace/intersect/alpha.wgsl"
#import "pathtrace/integrator/medium.wgsl"
#import "pathtrace/integrator/mis.wgsl"
#import "pathtrace/integrator/surface.wgsl"
#import "pathtrace/lights/lights.wgsl"
#import "pathtrace/integrator/camera.wgsl"
#import "pathtrace/integrator/integrator.wgsl"
#import "pathtrace/integrator/wave.wgsl"

// Rays traced by this invocation (camera, extension and shadow rays), for the report.
var<private> ray_count: u32;

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

// The tile a workgroup takes: its own, or with SPREAD_WORKGROUPS (CPU adapters) the rows of
// tiles spread over the image, which is the same work in another order (the images are
// bit-identical).
fn workgroup_tile(group: vec3u, groups: vec3u) -> vec2u {
    var tile = group.xy;
    if SPREAD_WORKGROUPS {
        tile.y = spread_row(group.y, groups.y);
    }
    return tile;
}

// With ADAPTIVE: a pixel adaptive sampling stopped takes no samples and outputs alpha 0.
fn clear_stopped(id: vec2u) {
    if ADAPTIVE && all(id < frame.window.zw) && adaptive_stopped[id.y * frame.window.z + id.x] != 0u {
        textureStore(output, id, vec4f(0.0));
    }
}

@compute @workgroup_size(8, 8)
fn main(
    @builtin(workgroup_id) group: vec3u,
    @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_id) local: vec3u,
    @builtin(local_invocation_index) lane: u32,
) {
    let tile = workgroup_tile(group, groups);
    let id = tile * 8u + local.xy;
    var at = id;
    var trace = true;
    if ADAPTIVE {
        // The pixels still sampling are traced by the first invocations, in the order the
        // adaptive pass listed them (workgroup by workgroup), so whole workgroups at the end
        // idle.
        clear_stopped(id);
        let k = (tile.y * groups.x + tile.x) * 64u + lane;
        trace = k < adaptive_active[0];
        if trace {
            let packed = adaptive_active[1u + k];
            at = vec2u(packed & 0xffffu, packed >> 16u);
        }
    }
    if WAVES {
        // Paths traced in steps are finished by `wave_finish`, their steps are `wave.wgsl`'s.
        return;
    }
    if trace {
        trace_pixel(at);
    }
    first_hit_aovs(id);
}

// The finish of a frame traced in steps (WAVES, with `frame.wave` WAVE_FINISH): the pixels'
// means from `chunk_sums`, and the first-hit AOVs. An entry point of its own, which reaches
// none of the megakernel's code: such a shader does not build `main` at all (a driver builds
// all the code an entry point can reach, a constant's `if` or not).
@compute @workgroup_size(8, 8)
fn wave_finish(
    @builtin(workgroup_id) group: vec3u,
    @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_id) local: vec3u,
) {
    let id = workgroup_tile(group, groups) * 8u + local.xy;
    clear_stopped(id);
    if WAVES && frame.wave == WAVE_FINISH {
        let slot = id.y * frame.window.z + id.x;
        if all(id < frame.window.zw) {
            let n = f32(max(frame.samples_per_frame, 1u));
            textureStore(output, id, vec4f(chunk_sums[slot].xyz / n, 1.0));
        }
        first_hit_aovs(id);
    }
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
                    add_sample(path.radiance, &sum, &dropped);
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
            let s = surface_at(ray, hit, vec2f(0.0, pixel_spread()));
            var m = scene_material(s.material);
            flag = select(1.0, 2.0, any(m.emission > vec3f(0.0)));
            if HAS_TEXTURES {
                m = textured_material(m, s.uv, s.lod, s.color);
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

