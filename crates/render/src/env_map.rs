//! The environment map on the GPU: texels with each pixel's sampling probability, and the
//! alias table that draws pixels by it (`shaders/pathtrace/env.wgsl`).
//!
//! A pixel's probability is proportional to the mean luminance of its 3×3 neighbourhood
//! (wrapping around in x) times `sin θ` at its center (the solid angle an equirectangular row
//! covers), so bright, large regions are sampled often; the shader turns it into a
//! solid-angle pdf with the same `sin θ`. The neighbourhood covers the texels the shader's
//! bilinear lookup (Mitsuba's) blends into the pixel, so every direction with radiance can
//! be sampled: light sampling alone converges to the same image.

use std::path::Path;

use lumagraph_scene::{alias_table, luminance};
use wgpu::util::DeviceExt as _;

use crate::context::GpuContext;
use crate::error::Result;

/// The map's buffers and size.
#[derive(Debug)]
pub struct EnvMap {
    /// `width × height` texels: rgb radiance, a = pixel probability.
    pub texels: wgpu::Buffer,
    /// Alias table over the pixels.
    pub alias: wgpu::Buffer,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

/// Texels with probabilities, and the alias table, of an equirectangular image. With
/// `uniform`, pixels are drawn by solid angle alone (uniform directions), the baseline
/// importance sampling is measured against.
pub fn tables(
    image: &crate::cpu::Image,
    uniform: bool,
) -> (Vec<[f32; 4]>, Vec<lumagraph_scene::GpuAliasEntry>) {
    let (w, h) = (image.width as usize, image.height as usize);
    let lum: Vec<f32> = image
        .pixels
        .iter()
        .map(|p| {
            let l = luminance(glam::Vec3::new(p[0], p[1], p[2]));
            if l.is_finite() { l.max(0.0) } else { 0.0 }
        })
        .collect();
    let mut weights = Vec::with_capacity(w * h);
    for y in 0..h {
        #[expect(clippy::cast_precision_loss, reason = "image rows")]
        let sin_theta = ((y as f64 + 0.5) / h as f64 * std::f64::consts::PI).sin();
        for x in 0..w {
            let l = if uniform {
                1.0
            } else {
                let mut sum = 0.0;
                for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                    for dx in [w - 1, 0, 1] {
                        sum += f64::from(lum[yy * w + (x + dx) % w]);
                    }
                }
                sum / 9.0
            };
            #[expect(clippy::cast_possible_truncation, reason = "weights in f32")]
            weights.push((l * sin_theta) as f32);
        }
    }
    let total: f64 = weights.iter().map(|&v| f64::from(v)).sum();
    let texels = image
        .pixels
        .iter()
        .zip(&weights)
        .map(|(p, &wgt)| {
            #[expect(clippy::cast_possible_truncation, reason = "probabilities in f32")]
            let prob = if total > 0.0 {
                (f64::from(wgt) / total) as f32
            } else {
                0.0
            };
            [p[0], p[1], p[2], prob]
        })
        .collect();
    (texels, alias_table(&weights))
}

impl EnvMap {
    /// Loads the image at `path` and uploads it with its sampling tables (`uniform`: see
    /// [`tables`]).
    ///
    /// # Errors
    /// When the image cannot be read.
    pub fn load(ctx: &GpuContext, path: &Path, uniform: bool) -> Result<Self> {
        let image = crate::image_io::load(path)?;
        let (texels, alias) = tables(&image, uniform);
        Ok(Self::upload(
            ctx,
            &texels,
            &alias,
            image.width,
            image.height,
        ))
    }

    /// A 1×1 black stand-in for scenes without a map (the bindings must exist).
    pub fn empty(ctx: &GpuContext) -> Self {
        let alias = [lumagraph_scene::GpuAliasEntry {
            prob: 1.0,
            other: 0,
        }; 2];
        Self::upload(ctx, &[[0.0; 4]; 1], &alias, 1, 1)
    }

    fn upload(
        ctx: &GpuContext,
        texels: &[[f32; 4]],
        alias: &[lumagraph_scene::GpuAliasEntry],
        width: u32,
        height: u32,
    ) -> Self {
        let buffer = |label, contents: &[u8]| {
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage: wgpu::BufferUsages::STORAGE,
                })
        };
        Self {
            texels: buffer("environment texels", bytemuck::cast_slice(texels)),
            alias: buffer("environment alias table", bytemuck::cast_slice(alias)),
            width,
            height,
        }
    }
}
