//! Exposure: color × 2^ev.

use lumagraph_graph::Pass;

use crate::context::GpuContext;
use crate::cpu::exposure_scale;
use crate::error::Result;
use crate::kernel::{Binding, Kernel, uniform_buffer};
use crate::nodes::{FrameIo, NodeExec, record_color_filter};
use crate::timing::GpuTimer;

pub(crate) struct Exposure {
    kernel: Kernel,
    params: wgpu::Buffer,
}

impl Exposure {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let kernel = Kernel::new(
            ctx,
            "post/exposure.wgsl",
            &[
                Binding::Texture,
                Binding::StorageTexture(wgpu::TextureFormat::Rgba32Float),
                Binding::Uniform,
            ],
        )?;
        let params = uniform_buffer(ctx, "exposure params", &[0; 16]);
        let mut node = Self { kernel, params };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Exposure {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let scale = exposure_scale(pass.params.float("ev"));
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&[scale, 0.0, 0.0, 0.0]));
        Ok(())
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        pass: &Pass,
        io: &FrameIo<'_>,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        record_color_filter(&self.kernel, &self.params, ctx, encoder, pass, io, timer)
    }
}
