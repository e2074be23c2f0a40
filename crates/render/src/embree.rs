//! Host (CPU) ray queries with Embree 3, loaded at run time.
//!
//! On CPU adapters (lavapipe) the WGSL BVH traversal is slow; the path tracer can hand its
//! rays to the host instead, where Embree traces them. Nothing links against Embree: the
//! library is opened with `libloading` on first use, so a machine without it builds and
//! runs, and the caller falls back to the WGSL traversal when [`Embree::load`] fails.
//!
//! - [`Embree`]: the loaded library and its device, one per process.
//! - [`HostScene`]: one triangle mesh, its primitive IDs the indices of the triangles as
//!   given (the path tracer's BVH order, [`lumagraph_scene::GpuScene::tri_corners`]).
//! - [`HostRay`] and [`HostHit`]: 32 and 16 bytes, the layouts the WGSL writes and reads.
//!
//! Library names tried, in order: the path in `LUMAGRAPH_EMBREE` when set, then
//! `libembree3.so.3`, `libembree3.so`, `libembree3.dylib`, `embree3.dll`.
//! `LUMAGRAPH_EMBREE=off` disables Embree. The environment is read once per process.
//!
//! Triangles are two-sided and hit where `tnear < t < tfar` (Embree makes no promise for
//! `t` at either end exactly). Barycentrics follow Embree's convention, which is also the
//! WGSL's Möller–Trumbore one: the hit point is `(1 - u - v)·c0 + u·c1 + v·c2`.
//!
//! Tracing: rays in chunks of 2048 over rayon's threads, each chunk handed to Embree as
//! `rtcIntersect1M`/`rtcOccluded1M` streams of 256 with the incoherent flag; the scene is a
//! triangle soup built at `RTC_BUILD_QUALITY_MEDIUM` without `RTC_SCENE_FLAG_ROBUST`. On the
//! mesh benchmark (82 k triangles, 2 cores) that measured fastest: high quality builds 5×
//! slower for no faster tracing, robust traversal is 15–25 % slower and found no hit the
//! default missed, and streams beat `rtcIntersect1` by up to 2× on shadow rays
//! (`examples/embree_rays.rs` prints the comparison).
//!
//! Every entry point into Embree follows its C headers (`embree3/rtcore*.h`, 3.13.5): the
//! structures below copy their layouts, and their sizes are checked at compile time.
#![allow(unsafe_code)]

use std::ffi::{CStr, c_char, c_void};
use std::ptr::NonNull;
use std::sync::{Arc, Mutex, OnceLock};

use rayon::prelude::*;

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
    fn is_active(&self) -> bool {
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
impl crate::params::ParamBlock for HostHit {
    const LAYOUT: crate::params::BlockLayout = crate::params::BlockLayout {
        name: "HostHit",
        shader: "pathtrace/pathtrace.wgsl",
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

// ---------------------------------------------------------------------------------------
// The C API (embree3/rtcore_*.h). Enums are C `int`s; every value is the header's.

type RtcDevice = *mut c_void;
type RtcScene = *mut c_void;
type RtcGeometry = *mut c_void;
/// `RTCErrorFunction`.
type RtcErrorFunction = unsafe extern "C" fn(user: *mut c_void, code: u32, message: *const c_char);

/// `struct RTCFilterFunctionNArguments`: the candidate hits of `n` rays, `ray` and `hit`
/// laid out as `RTCRayN` and `RTCHitN` (field `k` of ray `i` at `[k·n + i]`); setting
/// `valid[i]` to 0 rejects ray `i`'s candidate.
#[repr(C)]
struct RtcFilterArgs {
    valid: *mut i32,
    geometry_user_ptr: *mut c_void,
    context: *mut c_void,
    ray: *mut f32,
    hit: *mut f32,
    n: u32,
}

/// `RTCFilterFunctionN`.
type RtcFilterFunction = unsafe extern "C" fn(args: *const RtcFilterArgs);

/// The any-hit test of host intersection (Embree's intersect and occluded filter of the
/// triangle geometry): a candidate counts where
/// [`lumagraph_scene::traverse::triangle_hit_counts`] says so, the CPU mirror of the WGSL
/// intersectors' `triangle_hit_counts` (alpha masks and blending).
///
/// # Safety
/// Called by Embree with `args` as its headers describe, the geometry's user pointer a live
/// `GpuScene` (`HostScene` keeps it) whose triangles are the geometry's, in order.
unsafe extern "C" fn any_hit_filter(args: *const RtcFilterArgs) {
    // SAFETY: see the function's contract.
    let a = unsafe { &*args };
    // SAFETY: the user pointer is the `GpuScene` the `HostScene` holds.
    let scene = unsafe { &*a.geometry_user_ptr.cast::<lumagraph_scene::GpuScene>() };
    let n = a.n as usize;
    for i in 0..n {
        // SAFETY: `valid`, `ray` and `hit` hold `n` entries per field.
        unsafe {
            if *a.valid.add(i) == 0 {
                continue;
            }
            let ray = |k: usize| *a.ray.add(k * n + i);
            let hit = |k: usize| *a.hit.add(k * n + i);
            let r = lumagraph_scene::traverse::Ray {
                origin: glam::Vec3::new(ray(0), ray(1), ray(2)),
                dir: glam::Vec3::new(ray(4), ray(5), ray(6)),
            };
            let prim = *a.hit.cast::<u32>().add(5 * n + i);
            if !lumagraph_scene::traverse::triangle_hit_counts(scene, prim, hit(3), hit(4), &r) {
                *a.valid.add(i) = 0;
            }
        }
    }
}

/// `RTC_INVALID_GEOMETRY_ID`.
const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;
/// `RTCFormat`: `RTC_FORMAT_UINT3` (`RTC_FORMAT_UINT = 0x5001`, then 2, 3).
const RTC_FORMAT_UINT3: u32 = 0x5003;
/// `RTCFormat`: `RTC_FORMAT_FLOAT3` (`RTC_FORMAT_FLOAT = 0x9001`, then 2, 3).
const RTC_FORMAT_FLOAT3: u32 = 0x9003;
/// `RTCBufferType`.
const RTC_BUFFER_TYPE_INDEX: u32 = 0;
const RTC_BUFFER_TYPE_VERTEX: u32 = 1;
/// `RTCGeometryType`.
const RTC_GEOMETRY_TYPE_TRIANGLE: u32 = 0;
/// `RTCBuildQuality` (`RTC_BUILD_QUALITY_LOW` is 0).
const RTC_BUILD_QUALITY_MEDIUM: u32 = 1;
const RTC_BUILD_QUALITY_HIGH: u32 = 2;
/// `RTCSceneFlags`.
const RTC_SCENE_FLAG_NONE: u32 = 0;
const RTC_SCENE_FLAG_COMPACT: u32 = 1 << 1;
const RTC_SCENE_FLAG_ROBUST: u32 = 1 << 2;
/// `RTCIntersectContextFlags`.
const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: u32 = 0;
const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: u32 = 1;
/// `RTCDeviceProperty`.
const RTC_DEVICE_PROPERTY_VERSION_MAJOR: u32 = 1;
const RTC_DEVICE_PROPERTY_VERSION_MINOR: u32 = 2;
const RTC_DEVICE_PROPERTY_VERSION_PATCH: u32 = 3;
const RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED: u32 = 65;
const RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED: u32 = 96;

/// `RTCError` names, by code.
fn error_name(code: u32) -> &'static str {
    match code {
        0 => "RTC_ERROR_NONE",
        1 => "RTC_ERROR_UNKNOWN",
        2 => "RTC_ERROR_INVALID_ARGUMENT",
        3 => "RTC_ERROR_INVALID_OPERATION",
        4 => "RTC_ERROR_OUT_OF_MEMORY",
        5 => "RTC_ERROR_UNSUPPORTED_CPU",
        6 => "RTC_ERROR_CANCELLED",
        _ => "unknown RTCError",
    }
}

/// `struct RTCRay` (`RTC_ALIGN(16)`).
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

/// `struct RTCHit` (`RTC_ALIGN(16)`; `RTC_MAX_INSTANCE_LEVEL_COUNT` is 1).
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy)]
struct RtcRayHit {
    ray: RtcRay,
    hit: RtcHit,
}

