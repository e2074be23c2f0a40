//! Mesh import: glTF 2.0 ([`gltf`]), OBJ + MTL ([`obj`]) and PLY ([`ply`]).
//!
//! An importer returns world-space triangles (the file's node hierarchy and the caller's
//! transform applied) and the meshes it places several times (stored once, with a transform
//! per placement), its materials with indices local to the file, its cameras and its
//! lights.
//! Broken triangles (NaN or infinite corners, zero area) are dropped and counted in the
//! [`LoadReport`], never a panic.

pub mod gltf;
mod gltf_extensions;
pub mod obj;
pub mod ply;

use std::path::Path;

use glam::Mat4;

use crate::error::{ErrorKind, SceneError};
use crate::scene::{Camera, LoadReport, Material, PunctualLight, Triangle};

/// What a mesh file holds, placed in the world.
#[derive(Clone, Debug, Default)]
pub struct ImportedMesh {
    /// Triangles; `material` indexes [`ImportedMesh::materials`].
    pub triangles: Vec<Triangle>,
    /// Meshes placed several times (glTF: a mesh used by several nodes, or with
    /// `EXT_mesh_gpu_instancing`), their triangles in object space; `material` as above.
    pub instanced: Vec<crate::scene::InstancedMesh>,
    /// The file's materials (plus a default one when some triangles had none).
    pub materials: Vec<Material>,
    /// The textures the materials use, decoded; `Material::textures` index this.
    pub textures: Vec<crate::texture::Texture>,
    /// The file's cameras, in node order (glTF only).
    pub cameras: Vec<Camera>,
    /// The file's point, spot and directional lights, placed (glTF `KHR_lights_punctual`).
    pub lights: Vec<PunctualLight>,
    /// What was dropped or changed.
    pub report: LoadReport,
    /// How its textures' images were decoded.
    pub decode: DecodeStats,
}

/// How long decoding a file's texture images took, how many and how large they are.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DecodeStats {
    /// Wall time of the decoding.
    pub time: std::time::Duration,
    /// Distinct images decoded.
    pub images: usize,
    /// Their texels' bytes (RGBA8).
    pub bytes: u64,
    /// Threads that decoded them.
    pub threads: usize,
}

impl DecodeStats {
    /// Adds `other`'s images and time (files are decoded one after another).
    pub fn add(&mut self, other: &Self) {
        self.time += other.time;
        self.images += other.images;
        self.bytes += other.bytes;
        self.threads = self.threads.max(other.threads);
    }
}

/// Imports a `.gltf`, `.glb`, `.obj` or `.ply` file, placed by `transform`.
///
/// # Errors
/// When the file cannot be read or parsed, or its extension is not one of these; the
/// error names the file.
pub fn import_mesh(path: &Path, transform: Mat4) -> Result<ImportedMesh, SceneError> {
    import_mesh_with(path, transform, false)
}

/// [`import_mesh`], with every material reduced to [`crate::scene::Material::as_diffuse`]
/// where `diffuse` (a `Mesh`'s `diffuse: true`): a glTF file then decodes only the images
/// the reduced materials read (the Crytek Sponza's base colours, not its normal and
/// roughness maps), which takes half its loading off.
///
/// # Errors
/// As [`import_mesh`].
pub fn import_mesh_with(
    path: &Path,
    transform: Mat4,
    diffuse: bool,
) -> Result<ImportedMesh, SceneError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let result = match ext.as_str() {
        "gltf" | "glb" => gltf::import_gltf_with(path, transform, diffuse),
        "obj" => obj::import_obj(path, transform),
        "ply" => ply::import_ply(path, transform),
        _ => Err(SceneError::new(ErrorKind::MeshType(ext))),
    };
    result.map_err(|e| e.in_file(path))
}
