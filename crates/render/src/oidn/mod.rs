//! Intel Open Image Denoise 2 (OIDN), loaded at run time, for the `OIDN` node.
//!
//! Nothing links against OIDN: the library is opened with `libloading` on first use, so a
//! machine without it builds and runs, and only a graph with an `OIDN` node fails, with one
//! error saying what is missing and how to get it ([`Oidn::load`]).
//!
//! Where the library is looked for: the path in `LUMAGRAPH_OIDN_LIB` alone when it is set
//! (an explicit choice that fails is an error, not a fall-back); else
//! `~/.cache/lumagraph/oidn/lib/libOpenImageDenoise.so.2` (`$XDG_CACHE_HOME` when set), where
//! `scripts/setup.sh` unpacks the `pyoidn` wheel's copy; else the system's library path
//! (`libOpenImageDenoise.so.2`, `libOpenImageDenoise.so`). The environment is read once per
//! process.
//!
//! One CPU device per process (`oidnNewDevice(OIDN_DEVICE_TYPE_CPU)`), shared by every
//! [`Filter`]; OIDN serializes the calls on one device. Images are the caller's host memory
//! (`oidnSetSharedFilterImage`: `FLOAT3` over RGBA pixels, 16 bytes apart), bound only for
//! the duration of one [`Filter::run`], so no pointer outlives its borrow.
//!
//! The files: `mod.rs` finds the library and declares what a filtering takes; `ffi.rs`, the
//! one file with `unsafe` code, holds every call into OIDN's C API (`OpenImageDenoise/oidn.h`,
//! 2.x, as the `pyoidn` wheel declares it): the library and its device ([`Oidn`]) and the
//! filter ([`Filter`]).

use std::ffi::c_int;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

mod ffi;

pub use ffi::{Filter, Oidn};

/// The environment variable naming the library file.
pub const LIB_ENV: &str = "LUMAGRAPH_OIDN_LIB";

/// What the error of a missing library tells the user to do.
const HOW_TO_GET_IT: &str = "run `bash scripts/setup.sh` (it fetches the library from the \
    pyoidn wheel into ~/.cache/lumagraph/oidn/), or set LUMAGRAPH_OIDN_LIB to the path of a \
    libOpenImageDenoise.so (2.x)";

/// The system library names tried after the cache folder.
const SYSTEM_NAMES: [&str; 2] = ["libOpenImageDenoise.so.2", "libOpenImageDenoise.so"];

/// OIDN's quality presets (`OIDNQuality`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    /// `OIDN_QUALITY_DEFAULT`: the library's choice (high on the CPU).
    Default,
    /// `OIDN_QUALITY_HIGH`: for final frames.
    High,
    /// `OIDN_QUALITY_BALANCED`: for interactive rendering.
    Balanced,
    /// `OIDN_QUALITY_FAST`: for previews.
    Fast,
}

impl Quality {
    /// The preset of a name as OIDN writes it (`default`, `high`, `balanced`, `fast`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "default" => Some(Self::Default),
            "high" => Some(Self::High),
            "balanced" => Some(Self::Balanced),
            "fast" => Some(Self::Fast),
            _ => None,
        }
    }

    /// The `OIDNQuality` value.
    fn code(self) -> c_int {
        match self {
            Self::Default => 0,
            Self::Fast => 4,
            Self::Balanced => 5,
            Self::High => 6,
        }
    }
}

/// Where `scripts/setup.sh` unpacks the library: `lumagraph/oidn` in the user's cache
/// folder (`$XDG_CACHE_HOME`, else `~/.cache`).
pub fn cache_dir() -> Option<PathBuf> {
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))?;
    Some(cache.join("lumagraph").join("oidn"))
}

impl Oidn {
    /// The process's OIDN, loaded on first call from where the module documentation says;
    /// the error (the same on every call) names what was tried and how to get the library.
    ///
    /// # Errors
    /// When no library loads or its CPU device cannot be made.
    pub fn load() -> Result<Arc<Oidn>, String> {
        static OIDN: OnceLock<Result<Arc<Oidn>, String>> = OnceLock::new();
        OIDN.get_or_init(|| {
            let chosen = std::env::var(LIB_ENV).ok();
            Self::load_from(chosen.as_deref(), cache_dir().as_deref()).map(Arc::new)
        })
        .clone()
    }

    /// Loads OIDN as [`Oidn::load`] does, with `chosen` in place of `LUMAGRAPH_OIDN_LIB` and
    /// `cache` in place of the cache folder, without keeping it for the process.
    ///
    /// # Errors
    /// As [`Oidn::load`].
    pub fn load_from(chosen: Option<&str>, cache: Option<&Path>) -> Result<Oidn, String> {
        let chosen = chosen.map(str::trim).filter(|s| !s.is_empty());
        let tried = if let Some(path) = chosen {
            match Self::open(path) {
                Ok(oidn) => return Ok(oidn),
                Err(e) => format!("{LIB_ENV}={path}: {e}"),
            }
        } else {
            let mut failures = Vec::new();
            let cached = cache.map(|d| d.join("lib").join(SYSTEM_NAMES[0]));
            let names = cached.iter().map(|p| p.to_string_lossy().into_owned());
            for name in names.chain(SYSTEM_NAMES.map(str::to_owned)) {
                match Self::open(&name) {
                    Ok(oidn) => return Ok(oidn),
                    // The loader's message repeats the name and says the file was not found.
                    Err(e) if e.contains("cannot open shared object file") => {
                        failures.push(format!("{name} (not on the system's library path)"));
                    }
                    Err(e) => failures.push(format!("{name} ({e})")),
                }
            }
            format!("tried {}", failures.join(", "))
        };
        Err(format!(
            "Intel Open Image Denoise 2 is not available ({tried}): {HOW_TO_GET_IT}"
        ))
    }
}

/// The images of one [`Filter::run`]: rows of `width` RGBA pixels (alpha is not read),
/// each image `width × height` pixels.
#[derive(Clone, Copy, Debug)]
pub struct Images<'a> {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The noisy color (`color`); absent when a guide is filtered on its own.
    pub color: Option<&'a [[f32; 4]]>,
    /// The albedo guide (`albedo`).
    pub albedo: Option<&'a [[f32; 4]]>,
    /// The normal guide (`normal`); OIDN takes it only with an albedo.
    pub normal: Option<&'a [[f32; 4]]>,
}

/// The filter's settings of one [`Filter::run`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    /// The color is HDR (`hdr`).
    pub hdr: bool,
    /// The guides are noise-free (`cleanAux`).
    pub clean_aux: bool,
    /// The quality preset (`quality`).
    pub quality: Quality,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A missing library is one error that names the file and both ways to get it.
    #[test]
    fn a_missing_library_says_how_to_get_it() {
        let e = Oidn::load_from(Some("/nonexistent/libOpenImageDenoise.so.2"), None).unwrap_err();
        for want in [
            "Open Image Denoise",
            "LUMAGRAPH_OIDN_LIB=/nonexistent/libOpenImageDenoise.so.2: no such file",
            "bash scripts/setup.sh",
            "set LUMAGRAPH_OIDN_LIB",
        ] {
            assert!(e.contains(want), "«{want}» not in: {e}");
        }
    }

    #[test]
    fn every_quality_name_is_known() {
        for (name, code) in [("default", 0), ("fast", 4), ("balanced", 5), ("high", 6)] {
            assert_eq!(Quality::from_name(name).map(Quality::code), Some(code));
        }
        assert_eq!(Quality::from_name("best"), None);
    }
}
