//! Accumulate: progressive running mean with Kahan-compensated sums.
//!
//! The sums are history that outlives a frame, so they live in buffers the node owns, not
//! in the per-frame texture pool. [`NodeExec::reset`] clears them (scene or camera changed).

use lumagraph_graph::{Extent, Pass};

use crate::context::GpuContext;
use crate::error::Result;
use crate::kernel::{Binding, Kernel, uniform_buffer};
use crate::nodes::{FrameIo, NodeExec};
use crate::timing::GpuTimer;

pub(crate) struct Accumulate {
    kernel: Kernel,
    params: wgpu::Buffer,
    history: Option<(Extent, wgpu::Buffer, wgpu::Buffer)>,
    clear: bool,
}

impl Accumulate {
    pub(crate) fn new(ctx: &GpuContext) -> Result<Self> {
        let kernel = Kernel::new(
            ctx,
            "post/accumulate.wgsl",
            &[
                Binding::Texture,
                Binding::StorageTexture(wgpu::TextureFormat::Rgba32Float),
                Binding::Storage { read_only: false },
                Binding::Storage { read_only: false },
                Binding::Uniform,
            ],
        )?;
        let params = uniform_buffer(
            ctx,
            "accumulate params",
            bytemuck::bytes_of(&[1.0_f32, 0.0, 0.0, 0.0]),
        );
        Ok(Self {
            kernel,
            params,
            history: None,
            clear: true,
        })
    }
}

impl NodeExec for Accumulate {
    fn update(&mut self, _ctx: &GpuContext, _pass: &Pass) -> Result<()> {
        Ok(())
    }

    fn reset(&mut self) {
        self.clear = true;
    }

    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        pass: &Pass,
        io: &FrameIo<'_>,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let input = io.input(pass, "color")?;
        let Some(out) = pass.output("color") else {
            return Ok(());
        };
        let mut clear = std::mem::take(&mut self.clear);
        let extent = pass.extent;
        if self.history.as_ref().is_none_or(|(e, _, _)| *e != extent) {
            let make = |label| {
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: extent.pixels() * 16,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            };
            self.history = Some((
                extent,
                make("accumulate sum"),
                make("accumulate compensation"),
            ));
            clear = true;
        }
        let Some((_, sum, comp)) = &self.history else {
            return Ok(());
        };
        if clear {
            encoder.clear_buffer(sum, 0, None);
            encoder.clear_buffer(comp, 0, None);
        }
        self.kernel
            .pass(&pass.node)
            .read(&input.view)
            .write(&io.texture(out).view)
            .buffer(sum)
            .buffer(comp)
            .uniform(&self.params)
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}