/// `struct RTCRayHit4/8/16`: `RTCRayN` then `RTCHitN`, each field an array of `N` (SOA).
/// The sizes of the ray halves (48·N bytes) are multiples of the alignments (16, 32, 64
/// for N = 4, 8, 16), so one flat struct has the headers' offsets; 64-byte alignment
/// serves all three. `rtcOccludedN` reads the leading `RTCRayN` of the same memory.
#[repr(C, align(64))]
#[derive(Clone, Copy)]
struct RtcRayHitN<const N: usize> {
    org_x: [f32; N],
    org_y: [f32; N],
    org_z: [f32; N],
    tnear: [f32; N],
    dir_x: [f32; N],
    dir_y: [f32; N],
    dir_z: [f32; N],
    time: [f32; N],
    tfar: [f32; N],
    mask: [u32; N],
    id: [u32; N],
    flags: [u32; N],
    ng_x: [f32; N],
    ng_y: [f32; N],
    ng_z: [f32; N],
    u: [f32; N],
    v: [f32; N],
    prim_id: [u32; N],
    geom_id: [u32; N],
    inst_id: [u32; N],
}

/// The `valid` mask of `rtcIntersectN`/`rtcOccludedN`: -1 active, 0 not; Embree loads it
/// as one SIMD vector, so it is aligned as the packet is.
#[repr(C, align(64))]
struct ValidN<const N: usize>([i32; N]);

/// `struct RTCIntersectContext` with `RTC_MAX_INSTANCE_LEVEL_COUNT` 1 and `RTC_MIN_WIDTH`
/// 0: `flags`, `filter`, `instID[1]`.
#[repr(C)]
struct RtcIntersectContext {
    flags: u32,
    filter: Option<unsafe extern "C" fn(args: *const c_void)>,
    inst_id: [u32; 1],
}

impl RtcIntersectContext {
    /// What the inline `rtcInitIntersectContext` sets, with `flags` as given.
    fn new(coherent: bool) -> Self {
        Self {
            flags: if coherent {
                RTC_INTERSECT_CONTEXT_FLAG_COHERENT
            } else {
                RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT
            },
            filter: None,
            inst_id: [RTC_INVALID_GEOMETRY_ID],
        }
    }
}

const _: () = {
    use std::mem::{align_of, size_of};
    assert!(size_of::<HostRay>() == 32 && size_of::<HostHit>() == 16);
    assert!(size_of::<RtcRay>() == 48 && align_of::<RtcRay>() == 16);
    assert!(size_of::<RtcHit>() == 32 && align_of::<RtcHit>() == 16);
    assert!(size_of::<RtcRayHit>() == 80);
    assert!(std::mem::offset_of!(RtcRayHit, hit) == 48);
    assert!(size_of::<RtcRayHitN<16>>() == 20 * 16 * 4);
    assert!(std::mem::offset_of!(RtcRayHitN<8>, ng_x) == 12 * 8 * 4);
    assert!(size_of::<RtcIntersectContext>() == 24);
    assert!(std::mem::offset_of!(RtcIntersectContext, inst_id) == 16);
};

