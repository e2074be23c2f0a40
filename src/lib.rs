//! lumagraph: a modular node-graph renderer.
//!
//! This facade re-exports the workspace crates so a program can depend on one crate:
//! - [`graph`]: node kinds, graph files, validation and compilation (no GPU);
//! - [`scene`]: scene files, glTF/OBJ import, BVH and the GPU layout (no GPU);
//! - [`render`]: the wgpu executor, node implementations and image files.
//!
//! The `lumagraph` binary is the command-line front end; see `lumagraph --help`.

pub use lumagraph_graph as graph;
pub use lumagraph_render as render;
pub use lumagraph_scene as scene;
