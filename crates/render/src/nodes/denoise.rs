//! `Denoise`: the edge-avoiding à-trous wavelet filter: a demodulation pass, then
//! `iterations` filter passes of `shaders/post/denoise.wgsl` with the kernel's taps 1, 2, 4,
//! 8, 16… pixels apart, the last one remodulating into the output texture.
//!
//! Memory: the demodulation pass reads the node's inputs and writes illumination (rgb) and
//! its variance (alpha) into a node-owned `rgba32float` image of the pass's size; the filter
//! passes ping-pong between it and a second one; the last writes the output texture. Those
//! two images, created once and reused every frame, are all the memory the filter adds
//! ([`scratch_bytes`]); with one iteration only the first is created.
//!
//! The `variance` input is optional: without it, or with `variance_guided` off, the
//! luminance tolerance is a fixed one halved every pass, as in Dammertz et al., and the
//! shader's variance binding is given the color image (its alpha fills the variance slot
//! the filter then never reads).

use lumagraph_graph::{Extent, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, boxed, constant_r32};
use crate::pool::{PooledTexture, create};

/// Most passes the registry allows.
const MAX_ITERATIONS: u32 = 8;

/// The `Denoise` kind: it owns its scratch images.
pub(crate) const IMPL: NodeImpl =
    NodeImpl::new("Denoise", |ctx, pass, _| boxed(Denoise::new(ctx, pass))).owning(|pass| {
        let n = u32::try_from(pass.params.int("iterations")).unwrap_or(1);
        let what = if n > 1 {
            "2 rgba32f ping-pong images"
        } else {
            "1 rgba32f image (demodulated input)"
        };
        Some((scratch_bytes(pass.extent, n), what.to_owned()))
    });

crate::param_block! {
    /// One à-trous pass's params (and the demodulation pass's, `first`).
    pub(crate) struct DenoiseParams in "post/denoise.wgsl" as "Params" {
        step: i32,
        first: u32,
        last: u32,
        guided: u32,
        sigma_color: f32,
        sigma_normal: f32,
        sigma_depth: f32,
        scale: f32,
    }
}

pub(crate) struct Denoise {
    kernel: Kernel,
    /// One uniform buffer per pass (step, first/last flags, sigmas); the demodulation
    /// pass's is the last.
    params: Vec<wgpu::Buffer>,
    iterations: u32,
    /// How the luminance tolerance is set, for the notes.
    guidance: &'static str,
    extent: Extent,
    ping_pong: Option<(Extent, Vec<PooledTexture>)>,
    /// A constant depth (1) in place of an unconnected depth guide.
    no_depth: Option<PooledTexture>,
}

/// Images of node-owned memory a Denoise pass with `iterations` uses.
fn scratch_images(iterations: u32) -> u64 {
    if iterations <= 1 { 1 } else { 2 }
}

/// Bytes of node-owned memory a Denoise pass over `extent` with `iterations` adds: two
/// `rgba32float` ping-pong images (one for a single iteration).
pub fn scratch_bytes(extent: Extent, iterations: u32) -> u64 {
    scratch_images(iterations) * extent.pixels() * TexFormat::Rgba32Float.bytes_per_pixel()
}

fn iterations(pass: &Pass) -> u32 {
    u32::try_from(pass.params.int("iterations"))
        .unwrap_or(1)
        .clamp(1, MAX_ITERATIONS)
}

