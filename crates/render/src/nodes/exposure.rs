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

crate::param_block! {
    /// Exposure's params: the colour scale 2^ev.
    pub(crate) struct ExposureParams in "post/exposure.wgsl" as "Params" {
        scale: f32,
    }
}

pub(crate) struct Exposure {
    filter: ColorFilter<ExposureParams>,
}

impl Exposure {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let filter = ColorFilter::new(ctx)?;
        let mut node = Self { filter };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Exposure {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let scale = exposure_scale(pass.params.float("ev"));
        self.filter.set_params(ctx, &ExposureParams { scale });
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
