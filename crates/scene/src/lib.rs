//! lumagraph scenes, with no GPU in sight.
//!
//! - [`file`](mod@file): the RON scene format (`version: 2`): camera, named materials, shapes
//!   (meshes, spheres, Mitsuba-style rectangles and boxes, quads), point, spot and
//!   directional lights, environment, render settings. [`Scene::load`] reads it into a [`Scene`] with world-space triangles.
//! - [`import`]: glTF 2.0 and OBJ + MTL meshes, cameras, materials and
//!   (`KHR_lights_punctual`) lights.
//! - [`conductor`]: measured metals (complex index of refraction) and their Fresnel.
//! - [`save`]: an edited [`file::SceneFile`] written back over the text it was read from,
//!   keeping comments, layout and number spelling wherever a value did not change.
//! - [`export`]: the resolved scene as JSON + OBJ for other renderers (Mitsuba references).
//! - [`GpuScene`]: the scene flattened into `#[repr(C)]` arrays laid out as WGSL lays out
//!   storage buffers ([`gpu`]), with a BVH built by obvhs ([`bvh`]), lights and an alias
//!   table for picking them (half by power, half uniformly).
//! - [`lobes`]: the material's parameters, declared once: the GPU record and its WGSL twin,
//!   and the lobe parameters of the scene format, the loader, save, export and the editor.
//! - [`texture`]: decoded glTF textures, their packing for the GPU and a CPU sampler
//!   that mirrors the shader's.
//! - [`traverse`]: CPU ray queries over exactly that layout, mirrored by
//!   `shaders/pathtrace/intersect/bvh.wgsl`.
//!
//! Broken input never panics: syntax and semantic errors name the file, line:column and
//! the shape or material; broken triangles are dropped and counted in a [`LoadReport`].

pub mod bvh;
pub mod conductor;
pub mod edit;
mod error;
pub mod export;
pub mod file;
mod flatten;
pub mod gpu;
pub mod import;
pub mod lights;
mod load;
pub mod lobes;
pub mod orbit;
pub mod save;
mod scene;
pub mod shapes;
pub mod texture;
pub mod traverse;

pub use bvh::{BVH_END, BVH_MAX_DEPTH, BvhOptions};
pub use error::{ErrorKind, InstancedCopies, Pos, SceneError};
pub use file::{Environment, LightDesc, RenderSettings, VERSION};
pub use flatten::{GpuScene, LIGHT_UNIFORM_SHARE, alias_table, light_selection, luminance};
pub use gpu::*;
pub use load::transform_matrix;
pub use scene::{
    AUTO_FLATTEN_MAX_TRIANGLES, AlphaMode, Camera, InstancedMesh, Instancing, LoadReport,
    LoadStats, MAX_INSTANCED_TRIANGLES, Material, MaterialTextures, Medium, NO_TEXTURE,
    PunctualLight, Scene, Shape, Triangle, cube_quads, push_triangle, quad_triangles,
    rectangle_quad, transform_triangle,
};
pub use texture::{
    AtlasLimits, Downscaled, TexelRange, Texture, TextureAtlas, UvTransform, Wrap, fit_textures,
    fit_textures_with, pack_atlas, pack_atlas_with,
};
pub use traverse::{Hit, Ray, intersect, intersect_within, occluded};