impl Denoise {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let kernel = Kernel::new(ctx, "post/denoise.wgsl")?;
        let params = (0..=MAX_ITERATIONS)
            .map(|i| {
                uniform_buffer(
                    ctx,
                    &format!("denoise params {i}"),
                    bytemuck::bytes_of(&DenoiseParams::default()),
                )
            })
            .collect();
        let mut node = Self {
            kernel,
            params,
            iterations: 1,
            guidance: "",
            extent: pass.extent,
            ping_pong: None,
            no_depth: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Denoise {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        self.iterations = iterations(pass);
        let p = &pass.params;
        #[expect(clippy::cast_possible_truncation, reason = "params fit f32")]
        let (sigma_color, sigma_normal, sigma_depth) = (
            p.float("sigma_color") as f32,
            p.float("sigma_normal") as f32,
            p.float("sigma_depth") as f32,
        );
        let has_variance = pass.input("variance").is_some();
        self.guidance = match (p.bool("variance_guided"), has_variance) {
            (true, true) => "variance-guided luminance tolerance",
            (true, false) => {
                "fixed luminance tolerance (variance_guided is on, but no variance is connected)"
            }
            (false, _) => "fixed luminance tolerance (variance_guided off)",
        };
        let guided = u32::from(p.bool("variance_guided") && has_variance);
        let demodulate = DenoiseParams {
            first: 1,
            ..DenoiseParams::default()
        };
        ctx.queue.write_buffer(
            &self.params[MAX_ITERATIONS as usize],
            0,
            bytemuck::bytes_of(&demodulate),
        );
        for i in 0..self.iterations {
            let pass_i = i32::try_from(i).unwrap_or(0);
            let block = DenoiseParams {
                step: 1 << pass_i,
                first: 0,
                last: u32::from(i + 1 == self.iterations),
                guided,
                sigma_color,
                sigma_normal,
                sigma_depth,
                scale: 0.5_f32.powi(pass_i),
            };
            ctx.queue
                .write_buffer(&self.params[i as usize], 0, bytemuck::bytes_of(&block));
        }
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, mut timer) = rec.parts();
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        let extent = pass.extent;
        let images = scratch_images(self.iterations) as usize;
        if self
            .ping_pong
            .as_ref()
            .is_none_or(|(e, pp)| *e != extent || pp.len() != images)
        {
            let make = |i| {
                create(
                    ctx,
                    &format!("denoise ping-pong {i}"),
                    TexFormat::Rgba32Float,
                    extent,
                )
            };
            self.ping_pong = Some((extent, (0..images).map(make).collect()));
        }
        if pass.input("depth").is_none() {
            constant_r32(ctx, &mut self.no_depth, extent, 1.0);
        }
        let Some((_, pp)) = &self.ping_pong else {
            return Ok(());
        };
        let color = io.input(pass, "color")?;
        let variance = match pass.input("variance") {
            Some(t) => io.texture(t),
            None => color,
        };
        let albedo = io.input(pass, "albedo")?;
        let normal = io.input(pass, "normal")?;
        // Without a depth guide, a constant depth of 1 (0 would mean nothing was hit):
        // every depth difference is 0, its weight 1.
        let depth = match (pass.input("depth"), &self.no_depth) {
            (Some(t), _) => io.texture(t),
            (None, Some(z)) => z,
            (None, None) => return Err(RenderError::Gpu("no depth image".into())),
        };
        let output = &io.texture(out).view;
        // Pass -1 demodulates into image 0; pass i reads image i % 2 and writes the other
        // one, or the output for the last.
        let mut record = |src: &wgpu::TextureView,
                          dst: &wgpu::TextureView,
                          params: &wgpu::Buffer|
         -> Result<()> {
            self.kernel
                .pass(&pass.node)
                .read(src)
                .read(&variance.view)
                .read(&albedo.view)
                .read(&normal.view)
                .read(&depth.view)
                .write(dst)
                .uniform(params)
                .dispatch_2d(ctx, encoder, extent, timer.as_deref_mut())
        };
        record(
            &color.view,
            &pp[0].view,
            &self.params[MAX_ITERATIONS as usize],
        )?;
        for i in 0..self.iterations as usize {
            let src = &pp[i % 2].view;
            let dst = if i + 1 == self.iterations as usize {
                output
            } else {
                &pp[(i + 1) % 2].view
            };
            record(src, dst, &self.params[i])?;
        }
        Ok(())
    }

    fn notes(&self) -> Vec<String> {
        let bytes = scratch_bytes(self.extent, self.iterations);
        vec![format!(
            "demodulation + {} à-trous passes, ping-pong between {} node-owned rgba32f \
             images ({bytes} bytes); {}",
            self.iterations,
            scratch_images(self.iterations),
            self.guidance
        )]
    }
}
