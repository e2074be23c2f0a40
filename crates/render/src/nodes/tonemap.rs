//! Tonemap: tone curve and sRGB encoding into an 8-bit texture.

use lumagraph_graph::Pass;

use crate::context::GpuContext;
use crate::error::Result;
use crate::nodes::{ColorFilter, NodeExec, NodeImpl, Recording, boxed};

/// The `Tonemap` kind.
pub(crate) const IMPL: NodeImpl =
    NodeImpl::new("Tonemap", |ctx, pass, _| boxed(Tonemap::new(ctx, pass)));

crate::param_block! {
    /// Tonemap's params: the operator (its index in the registry's options) and the white
    /// point of extended Reinhard.
    pub(crate) struct TonemapParams in "post/tonemap.wgsl" as "Params" {
        op: u32,
        white: f32,
    }
}

pub(crate) struct Tonemap {
    filter: ColorFilter<TonemapParams>,
}

impl Tonemap {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let filter = ColorFilter::new(ctx)?;
        let mut node = Self { filter };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Tonemap {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let op = crate::params::enum_index(pass, "operator")?;
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
        let white = pass.params.float("white") as f32;
        self.filter.set_params(ctx, &TonemapParams { op, white });
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        self.filter.record(pass, rec)
    }
}
