//! `TemporalReuse`: reprojects a progressive render's history when the camera moves.
//!
//! The node learns the camera as the path tracer does: from the scene when it is made, then
//! from [`View::move_camera`](crate::nodes::View::move_camera) ([`crate::Executor::move_camera`]). A move restarts
//! Accumulate (its default `move_camera` is a reset) but not this node: the next frame
//! first reprojects what the node wrote last (rendered with the old camera) into the new
//! view, then blends every frame's mean with it. See `shaders/post/temporal.wgsl` for the
//! arithmetic and `cpu::temporal` for its mirror.
//!
//! How many frames Accumulate's mean holds is counted here, not read from Accumulate: the
//! node has history, so it runs in every frame Accumulate runs, and both restart together
//! (a reset, a move). So the weights need no new port or channel, and Accumulate's
//! outputs stay as they were.

use lumagraph_graph::{Extent, Pass, TexFormat};
use lumagraph_scene::GpuCamera;
use wgpu::util::DeviceExt as _;

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, Resources, View, boxed};
use crate::pool::{PooledTexture, create};

/// The `TemporalReuse` kind: it owns its history buffers.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("TemporalReuse", |ctx, pass, resources| {
    boxed(TemporalReuse::new(ctx, pass, resources))
})
.owning(|pass| {
    Some((
        3 * 16 * pass.extent.pixels(),
        "3 history buffers of 16 B per pixel (last color and weight, last normal and depth, \
         reprojected history)"
            .to_owned(),
    ))
});

crate::param_block! {
    /// `TemporalReuse`'s block: the two cameras, the stage and the frame count.
    pub(crate) struct TemporalParams in "post/temporal.wgsl" as "Params" {
        old_camera: GpuCamera,
        camera: GpuCamera,
        size: [u32; 2],
        stage: u32,
        frames: u32,
        history_cap: f32,
        depth_tolerance: f32,
        normal_cos: f32,
        has_normal: u32,
        has_albedo: u32,
        pad0: u32,
        pad1: u32,
        pad2: u32,
    }
}

const STAGE_REPROJECT: u32 = 0;
const STAGE_BLEND: u32 = 1;

/// The history buffers: last color and weight, last normal and depth, reprojected history.
struct History {
    extent: Extent,
    last: wgpu::Buffer,
    last_geo: wgpu::Buffer,
    reprojected: wgpu::Buffer,
}

pub(crate) struct TemporalReuse {
    kernel: Kernel,
    params: wgpu::Buffer,
    history: Option<History>,
    /// Clear the history before the next frame (a reset).
    clear: bool,
    /// The current camera (`None` without a scene: nothing ever moves).
    camera: Option<GpuCamera>,
    /// The camera the history in `last` was rendered with; `None` when there is none.
    history_camera: Option<GpuCamera>,
    /// Frames since the last move or reset.
    frames: u32,
    history_cap: f32,
    depth_tolerance: f32,
    normal_cos: f32,
    /// Stand-ins: the normal and albedo when unconnected, the outputs when unread.
    unused: [PooledTexture; 4],
}

impl TemporalReuse {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass, resources: &Resources) -> Result<Self> {
        let kernel = Kernel::new(ctx, "post/temporal.wgsl")?;
        let params = uniform_buffer(
            ctx,
            "temporal params",
            bytemuck::bytes_of(&TemporalParams::default()),
        );
        let one = Extent::new(1, 1);
        let mut node = Self {
            kernel,
            params,
            history: None,
            clear: true,
            camera: resources.scene.as_ref().map(|s| s.camera),
            history_camera: None,
            frames: 0,
            history_cap: 0.0,
            depth_tolerance: 0.0,
            normal_cos: 1.0,
            unused: [
                create(ctx, "unused temporal normal", TexFormat::Rgba32Float, one),
                create(ctx, "unused temporal albedo", TexFormat::Rgba32Float, one),
                create(ctx, "unused temporal color", TexFormat::Rgba32Float, one),
                create(ctx, "unused temporal weight", TexFormat::Rgba32Float, one),
            ],
        };
        node.update(ctx, pass)?;
        Ok(node)
    }

    fn block(&self, pass: &Pass, stage: u32) -> TemporalParams {
        let camera = self.camera.unwrap_or_default();
        TemporalParams {
            old_camera: self.history_camera.unwrap_or(camera),
            camera,
            size: [pass.extent.width, pass.extent.height],
            stage,
            frames: self.frames,
            history_cap: self.history_cap,
            depth_tolerance: self.depth_tolerance,
            normal_cos: self.normal_cos,
            has_normal: u32::from(pass.input("normal").is_some()),
            has_albedo: u32::from(pass.input("albedo").is_some()),
            ..TemporalParams::default()
        }
    }
}

