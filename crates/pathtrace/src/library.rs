//! Every built-in node kind with its implementation: the frame graph's
//! ([`NodeLibrary::frame_graph`]) and the path tracer's ([`crate::nodes`]). Programs start
//! from [`with_builtins`] (and add kinds of their own with [`NodeLibrary::with_kind`]);
//! [`executor`] and [`compile`] use [`builtins`].

use std::sync::LazyLock;

use lumagraph_graph::{Graph, GraphErrors, Plan};
use lumagraph_render::{Executor, GpuContext, NodeLibrary, Resources, Result};
use lumagraph_scene::GpuScene;

/// Every built-in kind with its implementation.
pub fn with_builtins() -> NodeLibrary {
    NodeLibrary::frame_graph()
        .with_implementations(crate::nodes::IMPLEMENTATIONS)
        .expect("the path tracer's kinds are built in and have no other implementation")
}

static BUILTINS: LazyLock<NodeLibrary> = LazyLock::new(with_builtins);

/// [`with_builtins`], made once and shared.
pub fn builtins() -> &'static NodeLibrary {
    &BUILTINS
}

/// An [`Executor`] of `plan` with the built-in kinds ([`Executor::with_library`] takes a
/// library).
///
/// # Errors
/// When a node cannot be set up (missing input file, unwritable output, shader error, a
/// kind that is not built in); the error names the node.
pub fn executor(ctx: &GpuContext, plan: Plan, resources: &Resources) -> Result<Executor> {
    Executor::with_library(ctx, plan, resources, builtins())
}

/// [`NodeLibrary::compile`] with the built-in kinds.
///
/// # Errors
/// Every problem found in the graph (first in its declared kinds).
pub fn compile(
    graph: &Graph,
    keep: &[String],
    scene: Option<&GpuScene>,
) -> std::result::Result<Plan, GraphErrors> {
    builtins().compile(graph, keep, scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The registry's kinds are exactly the implementations' and the generic post filters,
    /// each once.
    #[test]
    fn every_builtin_kind_has_one_implementation() {
        let library = with_builtins();
        let own = library
            .registry()
            .kinds()
            .iter()
            .filter(|k| k.shader.is_none());
        for kind in own.clone() {
            let n = library
                .implementations()
                .iter()
                .filter(|i| i.kind == kind.name);
            assert_eq!(n.count(), 1, "{}", kind.name);
        }
        assert_eq!(own.count(), library.implementations().len());
        assert!(
            NodeLibrary::frame_graph()
                .with_implementations(crate::nodes::IMPLEMENTATIONS)
                .unwrap()
                .with_implementations(&crate::nodes::IMPLEMENTATIONS[..1])
                .unwrap_err()
                .to_string()
                .contains("already has an implementation")
        );
    }
}
