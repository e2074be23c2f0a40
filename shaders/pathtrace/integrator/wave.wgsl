// Paths traced in steps (WAVES): the `wave_*` entry points of host intersection (HOST_RAYS)
// and of the wavefront (WAVEFRONT).
// requires: var frame, var wave, var chunk_sums, var stats (integrator/pathtrace.wgsl)
// requires: fn add_sample (integrator/pathtrace.wgsl)
#import "pathtrace/shared.wgsl"
#import "pathtrace/integrator/integrator.wgsl"
#import "pathtrace/intersect.wgsl"

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
//   [12S, ...)  with instances (HAS_INSTANCES), the instance of each hit in the step's
//               order, a u32 each: its node slot, or NO_INSTANCE (WAVE_INSTS_AT)
// The random numbers, their order and the arithmetic are `trace_pixel`'s; only the hits are
// the host's. The host counts the rays (`ray_count` is not kept).
//
// The wavefront (WAVEFRONT) takes the same steps, and `wave_trace` traces their rays on the
// device in between, through the intersector the megakernel would use, with the same rules
// for rays leaving a surface: its images are the megakernel's. Its sections differ from the
// list on:
//   [11S, 13S)  how the step's rays leave their surface, 2 vec4 per position j of the step:
//               the normal of the plane left towards the next ray (`origin_n`) and the
//               primitive left (`skip_prim`); the origin's error (`origin_err`) and 1 where
//               the shadow ray leaves towards the other side
//   [13S, ...)  two lists of slots, S words each: the step's and the next step's
//               (`frame.wave_list` is the step's); the slots whose ray missed (or that only
//               await a shadow ray) from the start, those whose ray hit from the end. List l
//               counts them in `stats[WAVE_COUNTS_AT + 2 l]` and the word after it.
// `Frame::wave`: WAVE_STEP, a step; WAVE_FINISH, the pass writing the pixels' means from
// `chunk_sums` (and the AOVs), recorded with the graph (pathtrace/shared.wgsl, generated).

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
// sample index and the dropped samples, only when a path ends or starts, then the ray
// cone's width and spread (HAS_TEXTURES: `PathState::cone`), every step. (llvmpipe loads
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
    if HAS_TEXTURES {
        wave[c + 3u].z = bitcast<u32>(path.cone.x);
        wave[c + 3u].w = bitcast<u32>(path.cone.y);
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

// A slot's state through a step: what `wave_load` reads, the step moves on and
// `wave_store` writes.
struct WaveSlot {
    // The window slot, and its sections of `wave` (see `save_slot`).
    slot: u32,
    b: u32,
    c: u32,
    pixel: vec2u,
    pixel_index: u32,
    flags: u32,
    // The sample being traced, the pixel's sum and its dropped samples.
    i: u32,
    sum: vec3f,
    dropped: u32,
    // Whether the sum or the sample moved on (a path ended): [6] and [7] are saved.
    moved: bool,
    // The path ended (before the step, or by it).
    ended: bool,
    // The host's `WaveHit` of the slot's ray.
    hit: vec4u,
}

// The state of window slot `slot`, the `j`-th of the step (see above), into the path
// globals: a new path for a `WAVE_KIND_START` step, else the path in flight, with the answer
// to its shadow ray added.
fn wave_load(slot: u32, j: u32, kind: u32) -> WaveSlot {
    let at = vec2u(slot % frame.window.z, slot / frame.window.z);
    let pixel = at + frame.window.xy;
    let slots = wave_slots();
    var s = WaveSlot(slot, 0u, 0u, pixel, pixel.y * frame.settings.width + pixel.x, 0u, frame.chunk_first, vec3f(0.0), 0u, true, false, vec4u(0u));
    host_shadow.pending = false;
    host_shadow.contribution = vec3f(0.0);
    // The slot's state: what every step moves, then the rest (see `save_slot`).
    s.b = WAVE_HOT_VEC4S * (slot - frame.wave_base);
    s.c = WAVE_HOT_VEC4S * slots + WAVE_COLD_VEC4S * (slot - frame.wave_base);
    if kind == WAVE_KIND_START {
        sampler_init(s.pixel_index, frame.sample_offset + s.i, frame.settings.seed, frame.sampler, frame.samples_per_frame, frame.replicates);
        start_path(pixel);
        return s;
    }
    s.moved = false;
    let s0 = wave[s.b];
    let s1 = wave[s.b + 1u];
    let s2 = wave[s.b + 2u];
    // No origin: a hit's point comes from its triangle's barycentrics.
    path.ray = Ray(vec3f(0.0), bitcast<vec3f>(s0.xyz));
    path.bsdf_pdf = bitcast<f32>(s0.w);
    path.throughput = bitcast<vec3f>(s1.xyz);
    rng_state = s1.w;
    path.radiance = bitcast<vec3f>(s2.xyz);
    path.bounce = s2.w & SLOT_BOUNCE_MASK;
    let flags = s2.w >> SLOT_FLAGS_SHIFT;
    if HAS_LIGHTS || HAS_MEDIA {
        let s3 = wave[s.c];
        path.prev_p = bitcast<vec3f>(s3.xyz);
        path.crossings = s3.w;
    }
    if HAS_TEXTURES {
        path.cone = bitcast<vec2f>(wave[s.c + 3u].zw);
    }
    sampler_sobol = frame.sampler == SAMPLER_SOBOL;
    // The `WaveHit` of this slot's ray; the sign bit of its `t` answers the shadow ray.
    s.hit = wave[WAVE_HITS_AT * slots + j];
    let shadow_out = (flags & SLOT_SHADOW) != 0u;
    if shadow_out || path.bounce == 0u {
        let s4 = wave[s.c + 1u];
        sampler_index = s4.w;
        if shadow_out && (s.hit.x >> 31u) == 0u {
            path.radiance += bitcast<vec3f>(s4.xyz);
        }
    }
    if path.bounce == 0u {
        sampler_seed = wave[s.c + 2u].w;
    }
    s.ended = (flags & SLOT_ENDED) != 0u;
    return s;
}

// After a step of a `kind` other than `WAVE_KIND_START`: a path that ended adds its sample
// and the slot starts the next one, or is done; or it waits, flagged, for the next step to
// do so.
fn wave_settle(s: ptr<function, WaveSlot>, kind: u32) {
    (*s).flags = 0u;
    if (*s).ended && (host_shadow.pending || kind == WAVE_KIND_HIT) {
        // The path's last shadow ray is still to be answered; or the path ended at a
        // surface, and the next step's `wave_misses` adds its sample and starts the next
        // one (so `wave_hits` carries none of that code).
        (*s).flags = SLOT_ENDED;
    } else if (*s).ended {
        (*s).moved = true;
        let s5 = wave[(*s).c + 2u];
        var sum = bitcast<vec3f>(s5.xyz);
        var dropped = wave[(*s).c + 3u].y;
        sampler_seed = s5.w;
        var i = wave[(*s).c + 3u].x;
        add_sample(path.radiance, &sum, &dropped);
        i++;
        if i >= frame.chunk_first + frame.chunk_count {
            (*s).flags = SLOT_DONE;
            chunk_sums[(*s).slot] = vec4f(sum, 0.0);
            if dropped > 0u {
                atomicAdd(&stats[0], dropped);
            }
        } else {
            sampler_init((*s).pixel_index, frame.sample_offset + i, frame.settings.seed, frame.sampler, frame.samples_per_frame, frame.replicates);
            start_path((*s).pixel);
        }
        (*s).i = i;
        (*s).sum = sum;
        (*s).dropped = dropped;
    }
}
// The rays of the slot's step, the `j`-th: its `WaveRays`, written word by word (fewer
// stores where a ray is absent), and where the wavefront traces them, how they leave their
// surface; then the slot's state.
fn wave_store(s: WaveSlot, j: u32) {
    let slots = wave_slots();
    // The rays leave from one point (`leave`): the next ray's origin is the shadow ray's.
    let r = WAVE_RAYS_AT * slots + WAVE_RAYS_VEC4S * j;
    var flags = s.flags;
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
    if WAVEFRONT && (next || host_shadow.pending) {
        // How the rays leave the surface, for `wave_trace`: the state `leave` set for the
        // last ray it made (the next ray's, or the shadow ray's where no next ray is out).
        let l = WAVE_LIST_AT * slots + WAVE_LEAVE_VEC4S * j;
        let other_side = host_shadow.pending && any(host_shadow.n != origin_n);
        wave[l] = vec4u(bitcast<vec3u>(origin_n), skip_prim);
        wave[l + 1u] = vec4u(bitcast<vec3u>(origin_err), select(0u, 1u, other_side));
    }
    save_slot(s.b, s.c, flags, s.moved, s.i, s.sum, s.dropped);
}

// The steps of host intersection and of the wavefront, one entry point per kind of step,
// each compiled on its own: llvmpipe runs the code behind every `if`, taken or not, so a
// step that started paths, shaded misses and shaded hits in one kernel paid for all three at
// every slot. The host lists a step's slots whose ray missed (or that only await a shadow
// ray) first, then those whose ray hit (`frame.wave_split` of them first), and dispatches
// `wave_misses` over the first and `wave_hits` over the others; `wave_start` starts the
// batch's first paths. Each kind has its own step function, and no entry point calls another
// kind's: a driver builds all the code an entry point can reach before it leaves out what a
// constant rules out, and the path step's surface code reached from all three cost over a
// second of compilation each on llvmpipe (`wave_start` took 1.2 s, 8 ms without it).
const WAVE_KIND_START: u32 = 0u;
const WAVE_KIND_MISS: u32 = 1u;
const WAVE_KIND_HIT: u32 = 2u;

// A step starting slot `slot`'s first path (the `j`-th slot of the step).
fn wave_step_start(slot: u32, j: u32) {
    let s = wave_load(slot, j, WAVE_KIND_START);
    wave_store(s, j);
}

// A step of a path whose ray missed (or that awaits only its shadow ray's answer).
fn wave_step_miss(slot: u32, j: u32) {
    var s = wave_load(slot, j, WAVE_KIND_MISS);
    if !s.ended {
        s.ended = path_step_missed();
    }
    wave_settle(&s, WAVE_KIND_MISS);
    wave_store(s, j);
}

// A step of a path whose ray hit a surface.
fn wave_step_hit(slot: u32, j: u32) {
    var s = wave_load(slot, j, WAVE_KIND_HIT);
    if !s.ended {
        let t = bitcast<f32>(s.hit.x & 0x7fffffffu);
        // The host's instance of the hit, where the scene has instances (the section after
        // the list): its hit reads as the binary BVH's two-level walk's.
        var inst = NO_INSTANCE;
        if HOST_RAYS && HAS_INSTANCES {
            inst = wave_word(WAVE_INSTS_AT * wave_slots(), j);
        }
        s.ended = path_step_from(Hit(s.hit.w, t, bitcast<f32>(s.hit.y), bitcast<f32>(s.hit.z), inst), false);
    }
    wave_settle(&s, WAVE_KIND_HIT);
    wave_store(s, j);
}

// The positions of the step's list a kind's dispatch takes, as (first, end, stride).
// Host intersection: each invocation takes the listed slots of its kind one `threads` apart
// (a 1D dispatch: llvmpipe pays a fixed cost per invocation, as much as a step of a path
// when the kernel is this large, so an invocation per slot would pay it for every step).
// The wavefront: invocation `i` of a dispatch over the batch's slots takes the i-th slot of
// its kind (misses from the list's start, hits from its end), if there is one.
fn wave_range(kind: u32, group: u32, groups: u32, lane: u32) -> vec3u {
    if WAVEFRONT {
        let i = group * 64u + lane;
        let j = wavefront_position(kind, i, lane);
        return vec3u(j, select(j, j + 1u, j != NO_SLOT), 1u);
    }
    let threads = groups * 64u;
    let count = wave_word(wave_list_at(), 0u);
    let first = select(0u, frame.wave_split, kind == WAVE_KIND_HIT);
    let end = select(count, min(frame.wave_split, count), kind == WAVE_KIND_MISS);
    return vec3u(first + group * 64u + lane, end, threads);
}

// The slot at position `j` of the step's list.
fn wave_listed(j: u32) -> u32 {
    if WAVEFRONT {
        return wave_word(wavefront_list_at(frame.wave_list), j);
    }
    return wave_word(wave_list_at(), 1u + j);
}

@compute @workgroup_size(8, 8)
fn wave_start(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u, @builtin(local_invocation_index) lane: u32) {
    if WAVES {
        let r = wave_range(WAVE_KIND_START, group.x, groups.x, lane);
        for (var j = r.x; j < r.y; j += r.z) {
            wave_step_start(wave_listed(j), j);
        }
    }
}

@compute @workgroup_size(8, 8)
fn wave_misses(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u, @builtin(local_invocation_index) lane: u32) {
    if WAVES {
        let r = wave_range(WAVE_KIND_MISS, group.x, groups.x, lane);
        for (var j = r.x; j < r.y; j += r.z) {
            wave_step_miss(wave_listed(j), j);
        }
    }
}

@compute @workgroup_size(8, 8)
fn wave_hits(@builtin(workgroup_id) group: vec3u, @builtin(num_workgroups) groups: vec3u, @builtin(local_invocation_index) lane: u32) {
    if WAVES {
        let r = wave_range(WAVE_KIND_HIT, group.x, groups.x, lane);
        for (var j = r.x; j < r.y; j += r.z) {
            wave_step_hit(wave_listed(j), j);
        }
    }
}

// The wavefront's list `list`: where it starts in `wave` (vec4), and the index in `stats` of
// its count of slots whose ray missed (that of those whose ray hit follows).
fn wavefront_list_at(list: u32) -> u32 {
    let slots = wave_slots();
    return WAVE_FRONT_LISTS_AT * slots + list * (slots / 4u);
}

fn wavefront_counts_at(list: u32) -> u32 {
    return WAVE_COUNTS_AT + 2u * list;
}

// The counts of the step's list, loaded once per workgroup (a load of one word by every
// invocation of a dispatch over a million slots costs more than the step's own loads).
var<workgroup> wave_counts: array<u32, 2>;

// Loads the counts of list `list` into `wave_counts` for the whole workgroup (called by all
// its invocations).
fn wavefront_load_counts(list: u32, lane: u32) {
    if lane == 0u {
        let counts = wavefront_counts_at(list);
        wave_counts[0] = atomicLoad(&stats[counts]);
        wave_counts[1] = atomicLoad(&stats[counts + 1u]);
    }
    workgroupBarrier();
}

// No position of the list for the invocation (`wavefront_position`).
const NO_SLOT: u32 = 0xffffffffu;

// The position in the step's list of the i-th slot of kind `kind` (misses from the list's
// start, hits from its end), or `NO_SLOT`.
fn wavefront_position(kind: u32, i: u32, lane: u32) -> u32 {
    let slots = wave_slots();
    let list = frame.wave_list;
    wavefront_load_counts(list, lane);
    if i == 0u && kind != WAVE_KIND_HIT {
        // The next step's list fills from empty (`wave_trace`, after this step's kernels);
        // the step before this one read it last.
        let next = wavefront_counts_at(1u - list);
        atomicStore(&stats[next], 0u);
        atomicStore(&stats[next + 1u], 0u);
    }
    let misses = wave_counts[0];
    let hits = wave_counts[1];
    if kind == WAVE_KIND_HIT {
        if i < hits {
            return slots - hits + i;
        }
    } else if i < misses {
        return i;
    }
    return NO_SLOT;
}

// What `wavefront_trace` found for a position of the step's list: the slot, the hit of its
// next ray (with the shadow ray's answer in the sign bit of `t`), which part of the next list
// it goes to (`TRACED_MISS`, `TRACED_HIT`, or `TRACED_DONE`: none, the slot traced all its
// samples), and the rays traced.
struct Traced {
    slot: u32,
    hit: vec4u,
    kind: u32,
    rays: u32,
}

const TRACED_MISS: u32 = 0u;
const TRACED_HIT: u32 = 1u;
const TRACED_DONE: u32 = 2u;

// The rays the step wrote at position `j` of its list, traced as `trace_pixel`'s path would
// trace them: the next ray's closest hit, whether the shadow ray is occluded, each leaving
// the surface as `leave` set it up.
fn wavefront_trace(j: u32) -> Traced {
    let slots = wave_slots();
    let r = WAVE_RAYS_AT * slots + WAVE_RAYS_VEC4S * j;
    let r0 = wave[r];
    let r1 = wave[r + 1u];
    let r2 = wave[r + 2u];
    let next_near = bitcast<f32>(r0.w);
    let shadow_far = bitcast<f32>(r2.w);
    let has_next = next_near >= 0.0;
    let has_shadow = shadow_far >= 0.0;
    var out = Traced(0u, vec4u(0u), TRACED_DONE, 0u);
    if !(has_next || has_shadow || next_near == WAVE_FINISH_ME) {
        return out;
    }
    let origin = bitcast<vec3f>(r0.xyz);
    let l = WAVE_LIST_AT * slots + WAVE_LEAVE_VEC4S * j;
    let l0 = wave[l];
    let l1 = wave[l + 1u];
    let n = bitcast<vec3f>(l0.xyz);
    skip_prim = l0.w;
    origin_err = bitcast<vec3f>(l1.xyz);
    // `leave`'s, the same for either side of the plane.
    origin_off = dot(abs(n), origin_err);
    var occluded_bit = 0u;
    if has_shadow {
        origin_n = select(n, -n, l1.w != 0u);
        origin_slab = bitcast<f32>(r1.w);
        if occluded(Ray(origin, bitcast<vec3f>(r2.xyz)), shadow_far) {
            occluded_bit = 0x80000000u;
        }
    }
    var hit = Hit(NO_HIT, F32_MAX, 0.0, 0.0, NO_INSTANCE);
    if has_next {
        origin_n = n;
        origin_slab = next_near;
        hit = intersect_scene(Ray(origin, bitcast<vec3f>(r1.xyz)));
    }
    out.slot = wave_word(wavefront_list_at(frame.wave_list), j);
    out.hit = vec4u(bitcast<u32>(hit.t) | occluded_bit, bitcast<u32>(hit.u), bitcast<u32>(hit.v), hit.prim);
    out.kind = select(TRACED_MISS, TRACED_HIT, has_next && hit.prim != NO_HIT);
    out.rays = select(0u, 1u, has_next) + select(0u, 1u, has_shadow);
    return out;
}

// Per workgroup of `wave_trace`: its slots of each part of the next list and the rays it
// traced (workgroup atomics), then where its slots go in the next list: one global atomic
// per part and workgroup, not per slot (a million atomics on two words serialize).
var<workgroup> wave_parts: array<atomic<u32>, 3>;
var<workgroup> wave_part_base: array<u32, 2>;

// The wavefront's tracing kernel, between two steps: one invocation per position of the
// step's list (a 1D dispatch over the batch's slots), each listing its slot for the next
// step with its ray's hit.
@compute @workgroup_size(64)
fn wave_trace(@builtin(global_invocation_id) id: vec3u, @builtin(local_invocation_index) lane: u32) {
    if !WAVEFRONT {
        return;
    }
    let slots = wave_slots();
    let list = frame.wave_list;
    if lane < 3u {
        atomicStore(&wave_parts[lane], 0u);
    }
    wavefront_load_counts(list, lane);
    let j = id.x;
    var t = Traced(0u, vec4u(0u), TRACED_DONE, 0u);
    if j < slots && (j < wave_counts[0] || j >= slots - wave_counts[1]) {
        t = wavefront_trace(j);
    }
    var local = 0u;
    if t.kind != TRACED_DONE {
        local = atomicAdd(&wave_parts[t.kind], 1u);
    }
    atomicAdd(&wave_parts[2], t.rays);
    workgroupBarrier();
    if lane == 0u {
        let counts = wavefront_counts_at(1u - list);
        wave_part_base[0] = atomicAdd(&stats[counts], atomicLoad(&wave_parts[0]));
        wave_part_base[1] = atomicAdd(&stats[counts + 1u], atomicLoad(&wave_parts[1]));
        // 64-bit ray count in two words, as `trace_pixel` keeps it.
        let rays = atomicLoad(&wave_parts[2]);
        let before = atomicAdd(&stats[1], rays);
        if before > 0xffffffffu - rays {
            atomicAdd(&stats[2], 1u);
        }
    }
    workgroupBarrier();
    if t.kind != TRACED_DONE {
        let k = select(wave_part_base[0] + local, slots - 1u - (wave_part_base[1] + local), t.kind == TRACED_HIT);
        let at = wavefront_list_at(1u - list);
        wave[at + k / 4u][k % 4u] = t.slot;
        wave[WAVE_HITS_AT * slots + k] = t.hit;
    }
}
