//! Graph errors: each names the file, the line and column where it can be found, and the
//! node it concerns.

use std::fmt;

pub use lumagraph_files::Pos;

/// What went wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The file could not be read or written.
    #[error("{action}: {source}")]
    Io {
        /// What was being done ("cannot read", "cannot write").
        action: &'static str,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is not valid RON for a graph.
    #[error("syntax error: {0}")]
    Syntax(String),
    /// The file's version is not one this build reads.
    #[error("unsupported graph version {found}: this build reads versions 1 to {supported}{}", if *found > *supported { " (the file was written by a newer lumagraph)" } else { "" })]
    Version {
        /// Version in the file.
        found: u32,
        /// Version this build reads.
        supported: u32,
    },
    /// Two nodes share an id.
    #[error("duplicate node id \"{0}\"")]
    DuplicateId(String),
    /// A node id is empty or contains a character edges cannot name.
    #[error(
        "invalid node id \"{0}\": use letters, digits, '_' and '-' ('/' separates a group node's id from its inner nodes')"
    )]
    InvalidId(String),
    /// No kind of that name is registered.
    #[error("unknown node kind \"{kind}\" (known kinds: {known})")]
    UnknownKind {
        /// The kind in the file.
        kind: String,
        /// Registered kinds, comma-separated.
        known: String,
    },
    /// The kind has no such parameter.
    #[error("unknown param \"{param}\" for {kind} (its params: {known})")]
    UnknownParam {
        /// The param in the file.
        param: String,
        /// The node kind.
        kind: String,
        /// The kind's params, comma-separated.
        known: String,
    },
    /// The value does not fit the parameter's type or range.
    #[error("param \"{param}\": {message}")]
    BadParam {
        /// The param.
        param: String,
        /// What is wrong.
        message: String,
    },
    /// An edge end is not of the form `node.port`.
    #[error("edge end \"{0}\" is not of the form \"node.port\"")]
    BadPortRef(String),
    /// An edge names a node that does not exist.
    #[error("edge {from} -> {to}: no node \"{node}\"")]
    MissingNode {
        /// Edge start.
        from: String,
        /// Edge end.
        to: String,
        /// The missing node id.
        node: String,
    },
    /// An edge names a port its node does not have.
    #[error(
        "edge {from} -> {to}: {kind} has no {direction} port \"{port}\" (its {direction} ports: {known})"
    )]
    MissingPort {
        /// Edge start.
        from: String,
        /// Edge end.
        to: String,
        /// Kind of the node.
        kind: String,
        /// "input" or "output".
        direction: &'static str,
        /// The missing port.
        port: String,
        /// The ports it does have.
        known: String,
    },
    /// The output port's type is not accepted by the input port.
    #[error("edge {from} -> {to}: {from} produces {produced}, but {to} accepts {accepted}")]
    IncompatibleTypes {
        /// Edge start.
        from: String,
        /// Edge end.
        to: String,
        /// Type produced by the output port.
        produced: String,
        /// Types accepted by the input port.
        accepted: String,
    },
    /// Two edges end at the same input port.
    #[error("input {to} has two incoming edges (from {first} and {second})")]
    TwoEdgesIntoInput {
        /// The input port.
        to: String,
        /// The first edge's start.
        first: String,
        /// The second edge's start.
        second: String,
    },
    /// A needed node has an input with no edge.
    #[error("input port \"{port}\" is not connected")]
    UnconnectedInput {
        /// The port.
        port: String,
    },
    /// The edges form a cycle.
    #[error("the graph has a cycle through nodes {0}")]
    Cycle(String),
    /// No node writes anything out.
    #[error("the graph has no output node (add an Output node)")]
    NoOutput,
    /// A source node could not tell its image size.
    #[error("{0}")]
    Source(String),
    /// An output path leaves the output folder.
    #[error("{0}")]
    OutsideOutput(crate::outputs::OutsideOutput),
}

/// One error with its location: the graph file, the line and column, the node.
pub type GraphError = lumagraph_files::Located<ErrorKind, NodeId>;

/// The node a graph error concerns, by id (displayed as `node "ID"`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeId(pub String);

impl std::ops::Deref for NodeId {
    type Target = str;
    fn deref(&self) -> &str {
        &self.0
    }
}

impl<T: AsRef<str> + ?Sized> From<&T> for NodeId {
    fn from(id: &T) -> Self {
        Self(id.as_ref().to_owned())
    }
}

impl fmt::Display for NodeId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "node \"{}\"", self.0)
    }
}

/// Every error found in one graph, in file order.
#[derive(Debug)]
pub struct GraphErrors(pub Vec<GraphError>);

impl GraphErrors {
    /// The errors that concern `node`.
    pub fn for_node<'a>(&'a self, node: &'a str) -> impl Iterator<Item = &'a GraphError> + 'a {
        self.0
            .iter()
            .filter(move |e| e.about.as_deref() == Some(node))
    }
}

impl From<GraphError> for GraphErrors {
    fn from(e: GraphError) -> Self {
        Self(vec![e])
    }
}

impl fmt::Display for GraphErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str("\n")?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for GraphErrors {}
