// Host intersection's side of the kernel (HOST_RAYS): the `wave_*` entry points.
// From its includer (pathtrace/pathtrace.wgsl): `frame`, the bindings `wave`, `chunk_sums`
// and `stats`, and `add_sample`.
#import "pathtrace/shared.wgsl"
#import "pathtrace/integrator.wgsl"

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
    wave[b] = vec4u(bitcast<vec3u>(path.ray.dir), bitcast<u32>(path.bsdf_pdf));
    wave[b + 1u] = vec4u(bitcast<vec3u>(path.throughput), rng_state);
    wave[b + 2u] = vec4u(bitcast<vec3u>(path.radiance), path.bounce | (flags << SLOT_FLAGS_SHIFT));
    if HAS_LIGHTS || HAS_MEDIA {
        wave[c] = vec4u(bitcast<vec3u>(path.prev_p), path.crossings);
    }
    if host_shadow.pending || path.bounce == 0u {
        wave[c + 1u] = vec4u(bitcast<vec3u>(host_shadow.contribution), sampler_index);
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
    host_shadow.pending = false;
    host_shadow.contribution = vec3f(0.0);
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
        path.ray = Ray(vec3f(0.0), bitcast<vec3f>(s0.xyz));
        path.bsdf_pdf = bitcast<f32>(s0.w);
        path.throughput = bitcast<vec3f>(s1.xyz);
        rng_state = s1.w;
        path.radiance = bitcast<vec3f>(s2.xyz);
        path.bounce = s2.w & SLOT_BOUNCE_MASK;
        flags = s2.w >> SLOT_FLAGS_SHIFT;
        if HAS_LIGHTS || HAS_MEDIA {
            let s3 = wave[c];
            path.prev_p = bitcast<vec3f>(s3.xyz);
            path.crossings = s3.w;
        }
        sampler_sobol = frame.sampler == SAMPLER_SOBOL;
        // The `WaveHit` of this slot's ray; the sign bit of its `t` answers the shadow ray.
        let hv = wave[WAVE_HITS_AT * slots + j];
        let shadow_out = (flags & SLOT_SHADOW) != 0u;
        if shadow_out || path.bounce == 0u {
            let s4 = wave[c + 1u];
            sampler_index = s4.w;
            if shadow_out && (hv.x >> 31u) == 0u {
                path.radiance += bitcast<vec3f>(s4.xyz);
            }
        }
        if path.bounce == 0u {
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
        if ended && (host_shadow.pending || kind == WAVE_KIND_HIT) {
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
            add_sample(path.radiance, &sum, &dropped);
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
    if next || host_shadow.pending {
        let origin = select(host_shadow.ray.origin, path.ray.origin, next);
        // Within `origin_slab` of its origin a hit is the origin's own error (see `leave`).
        wave[r] = vec4u(bitcast<vec3u>(origin), bitcast<u32>(select(WAVE_NO_RAY, origin_slab, next)));
    } else {
        // No ray; WAVE_FINISH_ME asks the host to list the slot all the same (an ended path
        // to finish).
        wave[r].w = bitcast<u32>(select(WAVE_NO_RAY, WAVE_FINISH_ME, flags == SLOT_ENDED));
    }
    if next {
        // A shadow ray ending before it starts is still a ray (never occluded), not none.
        wave[r + 1u] = vec4u(bitcast<vec3u>(path.ray.dir), bitcast<u32>(host_shadow.near));
    } else if host_shadow.pending {
        wave[r + 1u].w = bitcast<u32>(host_shadow.near);
    }
    if host_shadow.pending {
        wave[r + 2u] = vec4u(bitcast<vec3u>(host_shadow.ray.dir), bitcast<u32>(max(host_shadow.far, 0.0)));
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
