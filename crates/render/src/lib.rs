//! The lumagraph frame graph on wgpu: the executor, the post-processing nodes and image
//! files. The path tracer and the G-buffer, the kinds that render the scene, are
//! `lumagraph-pathtrace`'s, which adds them to a [`NodeLibrary`].
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
//! - [`oidn`]: Intel Open Image Denoise 2, loaded at run time, for the `OIDN` node.

pub mod checkpoint;
pub mod context;
pub mod cpu;
pub mod custom;
pub mod error;
pub mod executor;
pub mod image_io;
pub mod kernel;
pub mod library;
pub mod metrics;
pub mod nodes;
pub mod oidn;
pub mod params;
pub mod partial;
pub mod pool;
pub mod readback;
pub mod shader;
pub mod shared;
pub mod timing;

pub use checkpoint::Checkpoint;
pub use context::{
    AdapterTraits, GPU_TIMEOUT, GpuContext, for_tests, human_bytes, ray_queries_turned_off,
    turn_off_ray_queries,
};
pub use error::{RenderError, Result};
pub use executor::{Executor, FrameReport, PassClock};
pub use kernel::{Binding, Kernel, PassBuilder, uniform_buffer};
pub use library::NodeLibrary;
pub use nodes::output::write_image as write_output;
pub use nodes::{AsAny, Counter, Measurement, Resources, Settings, ShaderChoices};
pub use partial::Partial;
pub use pool::{PooledTexture, TexturePool, create as create_texture, wgpu_format};
pub use timing::GpuTimer;
/// The wgpu this crate is built on (its types appear in [`Binding`] and [`GpuContext`]).
pub use wgpu;
