//! The records the path tracer's shaders and the host intersector exchange: a ray and a hit,
//! 32 and 16 bytes.

/// A ray for the host intersector: 32 bytes, the layout the WGSL writes.
///
/// A ray whose `tfar` is negative, NaN, or not greater than `tnear` is "no ray": it misses
/// (and is not occluded) without reaching Embree. So is one with a non-finite origin or
/// direction. A negative `tnear` counts as 0 (Embree's segments start at the origin or
/// after). `dir` need not be unit length; `t` is in units of `dir`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HostRay {
    /// Origin.
    pub origin: [f32; 3],
    /// Hits count from here on (exclusive).
    pub tnear: f32,
    /// Direction.
    pub dir: [f32; 3],
    /// Hits count up to here (exclusive); may be `f32::INFINITY`.
    pub tfar: f32,
}

impl HostRay {
    /// Whether Embree should trace this ray (see the type's documentation).
    pub(super) fn is_active(&self) -> bool {
        self.tfar >= 0.0
            && self.tfar > self.tnear
            && self.origin.iter().all(|x| x.is_finite())
            && self.dir.iter().all(|x| x.is_finite())
    }
}

/// The closest hit of a [`HostRay`]: 16 bytes, the layout the WGSL reads.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HostHit {
    /// Distance along the ray, in units of its `dir`; `f32::MAX` on a miss.
    pub t: f32,
    /// Barycentric weight of corner 1.
    pub u: f32,
    /// Barycentric weight of corner 2.
    pub v: f32,
    /// The triangle's index in the corners given to [`HostScene::new`]; `u32::MAX` on a
    /// miss.
    pub prim: u32,
}

/// Its WGSL twin is `WaveHit` (the hits section of host intersection's `wave` buffer, into
/// which the host copies these as they are), checked field by field by the layout test.
impl lumagraph_render::params::ParamBlock for HostHit {
    const LAYOUT: lumagraph_render::params::BlockLayout = lumagraph_render::params::BlockLayout {
        name: "HostHit",
        shader: "pathtrace/integrator/pathtrace.wgsl",
        wgsl: "WaveHit",
        size: std::mem::size_of::<Self>(),
        fields: &[
            ("t", std::mem::offset_of!(Self, t)),
            ("u", std::mem::offset_of!(Self, u)),
            ("v", std::mem::offset_of!(Self, v)),
            ("prim", std::mem::offset_of!(Self, prim)),
        ],
    };
}

impl HostHit {
    /// No hit (what a "no ray" gets too).
    pub const MISS: HostHit = HostHit {
        t: f32::MAX,
        u: 0.0,
        v: 0.0,
        prim: u32::MAX,
    };

    /// Whether something was hit.
    pub fn is_hit(&self) -> bool {
        self.prim != u32::MAX
    }
}
