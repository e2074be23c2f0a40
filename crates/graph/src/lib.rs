//! The lumagraph render graph, with no GPU in sight.
//!
//! - [`registry`]: the node kinds, their typed ports and params, with docs.
//! - [`Graph`]: nodes and edges, loaded from and saved to versioned RON files.
//! - [`group`]: graph files used as nodes, flattened before compiling.
//! - [`compile`]: validation, topological order, pruning and texture assignment,
//!   giving a [`Plan`] that the render crate executes.
//! - [`outputs`]: where the files a plan writes go (inside the output folder).
//!
//! Everything here runs anywhere in microseconds, so it is tested without a GPU.

mod compile;
pub mod custom;
pub mod docs;
mod error;
pub mod expr;
mod graph;
pub mod group;
pub mod layout;
pub mod outputs;
mod plan;
pub mod registry;
pub mod tile;
mod types;
pub mod working_space;

pub use compile::{CompileOptions, Params, compile, resolve_params};
pub use error::{ErrorKind, GraphError, GraphErrors, NodeId, Pos};
pub use graph::{
    Edge, FrameDecl, Graph, Node, Origin, Rgb, VERSION, read_text, split_port_ref, write_atomic,
};
pub use plan::{LeftOut, Pass, Plan, Slot, TextureDesc, TextureId};
pub use registry::{Category, NodeKind, Registry};
pub use types::{Extent, ParamType, ParamValue, PortType, TexFormat};
pub use working_space::WorkingSpace;
