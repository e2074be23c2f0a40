//! The environment variables that change what lumagraph does, read in one place: the
//! command line, the editor (which it runs) and the Python module call [`apply`] once at
//! start-up, and pass what they find to the libraries, which read no such variable but
//! `LUMAGRAPH_ALLOW_NO_GPU` (a GPU test without an adapter is skipped instead of failing) and
//! `LUMAGRAPH_OIDN_LIB` (where the OIDN node's library is). docs/environment.md lists them all.
//!
//! | variable | what it does |
//! |---|---|
//! | `LUMAGRAPH_EMBREE=off` | never load Embree (the host intersector): `auto` traces on the GPU |
//! | `LUMAGRAPH_EMBREE=PATH` | the Embree 3 library to try first |
//! | `LUMAGRAPH_RAY_QUERY=off` | open devices without ray queries (the WGSL BVHs trace) |
//! | `LUMAGRAPH_DECODE_THREADS=N` | decode a glTF file's images on N threads (default: the machine's, at most 16) |
//!
//! The command line also takes `LUMAGRAPH_BVH`, `LUMAGRAPH_RAY_QUERY=on` and
//! `LUMAGRAPH_WAVEFRONT` as defaults for `--intersector` and `--schedule` (`cli::choice`).

use std::sync::Once;

/// Reads the variables above and passes them on; later calls do nothing. A value that
/// cannot be read (`LUMAGRAPH_DECODE_THREADS=many`) is named on stderr and ignored.
pub fn apply() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for warning in apply_from(|name| std::env::var(name).ok()) {
            eprintln!("warning: {warning}");
        }
    });
}

/// [`apply`] with the variables `var` gives; returns what it could not read.
fn apply_from(var: impl Fn(&str) -> Option<String>) -> Vec<String> {
    let mut warnings = Vec::new();
    if let Some(v) = var("LUMAGRAPH_EMBREE").map(|v| v.trim().to_owned()) {
        let library = match v.as_str() {
            "" => lumagraph_pathtrace::embree::Library::System,
            off if off.eq_ignore_ascii_case("off") => lumagraph_pathtrace::embree::Library::Off,
            path => lumagraph_pathtrace::embree::Library::Path(path.to_owned()),
        };
        // Already configured: by the program embedding lumagraph, which wins.
        let _ = lumagraph_pathtrace::embree::configure(library);
    }
    if var("LUMAGRAPH_RAY_QUERY").is_some_and(|v| v == "off" || v == "0") {
        lumagraph_render::turn_off_ray_queries();
    }
    if let Some(v) = var("LUMAGRAPH_DECODE_THREADS") {
        match v.trim().parse::<usize>() {
            Ok(n) => lumagraph_scene::import::gltf::set_decode_threads(n),
            Err(_) => warnings.push(format!(
                "LUMAGRAPH_DECODE_THREADS={v} is not a number of threads; ignored"
            )),
        }
    }
    warnings
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unreadable_value_is_named_and_ignored() {
        let w = apply_from(|n| (n == "LUMAGRAPH_DECODE_THREADS").then(|| "many".to_owned()));
        assert_eq!(
            w,
            ["LUMAGRAPH_DECODE_THREADS=many is not a number of threads; ignored"]
        );
        assert!(apply_from(|_| None).is_empty());
    }
}
