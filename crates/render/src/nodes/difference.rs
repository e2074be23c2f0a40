//! `Difference`: an image against a reference image. `shaders/post/difference.wgsl`
//! writes the heat map and one partial sum of the per-pixel error per 16×16 tile; the
//! measurement sums the tiles in f64 on the CPU after the frame. [`heat`] is the CPU
//! reference of the heat map; `render::metrics` holds the metrics.

use lumagraph_graph::{Extent, Pass};

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{Measurement, NodeExec, NodeImpl, Recording, boxed};
use crate::readback::ReadableBuffer;

/// The `Difference` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("Difference", |ctx, pass, _| {
    boxed(Difference::new(ctx, pass))
})
.owning(|pass| {
    Some((
        tiles(pass.extent) * 8,
        "one f32 per 16×16 tile, and its readback copy".to_owned(),
    ))
});

crate::param_block! {
    /// The shader's params.
    pub(crate) struct DifferenceParams in "post/difference.wgsl" as "Params" {
        metric: u32,
        max_error: f32,
        decades: f32,
        groups_x: u32,
    }
}

/// The metrics, in the registry's option order.
const METRICS: [&str; 2] = ["relmse", "rmse"];

const TILE: u32 = 16;

fn tiles(extent: Extent) -> u64 {
    u64::from(extent.width.div_ceil(TILE)) * u64::from(extent.height.div_ceil(TILE))
}

/// Inferno at 0, 1/4, 1/2, 3/4 and 1 (display-encoded), as the shader holds it.
const INFERNO: [[f32; 3]; 5] = [
    [0.0015, 0.0005, 0.0139],
    [0.2582, 0.0386, 0.4065],
    [0.5783, 0.1480, 0.4044],
    [0.8650, 0.3168, 0.2261],
    [0.9884, 0.9984, 0.6449],
];

/// The heat-map colour (display-encoded rgb) of per-pixel error `e`: inferno at
/// `1 + log10(e / max_error) / decades`, clamped to \[0, 1\]; 0 for no error.
pub fn heat(e: f32, max_error: f32, decades: f32) -> [f32; 3] {
    let t = if e <= 0.0 {
        0.0
    } else {
        (1.0 + (e / max_error).log2() / (decades * 10f32.log2())).clamp(0.0, 1.0)
    };
    let x = t * 4.0;
    #[expect(clippy::cast_possible_truncation, reason = "0 ≤ x ≤ 4")]
    #[expect(clippy::cast_sign_loss, reason = "0 ≤ x ≤ 4")]
    let i = (x as usize).min(3);
    #[expect(clippy::cast_precision_loss, reason = "i ≤ 3")]
    let f = x - i as f32;
    std::array::from_fn(|c| INFERNO[i][c] + (INFERNO[i + 1][c] - INFERNO[i][c]) * f)
}

struct Difference {
    kernel: Kernel,
    params: wgpu::Buffer,
    /// One f32 per tile.
    partial: ReadableBuffer,
    extent: Extent,
    /// The metric's option index, and whether a frame ran since the params last changed.
    metric: usize,
    ran: bool,
}

impl Difference {
    fn new(ctx: &GpuContext, pass: &Pass) -> Result<Self> {
        let extent = pass.extent;
        let mut node = Self {
            kernel: Kernel::new(ctx, "post/difference.wgsl")?,
            params: uniform_buffer(
                ctx,
                "difference params",
                bytemuck::bytes_of(&DifferenceParams::default()),
            ),
            partial: ReadableBuffer::new(ctx, "difference tiles", tiles(extent) * 4),
            extent,
            metric: 0,
            ran: false,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

impl NodeExec for Difference {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let metric = crate::params::enum_index(pass, "metric")?;
        self.metric = metric as usize;
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
        let block = DifferenceParams {
            metric,
            max_error: pass.params.float("max_error") as f32,
            decades: pass.params.int("decades") as f32,
            groups_x: self.extent.width.div_ceil(TILE),
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&block));
        self.ran = false;
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        let Some(out) = pass.output("heat") else {
            return Ok(());
        };
        self.kernel
            .pass(&pass.node)
            .read(&io.input(pass, "color")?.view)
            .read(&io.input(pass, "reference")?.view)
            .write(&io.texture(out).view)
            .buffer(&self.partial.buffer)
            .uniform(&self.params)
            .dispatch_2d(ctx, encoder, self.extent, timer)?;
        self.ran = true;
        Ok(())
    }

    fn measurements(&mut self, ctx: &GpuContext) -> Result<Vec<Measurement>> {
        if !self.ran {
            return Ok(Vec::new());
        }
        let sum: f64 = self.partial.read(ctx, |bytes| {
            bytemuck::cast_slice::<u8, f32>(bytes)
                .iter()
                .map(|&v| f64::from(v))
                .sum()
        })?;
        #[expect(clippy::cast_precision_loss, reason = "pixel counts")]
        let mean = sum / self.extent.pixels() as f64;
        let name = METRICS.get(self.metric).copied().unwrap_or(METRICS[0]);
        let value = if name == "rmse" { mean.sqrt() } else { mean };
        Ok(vec![Measurement::new(name, value)])
    }
}
