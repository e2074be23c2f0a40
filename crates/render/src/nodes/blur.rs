//! `Blur`: a separable Gaussian, `shaders/post/blur.wgsl` along x into a node-owned image,
//! then along y into the output.

use lumagraph_graph::{Extent, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, boxed};
use crate::pool::{PooledTexture, create};

/// The `Blur` kind: it owns the image between its two passes.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("Blur", |ctx, pass, _| boxed(Blur::new(ctx, pass)))
    .owning(|pass| {
        Some((
            pass.extent.pixels() * TexFormat::Rgba32Float.bytes_per_pixel(),
            "1 rgba32f image (the horizontal pass)".to_owned(),
        ))
    });

crate::param_block! {
    /// One pass's params.
    pub(crate) struct BlurParams in "post/blur.wgsl" as "Params" {
        sigma: f32,
        radius: i32,
        axis: u32,
        pad: u32,
    }
}

struct Blur {
    kernel: Kernel,
    /// The x pass's params, then the y pass's.
    params: [wgpu::Buffer; 2],
    scratch: Option<(Extent, PooledTexture)>,
}

impl Blur {
    fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let zero = BlurParams::default();
        let mut node = Self {
            kernel: Kernel::new(ctx, "post/blur.wgsl")?,
            params: [0, 1].map(|i| {
                uniform_buffer(ctx, &format!("blur params {i}"), bytemuck::bytes_of(&zero))
            }),
            scratch: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Blur {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        #[expect(clippy::cast_possible_truncation, reason = "sigma ≤ 64")]
        let sigma = pass.params.float("sigma") as f32;
        #[expect(clippy::cast_possible_truncation, reason = "≤ 192")]
        let radius = (3.0 * sigma).ceil() as i32;
        for (axis, buffer) in (0..).zip(&self.params) {
            let block = BlurParams {
                sigma,
                radius,
                axis,
                pad: 0,
            };
            ctx.queue
                .write_buffer(buffer, 0, bytemuck::bytes_of(&block));
        }
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, mut timer) = rec.parts();
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        let extent = pass.extent;
        if self.scratch.as_ref().is_none_or(|(e, _)| *e != extent) {
            let t = create(ctx, "blur x pass", TexFormat::Rgba32Float, extent);
            self.scratch = Some((extent, t));
        }
        let Some((_, scratch)) = &self.scratch else {
            return Ok(());
        };
        let input = io.input(pass, "color")?;
        let passes = [
            (&input.view, &scratch.view, &self.params[0]),
            (&scratch.view, &io.texture(out).view, &self.params[1]),
        ];
        for (src, dst, params) in passes {
            self.kernel
                .pass(&pass.node)
                .read(src)
                .write(dst)
                .uniform(params)
                .dispatch_2d(ctx, encoder, extent, timer.as_deref_mut())?;
        }
        Ok(())
    }
}
