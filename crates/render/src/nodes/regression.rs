//! `RegressionDenoise`: per-pixel weighted first-order regression of the illumination on the
//! G-buffer's features (`shaders/post/regression.wgsl`), after a pass that packs the
//! demodulated color, its variance, the features and the pixels' classes into two images
//! (`post/regression_prepare.wgsl`) and one that box-filters the luminance into a guide for
//! the luminance weight (`post/regression_guide.wgsl`).
//!
//! Memory: those three `rgba32float` images of the pass's size, created once and reused
//! ([`scratch_bytes`]). The `variance` input is optional: without it the luminance weight is
//! off, and the preparation pass's variance binding is given the color (its alpha is then
//! never used).

use lumagraph_graph::{Extent, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, boxed, constant_r32};
use crate::pool::{PooledTexture, create};

/// Scratch images: illumination, features, guide.
const IMAGES: u64 = 3;

/// The `RegressionDenoise` kind: it owns its scratch images.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("RegressionDenoise", |ctx, pass, _| {
    boxed(RegressionDenoise::new(ctx, pass))
})
.owning(|pass| {
    Some((
        scratch_bytes(pass.extent),
        "3 rgba32f images (illumination, features, guide)".to_owned(),
    ))
});

crate::param_block! {
    /// The regression pass's params.
    pub(crate) struct RegressionParams in "post/regression.wgsl" as "Params" {
        radius: i32,
        stride: i32,
        guided: u32,
        sigma_normal: f32,
        sigma_depth: f32,
        sigma_color: f32,
        ridge: f32,
        pad: f32,
    }
}

/// Bytes of node-owned memory a `RegressionDenoise` pass over `extent` adds: three
/// `rgba32float` images.
pub fn scratch_bytes(extent: Extent) -> u64 {
    IMAGES * extent.pixels() * TexFormat::Rgba32Float.bytes_per_pixel()
}

pub(crate) struct RegressionDenoise {
    prepare: Kernel,
    guide: Kernel,
    regress: Kernel,
    params: wgpu::Buffer,
    guided: bool,
    extent: Extent,
    scratch: Option<(Extent, [PooledTexture; 3])>,
    /// A constant depth (1) in place of an unconnected depth guide.
    no_depth: Option<PooledTexture>,
}

impl RegressionDenoise {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let mut node = Self {
            prepare: Kernel::new(ctx, "post/regression_prepare.wgsl")?,
            guide: Kernel::new(ctx, "post/regression_guide.wgsl")?,
            regress: Kernel::new(ctx, "post/regression.wgsl")?,
            params: uniform_buffer(
                ctx,
                "regression params",
                bytemuck::bytes_of(&RegressionParams::default()),
            ),
            guided: false,
            extent: pass.extent,
            scratch: None,
            no_depth: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for RegressionDenoise {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let p = &pass.params;
        let sigma_color = p.float("sigma_color");
        self.guided = sigma_color > 0.0 && pass.input("variance").is_some();
        #[expect(clippy::cast_possible_truncation, reason = "params fit f32 and i32")]
        let block = RegressionParams {
            radius: p.int("radius") as i32,
            stride: p.int("stride") as i32,
            guided: u32::from(self.guided),
            sigma_normal: p.float("sigma_normal") as f32,
            sigma_depth: p.float("sigma_depth") as f32,
            sigma_color: sigma_color as f32,
            ridge: p.float("ridge") as f32,
            pad: 0.0,
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&block));
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, mut timer) = rec.parts();
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        let extent = pass.extent;
        self.extent = extent;
        if self.scratch.as_ref().is_none_or(|(e, _)| *e != extent) {
            let make = |label| create(ctx, label, TexFormat::Rgba32Float, extent);
            self.scratch = Some((
                extent,
                [
                    make("regression illumination"),
                    make("regression features"),
                    make("regression guide"),
                ],
            ));
        }
        if pass.input("depth").is_none() {
            constant_r32(ctx, &mut self.no_depth, extent, 1.0);
        }
        let Some((_, [illumination, features, guide])) = &self.scratch else {
            return Ok(());
        };
        // Without a depth guide, a constant depth of 1 (0 would mean nothing was hit): a
        // constant feature, which the fit's ridge term leaves out.
        let depth = match (pass.input("depth"), &self.no_depth) {
            (Some(t), _) => io.texture(t),
            (None, Some(z)) => z,
            (None, None) => return Err(RenderError::Gpu("no depth image".into())),
        };
        let color = io.input(pass, "color")?;
        let variance = match pass.input("variance") {
            Some(t) => io.texture(t),
            None => color,
        };
        let albedo = io.input(pass, "albedo")?;
        self.prepare
            .pass(&pass.node)
            .read(&color.view)
            .read(&variance.view)
            .read(&albedo.view)
            .read(&io.input(pass, "normal")?.view)
            .read(&depth.view)
            .write(&illumination.view)
            .write(&features.view)
            .dispatch_2d(ctx, encoder, extent, timer.as_deref_mut())?;
        self.guide
            .pass(&pass.node)
            .read(&illumination.view)
            .read(&features.view)
            .write(&guide.view)
            .dispatch_2d(ctx, encoder, extent, timer.as_deref_mut())?;
        self.regress
            .pass(&pass.node)
            .read(&illumination.view)
            .read(&features.view)
            .read(&guide.view)
            .read(&albedo.view)
            .write(&io.texture(out).view)
            .uniform(&self.params)
            .dispatch_2d(ctx, encoder, extent, timer)
    }

    fn notes(&self) -> Vec<String> {
        vec![format!(
            "preparation, guide and regression passes, {IMAGES} node-owned rgba32f images \
             ({} bytes); \
             luminance weight {}",
            scratch_bytes(self.extent),
            if self.guided { "on" } else { "off" }
        )]
    }
}
