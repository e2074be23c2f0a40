//! lumagraph: a modular node-graph renderer.
//!
//! This facade re-exports the workspace crates so a program can depend on one crate:
//! - [`graph`]: node kinds, graph files, validation and compilation (no GPU);
//! - [`scene`]: scene files, glTF/OBJ import, BVH and the GPU layout (no GPU);
//! - [`color`]: OpenColorIO colour management (configs, processors, their WGSL);
//! - [`footage`]: EXR files as compositors read them (parts, layers, windows, colour),
//!   and frame sequences (no GPU);
//! - [`render`]: the frame graph on wgpu: the executor, the post-processing nodes and
//!   image files;
//! - [`pathtrace`]: the path tracer and the kinds that render the scene, and the library of
//!   every built-in kind ([`pathtrace::library`]);
//! - [`editor`]: the node editor.
//!
//! [`session::Session`] renders a graph and its scene from a program: progressively, read
//! back as images, params and the scene changed as it goes, checkpointed; the command line
//! and the editor's render job render through it. [`converge`] measures error against run
//! time.
//!
//! [`cli`] is the `lumagraph` command line (see `lumagraph --help`). A program that adds
//! node kinds of its own to a [`render::NodeLibrary`] runs it with
//! [`cli::main_with`] and gets every subcommand, the editor included, with its kinds in it
//! (`docs/extending.md`, `examples/custom-node/`).

pub mod cli;
pub mod converge;
pub mod overrides;

pub use lumagraph_color as color;
pub use lumagraph_editor as editor;
pub use lumagraph_footage as footage;
pub use lumagraph_graph as graph;
pub use lumagraph_pathtrace as pathtrace;
pub use lumagraph_render as render;
pub use lumagraph_scene as scene;
pub use lumagraph_session as session;
