//! `ColorSpace` and `DisplayView`: OpenColorIO conversions on the GPU, each the compute
//! shader `lumagraph_color` generates for its processor (OpenColorIO's own WGSL), with its
//! LUT textures and uniforms. A param edit builds the program again; the config is loaded
//! again only when `config` changes.

use lumagraph_color::{ColorConfig, GpuProgram, LutTexture, Processor, Slot};
use lumagraph_graph::{Pass, PortType};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::kernel::{Kernel, uniform_buffer};
use crate::nodes::{NodeExec, NodeImpl, Recording, Resources, boxed};

/// The `ColorSpace` kind.
pub(crate) const COLOR_SPACE: NodeImpl = NodeImpl::new("ColorSpace", |ctx, pass, resources| {
    boxed(OcioNode::new(ctx, pass, resources))
});

/// The `DisplayView` kind.
pub(crate) const DISPLAY_VIEW: NodeImpl = NodeImpl::new("DisplayView", |ctx, pass, resources| {
    boxed(OcioNode::new(ctx, pass, resources))
});

/// The config of `pass` (its `config` param), relative paths from the graph's folder.
///
/// # Errors
/// What [`ColorConfig::load`] refuses.
pub fn config_of(pass: &Pass, resources: &Resources) -> Result<ColorConfig> {
    config_for(pass.params.str("config"), resources).map_err(color_error)
}

/// `image`, linear colour in the working space `space`, converted to scene-linear Rec. 709
/// in place (nothing to do in a Rec. 709 graph): what is sRGB-encoded for a PNG or a
/// preview, whose encoding is Rec. 709's.
///
/// # Errors
/// The conversion's config cannot be loaded (it is built in).
pub fn working_to_rec709(
    space: lumagraph_graph::WorkingSpace,
    image: &mut crate::cpu::Image,
) -> Result<()> {
    use lumagraph_graph::WorkingSpace;
    // The editor's viewer calls this for every preview frame: the processor (a built-in
    // config parsed, a CPU program made) is made once per process.
    static ACESCG: std::sync::OnceLock<std::result::Result<Processor, String>> =
        std::sync::OnceLock::new();
    let processor = match space {
        WorkingSpace::Rec709 => return Ok(()),
        WorkingSpace::AcesCg => ACESCG.get_or_init(|| {
            ColorConfig::load(
                lumagraph_graph::working_space::CONVERSION_CONFIG,
                std::path::Path::new("."),
            )
            .and_then(|c| c.processor(space.ocio_names()[0], WorkingSpace::Rec709.ocio_names()[0]))
            .map_err(|e| e.0)
        }),
    };
    let processor = processor
        .as_ref()
        .map_err(|e| RenderError::Gpu(e.clone()))?;
    processor.apply(bytemuck::cast_slice_mut(&mut image.pixels));
    Ok(())
}

/// The config `spec` names ([`ColorConfig::load`]), its working space the graph's.
///
/// # Errors
/// What [`ColorConfig::load`] refuses; a config without the graph's working space.
pub fn config_for(spec: &str, resources: &Resources) -> lumagraph_color::Result<ColorConfig> {
    ColorConfig::load(spec, &resources.base_dir)
        .and_then(|c| c.with_working_space(resources.working_space.ocio_names()))
}

pub(crate) fn color_error(e: lumagraph_color::Error) -> RenderError {
    RenderError::Gpu(e.0)
}

/// The processor a pass of either kind applies.
///
/// # Errors
/// An unknown colour space, display, view or look (the message lists the config's).
pub fn processor_of(pass: &Pass, config: &ColorConfig) -> Result<Processor> {
    let p = &pass.params;
    let processor = if pass
        .kind
        .outputs
        .first()
        .is_some_and(|o| o.ty == PortType::LdrColor)
    {
        config.display_processor(
            p.str("from"),
            p.str("display"),
            p.str("view"),
            p.str("looks"),
        )
    } else {
        config.processor(p.str("from"), p.str("to"))
    };
    processor.map_err(color_error)
}

struct OcioNode {
    resources: Resources,
    config: Option<(String, ColorConfig)>,
    program: Option<Built>,
}

