//! Compute kernels and the declarative pass builder.
//!
//! A [`Kernel`] is a compute pipeline plus the list of bindings its shader declares, in
//! binding order. Recording a pass reads like its declaration:
//!
//! ```text
//! kernel.pass("exposure").read(&input).write(&output).uniform(&params)
//!     .dispatch_2d(&ctx, encoder, extent, timer)?;
//! ```
//!
//! The builder checks the resources it was given against the declared bindings, so a
//! mismatch is an error naming the pass, not a validation panic deep in wgpu.

use lumagraph_graph::Extent;

use wgpu::util::DeviceExt as _;

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::timing::GpuTimer;

/// One binding of a kernel, at `@group(0) @binding(i)` for the i-th entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Binding {
    /// `texture_2d<f32>`, read with `textureLoad`.
    Texture,
    /// `texture_storage_2d<format, write>`.
    StorageTexture(wgpu::TextureFormat),
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>` (or `read_write` when `read_only` is false).
    Storage {
        /// Whether the shader only reads it.
        read_only: bool,
    },
}

impl Binding {
    fn layout_type(self) -> wgpu::BindingType {
        match self {
            Self::Texture => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            Self::StorageTexture(format) => wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
            Self::Uniform => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            Self::Storage { read_only } => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        }
    }

    fn is_texture(self) -> bool {
        matches!(self, Self::Texture | Self::StorageTexture(_))
    }
}

/// A compute pipeline with its declared bindings.
#[derive(Debug)]
pub struct Kernel {
    label: String,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    bindings: Vec<Binding>,
    workgroup: [u32; 2],
}

impl Kernel {
    /// Builds a kernel from a shader file under `shaders/` (imports resolved), entry point `main`,
    /// workgroup size 8×8.
    ///
    /// # Errors
    /// When the shader is missing or does not compile.
    pub fn new(ctx: &GpuContext, shader: &str, bindings: &[Binding]) -> Result<Self> {
        let source = crate::shader::resolve(shader)?;
        Self::from_source(ctx, shader, &source, bindings)
    }

    /// Builds a kernel from WGSL text (entry point `main`, workgroup size 8×8).
    ///
    /// # Errors
    /// When the shader does not compile or does not match `bindings`.
    pub fn from_source(
        ctx: &GpuContext,
        label: &str,
        source: &str,
        bindings: &[Binding],
    ) -> Result<Self> {
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let entries: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupLayoutEntry {
                binding: u32::try_from(i).unwrap_or(u32::MAX),
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: b.layout_type(),
                count: None,
            })
            .collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Shader {
                name: label.to_owned(),
                message: e.to_string(),
            });
        }
        Ok(Self {
            label: label.to_owned(),
            pipeline,
            layout,
            bindings: bindings.to_vec(),
            workgroup: [8, 8],
        })
    }

    /// Starts recording a pass named `name` (the name its GPU time is reported under).
    pub fn pass<'a>(&'a self, name: &'a str) -> PassBuilder<'a> {
        PassBuilder {
            kernel: self,
            name,
            resources: Vec::with_capacity(self.bindings.len()),
            kinds: Vec::with_capacity(self.bindings.len()),
        }
    }
}

/// A pass being declared: its resources in binding order, then the dispatch.
#[derive(Debug)]
pub struct PassBuilder<'a> {
    kernel: &'a Kernel,
    name: &'a str,
    resources: Vec<wgpu::BindingResource<'a>>,
    kinds: Vec<bool>,
}

impl<'a> PassBuilder<'a> {
    /// A texture the pass reads.
    #[must_use]
    pub fn read(mut self, view: &'a wgpu::TextureView) -> Self {
        self.resources
            .push(wgpu::BindingResource::TextureView(view));
        self.kinds.push(true);
        self
    }

    /// A texture the pass writes.
    #[must_use]
    pub fn write(self, view: &'a wgpu::TextureView) -> Self {
        self.read(view)
    }

    /// A uniform or storage buffer.
    #[must_use]
    pub fn buffer(mut self, buffer: &'a wgpu::Buffer) -> Self {
        self.resources.push(buffer.as_entire_binding());
        self.kinds.push(false);
        self
    }

    /// A uniform buffer.
    #[must_use]
    pub fn uniform(self, buffer: &'a wgpu::Buffer) -> Self {
        self.buffer(buffer)
    }

    /// Records the pass over an image of `extent`, one invocation per pixel.
    ///
    /// # Errors
    /// When the resources given do not match the kernel's bindings.
    pub fn dispatch_2d(
        self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        extent: Extent,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let [wx, wy] = self.kernel.workgroup;
        let groups = [extent.width.div_ceil(wx), extent.height.div_ceil(wy), 1];
        self.dispatch(ctx, encoder, groups, timer)
    }

    /// Records the pass with an explicit workgroup count.
    ///
    /// # Errors
    /// When the resources given do not match the kernel's bindings.
    pub fn dispatch(
        self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        workgroups: [u32; 3],
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let declared = &self.kernel.bindings;
        let matches = declared.len() == self.kinds.len()
            && declared
                .iter()
                .zip(&self.kinds)
                .all(|(b, &is_tex)| b.is_texture() == is_tex);
        if !matches {
            return Err(RenderError::Shader {
                name: self.kernel.label.clone(),
                message: format!(
                    "pass \"{}\" binds {} resources that do not match the declared {declared:?}",
                    self.name,
                    self.kinds.len()
                ),
            });
        }
        let entries: Vec<_> = self
            .resources
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: u32::try_from(i).unwrap_or(u32::MAX),
                resource,
            })
            .collect();
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.name),
            layout: &self.kernel.layout,
            entries: &entries,
        });
        let timestamp_writes = timer.and_then(|t| t.writes(self.name));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.name),
            timestamp_writes,
        });
        pass.set_pipeline(&self.kernel.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
        Ok(())
    }
}

/// Creates a read-only storage buffer holding `contents`.
pub fn storage_buffer(ctx: &GpuContext, label: &str, contents: &[u8]) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        })
}

/// Creates a uniform buffer holding `data`.
pub fn uniform_buffer(ctx: &GpuContext, label: &str, data: &[u8]) -> wgpu::Buffer {
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (data.len() as u64).next_multiple_of(16).max(16),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    ctx.queue.write_buffer(&buffer, 0, data);
    buffer
}
