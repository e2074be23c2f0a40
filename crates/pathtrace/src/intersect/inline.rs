//! Inline intersection: every primitive tested in code written for the scene
//! ([`crate::specialize::inline_intersection`]), for scenes of at most
//! [`crate::specialize::INLINE_MAX_PRIMITIVES`] primitives. On CPU adapters loads in loops are what llvmpipe
//! pays most for, so small scenes are intersected this way there; GPUs traverse the BVH.

use lumagraph_scene::GpuScene;

use super::{Intersector, IntersectorKind};
use crate::specialize::support::Content;
use crate::specialize::{PathTraceOptions, parallelograms};

impl Intersector {
    /// Every primitive tested in code written for the scene.
    pub const INLINE: Self = Self::named("inline");
}

/// Inline intersection as an intersector.
pub struct Inline;

/// The scene's primitives, and the parallelograms tested as one.
fn reason(scene: &GpuScene) -> String {
    let prims = scene.tri_positions.len() + scene.shapes.len();
    let pairs = parallelograms(&scene.tri_positions)
        .iter()
        .filter(|(_, b)| b.is_some())
        .count();
    if pairs > 0 {
        format!("{prims} primitives, {pairs} parallelograms of 2 triangles tested as one")
    } else {
        format!("{prims} primitives")
    }
}

impl IntersectorKind for Inline {
    fn intersector(&self) -> Intersector {
        Intersector::INLINE
    }

    fn describe(&self) -> &'static str {
        "inline intersection"
    }

    fn how(&self) -> &'static str {
        "intersection inlined"
    }

    fn traces(&self) -> [bool; Content::ALL.len()] {
        use Content as C;
        Content::ALL.map(|c| !matches!(c, C::GeneralShader | C::ManyPrimitives | C::Instances))
    }

    fn auto(&self, scene: &GpuScene, options: PathTraceOptions) -> Result<String, String> {
        if options.cpu_adapter {
            Ok(reason(scene))
        } else {
            Err(format!(
                "a GPU adapter: the BVH measured 2.6-3.6x faster than testing {} primitives \
                 inline (64 spheres, NVIDIA H100; --intersector inline asks for it)",
                scene.tri_positions.len() + scene.shapes.len()
            ))
        }
    }

    fn asked(&self, scene: &GpuScene) -> String {
        reason(scene)
    }

    fn wgsl(&self, scene: &GpuScene, alpha: bool) -> Option<String> {
        crate::specialize::inline_intersection(scene, alpha)
    }

    fn inline(&self) -> bool {
        true
    }

    fn no_wavefront(&self) -> Option<&'static str> {
        Some("intersected inline: the megakernel")
    }
}