impl NodeExec for TemporalReuse {
    fn view(&mut self) -> Option<&mut dyn View> {
        Some(self)
    }

    #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
    fn update(&mut self, _ctx: &GpuContext, pass: &Pass) -> Result<()> {
        self.history_cap = pass.params.int("history_frames") as f32;
        self.depth_tolerance = pass.params.float("depth_tolerance") as f32;
        self.normal_cos = pass.params.float("normal_angle").to_radians().cos() as f32;
        Ok(())
    }

    fn reset(&mut self) {
        self.clear = true;
        self.history_camera = None;
        self.frames = 0;
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, mut timer) = rec.parts();
        let (out, weight) = (pass.output("color"), pass.output("weight"));
        if out.is_none() && weight.is_none() {
            return Ok(());
        }
        let extent = pass.extent;
        if self.history.as_ref().is_none_or(|h| h.extent != extent) {
            let make = |label| {
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: extent.pixels() * 16,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            self.history = Some(History {
                extent,
                last: make("temporal last"),
                last_geo: make("temporal last geometry"),
                reprojected: make("temporal reprojected"),
            });
            self.clear = true;
            self.history_camera = None;
        }
        let Some(h) = &self.history else {
            return Ok(());
        };
        if std::mem::take(&mut self.clear) {
            for b in [&h.last, &h.last_geo, &h.reprojected] {
                encoder.clear_buffer(b, 0, None);
            }
        }
        let moved = self.history_camera.is_some() && self.history_camera != self.camera;
        self.frames += 1;
        let color = io.input(pass, "color")?;
        let depth = io.input(pass, "depth")?;
        let guide = |port: &str, i: usize| {
            pass.input(port)
                .map_or(&self.unused[i].view, |t| &io.texture(t).view)
        };
        let view = |t: Option<lumagraph_graph::TextureId>, i: usize| {
            t.map_or(&self.unused[i].view, |t| &io.texture(t).view)
        };
        let stages: &[u32] = if moved {
            &[STAGE_REPROJECT, STAGE_BLEND]
        } else {
            &[STAGE_BLEND]
        };
        for &stage in stages {
            // Each frame has its own block: staged through a copy recorded in order, so
            // many frames can share one submission.
            let staging = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("temporal params staging"),
                    contents: bytemuck::bytes_of(&self.block(pass, stage)),
                    usage: wgpu::BufferUsages::COPY_SRC,
                });
            encoder.copy_buffer_to_buffer(&staging, 0, &self.params, 0, staging.size());
            self.kernel
                .pass(&pass.node)
                .read(&color.view)
                .read(&depth.view)
                .read(guide("normal", 0))
                .read(guide("albedo", 1))
                .write(view(out, 2))
                .write(view(weight, 3))
                .buffer(&h.last)
                .buffer(&h.last_geo)
                .buffer(&h.reprojected)
                .uniform(&self.params)
                .dispatch_2d(ctx, encoder, extent, timer.as_deref_mut())?;
        }
        self.history_camera = self.camera;
        Ok(())
    }
}

impl View for TemporalReuse {
    fn move_camera(&mut self, camera: &GpuCamera) {
        // The history stays, rendered with `history_camera`; the next frame reprojects it.
        self.camera = Some(*camera);
        self.frames = 0;
    }
}