/// The entry points used, resolved once from the library.
struct Api {
    new_device: unsafe extern "C" fn(config: *const c_char) -> RtcDevice,
    release_device: unsafe extern "C" fn(device: RtcDevice),
    get_device_property: unsafe extern "C" fn(device: RtcDevice, prop: u32) -> isize,
    get_device_error: unsafe extern "C" fn(device: RtcDevice) -> u32,
    set_device_error_function:
        unsafe extern "C" fn(device: RtcDevice, f: Option<RtcErrorFunction>, user: *mut c_void),
    new_scene: unsafe extern "C" fn(device: RtcDevice) -> RtcScene,
    release_scene: unsafe extern "C" fn(scene: RtcScene),
    set_scene_build_quality: unsafe extern "C" fn(scene: RtcScene, quality: u32),
    set_scene_flags: unsafe extern "C" fn(scene: RtcScene, flags: u32),
    attach_geometry: unsafe extern "C" fn(scene: RtcScene, geometry: RtcGeometry) -> u32,
    commit_scene: unsafe extern "C" fn(scene: RtcScene),
    new_geometry: unsafe extern "C" fn(device: RtcDevice, kind: u32) -> RtcGeometry,
    release_geometry: unsafe extern "C" fn(geometry: RtcGeometry),
    commit_geometry: unsafe extern "C" fn(geometry: RtcGeometry),
    set_geometry_build_quality: unsafe extern "C" fn(geometry: RtcGeometry, quality: u32),
    set_geometry_user_data: unsafe extern "C" fn(geometry: RtcGeometry, user: *mut c_void),
    set_geometry_intersect_filter:
        unsafe extern "C" fn(geometry: RtcGeometry, f: Option<RtcFilterFunction>),
    set_geometry_occluded_filter:
        unsafe extern "C" fn(geometry: RtcGeometry, f: Option<RtcFilterFunction>),
    set_new_geometry_buffer: unsafe extern "C" fn(
        geometry: RtcGeometry,
        kind: u32,
        slot: u32,
        format: u32,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void,
    intersect1:
        unsafe extern "C" fn(scene: RtcScene, ctx: *mut RtcIntersectContext, rh: *mut RtcRayHit),
    occluded1: unsafe extern "C" fn(scene: RtcScene, ctx: *mut RtcIntersectContext, r: *mut RtcRay),
    intersect1m: unsafe extern "C" fn(
        scene: RtcScene,
        ctx: *mut RtcIntersectContext,
        rh: *mut RtcRayHit,
        m: u32,
        byte_stride: usize,
    ),
    occluded1m: unsafe extern "C" fn(
        scene: RtcScene,
        ctx: *mut RtcIntersectContext,
        r: *mut RtcRayHit,
        m: u32,
        byte_stride: usize,
    ),
    intersect8: PacketFn<8>,
    occluded8: PacketFn<8>,
    intersect16: PacketFn<16>,
    occluded16: PacketFn<16>,
}

/// `rtcIntersect8/16` and `rtcOccluded8/16` (the ray-only functions read the leading ray
/// half of the same packet).
type PacketFn<const N: usize> = unsafe extern "C" fn(
    valid: *const ValidN<N>,
    scene: RtcScene,
    ctx: *mut RtcIntersectContext,
    rh: *mut RtcRayHitN<N>,
);

impl Api {
    /// Resolves every entry point, or names the first one missing.
    ///
    /// # Safety
    /// `lib` must be Embree 3, so that each symbol has the signature declared in [`Api`].
    unsafe fn resolve(lib: &libloading::Library) -> Result<Self, String> {
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the caller guarantees `lib` is Embree 3, whose `$name` has the
                // signature of the field it is stored in (copied from its headers).
                unsafe { symbol(lib, $name) }?
            };
        }
        Ok(Self {
            new_device: sym!("rtcNewDevice"),
            release_device: sym!("rtcReleaseDevice"),
            get_device_property: sym!("rtcGetDeviceProperty"),
            get_device_error: sym!("rtcGetDeviceError"),
            set_device_error_function: sym!("rtcSetDeviceErrorFunction"),
            new_scene: sym!("rtcNewScene"),
            release_scene: sym!("rtcReleaseScene"),
            set_scene_build_quality: sym!("rtcSetSceneBuildQuality"),
            set_scene_flags: sym!("rtcSetSceneFlags"),
            attach_geometry: sym!("rtcAttachGeometry"),
            commit_scene: sym!("rtcCommitScene"),
            new_geometry: sym!("rtcNewGeometry"),
            release_geometry: sym!("rtcReleaseGeometry"),
            commit_geometry: sym!("rtcCommitGeometry"),
            set_geometry_build_quality: sym!("rtcSetGeometryBuildQuality"),
            set_geometry_user_data: sym!("rtcSetGeometryUserData"),
            set_geometry_intersect_filter: sym!("rtcSetGeometryIntersectFilterFunction"),
            set_geometry_occluded_filter: sym!("rtcSetGeometryOccludedFilterFunction"),
            set_new_geometry_buffer: sym!("rtcSetNewGeometryBuffer"),
            intersect1: sym!("rtcIntersect1"),
            occluded1: sym!("rtcOccluded1"),
            intersect1m: sym!("rtcIntersect1M"),
            occluded1m: sym!("rtcOccluded1M"),
            intersect8: sym!("rtcIntersect8"),
            occluded8: sym!("rtcOccluded8"),
            intersect16: sym!("rtcIntersect16"),
            occluded16: sym!("rtcOccluded16"),
        })
    }
}

