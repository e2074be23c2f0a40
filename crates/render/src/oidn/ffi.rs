//! OIDN 2's C API as lumagraph calls it (`OpenImageDenoise/oidn.h`): the entry points are
//! looked up in the library at run time; every `unsafe` block of the OIDN support is here.
#![allow(
    unsafe_code,
    reason = "the C API of a library loaded at run time; every call into it is in this file"
)]

use std::ffi::{CStr, c_char, c_int, c_void};
use std::path::Path;
use std::ptr::NonNull;
use std::sync::Arc;

use super::{Images, Settings};

/// `OIDN_DEVICE_TYPE_CPU`.
const DEVICE_TYPE_CPU: c_int = 1;
/// `OIDN_FORMAT_FLOAT3`.
const FORMAT_FLOAT3: c_int = 3;
/// Bytes from one pixel to the next: RGBA `f32`.
const PIXEL_BYTES: usize = 16;

/// The entry points used, resolved once from the library.
struct Api {
    new_device: unsafe extern "C" fn(kind: c_int) -> *mut c_void,
    commit_device: unsafe extern "C" fn(device: *mut c_void),
    release_device: unsafe extern "C" fn(device: *mut c_void),
    get_device_int: unsafe extern "C" fn(device: *mut c_void, name: *const c_char) -> c_int,
    get_device_error:
        unsafe extern "C" fn(device: *mut c_void, message: *mut *const c_char) -> c_int,
    new_filter: unsafe extern "C" fn(device: *mut c_void, kind: *const c_char) -> *mut c_void,
    set_shared_image: unsafe extern "C" fn(
        filter: *mut c_void,
        name: *const c_char,
        data: *mut c_void,
        format: c_int,
        width: usize,
        height: usize,
        byte_offset: usize,
        pixel_byte_stride: usize,
        row_byte_stride: usize,
    ),
    unset_image: unsafe extern "C" fn(filter: *mut c_void, name: *const c_char),
    set_bool: unsafe extern "C" fn(filter: *mut c_void, name: *const c_char, value: bool),
    set_int: unsafe extern "C" fn(filter: *mut c_void, name: *const c_char, value: c_int),
    commit_filter: unsafe extern "C" fn(filter: *mut c_void),
    execute_filter: unsafe extern "C" fn(filter: *mut c_void),
    release_filter: unsafe extern "C" fn(filter: *mut c_void),
}

/// The function `name` of `lib`, copied out of its `Symbol`.
///
/// # Safety
/// `T` must be the function's type, and `lib` must stay loaded while it is used.
unsafe fn symbol<T: Copy>(lib: &libloading::Library, name: &CStr) -> Result<T, String> {
    // SAFETY: forwarded to the caller.
    let symbol = unsafe { lib.get::<T>(name.to_bytes_with_nul()) }
        .map_err(|e| format!("no symbol {}: {e}", name.to_string_lossy()))?;
    Ok(*symbol)
}

impl Api {
    /// Resolves every entry point, or names the first one missing.
    ///
    /// # Safety
    /// `lib` must be OIDN 2, so that each symbol has the signature declared in [`Api`].
    unsafe fn resolve(lib: &libloading::Library) -> Result<Self, String> {
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the caller guarantees `lib` is OIDN 2, whose `$name` has the
                // signature of the field it is stored in (copied from `oidn.h`).
                unsafe { symbol(lib, $name) }?
            };
        }
        Ok(Self {
            new_device: sym!(c"oidnNewDevice"),
            commit_device: sym!(c"oidnCommitDevice"),
            release_device: sym!(c"oidnReleaseDevice"),
            get_device_int: sym!(c"oidnGetDeviceInt"),
            get_device_error: sym!(c"oidnGetDeviceError"),
            new_filter: sym!(c"oidnNewFilter"),
            set_shared_image: sym!(c"oidnSetSharedFilterImage"),
            unset_image: sym!(c"oidnUnsetFilterImage"),
            set_bool: sym!(c"oidnSetFilterBool"),
            set_int: sym!(c"oidnSetFilterInt"),
            commit_filter: sym!(c"oidnCommitFilter"),
            execute_filter: sym!(c"oidnExecuteFilter"),
            release_filter: sym!(c"oidnReleaseFilter"),
        })
    }
}

