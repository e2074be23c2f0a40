//! lumagraph's layer above the executor ([`lumagraph_render`]): what renders a whole graph
//! and its scene for a program, the command line, the editor and Python.
//!
//! - [`Session`]: a graph, its scene and a device, rendered progressively and read back as
//!   images; params and the scene changed as it goes; checkpointed.
//! - [`frames`]: frame sequences (a graph's params as expressions of the frame number).
//! - [`tiled`] and [`tile_set`]: images larger than the device holds, rendered in tiles,
//!   and tile sets merged into one image.

mod session;

pub mod frames;
pub mod tile_set;
pub mod tiled;

pub use session::*;
