//! lumagraph's path tracer on wgpu, and the node kinds that render the scene.
//!
//! - [`scene_gpu`]: the flattened scene's buffers and texture atlas on the device.
//! - [`specialize`]: the path tracer's shader specialized to the scene (what it compiles
//!   in and leaves out, and why), the intersector and the schedule chosen.
//! - [`intersect`]: the intersectors, one file each behind one trait, listed once.
//! - [`embree`]: the path tracer's rays traced on the host with Embree 3, loaded at run
//!   time (for CPU adapters, where the WGSL BVH traversal is slow).
//! - [`accel`]: acceleration structures for ray queries.
//! - [`env_map`], [`bsdf_tables`], [`sampler`]: the environment's importance map, the
//!   BSDFs' precomputed tables, the low-discrepancy sampler.
//! - [`nodes`]: the `PathTrace` and `GBuffer` nodes on `lumagraph_render`'s frame graph.
//! - [`library`]: every built-in kind with its implementation, the library programs
//!   start from.

pub mod accel;
pub mod bsdf_check;
pub mod bsdf_tables;
pub mod embree;
pub mod env_map;
mod host_rays;
pub mod intersect;
pub mod library;
pub mod nodes;
pub mod raycast;
pub mod sampler;
mod scene_gpu;
pub mod specialize;
mod wavefront;

pub use scene_gpu::{SceneBuffers, check_limits as check_scene_limits};
pub use specialize::{Tracer, Tracing};

/// The param blocks of the path tracer and the G-buffer, whose WGSL twins the layout test
/// checks field by field (as `lumagraph_render::params::BLOCKS` for the frame graph's).
pub const BLOCKS: &[lumagraph_render::params::BlockLayout] = &[
    <nodes::pathtrace::Frame as lumagraph_render::params::ParamBlock>::LAYOUT,
    <nodes::gbuffer::RasterCamera as lumagraph_render::params::ParamBlock>::LAYOUT,
    <embree::HostHit as lumagraph_render::params::ParamBlock>::LAYOUT,
];

#[cfg(test)]
mod tests {
    /// Every param block matches its WGSL twin.
    #[test]
    fn param_blocks_match_their_wgsl_twins() {
        let errors: Vec<String> = super::BLOCKS
            .iter()
            .filter_map(|b| lumagraph_render::params::check_layout(b).err())
            .collect();
        assert!(errors.is_empty(), "{}", errors.join("\n"));
    }
}