/// The function `name` of `lib`, copied out of its `Symbol`.
///
/// # Safety
/// `T` must be the function's type, and `lib` must stay loaded while it is used (`Embree`
/// keeps it).
unsafe fn symbol<T: Copy>(lib: &libloading::Library, name: &str) -> Result<T, String> {
    let mut bytes = name.as_bytes().to_vec();
    bytes.push(0);
    // SAFETY: forwarded to the caller.
    let symbol = unsafe { lib.get::<T>(&bytes) }.map_err(|e| format!("symbol {name}: {e}"))?;
    Ok(*symbol)
}

/// Messages Embree's error callback reported, oldest first (at most a few kept).
type ErrorLog = Mutex<Vec<String>>;

/// Embree's error callback: keeps the message for [`Embree::check`]. Never unwinds.
unsafe extern "C" fn record_error(user: *mut c_void, code: u32, message: *const c_char) {
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated message valid for this call.
        unsafe { CStr::from_ptr(message) }
            .to_string_lossy()
            .into_owned()
    };
    // SAFETY: `user` is the `ErrorLog` boxed in the `Embree` that registered this callback,
    // which outlives its device (the device is released before the box is dropped).
    let log = unsafe { &*user.cast::<ErrorLog>() };
    if let Ok(mut log) = log.lock()
        && log.len() < 16
    {
        log.push(format!("{}: {text}", error_name(code)));
    }
}

/// The loaded Embree library and one device: see the module documentation.
pub struct Embree {
    api: Api,
    device: NonNull<c_void>,
    errors: Box<ErrorLog>,
    library: String,
    version: (isize, isize, isize),
    /// Declared last: dropped after the device is released.
    _lib: libloading::Library,
}

// SAFETY: an Embree device may be used from any thread and from several at once (the API
// is thread safe; error codes are per thread). The other fields are plain data, a mutex,
// and the library handle.
unsafe impl Send for Embree {}
// SAFETY: as above; `&Embree` only calls thread-safe device functions.
unsafe impl Sync for Embree {}

impl std::fmt::Debug for Embree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Embree")
            .field("library", &self.library)
            .field("version", &self.version())
            .finish_non_exhaustive()
    }
}

impl Drop for Embree {
    fn drop(&mut self) {
        // SAFETY: the device was made by `rtcNewDevice` and is released once; every scene
        // holds an `Arc<Embree>`, so none is left. The error log box is dropped after this.
        unsafe { (self.api.release_device)(self.device.as_ptr()) };
    }
}

/// The library names tried, in order, after `LUMAGRAPH_EMBREE`.
const LIBRARY_NAMES: [&str; 4] = [
    "libembree3.so.3",
    "libembree3.so",
    "libembree3.dylib",
    "embree3.dll",
];

impl Embree {
    /// The process's Embree, loaded on first call (see the module documentation for the
    /// names tried). The error says which names were tried and why each failed, or that
    /// `LUMAGRAPH_EMBREE=off` disabled it; it is the same on every call.
    pub fn load() -> Result<Arc<Embree>, String> {
        static EMBREE: OnceLock<Result<Arc<Embree>, String>> = OnceLock::new();
        EMBREE
            .get_or_init(|| {
                let chosen = std::env::var("LUMAGRAPH_EMBREE").ok();
                let chosen = chosen.as_deref().map(str::trim).filter(|s| !s.is_empty());
                if chosen.is_some_and(|s| s.eq_ignore_ascii_case("off")) {
                    return Err("Embree disabled by LUMAGRAPH_EMBREE=off".to_owned());
                }
                let mut failures = Vec::new();
                for name in chosen.into_iter().chain(LIBRARY_NAMES) {
                    match Self::open(name) {
                        Ok(e) => return Ok(Arc::new(e)),
                        Err(e) => failures.push(format!("{name} ({e})")),
                    }
                }
                Err(format!(
                    "Embree 3 not loaded: tried {}",
                    failures.join(", ")
                ))
            })
            .clone()
    }

    /// Opens one library and makes its device.
    fn open(name: &str) -> Result<Embree, String> {
        // SAFETY: loading a shared library runs its initializers; Embree's only set up its
        // own state. The name comes from our list or the user's `LUMAGRAPH_EMBREE`.
        let lib = unsafe { libloading::Library::new(name) }.map_err(|e| e.to_string())?;
        // SAFETY: a library named as Embree 3 that exports these symbols is taken to be
        // Embree 3; its major version is checked below before any scene is made.
        let api = unsafe { Api::resolve(&lib) }?;
        // SAFETY: a null config selects Embree's defaults.
        let device = unsafe { (api.new_device)(std::ptr::null()) };
        let Some(device) = NonNull::new(device) else {
            // SAFETY: a null device asks for the error of the failed `rtcNewDevice`.
            let code = unsafe { (api.get_device_error)(std::ptr::null_mut()) };
            return Err(format!("rtcNewDevice failed: {}", error_name(code)));
        };
        let errors: Box<ErrorLog> = Box::default();
        let user = std::ptr::from_ref::<ErrorLog>(&errors)
            .cast_mut()
            .cast::<c_void>();
        // SAFETY: `device` is live; `user` points to the boxed log, which `Embree` owns and
        // drops only after releasing the device, and `record_error` only locks it.
        unsafe { (api.set_device_error_function)(device.as_ptr(), Some(record_error), user) };
        // SAFETY: `device` is live; property queries have no other precondition.
        let property = |p| unsafe { (api.get_device_property)(device.as_ptr(), p) };
        let version = (
            property(RTC_DEVICE_PROPERTY_VERSION_MAJOR),
            property(RTC_DEVICE_PROPERTY_VERSION_MINOR),
            property(RTC_DEVICE_PROPERTY_VERSION_PATCH),
        );
        let triangles = property(RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED);
        let culling = property(RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED);
        let embree = Embree {
            api,
            device,
            errors,
            library: name.to_owned(),
            version,
            _lib: lib,
        };
        if version.0 != 3 {
            return Err(format!("version {} is not Embree 3", embree.version()));
        }
        if triangles == 0 {
            return Err("built without triangle geometry".to_owned());
        }
        if culling != 0 {
            return Err("built with back-face culling (triangles must be two-sided)".to_owned());
        }
        embree.check("rtcNewDevice")?;
        Ok(embree)
    }

