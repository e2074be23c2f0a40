//! Host intersection: on CPU adapters where Embree is found ([`crate::embree`]), the host
//! intersects the path tracer's rays on its own threads and the WGSL shades them step by
//! step (`host_rays.rs`, `pathtrace/integrator/wave.wgsl`).

use lumagraph_scene::GpuScene;

use super::{Intersector, IntersectorKind, Traversal};
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;
use crate::host_rays::HostRays;
use crate::specialize::support::Content;
use crate::specialize::{Feature, Features, PathTraceOptions};

impl Intersector {
    /// The host (Embree), on CPU adapters, for the scenes it can trace.
    pub const HOST: Self = Self::named("host");
}

/// Host intersection as an intersector.
pub struct Host;

/// Why the host cannot intersect: Embree was not found (or WGSL intersection was asked
/// for through `LUMAGRAPH_EMBREE=off`).
pub(crate) fn unavailable_reason() -> String {
    match crate::embree::Embree::load() {
        Ok(_) => "WGSL intersection asked for".to_owned(),
        Err(e) => e,
    }
}

impl IntersectorKind for Host {
    fn intersector(&self) -> Intersector {
        Intersector::HOST
    }

    fn describe(&self) -> &'static str {
        "host intersection"
    }

    fn how(&self) -> &'static str {
        "rays intersected on the host"
    }

    fn traces(&self) -> [bool; Content::ALL.len()] {
        use Content as C;
        Content::ALL.map(|c| matches!(c, C::ManyPrimitives | C::Instances | C::Alpha | C::Aovs))
    }

    fn lacks(&self, content: Content, scene: &GpuScene) -> String {
        match content {
            Content::GeneralShader | Content::GpuAdapter => {
                "a GPU adapter or the general shader: traced in WGSL".to_owned()
            }
            _ => crate::specialize::support::reason(content, scene),
        }
    }

    fn unavailable(&self, _scene: &GpuScene, options: PathTraceOptions) -> Option<String> {
        (!options.host_rays).then(|| format!("no host intersector: {}", unavailable_reason()))
    }

    fn auto(&self, scene: &GpuScene, _options: PathTraceOptions) -> Result<String, String> {
        Ok(self.asked(scene))
    }

    fn asked(&self, scene: &GpuScene) -> String {
        format!(
            "a CPU adapter: {} intersects the {} triangles on the host's threads, the WGSL shades",
            crate::embree::Embree::load().map_or_else(|e| e, |e| e.version()),
            scene.tri_positions.len()
        )
    }

    fn wgsl_const(&self) -> Option<&'static str> {
        Some("HOST_RAYS")
    }

    fn host_steps(&self) -> bool {
        true
    }

    fn no_wavefront(&self) -> Option<&'static str> {
        Some("rays intersected on the host, which steps the paths itself")
    }

    /// The first-hit AOVs are traced in WGSL (`first_hit_aovs`), and an instanced scene's
    /// instance records follow the nodes (they place the host's hits).
    fn reads_binary_bvh(&self, features: &Features) -> bool {
        features.on(Feature::FirstHitAovs) || features.on(Feature::Instances)
    }

    fn build(&self, ctx: &GpuContext, scene: &std::sync::Arc<GpuScene>) -> Result<Box<dyn Traversal>> {
        Ok(Box::new(HostRays::new(ctx, scene)?))
    }
}

impl Traversal for HostRays {
    fn host(&self) -> Option<&HostRays> {
        Some(self)
    }

    fn host_mut(&mut self) -> Option<&mut HostRays> {
        Some(self)
    }

    fn note(&self, _scene: &GpuScene) -> Option<String> {
        Some(self.note.clone())
    }
}