/// A processor on the device: its kernel, uniform buffer and LUT textures.
pub(crate) struct Built {
    kernel: Kernel,
    uniforms: Option<wgpu::Buffer>,
    luts: Vec<wgpu::TextureView>,
    slots: Vec<Slot>,
}

impl Built {
    /// `processor` on the device, writing `format` (`rgba32float` or `rgba8unorm`).
    ///
    /// # Errors
    /// What OpenColorIO's shader generation refuses; a shader that does not compile.
    pub(crate) fn new(
        ctx: &GpuContext,
        label: &str,
        processor: &Processor,
        format: &str,
    ) -> Result<Self> {
        let program = processor.gpu_program(format).map_err(color_error)?;
        build(ctx, label, &program)
    }

    /// Records the conversion of `input` into `output` (both `extent`).
    ///
    /// # Errors
    /// A program whose uniforms are missing.
    pub(crate) fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        (input, output): (&wgpu::TextureView, &wgpu::TextureView),
        extent: lumagraph_graph::Extent,
        timer: Option<&mut crate::timing::GpuTimer>,
    ) -> Result<()> {
        let mut builder = self.kernel.pass(label);
        for slot in &self.slots {
            builder = match slot {
                Slot::Uniforms => match &self.uniforms {
                    Some(b) => builder.uniform(b),
                    None => {
                        return Err(RenderError::Gpu(
                            "OpenColorIO's uniforms are missing".into(),
                        ));
                    }
                },
                Slot::Lut(i) => builder.read(&self.luts[*i]),
                Slot::Input => builder.read(input),
                Slot::Output => builder.write(output),
            };
        }
        builder.dispatch_2d(ctx, encoder, extent, timer)
    }
}

impl OcioNode {
    fn new(ctx: &GpuContext, pass: &Pass, resources: &Resources) -> Result<Self> {
        let mut node = Self {
            resources: resources.clone(),
            config: None,
            program: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }
}

fn upload_lut(ctx: &GpuContext, lut: &LutTexture) -> wgpu::TextureView {
    let size = wgpu::Extent3d {
        width: lut.size[0],
        height: lut.size[1],
        depth_or_array_layers: lut.size[2],
    };
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("ocio lut"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: if lut.dimensions == 3 {
            wgpu::TextureDimension::D3
        } else {
            wgpu::TextureDimension::D2
        },
        format: if lut.single_channel {
            wgpu::TextureFormat::R32Float
        } else {
            wgpu::TextureFormat::Rgba32Float
        },
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    ctx.queue.write_texture(
        texture.as_image_copy(),
        &lut.bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(lut.bytes_per_row),
            rows_per_image: Some(lut.size[1]),
        },
        size,
    );
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

fn build(ctx: &GpuContext, label: &str, program: &GpuProgram) -> Result<Built> {
    Ok(Built {
        kernel: Kernel::from_source(ctx, label, &program.wgsl)?,
        uniforms: program
            .uniforms
            .as_ref()
            .map(|bytes| uniform_buffer(ctx, "ocio uniforms", bytes)),
        luts: program.luts.iter().map(|l| upload_lut(ctx, l)).collect(),
        slots: program.slots.clone(),
    })
}

impl NodeExec for OcioNode {
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()> {
        let spec = pass.params.str("config").to_owned();
        if self.config.as_ref().is_none_or(|(s, _)| *s != spec) {
            self.config = Some((spec, config_of(pass, &self.resources)?));
        }
        let Some((_, config)) = &self.config else {
            return Ok(());
        };
        let processor = processor_of(pass, config)?;
        let format = if pass
            .kind
            .outputs
            .first()
            .is_some_and(|o| o.ty == PortType::LdrColor)
        {
            "rgba8unorm"
        } else {
            "rgba32float"
        };
        self.program = Some(Built::new(ctx, &pass.node, &processor, format)?);
        Ok(())
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        let (Some(out), Some(built)) = (pass.output("color"), &self.program) else {
            return Ok(());
        };
        let input = &io.input(pass, "color")?.view;
        let output = &io.texture(out).view;
        built.encode(
            ctx,
            encoder,
            &pass.node,
            (input, output),
            pass.extent,
            timer,
        )
    }
}
