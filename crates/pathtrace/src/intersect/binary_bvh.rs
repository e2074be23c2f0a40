//! The binary stackless BVH traversed in WGSL (`pathtrace/intersect/bvh.wgsl`, which
//! `pathtrace/intersect.wgsl` imports) over the scene's own buffers: the one intersector
//! that traces everything (the general shader, instanced meshes), and so the last the
//! adapter's choice tries.

use lumagraph_scene::GpuScene;

use super::{Intersector, IntersectorKind};
use crate::specialize::support::Content;
use crate::specialize::{Features, PathTraceOptions};

impl Intersector {
    /// The binary stackless BVH traversed in WGSL.
    pub const BINARY_BVH: Self = Self::named("binary");
}

/// The binary BVH as an intersector.
pub struct BinaryBvh;

impl IntersectorKind for BinaryBvh {
    fn intersector(&self) -> Intersector {
        Intersector::BINARY_BVH
    }

    fn describe(&self) -> &'static str {
        "the binary BVH"
    }

    fn how(&self) -> &'static str {
        "BVH traversal"
    }

    fn traces(&self) -> [bool; Content::ALL.len()] {
        [true; Content::ALL.len()]
    }

    fn auto(&self, scene: &GpuScene, options: PathTraceOptions) -> Result<String, String> {
        Ok(if options.specialize {
            format!("{} nodes", scene.bvh_nodes.len())
        } else {
            format!(
                "{} nodes (general shader: the binary BVH)",
                scene.bvh_nodes.len()
            )
        })
    }

    fn asked(&self, scene: &GpuScene) -> String {
        format!("{} nodes, asked for", scene.bvh_nodes.len())
    }

    fn reads_binary_bvh(&self, _features: &Features) -> bool {
        true
    }
}