    /// The library's version, e.g. "Embree 3.13.5".
    pub fn version(&self) -> String {
        let (major, minor, patch) = self.version;
        format!("Embree {major}.{minor}.{patch}")
    }

    /// The library name or path that was loaded.
    pub fn library(&self) -> &str {
        &self.library
    }

    /// This thread's pending device error, with the messages the callback kept, as an
    /// error naming `what`.
    fn check(&self, what: &str) -> Result<(), String> {
        // SAFETY: the device is live for as long as `self`.
        let code = unsafe { (self.api.get_device_error)(self.device.as_ptr()) };
        let messages = self
            .errors
            .lock()
            .map(|mut log| std::mem::take(&mut *log))
            .unwrap_or_default();
        if code == 0 {
            return Ok(());
        }
        let mut error = format!("Embree: {what} failed: {}", error_name(code));
        for m in messages {
            error.push_str("; ");
            error.push_str(&m);
        }
        Err(error)
    }
}

/// How a [`HostScene`] is built and traced. The defaults are what measured fastest on the
/// benchmark mesh (see `examples/embree_rays.rs`); the other settings exist to measure.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tuning {
    /// `RTC_BUILD_QUALITY_*`: 0 low, 1 medium, 2 high.
    pub quality: u32,
    /// `RTC_SCENE_FLAG_ROBUST`.
    pub robust: bool,
    /// `RTC_SCENE_FLAG_COMPACT`.
    pub compact: bool,
    /// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT` rather than `..._INCOHERENT`.
    pub coherent: bool,
    /// Rays per Embree call: 1 (`rtcIntersect1`), 8 or 16 (`rtcIntersect8/16` packets), or
    /// 0 for `rtcIntersect1M` streams of 256.
    pub packet: u32,
    /// Rays per parallel task.
    pub chunk: usize,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            quality: RTC_BUILD_QUALITY_MEDIUM,
            robust: false,
            compact: false,
            coherent: false,
            packet: 0,
            chunk: 2048,
        }
    }
}

/// Triangles in an Embree scene, traced from the host: see the module documentation.
pub struct HostScene {
    embree: Arc<Embree>,
    /// `None` without triangles: every ray misses.
    scene: Option<NonNull<c_void>>,
    triangles: usize,
    tuning: Tuning,
    /// The scene whose materials the any-hit filter reads (alpha), kept alive as long as
    /// Embree may call the filter with it.
    any_hit: Option<Arc<lumagraph_scene::GpuScene>>,
}

// SAFETY: a committed Embree scene is immutable; Embree allows ray queries on it from any
// number of threads at once. It is released once, by `Drop`, which has `&mut self`.
unsafe impl Send for HostScene {}
// SAFETY: as above: `&HostScene` only runs ray queries.
unsafe impl Sync for HostScene {}

impl std::fmt::Debug for HostScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HostScene")
            .field("triangles", &self.triangles)
            .field("tuning", &self.tuning)
            .finish_non_exhaustive()
    }
}

impl Drop for HostScene {
    fn drop(&mut self) {
        if let Some(scene) = self.scene.take() {
            // SAFETY: the scene came from `rtcNewScene` on this device and is released once;
            // no query can be running, as `drop` has `&mut self`.
            unsafe { (self.embree.api.release_scene)(scene.as_ptr()) };
        }
    }
}

impl HostScene {
    /// Triangles given by their three corners, in the order the path tracer indexes them
    /// (a hit's `prim` is the index here). Corners that are equal floats make a watertight
    /// mesh. Triangles with a non-finite corner are never hit (Embree leaves them out), nor
    /// are degenerate ones. Errors are Embree's (out of memory, invalid input); no
    /// triangles is fine.
    pub fn new(embree: Arc<Embree>, corners: &[[[f32; 3]; 3]]) -> Result<Self, String> {
        Self::with_tuning(embree, corners, Tuning::default())
    }

    /// [`HostScene::new`] over `scene`'s triangles (`tri_corners`), whose candidate hits
    /// take the any-hit test of every intersector
    /// ([`lumagraph_scene::traverse::triangle_hit_counts`]: alpha masks and blending),
    /// where its materials need it ([`lumagraph_scene::FEATURE_ALPHA`]).
    ///
    /// # Errors
    /// As [`HostScene::new`].
    pub fn of_scene(
        embree: Arc<Embree>,
        scene: &Arc<lumagraph_scene::GpuScene>,
    ) -> Result<Self, String> {
        let any_hit = (scene.header.features & lumagraph_scene::FEATURE_ALPHA != 0)
            .then(|| Arc::clone(scene));
        Self::build(embree, &scene.tri_corners, Tuning::default(), any_hit)
    }

    /// [`HostScene::new`] with other build and trace settings (for measurements).
    #[doc(hidden)]
    pub fn with_tuning(
        embree: Arc<Embree>,
        corners: &[[[f32; 3]; 3]],
        tuning: Tuning,
    ) -> Result<Self, String> {
        Self::build(embree, corners, tuning, None)
    }

