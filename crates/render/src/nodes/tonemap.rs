//! Tonemap: tone curve and sRGB encoding into an 8-bit texture.

use lumagraph_graph::Pass;
use lumagraph_graph::registry::TONEMAP_OPERATORS;

use crate::context::GpuContext;
use crate::error::Result;
use crate::nodes::{ColorFilter, FrameIo, NodeExec, NodeImpl, boxed, owns_nothing};
use crate::timing::GpuTimer;

/// The shader's number for an operator name (its index in the registry).
pub(crate) fn operator_index(name: &str) -> u32 {
    TONEMAP_OPERATORS
        .iter()
        .position(|(n, _)| *n == name)
        .and_then(|i| u32::try_from(i).ok())
        .unwrap_or(0)
}

/// The `Tonemap` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl {
    kind: "Tonemap",
    create: |ctx, pass, _| boxed(Tonemap::new(ctx, pass)),
    owned_memory: owns_nothing,
    source_extent: None,
    features: None,
};

pub(crate) struct Tonemap {
    filter: ColorFilter,
}

impl Tonemap {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let filter = ColorFilter::new(ctx, "post/tonemap.wgsl")?;
        let mut node = Self { filter };
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
