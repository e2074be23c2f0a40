//! Embree 3's C API as lumagraph calls it (`embree3/rtcore_*.h`, 3.13.5): the structures
//! copy the headers' layouts (sizes checked at compile time), the entry points are looked up
//! in the library at run time, and the any-hit filter calls the CPU mirror's alpha test.
#![allow(unsafe_code)]

use std::ffi::{CStr, c_char, c_void};
use std::sync::Mutex;

use super::{HostHit, HostRay};

// ---------------------------------------------------------------------------------------
// The C API (embree3/rtcore_*.h). Enums are C `int`s; every value is the header's.

pub(super) type RtcDevice = *mut c_void;
pub(super) type RtcScene = *mut c_void;
pub(super) type RtcGeometry = *mut c_void;
/// `RTCErrorFunction`.
pub(super) type RtcErrorFunction =
    unsafe extern "C" fn(user: *mut c_void, code: u32, message: *const c_char);

/// `struct RTCFilterFunctionNArguments`: the candidate hits of `n` rays, `ray` and `hit`
/// laid out as `RTCRayN` and `RTCHitN` (field `k` of ray `i` at `[k·n + i]`); setting
/// `valid[i]` to 0 rejects ray `i`'s candidate.
#[repr(C)]
pub(super) struct RtcFilterArgs {
    pub(super) valid: *mut i32,
    pub(super) geometry_user_ptr: *mut c_void,
    pub(super) context: *mut c_void,
    pub(super) ray: *mut f32,
    pub(super) hit: *mut f32,
    pub(super) n: u32,
}

/// `RTCFilterFunctionN`.
pub(super) type RtcFilterFunction = unsafe extern "C" fn(args: *const RtcFilterArgs);

/// What the any-hit filter of one triangle geometry reads (its user data): the scene whose
/// materials decide, and the index, in the path tracer's order, of the geometry's first
/// triangle (an instanced mesh's triangles follow the scene's own ones).
pub(super) struct FilterGeometry {
    pub(super) scene: *const lumagraph_scene::GpuScene,
    pub(super) base: u32,
}

/// The context of every query: Embree's, then the rays of the query (a ray's `id` is its
/// index there), so the filter reads a candidate's ray as given, in world space, even where
/// Embree hands it the ray moved into an instance's space.
#[repr(C)]
pub(super) struct QueryContext {
    pub(super) base: RtcIntersectContext,
    pub(super) rays: *const HostRay,
    pub(super) len: usize,
}

/// The any-hit test of host intersection (Embree's intersect and occluded filter of the
/// triangle geometries): a candidate counts where
/// [`lumagraph_scene::traverse::triangle_hit_counts`] says so, the CPU mirror of the WGSL
/// intersectors' `triangle_hit_counts` (alpha masks and blending), with the triangle's index
/// in the path tracer's order and the world-space ray, as the WGSL tests an instanced
/// triangle (`candidate_instance_triangle`) and a copy of it.
///
/// # Safety
/// Called by Embree with `args` as its headers describe, the geometry's user pointer a live
/// `FilterGeometry` (`HostScene` keeps it, and the `GpuScene` it names) whose triangles from
/// `base` on are the geometry's, in order, and the context a `QueryContext` whose rays
/// outlive the query.
pub(super) unsafe extern "C" fn any_hit_filter(args: *const RtcFilterArgs) {
    // SAFETY: see the function's contract.
    let a = unsafe { &*args };
    // SAFETY: the user pointer is the `FilterGeometry` the `HostScene` holds.
    let g = unsafe { &*a.geometry_user_ptr.cast::<FilterGeometry>() };
    // SAFETY: as above: it names the `GpuScene` the `HostScene` holds.
    let scene = unsafe { &*g.scene };
    // SAFETY: every query passes a `QueryContext` (its first field is Embree's context).
    let ctx = unsafe { &*a.context.cast::<QueryContext>() };
    let n = a.n as usize;
    for i in 0..n {
        // SAFETY: `valid`, `ray` and `hit` hold `n` entries per field; `ctx.rays` holds
        // `ctx.len` rays.
        unsafe {
            if *a.valid.add(i) == 0 {
                continue;
            }
            let id = *a.ray.cast::<u32>().add(10 * n + i) as usize;
            let r = if id < ctx.len {
                let given = &*ctx.rays.add(id);
                lumagraph_scene::traverse::Ray {
                    origin: glam::Vec3::from_array(given.origin),
                    dir: glam::Vec3::from_array(given.dir),
                }
            } else {
                let ray = |k: usize| *a.ray.add(k * n + i);
                lumagraph_scene::traverse::Ray {
                    origin: glam::Vec3::new(ray(0), ray(1), ray(2)),
                    dir: glam::Vec3::new(ray(4), ray(5), ray(6)),
                }
            };
            let hit = |k: usize| *a.hit.add(k * n + i);
            let prim = g.base + *a.hit.cast::<u32>().add(5 * n + i);
            if !lumagraph_scene::traverse::triangle_hit_counts(scene, prim, hit(3), hit(4), &r) {
                *a.valid.add(i) = 0;
            }
        }
    }
}

