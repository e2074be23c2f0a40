//! `OIDN`: Intel Open Image Denoise's `RT` filter on the CPU ([`crate::oidn`]).
//!
//! The node works on the host: [`OwnWork::submit_own`](crate::nodes::OwnWork::submit_own) runs after the graph's work so far
//! is submitted, reads the inputs back ([`crate::readback::read_texture`]), filters them and
//! writes the result into the output texture (`Queue::write_texture`, which lands before
//! the passes recorded after it); [`NodeExec::record`] records nothing. The last inputs
//! (as read back) and the result are kept: while the inputs and the params do not change,
//! as when a frame re-runs over an accumulation that did not move, the result is uploaded
//! again without filtering (the `oidn_filter_runs` counter counts the filterings).
//!
//! Inputs are cleaned before OIDN sees them: a non-finite value becomes 0, the color's rgb
//! is clamped to at least 0 and the albedo's to \[0, 1\], the ranges OIDN expects. The
//! output's alpha is the color's.

use std::sync::Arc;

use lumagraph_graph::{Extent, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::nodes::{Counter, FrameIo, NodeExec, NodeImpl, OwnWork, Recording, boxed};
use crate::oidn::{Filter, Images, Oidn, Quality, Settings};
use crate::readback::{read_texture, to_image};

/// The `OIDN` kind: it keeps its last inputs and result in host memory.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("OIDN", |_, pass, _| boxed(OidnNode::new(pass)))
    .owning(|pass| {
        Some((
            kept_bytes(pass),
            "host memory: the last inputs and result (rgba32f), to skip an unchanged \
             filtering; OIDN's own working memory besides"
                .to_owned(),
        ))
    });

/// Bytes of host memory a pass keeps between frames: its inputs as read back and the
/// result, 16 bytes a pixel each.
fn kept_bytes(pass: &Pass) -> u64 {
    let guides = ["albedo", "normal"]
        .iter()
        .filter(|g| pass.input(g).is_some())
        .count() as u64;
    (2 + guides) * pass.extent.pixels() * TexFormat::Rgba32Float.bytes_per_pixel()
}

/// What one filtering depends on: the params and the inputs' bytes as read back.
#[derive(PartialEq)]
struct Key {
    settings: Settings,
    prefilter: bool,
    inputs: [Option<Vec<u8>>; 3],
}

struct OidnNode {
    oidn: Arc<Oidn>,
    filter: Filter,
    /// The guides' own filters (albedo, normal), made when `prefilter` is first on.
    guide_filters: Option<[Filter; 2]>,
    settings: Settings,
    prefilter: bool,
    /// The last filtering's key and result.
    last: Option<(Key, Vec<[f32; 4]>)>,
    /// Filterings since the last reset.
    runs: u64,
}

impl OidnNode {
    fn new(pass: &Pass) -> Result<Self> {
        if pass.input("normal").is_some() && pass.input("albedo").is_none() {
            return Err(RenderError::External(
                "`normal` is connected without `albedo`: OIDN takes color, color + albedo, \
                 or color + albedo + normal"
                    .to_owned(),
            ));
        }
        let oidn = Oidn::load().map_err(RenderError::External)?;
        let filter = Filter::new(&oidn).map_err(RenderError::External)?;
        let mut node = Self {
            oidn,
            filter,
            guide_filters: None,
            settings: Settings {
                hdr: true,
                clean_aux: true,
                quality: Quality::High,
            },
            prefilter: false,
            last: None,
            runs: 0,
        };
        node.read_params(pass)?;
        Ok(node)
    }

    fn read_params(&mut self, pass: &Pass) -> Result<()> {
        let quality = pass.params.str("quality");
        self.settings = Settings {
            hdr: pass.params.bool("hdr"),
            clean_aux: pass.params.bool("clean_aux"),
            quality: Quality::from_name(quality).ok_or_else(|| {
                RenderError::External(format!("quality \"{quality}\" is not an OIDN preset"))
            })?,
        };
        self.prefilter = pass.params.bool("prefilter");
        Ok(())
    }

    /// Filters `inputs` (color, albedo, normal as read back) of `extent`.
    fn filter(&mut self, inputs: &[Option<Vec<u8>>; 3], extent: Extent) -> Result<Vec<[f32; 4]>> {
        let pixels = |i: usize, clean: fn(&mut [f32; 4])| {
            inputs[i].as_ref().map(|bytes| {
                let mut image = to_image(bytes, TexFormat::Rgba32Float, extent).pixels;
                image.iter_mut().for_each(clean);
                image
            })
        };
        let color = pixels(0, |p| clean(p, 0.0, f32::MAX)).unwrap_or_default();
        let albedo = pixels(1, |p| clean(p, 0.0, 1.0));
        let normal = pixels(2, |p| clean(p, f32::MIN, f32::MAX));
        let (width, height) = (extent.width as usize, extent.height as usize);
        let external = RenderError::External;
        // The guides, each through its own filter first when prefiltering.
        let (albedo, normal) = match (&mut self.guide_filters, albedo) {
            (filters, Some(albedo)) if self.prefilter => {
                let [albedo_filter, normal_filter] = match filters {
                    Some(f) => f,
                    slot @ None => slot.insert([
                        Filter::new(&self.oidn).map_err(external)?,
                        Filter::new(&self.oidn).map_err(external)?,
                    ]),
                };
                let guide = Settings {
                    hdr: false,
                    clean_aux: false,
                    quality: self.settings.quality,
                };
                let albedo = prefilter(albedo_filter, &albedo, false, extent, guide)?;
                let normal = normal
                    .map(|n| prefilter(normal_filter, &n, true, extent, guide))
                    .transpose()?;
                (Some(albedo), normal)
            }
            (_, albedo) => (albedo, normal),
        };
        let mut output = color.clone();
        let images = Images {
            width,
            height,
            color: Some(&color),
            albedo: albedo.as_deref(),
            normal: normal.as_deref(),
        };
        self.filter
            .run(&images, &mut output, self.settings)
            .map_err(external)?;
        self.runs += 1;
        Ok(output)
    }
}

/// `image`, a guide (the normal when `normal`, else the albedo), through `filter` alone.
fn prefilter(
    filter: &mut Filter,
    image: &[[f32; 4]],
    normal: bool,
    extent: Extent,
    settings: Settings,
) -> Result<Vec<[f32; 4]>> {
    let mut out = image.to_vec();
    let images = Images {
        width: extent.width as usize,
        height: extent.height as usize,
        color: None,
        albedo: (!normal).then_some(image),
        normal: normal.then_some(image),
    };
    filter
        .run(&images, &mut out, settings)
        .map_err(RenderError::External)?;
    Ok(out)
}

/// A non-finite value becomes 0; rgb is clamped to `[lo, hi]`.
fn clean(p: &mut [f32; 4], lo: f32, hi: f32) {
    for (i, v) in p.iter_mut().enumerate() {
        if !v.is_finite() {
            *v = 0.0;
        } else if i < 3 {
            *v = v.clamp(lo, hi);
        }
    }
}

impl NodeExec for OidnNode {
    fn own_work(&mut self) -> Option<&mut dyn OwnWork> {
        Some(self)
    }

    fn update(&mut self, _ctx: &GpuContext, pass: &Pass) -> Result<()> {
        self.read_params(pass)
    }

    fn reset(&mut self) {
        // A restarted accumulation is filtered again, even where it comes out the same
        // (a warm-up frame, then the render): its time is then what a filtering costs.
        self.runs = 0;
        self.last = None;
    }

    fn record(&mut self, _pass: &Pass, _rec: Recording<'_>) -> Result<()> {
        // The work is done on the host, in `submit_own`.
        Ok(())
    }

    fn notes(&self) -> Vec<String> {
        vec![format!(
            "Open Image Denoise {} on the CPU ({})",
            self.oidn.version(),
            self.oidn.library()
        )]
    }

    fn counters(&mut self, _ctx: &GpuContext) -> Result<Vec<Counter>> {
        Ok(vec![Counter::new("oidn_filter_runs", self.runs)])
    }
}

impl OwnWork for OidnNode {
    fn submits_own(&self) -> bool {
        true
    }

    fn submit_own(&mut self, ctx: &GpuContext, pass: &Pass, io: &FrameIo<'_>) -> Result<()> {
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        let extent = io.plan.texture(out).extent;
        let read = |port: &str| -> Result<Option<Vec<u8>>> {
            pass.input(port)
                .map(|t| {
                    let desc = io.plan.texture(t);
                    if desc.format != TexFormat::Rgba32Float || desc.extent != extent {
                        return Err(RenderError::External(format!(
                            "input \"{port}\" is {} {}, not rgba32f {extent}",
                            desc.format.name(),
                            desc.extent
                        )));
                    }
                    read_texture(ctx, &io.texture(t).texture, desc.format, extent)
                })
                .transpose()
        };
        let key = Key {
            settings: self.settings,
            prefilter: self.prefilter,
            inputs: [read("color")?, read("albedo")?, read("normal")?],
        };
        let output = match self.last.take() {
            Some((last, output)) if last == key => (key, output),
            _ => {
                let output = self.filter(&key.inputs, extent)?;
                (key, output)
            }
        };
        let texture = &io.texture(out).texture;
        ctx.queue.write_texture(
            texture.as_image_copy(),
            bytemuck::cast_slice(&output.1),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(extent.width * 16),
                rows_per_image: Some(extent.height),
            },
            wgpu::Extent3d {
                width: extent.width,
                height: extent.height,
                depth_or_array_layers: 1,
            },
        );
        self.last = Some(output);
        Ok(())
    }
}
