//! Render errors. Node failures carry the node id (see [`RenderError::Node`]).

use std::path::PathBuf;

/// What can go wrong while setting up the GPU or executing a plan.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// No GPU adapter could be found.
    #[error(
        "no GPU adapter found{0} (on Linux, install a Vulkan driver; `mesa-vulkan-drivers` gives the CPU driver lavapipe)"
    )]
    NoAdapter(String),
    /// The adapter refused to give a device.
    #[error("cannot open GPU device on {adapter}: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// Cause.
        message: String,
    },
    /// A shader failed to load or compile.
    #[error("shader {name}: {message}")]
    Shader {
        /// Shader path under `shaders/`.
        name: String,
        /// Cause.
        message: String,
    },
    /// Reading or writing an image file failed.
    #[error("{}: {message}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// Cause.
        message: String,
    },
    /// The GPU did not finish in time or the device was lost.
    #[error("GPU: {0}")]
    Gpu(String),
    /// A node failed.
    #[error("node \"{node}\": {source}")]
    Node {
        /// Node id.
        node: String,
        /// Cause.
        #[source]
        source: Box<RenderError>,
    },
    /// The render needs more than the device allows or holds.
    #[error("{what} on {adapter}: {message}")]
    TooLarge {
        /// What is too large (`node "pathtrace": 100000×100000 image`).
        what: String,
        /// The adapter.
        adapter: String,
        /// The limit and the numbers.
        message: String,
    },
    /// The device was lost (driver reset, GPU removed): nothing more runs on it.
    #[error(
        "the GPU device ({adapter}) was lost ({reason}): the render cannot go on on it; run it \
         again (with --checkpoint-every, a render goes on from its last checkpoint with --resume)"
    )]
    DeviceLost {
        /// The adapter.
        adapter: String,
        /// Why, as the driver says.
        reason: String,
    },
    /// The scene asks for what a node cannot do yet (the message says what, and the way
    /// around it).
    #[error("{0}")]
    Unsupported(String),
    /// A node kind has no GPU implementation in this build.
    #[error("node kind {0} has no implementation")]
    Unimplemented(String),
    /// An output path leaves the output folder (a path from a graph or tile set file).
    #[error("{0}")]
    OutsideOutput(#[from] lumagraph_graph::outputs::OutsideOutput),
    /// A library a node runs on the host (Open Image Denoise) is missing or failed; the
    /// message says which, and for a missing one how to get it.
    #[error("{0}")]
    External(String),
    /// A node kind could not be added to a [`NodeLibrary`](crate::NodeLibrary); the
    /// message names it.
    #[error("{0}")]
    Library(String),
}

impl RenderError {
    /// Wraps this error with the id of the node it happened in.
    #[must_use]
    pub fn in_node(self, node: &str) -> Self {
        Self::Node {
            node: node.to_owned(),
            source: Box::new(self),
        }
    }

    /// An image file's error: `path`, then `message`.
    pub fn image(path: &std::path::Path, message: impl std::fmt::Display) -> Self {
        Self::Image {
            path: path.to_owned(),
            message: message.to_string(),
        }
    }
}

/// Result with [`RenderError`].
pub type Result<T, E = RenderError> = std::result::Result<T, E>;