/// `RTC_INVALID_GEOMETRY_ID`.
pub(super) const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;
/// `RTCFormat`: `RTC_FORMAT_UINT3` (`RTC_FORMAT_UINT = 0x5001`, then 2, 3).
pub(super) const RTC_FORMAT_UINT3: u32 = 0x5003;
/// `RTCFormat`: `RTC_FORMAT_FLOAT3` (`RTC_FORMAT_FLOAT = 0x9001`, then 2, 3).
pub(super) const RTC_FORMAT_FLOAT3: u32 = 0x9003;
/// `RTCBufferType`.
pub(super) const RTC_BUFFER_TYPE_INDEX: u32 = 0;
pub(super) const RTC_BUFFER_TYPE_VERTEX: u32 = 1;
/// `RTCGeometryType`.
pub(super) const RTC_GEOMETRY_TYPE_TRIANGLE: u32 = 0;
pub(super) const RTC_GEOMETRY_TYPE_INSTANCE: u32 = 121;
/// `RTCFormat`: `RTC_FORMAT_FLOAT3X4_ROW_MAJOR` (a 3×4 matrix, row after row).
pub(super) const RTC_FORMAT_FLOAT3X4_ROW_MAJOR: u32 = 0x9134;
/// `RTCBuildQuality` (`RTC_BUILD_QUALITY_LOW` is 0).
pub(super) const RTC_BUILD_QUALITY_MEDIUM: u32 = 1;
pub(super) const RTC_BUILD_QUALITY_HIGH: u32 = 2;
/// `RTCSceneFlags`.
pub(super) const RTC_SCENE_FLAG_NONE: u32 = 0;
pub(super) const RTC_SCENE_FLAG_COMPACT: u32 = 1 << 1;
pub(super) const RTC_SCENE_FLAG_ROBUST: u32 = 1 << 2;
/// `RTCIntersectContextFlags`.
pub(super) const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: u32 = 0;
pub(super) const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: u32 = 1;
/// `RTCDeviceProperty`.
pub(super) const RTC_DEVICE_PROPERTY_VERSION_MAJOR: u32 = 1;
pub(super) const RTC_DEVICE_PROPERTY_VERSION_MINOR: u32 = 2;
pub(super) const RTC_DEVICE_PROPERTY_VERSION_PATCH: u32 = 3;
pub(super) const RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED: u32 = 65;
pub(super) const RTC_DEVICE_PROPERTY_TRIANGLE_GEOMETRY_SUPPORTED: u32 = 96;

/// `RTCError` names, by code.
pub(super) fn error_name(code: u32) -> &'static str {
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
pub(super) struct RtcRay {
    pub(super) org: [f32; 3],
    pub(super) tnear: f32,
    pub(super) dir: [f32; 3],
    pub(super) time: f32,
    pub(super) tfar: f32,
    pub(super) mask: u32,
    pub(super) id: u32,
    pub(super) flags: u32,
}