    fn build(
        embree: Arc<Embree>,
        corners: &[[[f32; 3]; 3]],
        tuning: Tuning,
        any_hit: Option<Arc<lumagraph_scene::GpuScene>>,
    ) -> Result<Self, String> {
        let mut out = Self {
            embree,
            scene: None,
            triangles: corners.len(),
            tuning: Tuning {
                chunk: tuning.chunk.max(16),
                ..tuning
            },
            any_hit,
        };
        if corners.is_empty() {
            return Ok(out);
        }
        if corners.len() > (u32::MAX / 3) as usize {
            return Err(format!("{} triangles: too many for Embree", corners.len()));
        }
        let e = Arc::clone(&out.embree);
        let api = &e.api;
        let device = e.device.as_ptr();
        // Clears an error left on this thread by an earlier call, so it is not taken for
        // this build's.
        let _ = e.check("earlier call");
        // SAFETY: `device` is live; a null result is handled.
        let scene = unsafe { (api.new_scene)(device) };
        out.scene = NonNull::new(scene);
        let Some(scene) = out.scene else {
            return Err(e
                .check("rtcNewScene")
                .err()
                .unwrap_or_else(|| "rtcNewScene failed".into()));
        };
        let scene = scene.as_ptr();
        // SAFETY: `device` is live; a null result is handled.
        let geometry = unsafe { (api.new_geometry)(device, RTC_GEOMETRY_TYPE_TRIANGLE) };
        if geometry.is_null() {
            return Err(e
                .check("rtcNewGeometry")
                .err()
                .unwrap_or_else(|| "rtcNewGeometry failed".into()));
        }
        let filled = Self::fill(&e, geometry, corners);
        if filled.is_ok() {
            let mut flags = RTC_SCENE_FLAG_NONE;
            if tuning.robust {
                flags |= RTC_SCENE_FLAG_ROBUST;
            }
            if tuning.compact {
                flags |= RTC_SCENE_FLAG_COMPACT;
            }
            let quality = tuning.quality.min(RTC_BUILD_QUALITY_HIGH);
            if let Some(g) = &out.any_hit {
                // SAFETY: `geometry` is live; the user pointer is the `GpuScene` that
                // `out.any_hit` keeps alive as long as the Embree scene, and
                // `any_hit_filter` reads it as one.
                unsafe {
                    (api.set_geometry_user_data)(
                        geometry,
                        Arc::as_ptr(g).cast::<c_void>().cast_mut(),
                    );
                    (api.set_geometry_intersect_filter)(geometry, Some(any_hit_filter));
                    (api.set_geometry_occluded_filter)(geometry, Some(any_hit_filter));
                }
            }
            // SAFETY: `geometry` and `scene` are live and belong to `device`; the geometry
            // has both buffers set. Attaching takes a reference, so releasing ours below
            // leaves the scene owning it.
            unsafe {
                (api.set_geometry_build_quality)(geometry, quality);
                (api.commit_geometry)(geometry);
                (api.attach_geometry)(scene, geometry);
                (api.set_scene_flags)(scene, flags);
                (api.set_scene_build_quality)(scene, quality);
            }
        }
        // SAFETY: our reference to the geometry, made above, is released once.
        unsafe { (api.release_geometry)(geometry) };
        filled?;
        // SAFETY: `scene` is live and complete; nothing traces it yet.
        unsafe { (api.commit_scene)(scene) };
        e.check("rtcCommitScene")?;
        Ok(out)
    }

    /// Gives `geometry` its vertex and index buffers: a triangle soup, corner `3i + k` of
    /// triangle `i` at vertex `3i + k`.
    fn fill(e: &Embree, geometry: RtcGeometry, corners: &[[[f32; 3]; 3]]) -> Result<(), String> {
        let n = corners.len();
        // SAFETY: `geometry` is live; 12-byte FLOAT3 items, 3 per triangle. Embree pads
        // vertex buffers for its 16-byte loads itself.
        let vertices = unsafe {
            (e.api.set_new_geometry_buffer)(
                geometry,
                RTC_BUFFER_TYPE_VERTEX,
                0,
                RTC_FORMAT_FLOAT3,
                12,
                3 * n,
            )
        };
        e.check("vertex buffer")?;
        // SAFETY: as above, 12-byte UINT3 items, one per triangle.
        let indices = unsafe {
            (e.api.set_new_geometry_buffer)(
                geometry,
                RTC_BUFFER_TYPE_INDEX,
                0,
                RTC_FORMAT_UINT3,
                12,
                n,
            )
        };
        e.check("index buffer")?;
        if vertices.is_null() || indices.is_null() {
            return Err("Embree: rtcSetNewGeometryBuffer returned no buffer".to_owned());
        }
        // SAFETY: Embree allocated `3n` FLOAT3 vertices and `n` UINT3 triangles at these
        // (16-byte aligned) addresses, owned by `geometry` and written by nobody else now.
        let (vertices, indices) = unsafe {
            (
                std::slice::from_raw_parts_mut(vertices.cast::<[[f32; 3]; 3]>(), n),
                std::slice::from_raw_parts_mut(indices.cast::<[u32; 3]>(), n),
            )
        };
        vertices.copy_from_slice(corners);
        for (i, tri) in indices.iter_mut().enumerate() {
            let first = 3 * i as u32;
            *tri = [first, first + 1, first + 2];
        }
        Ok(())
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles == 0
    }

