//! Constants the Rust side and the WGSL side must agree on, declared once, here.
//!
//! `pathtrace/shared.wgsl` is not a file on disk: the shader loader serves the text
//! [`wgsl`] writes from these values ([`crate::shader::raw`]), so a shader that imports it
//! and the Rust code that fills or reads the same buffers cannot disagree. Records that
//! cross between the two (the host intersector's rays and hits) are `Pod` structs whose
//! WGSL twins naga checks field by field ([`crate::params::BLOCKS`]).

use std::fmt::Write as _;

/// The generated file's name, as shaders import it.
pub const FILE: &str = "pathtrace/shared.wgsl";

/// The `wave` buffer of host intersection and of the wavefront, per slot of the batch (vec4 units): the path state a
/// step always moves ...
pub const WAVE_HOT_VEC4S: u32 = 3;
/// ... the path state it moves now and then ...
pub const WAVE_COLD_VEC4S: u32 = 4;
/// ... then, section after section over all the slots: the rays of a step
/// ([`WaveRays`], from [`WAVE_RAYS_AT`]), the hit of the next ray (`lumagraph_pathtrace::embree::HostHit`,
/// from [`WAVE_HITS_AT`]), and the list of the slots to step (from [`WAVE_LIST_AT`]: their
/// count, then each slot's index).
pub const WAVE_RAYS_VEC4S: u32 = 3;
/// Where the rays section starts, in vec4 per slot of the batch.
pub const WAVE_RAYS_AT: u32 = WAVE_HOT_VEC4S + WAVE_COLD_VEC4S;
/// Where the hits section starts.
pub const WAVE_HITS_AT: u32 = WAVE_RAYS_AT + WAVE_RAYS_VEC4S;
/// Where the list of slots starts.
pub const WAVE_LIST_AT: u32 = WAVE_HITS_AT + 1;
/// Host intersection, where the scene has instances: after the list (its count and a word
/// per slot fit in a vec4 per slot), the instance of each listed position's hit (a word
/// per slot: its node slot, or `NO_INSTANCE`). The wavefront keeps its own sections there.
pub const WAVE_INSTS_AT: u32 = WAVE_LIST_AT + 1;
/// The wavefront (`lumagraph_pathtrace`'s `wavefront`) keeps, in the host's list's place, how each step's
/// rays leave their surface (`WAVE_LEAVE_VEC4S` vec4 per listed position, from
/// [`WAVE_LIST_AT`]) ...
pub const WAVE_LEAVE_VEC4S: u32 = 2;
/// ... then its two lists of slots, the step's and the next step's, a word per slot each.
pub const WAVE_FRONT_LISTS_AT: u32 = WAVE_LIST_AT + WAVE_LEAVE_VEC4S;
/// Where in the path tracer's `stats` the wavefront's lists keep their counts: for list `l`,
/// the slots whose ray missed at `WAVE_COUNTS_AT + 2 l`, those whose ray hit after it.
pub const WAVE_COUNTS_AT: u32 = 4;

/// The next ray's `t_near` for a slot with no ray out that is to be stepped all the same:
/// its path ended at a surface, and the next step's `wave_misses` adds its sample and starts
/// the next path.
pub const WAVE_FINISH_ME: f32 = -2.0;
/// A `t_near` or `t_far` saying there is no such ray.
pub const WAVE_NO_RAY: f32 = -1.0;
/// `Frame::chunk_flags`: the frame's first dispatch (starts the sums).
pub const CHUNK_FIRST: u32 = 1;
/// `Frame::chunk_flags`: the frame's last dispatch (writes the mean).
pub const CHUNK_LAST: u32 = 2;
/// `Frame::wave` (`pathtrace/integrator/wave.wgsl`): a step of a frame's paths (its entry points
/// `wave_start`, `wave_misses`, `wave_hits`).
pub const WAVE_STEP: u32 = 1;
/// `Frame::wave`: the pass writing the pixels' means from `chunk_sums` (and the AOVs).
pub const WAVE_FINISH: u32 = 2;

/// The share of light selection spread uniformly over the lights (the rest by power):
/// the alias table (`lumagraph_scene::light_selection`) and the shader's pdf of choosing a
/// light must use the same, or MIS is biased.
pub const LIGHT_UNIFORM_SHARE: f32 = lumagraph_scene::LIGHT_UNIFORM_SHARE;

/// The custom data of the ray queries' instance of the triangles' boxes
/// (`lumagraph_pathtrace::accel`, `pathtrace/intersect/ray_query.wgsl`).
pub const ACCEL_TRIANGLES: u32 = 0;
/// The custom data of the ray queries' instance of the analytic shapes' boxes.
pub const ACCEL_SHAPES: u32 = 1;

crate::param_block! {
    /// The rays a step of host intersection writes for one slot: the next ray and the
    /// shadow ray leave from the same point (`t_near` < 0: no such ray;
    /// [`WAVE_FINISH_ME`]: none, but the slot is to be stepped).
    pub struct WaveRays in "pathtrace/integrator/pathtrace.wgsl" as "WaveRays" {
        origin: [f32; 3],
        next_near: f32,
        next_dir: [f32; 3],
        shadow_near: f32,
        shadow_dir: [f32; 3],
        shadow_far: f32,
    }
}

/// `pathtrace/shared.wgsl`.
pub fn wgsl() -> String {
    let mut out = String::from(
        "// Generated from crates/render/src/shared.rs (constants the Rust side shares).\n",
    );
    for (name, value) in [
        ("WAVE_HOT_VEC4S", WAVE_HOT_VEC4S),
        ("WAVE_COLD_VEC4S", WAVE_COLD_VEC4S),
        ("WAVE_RAYS_VEC4S", WAVE_RAYS_VEC4S),
        ("WAVE_RAYS_AT", WAVE_RAYS_AT),
        ("WAVE_HITS_AT", WAVE_HITS_AT),
        ("WAVE_LIST_AT", WAVE_LIST_AT),
        ("WAVE_INSTS_AT", WAVE_INSTS_AT),
        ("WAVE_LEAVE_VEC4S", WAVE_LEAVE_VEC4S),
        ("WAVE_FRONT_LISTS_AT", WAVE_FRONT_LISTS_AT),
        ("WAVE_COUNTS_AT", WAVE_COUNTS_AT),
        ("ACCEL_TRIANGLES", ACCEL_TRIANGLES),
        ("ACCEL_SHAPES", ACCEL_SHAPES),
        ("CHUNK_FIRST", CHUNK_FIRST),
        ("CHUNK_LAST", CHUNK_LAST),
        ("WAVE_STEP", WAVE_STEP),
        ("WAVE_FINISH", WAVE_FINISH),
    ] {
        let _ = writeln!(out, "const {name}: u32 = {value}u;");
    }
    for (name, value) in [
        ("WAVE_FINISH_ME", WAVE_FINISH_ME),
        ("WAVE_NO_RAY", WAVE_NO_RAY),
        ("LIGHT_UNIFORM_SHARE", LIGHT_UNIFORM_SHARE),
    ] {
        let _ = writeln!(out, "const {name}: f32 = {value:?};");
    }
    out
}
