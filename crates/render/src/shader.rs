//! WGSL sources and the `#import` resolver.
//!
//! Shaders live in `shaders/` by topic; a line `#import "common/color.wgsl"` is replaced by
//! that file's text (each file at most once, recursively; `lumagraph-wgsl`), so shared code
//! is written once.
//! Release builds use copies embedded at build time; debug builds read the folder on disk
//! when it is there, so an edited shader is picked up by the next pipeline created. The
//! same resolver is used by the naga validation test, so every shader the program can
//! load is checked without a GPU.

use std::path::PathBuf;

use crate::error::{RenderError, Result};

mod embedded {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

/// Names of every shader file, relative to `shaders/`.
pub fn all_names() -> impl Iterator<Item = &'static str> {
    embedded::EMBEDDED.iter().map(|(name, _)| *name)
}

fn disk_dir() -> Option<PathBuf> {
    if cfg!(debug_assertions) {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
        dir.is_dir().then_some(dir)
    } else {
        None
    }
}

/// The raw text of one shader file (or of a generated one: [`crate::shared::FILE`];
/// [`lumagraph_scene::shapes::FILE`], which calls each kind of shape;
/// [`lumagraph_scene::lights::FILE`], each kind of light without area; and
/// [`lumagraph_scene::lobes::FILE`], the `Material` struct).
///
/// # Errors
/// When there is no such file.
pub fn raw(name: &str) -> Result<String> {
    if name == crate::shared::FILE {
        return Ok(crate::shared::wgsl());
    }
    if name == lumagraph_scene::shapes::FILE {
        return Ok(lumagraph_scene::shapes::wgsl());
    }
    if name == lumagraph_scene::lights::FILE {
        return Ok(lumagraph_scene::lights::wgsl());
    }
    if name == lumagraph_scene::lobes::FILE {
        return Ok(lumagraph_scene::lobes::wgsl());
    }
    // Only names inside the folder: an `#import` of a kind declared in a graph file names
    // a shader, never another file on disk.
    let inside = std::path::Path::new(name)
        .components()
        .all(|c| matches!(c, std::path::Component::Normal(_)));
    if inside
        && let Some(dir) = disk_dir()
        && let Ok(text) = std::fs::read_to_string(dir.join(name))
    {
        return Ok(text);
    }
    embedded::EMBEDDED
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| (*text).to_owned())
        .ok_or_else(|| RenderError::Shader {
            name: name.to_owned(),
            message: "no such shader file".to_owned(),
        })
}

/// A shader's text with its `#import` lines resolved.
///
/// # Errors
/// When the file or one it imports is missing, or an import line is malformed.
pub fn resolve(name: &str) -> Result<String> {
    resolve_with(name, &[])
}

/// The whole text of a generic filter's shader: a file's with its imports resolved, or the
/// module generated for a kind declared in a graph file.
///
/// # Errors
/// As [`resolve`].
pub fn source_of(shader: &lumagraph_graph::registry::Shader) -> Result<String> {
    match shader {
        lumagraph_graph::registry::Shader::File(name) => resolve(name),
        lumagraph_graph::registry::Shader::Generated(g) => Ok(g.text.clone()),
    }
}

/// Like [`resolve`], with some files replaced by generated text (`(name, text)` pairs):
/// how shaders are specialized to a scene.
///
/// # Errors
/// When a file or one it imports is missing, or an import line is malformed.
pub fn resolve_with(name: &str, overrides: &[(&str, String)]) -> Result<String> {
    lumagraph_wgsl::resolve(name, overrides, &|n: &str| raw(n).ok()).map_err(shader_error)
}

/// Every file `name` imports, directly or not, in inclusion order (itself included).
///
/// # Errors
/// As [`resolve`].
pub fn imports(name: &str) -> Result<Vec<String>> {
    lumagraph_wgsl::imports(name, &|n: &str| raw(n).ok()).map_err(shader_error)
}

fn shader_error(e: lumagraph_wgsl::ImportError) -> RenderError {
    RenderError::Shader {
        name: e.file,
        message: e.message,
    }
}

#[cfg(test)]
mod tests {
    /// A name that leaves `shaders/` is no shader, in debug builds (which read the folder
    /// on disk) as in release builds: a declared kind's `#import "../Cargo.toml"` reads
    /// nothing.
    #[test]
    fn only_files_inside_the_shader_folder_are_read() {
        assert!(super::raw("common/color.wgsl").is_ok());
        for name in [
            "../Cargo.toml",
            "../../Cargo.toml",
            "common/../../Cargo.toml",
        ] {
            assert!(super::raw(name).is_err(), "{name} was read");
        }
        let abs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
        assert!(super::raw(abs.to_str().unwrap()).is_err());
    }
}