    /// The closest hit of each ray, into `hits` (same length; [`HostHit::MISS`] where a ray
    /// misses or is "no ray"), traced on rayon's threads.
    ///
    /// # Panics
    /// If `hits` and `rays` differ in length.
    pub fn intersect(&self, rays: &[HostRay], hits: &mut [HostHit]) {
        assert_eq!(rays.len(), hits.len(), "one hit per ray");
        let Some(scene) = self.scene else {
            hits.fill(HostHit::MISS);
            return;
        };
        let scene = Scene(scene.as_ptr());
        let chunk = self.tuning.chunk;
        rays.par_chunks(chunk)
            .zip(hits.par_chunks_mut(chunk))
            .for_each(|(rays, hits)| match self.tuning.packet {
                0 => self.intersect_stream(scene, rays, hits),
                8 => self.intersect_packets::<8>(scene, rays, hits, self.embree.api.intersect8),
                16 => self.intersect_packets::<16>(scene, rays, hits, self.embree.api.intersect16),
                _ => self.intersect_single(scene, rays, hits),
            });
    }

    /// Whether each ray hits anything between `tnear` and `tfar`, into `out` (same
    /// length): 1 or 0 (0 for "no ray"), traced on rayon's threads.
    ///
    /// # Panics
    /// If `out` and `rays` differ in length.
    pub fn occluded(&self, rays: &[HostRay], out: &mut [u32]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray");
        let Some(scene) = self.scene else {
            out.fill(0);
            return;
        };
        let scene = Scene(scene.as_ptr());
        let chunk = self.tuning.chunk;
        rays.par_chunks(chunk)
            .zip(out.par_chunks_mut(chunk))
            .for_each(|(rays, out)| match self.tuning.packet {
                0 => self.occluded_stream(scene, rays, out),
                8 => self.occluded_packets::<8>(scene, rays, out, self.embree.api.occluded8),
                16 => self.occluded_packets::<16>(scene, rays, out, self.embree.api.occluded16),
                _ => self.occluded_single(scene, rays, out),
            });
    }

    fn context(&self) -> RtcIntersectContext {
        RtcIntersectContext::new(self.tuning.coherent)
    }

    fn intersect_single(&self, scene: Scene, rays: &[HostRay], hits: &mut [HostHit]) {
        let mut ctx = self.context();
        for (ray, hit) in rays.iter().zip(hits) {
            if !ray.is_active() {
                *hit = HostHit::MISS;
                continue;
            }
            let mut rh = RtcRayHit {
                ray: rtc_ray(ray),
                hit: NO_HIT,
            };
            // SAFETY: `scene` is committed and outlives the call; `ctx` and `rh` are
            // initialized as the headers require (16-byte aligned, valid segment, geomID
            // invalid, flags 0).
            unsafe { (self.embree.api.intersect1)(scene.0, &raw mut ctx, &raw mut rh) };
            *hit = host_hit(
                rh.ray.tfar,
                rh.hit.u,
                rh.hit.v,
                rh.hit.prim_id,
                rh.hit.geom_id,
            );
        }
    }

    fn occluded_single(&self, scene: Scene, rays: &[HostRay], out: &mut [u32]) {
        let mut ctx = self.context();
        for (ray, out) in rays.iter().zip(out) {
            if !ray.is_active() {
                *out = 0;
                continue;
            }
            let mut r = rtc_ray(ray);
            // SAFETY: as in `intersect_single`; Embree sets `tfar` to -inf on a hit.
            unsafe { (self.embree.api.occluded1)(scene.0, &raw mut ctx, &raw mut r) };
            *out = u32::from(r.tfar == f32::NEG_INFINITY);
        }
    }

    fn intersect_stream(&self, scene: Scene, rays: &[HostRay], hits: &mut [HostHit]) {
        let mut ctx = self.context();
        let mut stream = [EMPTY_RAY_HIT; STREAM];
        for (rays, hits) in rays.chunks(STREAM).zip(hits.chunks_mut(STREAM)) {
            let stream = &mut stream[..rays.len()];
            for (s, r) in stream.iter_mut().zip(rays) {
                *s = stream_ray(r);
            }
            // SAFETY: `stream` holds `rays.len()` (at most `STREAM`) 16-byte aligned
            // ray/hits set up as for `rtcIntersect1`, inactive ones with tnear > tfar as
            // the API defines; `scene` is committed.
            unsafe {
                (self.embree.api.intersect1m)(
                    scene.0,
                    &raw mut ctx,
                    stream.as_mut_ptr(),
                    stream.len() as u32,
                    std::mem::size_of::<RtcRayHit>(),
                );
            }
            for (rh, hit) in stream.iter().zip(hits) {
                *hit = host_hit(
                    rh.ray.tfar,
                    rh.hit.u,
                    rh.hit.v,
                    rh.hit.prim_id,
                    rh.hit.geom_id,
                );
            }
        }
    }

    fn occluded_stream(&self, scene: Scene, rays: &[HostRay], out: &mut [u32]) {
        let mut ctx = self.context();
        let mut stream = [EMPTY_RAY_HIT; STREAM];
        for (rays, out) in rays.chunks(STREAM).zip(out.chunks_mut(STREAM)) {
            let stream = &mut stream[..rays.len()];
            for (s, r) in stream.iter_mut().zip(rays) {
                *s = stream_ray(r);
            }
            // SAFETY: as in `intersect_stream`; the stride steps over the hit halves, which
            // `rtcOccluded1M` does not touch.
            unsafe {
                (self.embree.api.occluded1m)(
                    scene.0,
                    &raw mut ctx,
                    stream.as_mut_ptr(),
                    stream.len() as u32,
                    std::mem::size_of::<RtcRayHit>(),
                );
            }
            for (rh, out) in stream.iter().zip(out) {
                *out = u32::from(rh.ray.tfar == f32::NEG_INFINITY);
            }
        }
    }

