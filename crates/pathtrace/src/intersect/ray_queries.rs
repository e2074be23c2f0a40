//! Ray queries: the device's acceleration structure ([`crate::accel`]) finds the
//! candidates, the WGSL tests them (`pathtrace/intersect/ray_query.wgsl`).

use lumagraph_scene::GpuScene;

use super::{Intersector, IntersectorKind, Traversal};
use crate::accel::SceneAccel;
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;
use crate::specialize::PathTraceOptions;
use crate::specialize::support::Content;

impl Intersector {
    /// The device's ray queries, where it has them and they can trace the scene.
    pub const RAY_QUERIES: Self = Self::named("rays");
}

/// Why a CPU adapter does not trace through its ray queries unless asked to (lavapipe
/// has them from Mesa 25): measured in `docs/benchmarks.md` ("Ray queries on lavapipe").
const CPU_REASON: &str = "a CPU adapter: lavapipe's ray queries measured 0.16-0.36x \
     the kernel's own intersection (--intersector rays asks for them)";

/// Ray queries as an intersector.
pub struct RayQueries;

impl IntersectorKind for RayQueries {
    fn intersector(&self) -> Intersector {
        Intersector::RAY_QUERIES
    }

    fn describe(&self) -> &'static str {
        "ray queries"
    }

    fn how(&self) -> &'static str {
        "ray queries"
    }

    fn traces(&self) -> [bool; Content::ALL.len()] {
        use Content as C;
        Content::ALL.map(|c| !matches!(c, C::GeneralShader | C::Instances))
    }

    fn lacks(&self, content: Content, scene: &GpuScene) -> String {
        match content {
            Content::GeneralShader => "general shader: WGSL BVH".to_owned(),
            _ => crate::specialize::support::reason(content, scene),
        }
    }

    fn unavailable(&self, scene: &GpuScene, options: PathTraceOptions) -> Option<String> {
        match options.ray_query_limit {
            None => Some(
                "the device has no ray queries (or they were turned off: LUMAGRAPH_RAY_QUERY=off)"
                    .to_owned(),
            ),
            Some(most) => crate::accel::unsupported(scene, most),
        }
    }

    fn auto(&self, _scene: &GpuScene, options: PathTraceOptions) -> Result<String, String> {
        if options.cpu_adapter {
            Err(CPU_REASON.to_owned())
        } else {
            Ok("the device's acceleration structure finds the candidates, the WGSL tests them"
                .to_owned())
        }
    }

    fn wgsl(&self, _scene: &GpuScene, _alpha: bool) -> Option<String> {
        Some("#import \"pathtrace/intersect/ray_query.wgsl\"\n".to_owned())
    }

    fn enable(&self) -> Option<&'static str> {
        Some("wgpu_ray_query")
    }

    fn build(&self, ctx: &GpuContext, scene: &std::sync::Arc<GpuScene>) -> Result<Box<dyn Traversal>> {
        let start = std::time::Instant::now();
        let accel = SceneAccel::build(ctx, scene)?;
        Ok(Box::new(Built {
            accel,
            took: start.elapsed(),
        }))
    }
}

/// The scene's acceleration structure, and how long it took to build.
struct Built {
    accel: SceneAccel,
    took: std::time::Duration,
}

impl Traversal for Built {
    fn accel(&self) -> Option<&SceneAccel> {
        Some(&self.accel)
    }

    fn note(&self, scene: &GpuScene) -> Option<String> {
        Some(format!(
            "ray queries: acceleration structure over {} triangles and {} spheres ({} of \
             boxes) built in {:.1} ms",
            scene.tri_positions.len(),
            scene.shapes.len(),
            lumagraph_render::human_bytes(self.accel.input_bytes),
            self.took.as_secs_f64() * 1e3
        ))
    }
}
