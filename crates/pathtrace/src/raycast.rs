//! Ray queries on the GPU: the closest hit of each ray, through the path tracer's BVH
//! traversal (`shaders/pathtrace/intersect/raycast.wgsl`, over the binary BVH or the 8-wide one).
//! Used to check the GPU traversal against the CPU one, for picking, and to time traversal
//! alone (`lumagraph bench --traversal`).

use bytemuck::{Pod, Zeroable};
use lumagraph_scene::Hit;

use crate::scene_gpu::SceneBuffers;
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;
use lumagraph_render::kernel::{Kernel, storage_buffer, uniform_buffer};
use lumagraph_render::readback::{compute_and_read, groups_1d};

/// One ray: origin, direction (any length) and the largest `t` that counts.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RayQuery {
    /// Origin.
    pub origin: [f32; 3],
    /// Hits count for `0 < t < t_max`.
    pub t_max: f32,
    /// Direction; `t` is measured in its length.
    pub dir: [f32; 3],
    /// Padding.
    pub pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct GpuHit {
    prim: u32,
    t: f32,
    u: f32,
    v: f32,
    inst: u32,
}

/// A ray-query kernel bound to one scene's buffers.
#[derive(Debug)]
pub struct Raycaster {
    kernel: Kernel,
}

impl Raycaster {
    /// Compiles the kernel over the binary BVH.
    ///
    /// # Errors
    /// When the shader does not compile.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let kernel = Kernel::new(ctx, "pathtrace/intersect/raycast.wgsl")?;
        Ok(Self { kernel })
    }

    /// Compiles the kernel over the 8-wide BVH ([`crate::intersect::wide_bvh`]): its buffer goes where
    /// [`Raycaster::cast_through`] and [`Raycaster::time`] take the nodes.
    ///
    /// # Errors
    /// When the shader does not compile.
    pub fn wide(ctx: &GpuContext) -> Result<Self> {
        let source = lumagraph_render::shader::resolve_with(
            "pathtrace/intersect/raycast.wgsl",
            &[(
                "pathtrace/intersect/bvh.wgsl",
                "#import \"pathtrace/intersect/wide_bvh.wgsl\"\n".to_owned(),
            )],
        )?;
        let kernel = Kernel::from_source(
            ctx,
            "pathtrace/intersect/raycast.wgsl (8-wide BVH)",
            &source,
        )?;
        Ok(Self { kernel })
    }

    /// The wall time of `repeats` dispatches over `rays` (one submission, hits not read
    /// back), through `nodes` (the binary BVH's `scene.bvh_nodes`, or the wide BVH's buffer
    /// for a kernel made by [`Raycaster::wide`]).
    ///
    /// # Errors
    /// When the GPU work fails.
    pub fn time(
        &self,
        ctx: &GpuContext,
        scene: &SceneBuffers,
        nodes: &wgpu::Buffer,
        rays: &[RayQuery],
        repeats: u32,
    ) -> Result<std::time::Duration> {
        let count = u32::try_from(rays.len()).unwrap_or(u32::MAX);
        let params = uniform_buffer(ctx, "raycast params", bytemuck::bytes_of(&[count, 0, 0, 0]));
        let queries = storage_buffer(ctx, "raycast queries", bytemuck::cast_slice(rays));
        let hits = storage_buffer(
            ctx,
            "raycast hits",
            &vec![0u8; rays.len().max(1) * std::mem::size_of::<GpuHit>()],
        );
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("raycast timing"),
            });
        for _ in 0..repeats {
            self.kernel
                .pass("raycast")
                .uniform(&params)
                .buffer(&queries)
                .buffer(&hits)
                .buffer(nodes)
                .buffer(&scene.tri_positions)
                .buffer(&scene.shapes)
                .dispatch(ctx, &mut encoder, groups_1d(count, 64), None)?;
        }
        // Uploads done before the clock starts.
        ctx.wait()?;
        let start = std::time::Instant::now();
        ctx.queue.submit([encoder.finish()]);
        ctx.wait()?;
        Ok(start.elapsed())
    }

    /// The closest hit of every ray (`prim == NO_HIT` for a miss).
    ///
    /// # Errors
    /// When the GPU work fails.
    pub fn cast(
        &self,
        ctx: &GpuContext,
        scene: &SceneBuffers,
        rays: &[RayQuery],
    ) -> Result<Vec<Hit>> {
        self.cast_through(ctx, scene, &scene.bvh_nodes, rays)
    }

    /// [`Raycaster::cast`] through `nodes` (see [`Raycaster::time`]).
    ///
    /// # Errors
    /// When the GPU work fails.
    pub fn cast_through(
        &self,
        ctx: &GpuContext,
        scene: &SceneBuffers,
        nodes: &wgpu::Buffer,
        rays: &[RayQuery],
    ) -> Result<Vec<Hit>> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let count = u32::try_from(rays.len()).unwrap_or(u32::MAX);
        let params = uniform_buffer(ctx, "raycast params", bytemuck::bytes_of(&[count, 0, 0, 0]));
        let queries = storage_buffer(ctx, "raycast queries", bytemuck::cast_slice(rays));
        let hits =
            compute_and_read::<GpuHit>(ctx, "raycast hits", rays.len(), |encoder, output| {
                self.kernel
                    .pass("raycast")
                    .uniform(&params)
                    .buffer(&queries)
                    .buffer(output)
                    .buffer(nodes)
                    .buffer(&scene.tri_positions)
                    .buffer(&scene.shapes)
                    .dispatch(ctx, encoder, groups_1d(count, 64), None)
            })?;
        Ok(hits
            .into_iter()
            .map(|h| Hit {
                prim: h.prim,
                t: h.t,
                u: h.u,
                v: h.v,
                inst: h.inst,
            })
            .collect())
    }
}
