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

/// One binding of a kernel, at `@group(0) @binding(i)` for the i-th entry, as the shader
/// declares it ([`reflect`] reads them from the WGSL).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Binding {
    /// `texture_2d<f32>`, read with `textureLoad`.
    Texture,
    /// `texture_2d_array<f32>`, read with `textureLoad`.
    TextureArray,
    /// `texture_2d<f32>` or `texture_3d<f32>` in a shader that declares a filtering
    /// `sampler`: bound as filterable float (`rgba32float` needs the adapter's
    /// `FLOAT32_FILTERABLE`, which [`GpuContext`] asks for).
    FilteredTexture {
        /// 2D or 3D.
        dim: wgpu::TextureViewDimension,
    },
    /// `texture_3d<f32>` read with `textureLoad` (no sampler in the shader).
    Texture3d,
    /// `sampler` (filtering; comparison samplers are not supported).
    Sampler,
    /// `texture_storage_2d<format, access>`.
    StorageTexture {
        /// Texel format.
        format: wgpu::TextureFormat,
        /// `read`, `write` or `read_write`.
        access: wgpu::StorageTextureAccess,
    },
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>` (or `read_write` when `read_only` is false).
    Storage {
        /// Whether the shader only reads it.
        read_only: bool,
    },
    /// `acceleration_structure` (ray queries, `lumagraph_pathtrace::accel`).
    AccelerationStructure,
}

impl Binding {
    fn layout_type(self) -> wgpu::BindingType {
        match self {
            Self::Texture => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            Self::FilteredTexture { dim } => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: dim,
                multisampled: false,
            },
            Self::TextureArray => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2Array,
                multisampled: false,
            },
            Self::Sampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            Self::Texture3d => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D3,
                multisampled: false,
            },
            Self::StorageTexture { format, access } => wgpu::BindingType::StorageTexture {
                access,
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
            Self::AccelerationStructure => wgpu::BindingType::AccelerationStructure {
                vertex_return: false,
            },
        }
    }

    /// What the pass builder calls this binding: the method that binds it.
    fn builder_method(self) -> &'static str {
        match self {
            Self::Texture
            | Self::TextureArray
            | Self::Texture3d
            | Self::FilteredTexture { .. }
            | Self::StorageTexture {
                access: wgpu::StorageTextureAccess::ReadOnly,
                ..
            } => "read",
            Self::StorageTexture { .. } => "write",
            Self::Uniform => "uniform",
            Self::Storage { .. } => "buffer",
            Self::Sampler => "sampler",
            Self::AccelerationStructure => "accel",
        }
    }
}

fn storage_format(format: naga::StorageFormat) -> Option<wgpu::TextureFormat> {
    use naga::StorageFormat as S;
    use wgpu::TextureFormat as T;
    Some(match format {
        S::Rgba32Float => T::Rgba32Float,
        S::Rgba16Float => T::Rgba16Float,
        S::R32Float => T::R32Float,
        S::Rg32Float => T::Rg32Float,
        S::Rgba8Unorm => T::Rgba8Unorm,
        S::R32Uint => T::R32Uint,
        _ => return None,
    })
}

/// The binding of a texture of dimension `dim` (`arrayed` or not) and `class`, bound
/// filterable where the shader has a sampler (`filtering`).
fn image_binding(
    dim: naga::ImageDimension,
    arrayed: bool,
    class: naga::ImageClass,
    filtering: bool,
) -> std::result::Result<Binding, String> {
    let float = matches!(
        class,
        naga::ImageClass::Sampled {
            kind: naga::ScalarKind::Float,
            multi: false,
        }
    );
    Ok(match (dim, arrayed, class) {
        (naga::ImageDimension::D3, false, _) if float => {
            if filtering {
                Binding::FilteredTexture {
                    dim: wgpu::TextureViewDimension::D3,
                }
            } else {
                Binding::Texture3d
            }
        }
        (naga::ImageDimension::D2, true, _) if float && !filtering => Binding::TextureArray,
        (naga::ImageDimension::D2, false, _) if float && filtering => Binding::FilteredTexture {
            dim: wgpu::TextureViewDimension::D2,
        },
        (naga::ImageDimension::D2, false, _) if float => Binding::Texture,
        (naga::ImageDimension::D2, false, naga::ImageClass::Storage { format, access }) => {
            Binding::StorageTexture {
                format: storage_format(format)
                    .ok_or_else(|| format!("storage format {format:?} is not supported"))?,
                access: match (
                    access.contains(naga::StorageAccess::LOAD),
                    access.contains(naga::StorageAccess::STORE),
                ) {
                    (true, true) => wgpu::StorageTextureAccess::ReadWrite,
                    (true, false) => wgpu::StorageTextureAccess::ReadOnly,
                    _ => wgpu::StorageTextureAccess::WriteOnly,
                },
            }
        }
        _ => return Err("this kind of texture is not supported".to_owned()),
    })
}

/// The bindings of group 0 of a compute shader, in binding order, and the workgroup size
/// of its entry point `main`, read from the WGSL with naga: a node states its bindings once,
/// in its shader.
///
/// # Errors
/// When the shader does not parse, has no entry point `main`, uses another bind group, leaves
/// a binding index out, or declares a binding kind kernels do not support.
pub fn reflect(label: &str, source: &str) -> Result<(Vec<Binding>, [u32; 3])> {
    let err = |message: String| RenderError::Shader {
        name: label.to_owned(),
        message,
    };
    let module = naga::front::wgsl::parse_str(source).map_err(|e| err(e.emit_to_string(source)))?;
    let entry = module
        .entry_points
        .iter()
        .find(|e| e.name == "main")
        .ok_or_else(|| err("no entry point `main`".to_owned()))?;
    // Textures are bound filterable exactly when the shader has a sampler to filter them.
    let filtering = module.global_variables.iter().any(|(_, var)| {
        matches!(
            module.types[var.ty].inner,
            naga::TypeInner::Sampler { comparison: false }
        )
    });
    let mut bindings: Vec<(u32, Binding)> = Vec::new();
    for (_, var) in module.global_variables.iter() {
        let Some(rb) = var.binding else { continue };
        let name = var.name.as_deref().unwrap_or("?");
        if rb.group != 0 {
            return Err(err(format!(
                "`{name}` is in group {}; kernels use group 0",
                rb.group
            )));
        }
        let binding = match (var.space, &module.types[var.ty].inner) {
            (naga::AddressSpace::Uniform, _) => Binding::Uniform,
            (naga::AddressSpace::Storage { access }, _) => Binding::Storage {
                read_only: !access.contains(naga::StorageAccess::STORE),
            },
            (naga::AddressSpace::Handle, naga::TypeInner::Sampler { comparison: false }) => {
                Binding::Sampler
            }
            (
                naga::AddressSpace::Handle,
                naga::TypeInner::AccelerationStructure {
                    vertex_return: false,
                },
            ) => Binding::AccelerationStructure,
            (
                naga::AddressSpace::Handle,
                &naga::TypeInner::Image {
                    dim,
                    arrayed,
                    class,
                },
            ) => image_binding(dim, arrayed, class, filtering)
                .map_err(|message| err(format!("`{name}`: {message}")))?,
            (_, inner) => {
                return Err(err(format!(
                    "`{name}` (binding {}): {inner:?} is not a supported binding",
                    rb.binding
                )));
            }
        };
        bindings.push((rb.binding, binding));
    }
    bindings.sort_by_key(|b| b.0);
    for (i, (b, _)) in bindings.iter().enumerate() {
        if *b as usize != i {
            return Err(err(format!(
                "binding {i} is missing (bindings must be 0, 1, 2, …)"
            )));
        }
    }
    Ok((
        bindings.into_iter().map(|b| b.1).collect(),
        entry.workgroup_size,
    ))
}

/// The sampler of filtering kernels: bilinear, clamped to the edge (no mipmaps).
pub fn linear_sampler(ctx: &GpuContext) -> wgpu::Sampler {
    ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("linear clamp"),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        address_mode_w: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Nearest,
        ..Default::default()
    })
}

/// The kernels compiled on a device, by their WGSL and entry points: a shader built again
/// with the same text (the same node in a new executor, a specialized shader of an
/// unchanged scene, a test's many renders) takes the pipelines already compiled instead
/// of compiling them again, which on a CPU adapter takes most of a second to several
/// seconds each. Holds the last [`KERNEL_CACHE_SIZE`] kernels built.
#[derive(Debug, Default)]
pub struct KernelCache {
    kernels: std::sync::Mutex<std::collections::VecDeque<(String, Vec<String>, Kernel)>>,
}

/// How many kernels a [`KernelCache`] keeps (the oldest goes first).
pub const KERNEL_CACHE_SIZE: usize = 48;

impl KernelCache {
    fn get(&self, source: &str, entry_points: &[&str]) -> Option<Kernel> {
        let kernels = self
            .kernels
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        kernels
            .iter()
            .find(|(s, e, _)| {
                s == source
                    && e.iter()
                        .map(String::as_str)
                        .eq(entry_points.iter().copied())
            })
            .map(|(_, _, k)| k.clone())
    }

    fn put(&self, source: &str, entry_points: &[&str], kernel: &Kernel) {
        let mut kernels = self
            .kernels
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if kernels.len() >= KERNEL_CACHE_SIZE {
            kernels.pop_front();
        }
        kernels.push_back((
            source.to_owned(),
            entry_points.iter().map(|e| (*e).to_owned()).collect(),
            kernel.clone(),
        ));
    }
}

/// A compute pipeline with the bindings its shader declares (and, where asked for, one per
/// further entry point of the same shader, bound alike).
#[derive(Clone, Debug)]
pub struct Kernel {
    label: String,
    pipeline: wgpu::ComputePipeline,
    /// The further entry points' pipelines, by name.
    entries: Vec<(String, wgpu::ComputePipeline)>,
    layout: wgpu::BindGroupLayout,
    bindings: Vec<Binding>,
    workgroup: [u32; 3],
}

impl Kernel {
    /// Builds a kernel from a shader file under `shaders/` (imports resolved), entry point
    /// `main`; its bindings and workgroup size are the shader's ([`reflect`]).
    ///
    /// # Errors
    /// When the shader is missing or does not compile.
    pub fn new(ctx: &GpuContext, shader: &str) -> Result<Self> {
        let source = crate::shader::resolve(shader)?;
        Self::from_source(ctx, shader, &source)
    }

    /// Builds a kernel from WGSL text (entry point `main`).
    ///
    /// # Errors
    /// When the shader does not compile or declares bindings kernels do not support.
    pub fn from_source(ctx: &GpuContext, label: &str, source: &str) -> Result<Self> {
        Self::with_entries(ctx, label, source, "main", &[])
    }

    /// [`Kernel::from_source`] with entry point `main` as the kernel's own pipeline (a shader
    /// whose `main` would not run names another, and `main` is then not built), and a pipeline
    /// for each of the further entry points `entry_points` too, chosen with
    /// [`PassBuilder::entry`]: a driver compiles each entry point on its own, with only the code
    /// it reaches (llvmpipe runs the code behind every `if`, taken or not, so a smaller entry
    /// point runs faster; and it builds all the code an entry point reaches before it leaves
    /// out what a constant rules out, so a smaller entry point also compiles faster).
    ///
    /// # Errors
    /// As [`Kernel::from_source`], and when an entry point is missing.
    pub fn with_entries(
        ctx: &GpuContext,
        label: &str,
        source: &str,
        main: &str,
        entry_points: &[&str],
    ) -> Result<Self> {
        let names: Vec<&str> = std::iter::once(main)
            .chain(entry_points.iter().copied())
            .collect();
        if let Some(kernel) = ctx.kernels.get(source, &names) {
            return Ok(Self {
                label: label.to_owned(),
                ..kernel
            });
        }
        let kernel = Self::compile(ctx, label, source, &names)?;
        ctx.kernels.put(source, &names, &kernel);
        Ok(kernel)
    }

    /// `names[0]` is the kernel's own pipeline, the others its further entry points.
    fn compile(ctx: &GpuContext, label: &str, source: &str, names: &[&str]) -> Result<Self> {
        let (bindings, workgroup) = reflect(label, source)?;
        let device = &ctx.device;
        if bindings
            .iter()
            .any(|b| matches!(b, Binding::FilteredTexture { .. }))
            && !device
                .features()
                .contains(wgpu::Features::FLOAT32_FILTERABLE)
        {
            return Err(RenderError::Shader {
                name: label.to_owned(),
                message: "filters float textures with a sampler, and this adapter cannot \
                          (no FLOAT32_FILTERABLE feature)"
                    .to_owned(),
            });
        }
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
        let create = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            })
        };
        // The entry points' pipelines on as many threads as there are cores: a driver
        // compiles the whole program for each (over a second each on a CPU adapter for the
        // path tracer's host intersection steps), and nothing orders them. No more threads
        // than cores: each compilation holds hundreds of MiB while it runs. Error scopes are
        // per thread.
        let next = std::sync::atomic::AtomicUsize::new(0);
        let threads = std::thread::available_parallelism()
            .map_or(1, std::num::NonZero::get)
            .min(names.len());
        let mut made: Vec<(usize, wgpu::ComputePipeline, Option<wgpu::Error>)> =
            std::thread::scope(|s| {
                let workers: Vec<_> = (0..threads)
                    .map(|_| {
                        s.spawn(|| {
                            let mut out = Vec::new();
                            loop {
                                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                                let Some(&e) = names.get(i) else { break out };
                                let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
                                let p = create(e);
                                out.push((i, p, pollster::block_on(scope.pop())));
                            }
                        })
                    })
                    .collect();
                workers
                    .into_iter()
                    .flat_map(|t| {
                        t.join()
                            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
                    })
                    .collect()
            });
        made.sort_by_key(|m| m.0);
        let mut first_error = pollster::block_on(scope.pop());
        let mut pipelines = Vec::with_capacity(made.len());
        for (_, p, e) in made {
            first_error = first_error.or(e);
            pipelines.push(p);
        }
        if let Some(e) = first_error {
            return Err(RenderError::Shader {
                name: label.to_owned(),
                message: e.to_string(),
            });
        }
        let mut pipelines = pipelines.into_iter();
        let pipeline = pipelines.next().ok_or_else(|| RenderError::Shader {
            name: label.to_owned(),
            message: "no pipeline was made".to_owned(),
        })?;
        let entries: Vec<_> = names[1..]
            .iter()
            .map(|e| (*e).to_owned())
            .zip(pipelines)
            .collect();
        Ok(Self {
            label: label.to_owned(),
            pipeline,
            entries,
            layout,
            bindings,
            workgroup,
        })
    }

    /// The bindings its shader declares, in binding order.
    pub fn bindings(&self) -> &[Binding] {
        &self.bindings
    }

    /// Starts recording a pass named `name` (the name its GPU time is reported under).
    pub fn pass<'a>(&'a self, name: &'a str) -> PassBuilder<'a> {
        PassBuilder {
            kernel: self,
            entry: None,
            name,
            resources: Vec::with_capacity(self.bindings.len()),
            methods: Vec::with_capacity(self.bindings.len()),
        }
    }
}

/// A pass being declared: its resources in binding order, then the dispatch. Each resource
/// is given by the method of its binding's kind — `read` (a sampled or read-only storage
/// texture), `write` (a writable storage texture), `sampler`, `uniform`, `buffer`
/// (storage) — and the dispatch refuses any other order or kind, naming the pass and the
/// binding.
#[derive(Debug)]
pub struct PassBuilder<'a> {
    kernel: &'a Kernel,
    /// A further entry point to run instead of `main`.
    entry: Option<&'a str>,
    name: &'a str,
    resources: Vec<wgpu::BindingResource<'a>>,
    methods: Vec<&'static str>,
}

impl<'a> PassBuilder<'a> {
    fn push(mut self, method: &'static str, resource: wgpu::BindingResource<'a>) -> Self {
        self.resources.push(resource);
        self.methods.push(method);
        self
    }

    /// Runs the kernel's further entry point `entry` (one given to
    /// [`Kernel::with_entries`]) instead of `main`.
    #[must_use]
    pub fn entry(mut self, entry: &'a str) -> Self {
        self.entry = Some(entry);
        self
    }

    /// A texture the pass reads.
    #[must_use]
    pub fn read(self, view: &'a wgpu::TextureView) -> Self {
        self.push("read", wgpu::BindingResource::TextureView(view))
    }

    /// A texture the pass writes.
    #[must_use]
    pub fn write(self, view: &'a wgpu::TextureView) -> Self {
        self.push("write", wgpu::BindingResource::TextureView(view))
    }

    /// A sampler.
    #[must_use]
    pub fn sampler(self, sampler: &'a wgpu::Sampler) -> Self {
        self.push("sampler", wgpu::BindingResource::Sampler(sampler))
    }

    /// A storage buffer.
    #[must_use]
    pub fn buffer(self, buffer: &'a wgpu::Buffer) -> Self {
        self.push("buffer", buffer.as_entire_binding())
    }

    /// A uniform buffer.
    #[must_use]
    pub fn uniform(self, buffer: &'a wgpu::Buffer) -> Self {
        self.push("uniform", buffer.as_entire_binding())
    }

    /// An acceleration structure (ray queries).
    #[must_use]
    pub fn accel(self, tlas: &'a wgpu::Tlas) -> Self {
        self.push("accel", tlas.as_binding())
    }

    /// Whether the resources given match the shader's bindings, one by one.
    ///
    /// # Errors
    /// At the first binding given by the wrong method (a written texture bound with `read`,
    /// a storage buffer with `uniform`…) or when there are too many or too few.
    pub fn check(&self) -> Result<()> {
        let declared = &self.kernel.bindings;
        let err = |message: String| RenderError::Shader {
            name: self.kernel.label.clone(),
            message: format!("pass \"{}\": {message}", self.name),
        };
        for (i, (b, given)) in declared.iter().zip(&self.methods).enumerate() {
            if b.builder_method() != *given {
                return Err(err(format!(
                    "binding {i} is {b:?}, bound with `{}`; the shader wants `{}`",
                    given,
                    b.builder_method()
                )));
            }
        }
        if declared.len() != self.methods.len() {
            return Err(err(format!(
                "{} resources given for {} bindings",
                self.methods.len(),
                declared.len()
            )));
        }
        Ok(())
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
        let [wx, wy, _] = self.kernel.workgroup;
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
        let entry = self.entry;
        self.bound(ctx)?.dispatch(encoder, entry, workgroups, timer)
    }

    /// The pass's bind group, made once, for several dispatches of the kernel's entry
    /// points (the steps of a wavefront, which bind the same resources again and again).
    ///
    /// # Errors
    /// When the resources given do not match the kernel's bindings.
    pub fn bound(self, ctx: &GpuContext) -> Result<BoundPass<'a>> {
        self.check()?;
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
        Ok(BoundPass {
            kernel: self.kernel,
            name: self.name,
            bind_group,
        })
    }
}

/// A pass whose resources are bound ([`PassBuilder::bound`]): dispatches of its kernel's
/// entry points, each recorded as a compute pass of its own.
#[derive(Debug)]
pub struct BoundPass<'a> {
    kernel: &'a Kernel,
    name: &'a str,
    bind_group: wgpu::BindGroup,
}

impl BoundPass<'_> {
    /// Records a dispatch of `entry` (`None`: `main`) over `workgroups`.
    ///
    /// # Errors
    /// When `entry` is not one of the kernel's entry points.
    pub fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        entry: Option<&str>,
        workgroups: [u32; 3],
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let pipeline = match entry {
            None => &self.kernel.pipeline,
            Some(entry) => self
                .kernel
                .entries
                .iter()
                .find(|(e, _)| e == entry)
                .map(|(_, p)| p)
                .ok_or_else(|| RenderError::Shader {
                    name: self.kernel.label.clone(),
                    message: format!("pass `{}`: no entry point `{entry}` built", self.name),
                })?,
        };
        let timestamp_writes = timer.and_then(|t| t.writes(self.name));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.name),
            timestamp_writes,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
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