    fn intersect_packets<const N: usize>(
        &self,
        scene: Scene,
        rays: &[HostRay],
        hits: &mut [HostHit],
        f: PacketFn<N>,
    ) {
        let mut ctx = self.context();
        for (rays, hits) in rays.chunks(N).zip(hits.chunks_mut(N)) {
            let (valid, mut packet) = packet::<N>(rays);
            if valid.0.iter().all(|&v| v == 0) {
                hits.fill(HostHit::MISS);
                continue;
            }
            // SAFETY: `packet` and `valid` are 64-byte aligned, active lanes initialized as
            // for `rtcIntersect1`; `scene` is committed.
            unsafe { f(&raw const valid, scene.0, &raw mut ctx, &raw mut packet) };
            for (i, hit) in hits.iter_mut().enumerate() {
                *hit = if valid.0[i] == 0 {
                    HostHit::MISS
                } else {
                    host_hit(
                        packet.tfar[i],
                        packet.u[i],
                        packet.v[i],
                        packet.prim_id[i],
                        packet.geom_id[i],
                    )
                };
            }
        }
    }

    fn occluded_packets<const N: usize>(
        &self,
        scene: Scene,
        rays: &[HostRay],
        out: &mut [u32],
        f: PacketFn<N>,
    ) {
        let mut ctx = self.context();
        for (rays, out) in rays.chunks(N).zip(out.chunks_mut(N)) {
            let (valid, mut packet) = packet::<N>(rays);
            if valid.0.iter().all(|&v| v == 0) {
                out.fill(0);
                continue;
            }
            // SAFETY: as in `intersect_packets`; `rtcOccludedN` reads the ray half.
            unsafe { f(&raw const valid, scene.0, &raw mut ctx, &raw mut packet) };
            for (i, out) in out.iter_mut().enumerate() {
                *out = u32::from(valid.0[i] != 0 && packet.tfar[i] == f32::NEG_INFINITY);
            }
        }
    }
}

/// A committed scene handle, copied into rayon's tasks.
#[derive(Clone, Copy)]
struct Scene(RtcScene);
// SAFETY: see `HostScene`: queries on a committed scene may run on any thread.
unsafe impl Send for Scene {}
// SAFETY: as above.
unsafe impl Sync for Scene {}

/// An active ray as Embree's (`tnear` clamped to 0, mask all ones, flags 0).
fn rtc_ray(r: &HostRay) -> RtcRay {
    RtcRay {
        org: r.origin,
        tnear: r.tnear.max(0.0),
        dir: r.dir,
        time: 0.0,
        tfar: r.tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// A ray for `rtcIntersect1M`/`rtcOccluded1M`: inactive ones get `tnear` > `tfar`.
fn stream_ray(r: &HostRay) -> RtcRayHit {
    if r.is_active() {
        RtcRayHit {
            ray: rtc_ray(r),
            hit: NO_HIT,
        }
    } else {
        EMPTY_RAY_HIT
    }
}

/// Rays per `rtcIntersect1M`/`rtcOccluded1M` call, on the stack (20 KiB).
const STREAM: usize = 256;

/// `RTCHit` before a query: no geometry.
const NO_HIT: RtcHit = RtcHit {
    ng: [0.0; 3],
    u: 0.0,
    v: 0.0,
    prim_id: RTC_INVALID_GEOMETRY_ID,
    geom_id: RTC_INVALID_GEOMETRY_ID,
    inst_id: [RTC_INVALID_GEOMETRY_ID],
};

/// An inactive stream entry (tnear > tfar).
const EMPTY_RAY_HIT: RtcRayHit = RtcRayHit {
    ray: RtcRay {
        org: [0.0; 3],
        tnear: 1.0,
        dir: [1.0, 0.0, 0.0],
        time: 0.0,
        tfar: 0.0,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    },
    hit: NO_HIT,
};

/// Up to `N` rays as a packet and its valid mask (missing and inactive lanes off).
fn packet<const N: usize>(rays: &[HostRay]) -> (ValidN<N>, RtcRayHitN<N>) {
    let mut valid = ValidN([0; N]);
    let mut p = RtcRayHitN::<N> {
        org_x: [0.0; N],
        org_y: [0.0; N],
        org_z: [0.0; N],
        tnear: [0.0; N],
        dir_x: [1.0; N],
        dir_y: [0.0; N],
        dir_z: [0.0; N],
        time: [0.0; N],
        tfar: [-1.0; N],
        mask: [u32::MAX; N],
        id: [0; N],
        flags: [0; N],
        ng_x: [0.0; N],
        ng_y: [0.0; N],
        ng_z: [0.0; N],
        u: [0.0; N],
        v: [0.0; N],
        prim_id: [RTC_INVALID_GEOMETRY_ID; N],
        geom_id: [RTC_INVALID_GEOMETRY_ID; N],
        inst_id: [RTC_INVALID_GEOMETRY_ID; N],
    };
    for (i, r) in rays.iter().enumerate().take(N) {
        if !r.is_active() {
            continue;
        }
        valid.0[i] = -1;
        [p.org_x[i], p.org_y[i], p.org_z[i]] = r.origin;
        [p.dir_x[i], p.dir_y[i], p.dir_z[i]] = r.dir;
        p.tnear[i] = r.tnear.max(0.0);
        p.tfar[i] = r.tfar;
    }
    (valid, p)
}

/// A [`HostHit`] from Embree's output: a miss where `geom_id` is invalid.
fn host_hit(tfar: f32, u: f32, v: f32, prim_id: u32, geom_id: u32) -> HostHit {
    if geom_id == RTC_INVALID_GEOMETRY_ID {
        HostHit::MISS
    } else {
        HostHit {
            t: tfar,
            u,
            v,
            prim: prim_id,
        }
    }
}