/// The loaded library and its CPU device: see the module documentation.
pub struct Oidn {
    api: Api,
    device: NonNull<c_void>,
    library: String,
    version: c_int,
    /// Declared last: dropped after the device is released.
    _lib: libloading::Library,
}

// SAFETY: OIDN's API is thread safe; calls on one device are serialized by the library.
// The other fields are plain data and the library handle.
unsafe impl Send for Oidn {}
// SAFETY: as above.
unsafe impl Sync for Oidn {}

impl std::fmt::Debug for Oidn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Oidn")
            .field("library", &self.library)
            .field("version", &self.version())
            .finish_non_exhaustive()
    }
}

impl Drop for Oidn {
    fn drop(&mut self) {
        // SAFETY: the device was made by `oidnNewDevice` and is released once; every filter
        // holds an `Arc<Oidn>`, so none is left.
        unsafe { (self.api.release_device)(self.device.as_ptr()) };
    }
}

impl Oidn {
    /// Opens one library and makes its CPU device.
    pub(super) fn open(name: &str) -> Result<Oidn, String> {
        if name.contains('/') && !Path::new(name).exists() {
            return Err("no such file".to_owned());
        }
        // SAFETY: loading a shared library runs its initializers; OIDN's only set up its own
        // state. The name comes from our list or the user's `LUMAGRAPH_OIDN_LIB`.
        let lib = unsafe { libloading::Library::new(name) }.map_err(|e| e.to_string())?;
        // SAFETY: a library named as OIDN that exports these symbols is taken to be OIDN 2;
        // its version is checked below before any filter is made.
        let api = unsafe { Api::resolve(&lib) }?;
        // SAFETY: `oidnNewDevice` takes a device type and returns null on failure.
        let device = unsafe { (api.new_device)(DEVICE_TYPE_CPU) };
        let Some(device) = NonNull::new(device) else {
            let mut message: *const c_char = std::ptr::null();
            // SAFETY: a null device asks for this thread's error of the failed call.
            let code = unsafe { (api.get_device_error)(std::ptr::null_mut(), &raw mut message) };
            // SAFETY: the message, when not null, is a C string valid until the next call.
            let text = unsafe { message_text(message) };
            return Err(format!("no CPU device ({}: {text})", error_name(code)));
        };
        // SAFETY: `device` is live; committing has no other precondition.
        unsafe { (api.commit_device)(device.as_ptr()) };
        // SAFETY: `device` is live; `c"version"` is a C string.
        let version = unsafe { (api.get_device_int)(device.as_ptr(), c"version".as_ptr()) };
        let oidn = Oidn {
            api,
            device,
            library: name.to_owned(),
            version,
            _lib: lib,
        };
        oidn.check("oidnCommitDevice")?;
        if version < 20000 {
            return Err(format!("version {} is not 2.x", oidn.version()));
        }
        Ok(oidn)
    }

    /// The library's version, e.g. "2.5.1".
    pub fn version(&self) -> String {
        let v = self.version;
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// The library name or path that was loaded.
    pub fn library(&self) -> &str {
        &self.library
    }

    /// The device's pending error as an error naming `what`.
    fn check(&self, what: &str) -> Result<(), String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: the device is live for as long as `self`.
        let code = unsafe { (self.api.get_device_error)(self.device.as_ptr(), &raw mut message) };
        if code == 0 {
            return Ok(());
        }
        // SAFETY: the message, when not null, is a C string valid until the next call.
        let text = unsafe { message_text(message) };
        Err(format!("OIDN: {what} failed: {}: {text}", error_name(code)))
    }
}

/// A message OIDN returned, copied.
///
/// # Safety
/// `message` is null or a NUL-terminated string valid for this call.
unsafe fn message_text(message: *const c_char) -> String {
    if message.is_null() {
        return "no message".to_owned();
    }
    // SAFETY: see the function's contract.
    unsafe { CStr::from_ptr(message) }
        .to_string_lossy()
        .into_owned()
}

