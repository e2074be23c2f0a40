//! Exposure: color × 2^ev.

use lumagraph_graph::Pass;

use crate::context::GpuContext;
use crate::cpu::exposure_scale;
use crate::error::Result;
use crate::nodes::{ColorFilter, FrameIo, NodeExec, NodeImpl, boxed, owns_nothing};
use crate::timing::GpuTimer;

/// The `Exposure` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl {
    kind: "Exposure",
    create: |ctx, pass, _| boxed(Exposure::new(ctx, pass)),
    owned_memory: owns_nothing,
    source_extent: None,
    features: None,
};

pub(crate) struct Exposure {
    filter: ColorFilter,
}

impl Exposure {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let filter = ColorFilter::new(ctx, "post/exposure.wgsl")?;
        let mut node = Self { filter };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Exposure {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let scale = exposure_scale(pass.params.float("ev"));
        let mut bytes = [0_u8; 16];
        bytes[..4].copy_from_slice(&scale.to_le_bytes());
        self.filter.set_params(ctx, &bytes);
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
        self.filter.record(ctx, encoder, pass, io, timer)
    }
}
