//! The path tracer's images and intersection: against Mitsuba 3 on the Cornell box,
//! every intersector against the others, alpha, textures, specialization, the G-buffer.
//!
//! One test binary per area (`cargo test --test pathtrace`); one module per subject
//! (`cargo test --test pathtrace images::`).

#[path = "../common/mod.rs"]
mod common;

mod alpha;
mod bvh_gpu;
mod gbuffer;
mod gltf_conformance;
mod images;
mod instancing;
mod ray_query;
mod shaders;
mod specialization;
mod texture_atlas;
mod textures;
mod wavefront;
mod wide_bvh;