/// `struct RTCHit` (`RTC_ALIGN(16)`; `RTC_MAX_INSTANCE_LEVEL_COUNT` is 1).
#[repr(C, align(16))]
#[derive(Clone, Copy)]
pub(super) struct RtcHit {
    pub(super) ng: [f32; 3],
    pub(super) u: f32,
    pub(super) v: f32,
    pub(super) prim_id: u32,
    pub(super) geom_id: u32,
    pub(super) inst_id: [u32; 1],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy)]
pub(super) struct RtcRayHit {
    pub(super) ray: RtcRay,
    pub(super) hit: RtcHit,
}

/// `struct RTCRayHit4/8/16`: `RTCRayN` then `RTCHitN`, each field an array of `N` (SOA).
/// The sizes of the ray halves (48·N bytes) are multiples of the alignments (16, 32, 64
/// for N = 4, 8, 16), so one flat struct has the headers' offsets; 64-byte alignment
/// serves all three. `rtcOccludedN` reads the leading `RTCRayN` of the same memory.
#[repr(C, align(64))]
#[derive(Clone, Copy)]
pub(super) struct RtcRayHitN<const N: usize> {
    pub(super) org_x: [f32; N],
    pub(super) org_y: [f32; N],
    pub(super) org_z: [f32; N],
    pub(super) tnear: [f32; N],
    pub(super) dir_x: [f32; N],
    pub(super) dir_y: [f32; N],
    pub(super) dir_z: [f32; N],
    pub(super) time: [f32; N],
    pub(super) tfar: [f32; N],
    pub(super) mask: [u32; N],
    pub(super) id: [u32; N],
    pub(super) flags: [u32; N],
    pub(super) ng_x: [f32; N],
    pub(super) ng_y: [f32; N],
    pub(super) ng_z: [f32; N],
    pub(super) u: [f32; N],
    pub(super) v: [f32; N],
    pub(super) prim_id: [u32; N],
    pub(super) geom_id: [u32; N],
    pub(super) inst_id: [u32; N],
}

/// The `valid` mask of `rtcIntersectN`/`rtcOccludedN`: -1 active, 0 not; Embree loads it
/// as one SIMD vector, so it is aligned as the packet is.
#[repr(C, align(64))]
pub(super) struct ValidN<const N: usize>(pub(super) [i32; N]);

/// `struct RTCIntersectContext` with `RTC_MAX_INSTANCE_LEVEL_COUNT` 1 and `RTC_MIN_WIDTH`
/// 0: `flags`, `filter`, `instID[1]`.
#[repr(C)]
pub(super) struct RtcIntersectContext {
    pub(super) flags: u32,
    pub(super) filter: Option<unsafe extern "C" fn(args: *const c_void)>,
    pub(super) inst_id: [u32; 1],
}

