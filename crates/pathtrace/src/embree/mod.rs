//! Host (CPU) ray queries with Embree 3, loaded at run time.
//!
//! On CPU adapters (lavapipe) the WGSL BVH traversal is slow; the path tracer can hand its
//! rays to the host instead, where Embree traces them. Nothing links against Embree: the
//! library is opened with `libloading` on first use, so a machine without it builds and
//! runs, and the caller falls back to the WGSL traversal when [`Embree::load`] fails.
//!
//! - [`Embree`]: the loaded library and its device, one per process.
//! - [`HostScene`]: one triangle mesh, its primitive IDs the indices of the triangles as
//!   given (the path tracer's BVH order, [`lumagraph_scene::GpuScene::tri_corners`]); for a
//!   scene with instanced meshes, an Embree scene per mesh placed by instance geometries
//!   beside the scene's own triangles, its hits naming the triangle in the same order and
//!   the instance ([`HostScene::intersect_instances`]).
//! - [`HostRay`] and [`HostHit`]: 32 and 16 bytes, the layouts the WGSL writes and reads.
//!
//! Library names tried, in order: the path the application gave ([`configure`]) when it gave
//! one, then `libembree3.so.3`, `libembree3.so`, `libembree3.dylib`, `embree3.dll` (the
//! system's search path: `LD_LIBRARY_PATH` and the like). The application may also turn
//! Embree off; the command line, the editor and the Python module do so for
//! `LUMAGRAPH_EMBREE=off` and take `LUMAGRAPH_EMBREE=PATH` as the path (`lumagraph::overrides`).
//! The library itself reads no environment variable.
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
//! structures of `ffi.rs` copy their layouts, and their sizes are checked at compile time.
//!
//! The files: `mod.rs` loads the library and holds its device ([`Embree`]); `ffi.rs` the C
//! API (layouts, entry points, error callback, the any-hit filter); `records.rs` the ray and
//! hit records; `scene.rs` the mesh, its build and its tracers ([`HostScene`], [`Tuning`]).
#![allow(unsafe_code)]

use std::ffi::c_void;
use std::ptr::NonNull;
use std::sync::{Arc, OnceLock};

mod ffi;
mod records;
mod scene;

pub use records::{HostHit, HostRay};
pub(crate) use scene::flat_only;
pub use scene::{HostScene, Tuning};

use ffi::*;

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

/// Where the application tells the loader to look for Embree ([`configure`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Library {
    /// The system's names ([`LIBRARY_NAMES`]).
    #[default]
    System,
    /// This file first, then the system's names.
    Path(String),
    /// Never load Embree.
    Off,
}

static LIBRARY: OnceLock<Library> = OnceLock::new();

/// Tells the loader where to look for Embree, before anything loads it (once per process).
///
/// # Errors
/// When it was configured already, with what it was configured to.
pub fn configure(library: Library) -> Result<(), Library> {
    LIBRARY.set(library)
}

/// The library names tried, in order, after the path [`configure`] gave.
const LIBRARY_NAMES: [&str; 4] = [
    "libembree3.so.3",
    "libembree3.so",
    "libembree3.dylib",
    "embree3.dll",
];

impl Embree {
    /// The process's Embree, loaded on first call (see the module documentation for the
    /// names tried). The error says which names were tried and why each failed, or that
    /// the application turned it off; it is the same on every call.
    pub fn load() -> Result<Arc<Embree>, String> {
        static EMBREE: OnceLock<Result<Arc<Embree>, String>> = OnceLock::new();
        EMBREE
            .get_or_init(|| {
                let chosen = match LIBRARY.get_or_init(Library::default) {
                    Library::Off => {
                        return Err("Embree turned off (LUMAGRAPH_EMBREE=off)".to_owned());
                    }
                    Library::Path(p) => Some(p.as_str()),
                    Library::System => None,
                };
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
        // own state. The name comes from our list or the path the application gave.
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
