//! What traces a `PathTrace` node's rays, with what it holds: one value per node, made from
//! the shader's features ([`crate::specialize::Features::intersector`]).

use std::time::{Duration, Instant};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::host_rays::HostRays;
use crate::specialize::{Features, Intersector};

/// The intersector of a node and its state.
pub(crate) enum Backend {
    /// Inline code or the binary BVH in WGSL, over the scene's buffers: nothing of its own.
    Wgsl,
    /// The 8-wide BVH's buffer (bound in the binary BVH's place), with its node count,
    /// depth, size and build time.
    WideBvh(wgpu::Buffer, crate::wide_bvh::WideBvh, Duration),
    /// The scene's acceleration structure for the device's ray queries, and how long it
    /// took to build.
    RayQueries(crate::accel::SceneAccel, Duration),
    /// Host intersection's state (Embree traces, the WGSL shades in steps).
    Host(HostRays),
}

impl Backend {
    /// The backend `features` trace `scene` with, built.
    ///
    /// # Errors
    /// When building its structure fails (Embree's scene, the acceleration structure, the
    /// 8-wide BVH or its upload).
    pub(crate) fn new(
        ctx: &GpuContext,
        scene: &std::sync::Arc<lumagraph_scene::GpuScene>,
        features: &Features,
    ) -> Result<Self> {
        let start = Instant::now();
        Ok(match features.intersector() {
            Intersector::Host => Self::Host(HostRays::new(ctx, scene)?),
            Intersector::RayQueries => {
                let accel = crate::accel::SceneAccel::build(ctx, scene)?;
                Self::RayQueries(accel, start.elapsed())
            }
            Intersector::WideBvh => {
                let mut bvh = crate::wide_bvh::WideBvh::build(scene).map_err(|e| {
                    RenderError::Gpu(format!(
                        "{e} (--intersector binary traverses the binary BVH)"
                    ))
                })?;
                let took = start.elapsed();
                let buffer = crate::wide_bvh::upload(ctx, &bvh)?;
                bvh.records = Vec::new();
                Self::WideBvh(buffer, bvh, took)
            }
            Intersector::Auto | Intersector::Inline | Intersector::BinaryBvh => Self::Wgsl,
        })
    }

    /// Host intersection's state, where the host traces.
    pub(crate) fn host(&self) -> Option<&HostRays> {
        match self {
            Self::Host(host) => Some(host),
            _ => None,
        }
    }

    /// The buffer bound as the BVH's nodes: the 8-wide BVH's where it is walked, else the
    /// scene's binary BVH (`binary`).
    pub(crate) fn bvh_nodes<'a>(&'a self, binary: &'a wgpu::Buffer) -> &'a wgpu::Buffer {
        match self {
            Self::WideBvh(buffer, _, _) => buffer,
            _ => binary,
        }
    }

    /// The acceleration structure, where ray queries trace.
    pub(crate) fn accel(&self) -> Option<&crate::accel::SceneAccel> {
        match self {
            Self::RayQueries(accel, _) => Some(accel),
            _ => None,
        }
    }

    /// What the render prints about it (nothing for the WGSL's own intersection).
    pub(crate) fn note(&self, scene: &lumagraph_scene::GpuScene) -> Option<String> {
        match self {
            Self::Wgsl => None,
            Self::Host(host) => Some(host.note.clone()),
            Self::RayQueries(accel, took) => Some(format!(
                "ray queries: acceleration structure over {} triangles and {} spheres ({} of \
                 boxes) built in {:.1} ms",
                scene.tri_positions.len(),
                scene.shapes.len(),
                crate::human_bytes(accel.input_bytes),
                took.as_secs_f64() * 1e3
            )),
            Self::WideBvh(_, bvh, took) => Some(format!(
                "8-wide BVH: {} nodes, {} deep, {} built in {:.1} ms",
                bvh.nodes,
                bvh.depth,
                crate::human_bytes(bvh.bytes),
                took.as_secs_f64() * 1e3
            )),
        }
    }
}