impl RtcIntersectContext {
    /// What the inline `rtcInitIntersectContext` sets, with `flags` as given.
    pub(super) fn new(coherent: bool) -> Self {
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
pub(super) struct Api {
    pub(super) new_device: unsafe extern "C" fn(config: *const c_char) -> RtcDevice,
    pub(super) release_device: unsafe extern "C" fn(device: RtcDevice),
    pub(super) get_device_property: unsafe extern "C" fn(device: RtcDevice, prop: u32) -> isize,
    pub(super) get_device_error: unsafe extern "C" fn(device: RtcDevice) -> u32,
    pub(super) set_device_error_function:
        unsafe extern "C" fn(device: RtcDevice, f: Option<RtcErrorFunction>, user: *mut c_void),
    pub(super) new_scene: unsafe extern "C" fn(device: RtcDevice) -> RtcScene,
    pub(super) release_scene: unsafe extern "C" fn(scene: RtcScene),
    pub(super) set_scene_build_quality: unsafe extern "C" fn(scene: RtcScene, quality: u32),
    pub(super) set_scene_flags: unsafe extern "C" fn(scene: RtcScene, flags: u32),
    pub(super) attach_geometry: unsafe extern "C" fn(scene: RtcScene, geometry: RtcGeometry) -> u32,
    pub(super) attach_geometry_by_id:
        unsafe extern "C" fn(scene: RtcScene, geometry: RtcGeometry, id: u32),
    pub(super) set_geometry_instanced_scene:
        unsafe extern "C" fn(geometry: RtcGeometry, scene: RtcScene),
    pub(super) set_geometry_transform: unsafe extern "C" fn(
        geometry: RtcGeometry,
        time_step: u32,
        format: u32,
        xfm: *const c_void,
    ),
    pub(super) commit_scene: unsafe extern "C" fn(scene: RtcScene),
    pub(super) new_geometry: unsafe extern "C" fn(device: RtcDevice, kind: u32) -> RtcGeometry,
    pub(super) release_geometry: unsafe extern "C" fn(geometry: RtcGeometry),
    pub(super) commit_geometry: unsafe extern "C" fn(geometry: RtcGeometry),
    pub(super) set_geometry_build_quality:
        unsafe extern "C" fn(geometry: RtcGeometry, quality: u32),
    pub(super) set_geometry_user_data:
        unsafe extern "C" fn(geometry: RtcGeometry, user: *mut c_void),
    pub(super) set_geometry_intersect_filter:
        unsafe extern "C" fn(geometry: RtcGeometry, f: Option<RtcFilterFunction>),
    pub(super) set_geometry_occluded_filter:
        unsafe extern "C" fn(geometry: RtcGeometry, f: Option<RtcFilterFunction>),
    pub(super) set_new_geometry_buffer: unsafe extern "C" fn(
        geometry: RtcGeometry,
        kind: u32,
        slot: u32,
        format: u32,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void,
    pub(super) intersect1:
        unsafe extern "C" fn(scene: RtcScene, ctx: *mut RtcIntersectContext, rh: *mut RtcRayHit),
    pub(super) occluded1:
        unsafe extern "C" fn(scene: RtcScene, ctx: *mut RtcIntersectContext, r: *mut RtcRay),
    pub(super) intersect1m: unsafe extern "C" fn(
        scene: RtcScene,
        ctx: *mut RtcIntersectContext,
        rh: *mut RtcRayHit,
        m: u32,
        byte_stride: usize,
    ),
    pub(super) occluded1m: unsafe extern "C" fn(
        scene: RtcScene,
        ctx: *mut RtcIntersectContext,
        r: *mut RtcRayHit,
        m: u32,
        byte_stride: usize,
    ),
    pub(super) intersect8: PacketFn<8>,
    pub(super) occluded8: PacketFn<8>,
    pub(super) intersect16: PacketFn<16>,
    pub(super) occluded16: PacketFn<16>,
}

/// `rtcIntersect8/16` and `rtcOccluded8/16` (the ray-only functions read the leading ray
/// half of the same packet).
pub(super) type PacketFn<const N: usize> = unsafe extern "C" fn(
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
    pub(super) unsafe fn resolve(lib: &libloading::Library) -> Result<Self, String> {
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
            attach_geometry_by_id: sym!("rtcAttachGeometryByID"),
            set_geometry_instanced_scene: sym!("rtcSetGeometryInstancedScene"),
            set_geometry_transform: sym!("rtcSetGeometryTransform"),
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
pub(super) unsafe fn symbol<T: Copy>(lib: &libloading::Library, name: &str) -> Result<T, String> {
    let mut bytes = name.as_bytes().to_vec();
    bytes.push(0);
    // SAFETY: forwarded to the caller.
    let symbol = unsafe { lib.get::<T>(&bytes) }.map_err(|e| format!("symbol {name}: {e}"))?;
    Ok(*symbol)
}

/// Messages Embree's error callback reported, oldest first (at most a few kept).
pub(super) type ErrorLog = Mutex<Vec<String>>;

/// Embree's error callback: keeps the message for [`Embree::check`]. Never unwinds.
pub(super) unsafe extern "C" fn record_error(user: *mut c_void, code: u32, message: *const c_char) {
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
