//! The node kinds that render the scene, on `lumagraph_render`'s frame graph.

pub mod gbuffer;
pub mod pathtrace;

/// The implementations of the built-in kinds that render the scene.
pub static IMPLEMENTATIONS: &[lumagraph_render::nodes::NodeImpl] =
    &[pathtrace::IMPL, gbuffer::IMPL];
