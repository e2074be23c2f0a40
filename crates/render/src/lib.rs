//! The lumagraph GPU executor, on wgpu.
//!
//! - [`GpuContext`]: headless adapter/device chosen from the environment, or a device
//!   shared with the editor.
//! - [`Kernel`]: a compute shader with declared bindings; passes are recorded through a
//!   small builder that reads like their declaration.
//! - [`TexturePool`]: the plan's texture slots as GPU textures, reused across plans.
//! - [`GpuTimer`]: per-pass GPU time from timestamp queries.
//! - [`NodeLibrary`]: the node kinds a program knows and their implementations; the
//!   built-in ones, to which a program adds its own.
//! - [`Executor`]: runs a [`lumagraph_graph::Plan`] frame by frame.
//! - [`image_io`] and [`cpu`]: image files, and plain-Rust references of every post node.
//! - [`custom`]: node kinds declared in graph files, their shaders generated and checked.
//! - [`embree`]: the path tracer's rays traced on the host with Embree 3, loaded at run
//!   time (for CPU adapters, where the WGSL BVH traversal is slow).
//! - [`oidn`]: Intel Open Image Denoise 2, loaded at run time, for the `OIDN` node.

pub mod accel;
pub mod bsdf_check;
pub mod bsdf_tables;
pub mod checkpoint;
mod context;
pub mod cpu;
pub mod custom;
pub mod embree;
pub mod env_map;
mod error;
mod executor;
mod host_rays;
pub mod image_io;
pub mod intersect;
pub mod kernel;
mod library;
pub mod metrics;
pub mod nodes;
pub mod oidn;
pub mod params;
pub mod partial;
mod pool;
pub mod raycast;
pub mod readback;
pub mod sampler;
mod scene_gpu;
pub mod shader;
pub mod shared;
pub mod specialize;
mod timing;
mod wavefront;

pub use checkpoint::Checkpoint;
pub use context::{
    GPU_TIMEOUT, GpuContext, for_tests, human_bytes, ray_queries_turned_off, turn_off_ray_queries,
};
pub use error::{RenderError, Result};
pub use executor::{Executor, FrameReport, PassClock};
pub use kernel::{Binding, Kernel, PassBuilder, uniform_buffer};
pub use library::{NodeLibrary, compile, compile_with};
pub use nodes::output::write_image as write_output;
pub use nodes::{Counter, Measurement, Resources};
pub use partial::Partial;
pub use pool::{PooledTexture, TexturePool, create as create_texture, wgpu_format};
pub use scene_gpu::{SceneBuffers, check_limits as check_scene_limits};
pub use timing::GpuTimer;
/// The wgpu this crate is built on (its types appear in [`Binding`] and [`GpuContext`]).
pub use wgpu;
