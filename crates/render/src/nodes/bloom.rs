//! `Bloom`: the image halved `levels` times (`shaders/post/bloom_down.wgsl`), the levels
//! added back from the smallest up (`shaders/post/bloom_up.wgsl`), and the sum over the
//! levels, divided by their number, mixed with the image by `intensity`. The pyramid's
//! images (each level and each partial sum) are node-owned, created once per size.

use lumagraph_graph::{Extent, Pass, TexFormat};

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, boxed};
use crate::pool::{PooledTexture, create};

/// The `Bloom` kind: it owns its pyramid.
pub(crate) const IMPL: NodeImpl =
    NodeImpl::new("Bloom", |ctx, pass, _| boxed(Bloom::new(ctx, pass))).owning(|pass| {
        let sizes = level_sizes(pass.extent, levels(pass));
        let pixels: u64 = sizes.iter().map(|e| e.pixels()).sum::<u64>() * 2
            - sizes.last().map_or(0, |e| e.pixels());
        Some((
            pixels * TexFormat::Rgba32Float.bytes_per_pixel(),
            format!(
                "{} pyramid levels and {} partial sums, rgba32f",
                sizes.len(),
                sizes.len().saturating_sub(1)
            ),
        ))
    });

crate::param_block! {
    /// The upsample-and-add pass's weights.
    pub(crate) struct BloomParams in "post/bloom_up.wgsl" as "Params" {
        fine_weight: f32,
        coarse_weight: f32,
        pad0: f32,
        pad1: f32,
    }
}

fn levels(pass: &Pass) -> usize {
    usize::try_from(pass.params.int("levels"))
        .unwrap_or(1)
        .max(1)
}

/// The sizes of levels 1… of the pyramid over `extent`: each half the last, rounded up;
/// it stops early when a level is 1×1.
pub fn level_sizes(extent: Extent, levels: usize) -> Vec<Extent> {
    let mut sizes = Vec::with_capacity(levels);
    let mut e = extent;
    for _ in 0..levels {
        if e.width == 1 && e.height == 1 {
            break;
        }
        e = Extent::new(e.width.div_ceil(2), e.height.div_ceil(2));
        sizes.push(e);
    }
    sizes
}

struct Pyramid {
    extent: Extent,
    /// The sizes of levels 1…n.
    sizes: Vec<Extent>,
    /// Levels 1…n.
    down: Vec<PooledTexture>,
    /// Partial sums of levels 1…n−1 (sum i holds levels i…n).
    sums: Vec<PooledTexture>,
}

/// The pyramid in `slot` for an image of `extent`, made anew when the size or the number of
/// levels changed.
fn pyramid<'p>(
    slot: &'p mut Option<Pyramid>,
    ctx: &GpuContext,
    extent: Extent,
    levels: usize,
) -> &'p Pyramid {
    let sizes = level_sizes(extent, levels);
    if slot
        .as_ref()
        .is_some_and(|p| p.extent == extent && p.sizes == sizes)
    {
        return slot.as_ref().expect("checked above");
    }
    let make = |what: &str, (i, e): (usize, &Extent)| {
        create(
            ctx,
            &format!("bloom {what} {}", i + 1),
            TexFormat::Rgba32Float,
            *e,
        )
    };
    let n = sizes.len();
    slot.insert(Pyramid {
        extent,
        down: sizes.iter().enumerate().map(|l| make("level", l)).collect(),
        sums: sizes[..n.saturating_sub(1)]
            .iter()
            .enumerate()
            .map(|l| make("sum", l))
            .collect(),
        sizes,
    })
}

struct Bloom {
    down: Kernel,
    up: Kernel,
    /// Weights (1, 1) for the partial sums, then the final mix's.
    params: [wgpu::Buffer; 2],
    pyramid: Option<Pyramid>,
    levels: usize,
}

impl Bloom {
    fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let zero = BloomParams::default();
        let mut node = Self {
            down: Kernel::new(ctx, "post/bloom_down.wgsl")?,
            up: Kernel::new(ctx, "post/bloom_up.wgsl")?,
            params: [0, 1].map(|i| {
                uniform_buffer(ctx, &format!("bloom params {i}"), bytemuck::bytes_of(&zero))
            }),
            pyramid: None,
            levels: 1,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Bloom {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        self.levels = levels(pass);
        let n = level_sizes(pass.extent, self.levels).len().max(1);
        #[expect(clippy::cast_possible_truncation, reason = "a weight in [0, 1]")]
        let intensity = pass.params.float("intensity") as f32;
        #[expect(clippy::cast_precision_loss, reason = "at most 12 levels")]
        let blocks = [
            BloomParams {
                fine_weight: 1.0,
                coarse_weight: 1.0,
                ..BloomParams::default()
            },
            BloomParams {
                fine_weight: 1.0 - intensity,
                coarse_weight: intensity / n as f32,
                ..BloomParams::default()
            },
        ];
        for (buffer, block) in self.params.iter().zip(&blocks) {
            ctx.queue.write_buffer(buffer, 0, bytemuck::bytes_of(block));
        }
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, mut timer) = rec.parts();
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        let input = io.input(pass, "color")?;
        let p = pyramid(&mut self.pyramid, ctx, pass.extent, self.levels);
        let (down, up, params, sizes) = (&self.down, &self.up, &self.params, &p.sizes);
        for (i, level) in p.down.iter().enumerate() {
            let src = if i == 0 {
                &input.view
            } else {
                &p.down[i - 1].view
            };
            down.pass(&pass.node)
                .read(src)
                .write(&level.view)
                .dispatch_2d(ctx, encoder, sizes[i], timer.as_deref_mut())?;
        }
        // Sum i = level i + up(sum i+1), from the smallest: the last sum adds the top level.
        let n = p.down.len();
        for i in (0..n.saturating_sub(1)).rev() {
            let coarse = if i + 1 == n - 1 {
                &p.down[n - 1]
            } else {
                &p.sums[i + 1]
            };
            up.pass(&pass.node)
                .read(&p.down[i].view)
                .read(&coarse.view)
                .write(&p.sums[i].view)
                .uniform(&params[0])
                .dispatch_2d(ctx, encoder, sizes[i], timer.as_deref_mut())?;
        }
        let glow = p.sums.first().or(p.down.first()).unwrap_or(input);
        up.pass(&pass.node)
            .read(&input.view)
            .read(&glow.view)
            .write(&io.texture(out).view)
            .uniform(&params[1])
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}
