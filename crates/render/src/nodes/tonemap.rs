//! Tonemap: tone curve and sRGB encoding into an 8-bit texture.

use lumagraph_graph::Pass;
use lumagraph_graph::registry::TONEMAP_OPERATORS;

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Binding, Kernel, uniform_buffer};
use crate::nodes::{FrameIo, NodeExec, record_color_filter};
use crate::timing::GpuTimer;

/// The shader's number for an operator name (its index in the registry).
pub(crate) fn operator_index(name: &str) -> u32 {
    TONEMAP_OPERATORS
        .iter()
        .position(|(n, _)| *n == name)
        .and_then(|i| u32::try_from(i).ok())
        .unwrap_or(0)
}

pub(crate) struct Tonemap {
    kernel: Kernel,
    params: wgpu::Buffer,
}

impl Tonemap {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let kernel = Kernel::new(
            ctx,
            "post/tonemap.wgsl",
            &[
                Binding::Texture,
                Binding::StorageTexture(wgpu::TextureFormat::Rgba8Unorm),
                Binding::Uniform,
            ],
        )?;
        let params = uniform_buffer(ctx, "tonemap params", &[0; 16]);
        let mut node = Self { kernel, params };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Tonemap {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let op = operator_index(pass.params.str("operator"));
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
        let white = pass.params.float("white") as f32;
        let mut bytes = [0_u8; 16];
        bytes[..4].copy_from_slice(&op.to_le_bytes());
        bytes[4..8].copy_from_slice(&white.to_le_bytes());
        ctx.queue.write_buffer(&self.params, 0, &bytes);
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