/// `OIDNError` names, by code.
fn error_name(code: c_int) -> &'static str {
    match code {
        0 => "OIDN_ERROR_NONE",
        1 => "OIDN_ERROR_UNKNOWN",
        2 => "OIDN_ERROR_INVALID_ARGUMENT",
        3 => "OIDN_ERROR_INVALID_OPERATION",
        4 => "OIDN_ERROR_OUT_OF_MEMORY",
        5 => "OIDN_ERROR_UNSUPPORTED_HARDWARE",
        6 => "OIDN_ERROR_CANCELLED",
        _ => "unknown OIDNError",
    }
}

/// One `RT` filter on the process's device.
pub struct Filter {
    oidn: Arc<Oidn>,
    raw: NonNull<c_void>,
}

impl std::fmt::Debug for Filter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Filter").finish_non_exhaustive()
    }
}

impl Drop for Filter {
    fn drop(&mut self) {
        // SAFETY: the filter was made by `oidnNewFilter` and is released once, before its
        // device (this filter holds the device's `Arc`).
        unsafe { (self.oidn.api.release_filter)(self.raw.as_ptr()) };
    }
}

impl Filter {
    /// A new `RT` filter (the one for path-traced images).
    ///
    /// # Errors
    /// When OIDN refuses to make it.
    pub fn new(oidn: &Arc<Oidn>) -> Result<Self, String> {
        // SAFETY: the device is live; `c"RT"` is a C string.
        let raw = unsafe { (oidn.api.new_filter)(oidn.device.as_ptr(), c"RT".as_ptr()) };
        oidn.check("oidnNewFilter(\"RT\")")?;
        let raw = NonNull::new(raw).ok_or("OIDN: oidnNewFilter(\"RT\") returned null")?;
        Ok(Self {
            oidn: Arc::clone(oidn),
            raw,
        })
    }

    /// Filters `images` into `output` (its alpha is left as it is) with `settings`.
    ///
    /// # Errors
    /// When an image is not `width × height` pixels, or OIDN fails (the error names the
    /// call and OIDN's message).
    pub fn run(
        &mut self,
        images: &Images<'_>,
        output: &mut [[f32; 4]],
        settings: Settings,
    ) -> Result<(), String> {
        let (width, height) = (images.width, images.height);
        let pixels = width * height;
        let inputs = [
            (c"color", images.color),
            (c"albedo", images.albedo),
            (c"normal", images.normal),
        ];
        if pixels == 0
            || output.len() != pixels
            || inputs
                .iter()
                .any(|(_, i)| i.is_some_and(|i| i.len() != pixels))
        {
            return Err(format!("OIDN: images are not all {width}×{height} pixels"));
        }
        let api = &self.oidn.api;
        let filter = self.raw.as_ptr();
        let bind = |name: &CStr, data: *mut c_void| {
            // SAFETY: the filter is live; `data` holds `width × height` pixels of 16 bytes
            // (checked above), bound only until the images are unset below.
            unsafe {
                (api.set_shared_image)(
                    filter,
                    name.as_ptr(),
                    data,
                    FORMAT_FLOAT3,
                    width,
                    height,
                    0,
                    PIXEL_BYTES,
                    width * PIXEL_BYTES,
                );
            }
        };
        for (name, image) in inputs {
            match image {
                // OIDN only reads input images: the pointer is made mutable for the C type.
                Some(image) => bind(name, image.as_ptr().cast_mut().cast()),
                // SAFETY: the filter is live; unsetting an unset image is allowed.
                None => unsafe { (api.unset_image)(filter, name.as_ptr()) },
            }
        }
        bind(c"output", output.as_mut_ptr().cast());
        // SAFETY: the filter is live; the names are C strings of the filter's params.
        unsafe {
            (api.set_bool)(filter, c"hdr".as_ptr(), settings.hdr);
            (api.set_bool)(filter, c"cleanAux".as_ptr(), settings.clean_aux);
            (api.set_int)(filter, c"quality".as_ptr(), settings.quality.code());
            (api.commit_filter)(filter);
        }
        let result = self.oidn.check("oidnCommitFilter").and_then(|()| {
            // SAFETY: the filter is committed with its images bound to live memory.
            unsafe { (api.execute_filter)(filter) };
            self.oidn.check("oidnExecuteFilter")
        });
        for name in [c"color", c"albedo", c"normal", c"output"] {
            // SAFETY: the filter is live; no pointer to the caller's memory stays bound.
            unsafe { (api.unset_image)(filter, name.as_ptr()) };
        }
        result
    }
}
