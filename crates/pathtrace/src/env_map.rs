//! The environment map on the GPU: texels with their sampling weights, and the alias table
//! that draws cells by them (`shaders/pathtrace/lights/env.wgsl`).
//!
//! Radiance is Mitsuba's `envmap` lookup: bilinear between texel values placed at
//! u = (x + ½) / W (wrapping around) and v = y / (H − 1). Sampling follows the same
//! interpolant: each texel point carries the weight luminance × sin θ (θ = π v, the solid
//! angle a row of the equirectangular map covers); a cell between four texel points is drawn
//! in proportion to its weights' mean, then a point in it from their bilinear interpolant.
//! The pdf in (u, v) is that interpolant over its integral, so it is proportional to the
//! interpolated luminance × sin θ up to sin θ's variation inside a cell, and positive
//! wherever the radiance is: light sampling alone converges to the same image.

use std::path::Path;

use lumagraph_scene::{alias_table, luminance};

use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use lumagraph_render::kernel::storage_buffer;

/// The map's buffers and size.
#[derive(Debug)]
pub struct EnvMap {
    /// `width × height` texels: rgb radiance, a = sampling weight over the interpolant's
    /// integral in (u, v) (the pdf in (u, v) at the texel point).
    pub texels: wgpu::Buffer,
    /// Alias table over the `width × (height − 1)` cells between texel points.
    pub alias: wgpu::Buffer,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels (at least 2).
    pub height: u32,
}

/// Texels with their (u, v) pdf, and the alias table over cells, of an equirectangular
/// image at least 2 pixels tall. With `uniform`, every texel has luminance 1 (uniform
/// directions up to the interpolation of sin θ), the baseline importance sampling is
/// measured against.
pub fn tables(
    image: &lumagraph_render::cpu::Image,
    uniform: bool,
) -> (Vec<[f32; 4]>, Vec<lumagraph_scene::GpuAliasEntry>) {
    let (w, h) = (image.width as usize, image.height as usize);
    let weights: Vec<f64> = image
        .pixels
        .iter()
        .enumerate()
        .map(|(i, p)| {
            #[expect(clippy::cast_precision_loss, reason = "image rows")]
            let sin_theta = ((i / w) as f64 / (h - 1) as f64 * std::f64::consts::PI).sin();
            let l = if uniform {
                1.0
            } else {
                f64::from(luminance(glam::Vec3::new(p[0], p[1], p[2])))
            };
            if l.is_finite() {
                l.max(0.0) * sin_theta
            } else {
                0.0
            }
        })
        .collect();
    // Cell (x, y) between texel points (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1),
    // wrapping in x; its integral is the corners' mean times its area 1 / (W (H − 1)).
    let mut cells = Vec::with_capacity(w * (h - 1));
    for y in 0..h - 1 {
        for x in 0..w {
            let x1 = (x + 1) % w;
            let c = weights[y * w + x]
                + weights[y * w + x1]
                + weights[(y + 1) * w + x]
                + weights[(y + 1) * w + x1];
            cells.push(0.25 * c);
        }
    }
    #[expect(clippy::cast_precision_loss, reason = "image sizes")]
    let total = cells.iter().sum::<f64>() / (w * (h - 1)) as f64;
    let texels = image
        .pixels
        .iter()
        .zip(&weights)
        .map(|(p, &wgt)| {
            #[expect(clippy::cast_possible_truncation, reason = "pdfs in f32")]
            let pdf = if total > 0.0 {
                (wgt / total) as f32
            } else {
                0.0
            };
            [p[0], p[1], p[2], pdf]
        })
        .collect();
    #[expect(clippy::cast_possible_truncation, reason = "weights in f32")]
    let cells: Vec<f32> = cells.iter().map(|&c| c as f32).collect();
    (texels, alias_table(&cells))
}

impl EnvMap {
    /// Loads the image at `path` and uploads it with its sampling tables (`uniform`: see
    /// [`tables`]).
    ///
    /// # Errors
    /// When the image cannot be read.
    pub fn load(ctx: &GpuContext, path: &Path, uniform: bool) -> Result<Self> {
        let image = lumagraph_render::image_io::load(path)?;
        if image.height < 2 {
            return Err(RenderError::Image {
                path: path.to_owned(),
                message: format!(
                    "environment map of {}x{} pixels: it must be at least 2 pixels tall",
                    image.width, image.height
                ),
            });
        }
        let (texels, alias) = tables(&image, uniform);
        Ok(Self::upload(
            ctx,
            &texels,
            &alias,
            image.width,
            image.height,
        ))
    }

    /// A 1×2 black stand-in for scenes without a map (the bindings must exist).
    pub fn empty(ctx: &GpuContext) -> Self {
        let alias = [lumagraph_scene::GpuAliasEntry {
            prob: 1.0,
            other: 0,
        }; 1];
        Self::upload(ctx, &[[0.0; 4]; 2], &alias, 1, 2)
    }

    fn upload(
        ctx: &GpuContext,
        texels: &[[f32; 4]],
        alias: &[lumagraph_scene::GpuAliasEntry],
        width: u32,
        height: u32,
    ) -> Self {
        Self {
            texels: storage_buffer(ctx, "environment texels", bytemuck::cast_slice(texels)),
            alias: storage_buffer(ctx, "environment alias table", bytemuck::cast_slice(alias)),
            width,
            height,
        }
    }
}
