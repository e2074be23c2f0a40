//! GPU implementations of the node kinds, one file per kind, each named as in the registry.

mod accumulate;
mod denoise;
mod exposure;
mod gbuffer;
mod image_input;
mod output;
mod pathtrace;
mod tonemap;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use lumagraph_graph::{Pass, Plan, TextureId};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::pool::PooledTexture;
use crate::timing::GpuTimer;

/// What nodes read from outside the graph: where relative paths point, and the scene.
#[derive(Clone, Debug, Default)]
pub struct Resources {
    /// Folder input paths are relative to (the graph file's folder).
    pub base_dir: PathBuf,
    /// Folder output paths are relative to.
    pub out_dir: PathBuf,
    /// The scene, flattened, for nodes that render one.
    pub scene: Option<Arc<lumagraph_scene::GpuScene>>,
    /// Use the general shaders even where a scene-specialized one exists (benchmarks).
    pub general_shaders: bool,
    /// In the specialized shader, keep materials, lights and shading data in their storage
    /// buffers even where they could be written into the code (tests and benchmarks).
    pub scene_data_in_buffers: bool,
}

/// A named count a node keeps (samples, rays, dropped samples), since its last reset.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Counter {
    /// What is counted.
    pub name: &'static str,
    /// The count.
    pub value: u64,
}

impl Counter {
    /// A counter.
    pub fn new(name: &'static str, value: u64) -> Self {
        Self { name, value }
    }
}

impl Resources {
    /// An input path resolved against the base folder.
    pub fn input(&self, p: &str) -> PathBuf {
        self.base_dir.join(p)
    }

    /// An output path resolved against the output folder.
    pub fn output(&self, p: &str) -> PathBuf {
        self.out_dir.join(p)
    }
}

/// What a node sees of the frame: the plan and the textures its ports are bound to.
#[derive(Debug)]
pub struct FrameIo<'a> {
    /// The plan being executed.
    pub plan: &'a Plan,
    /// One texture per plan slot.
    pub slots: &'a [PooledTexture],
}

impl FrameIo<'_> {
    /// The texture holding logical texture `id`.
    pub fn texture(&self, id: TextureId) -> &PooledTexture {
        &self.slots[self.plan.textures[id.0].slot]
    }

    /// The texture bound to input `port` of `pass`.
    ///
    /// # Errors
    /// When the port is not bound (a plan/implementation mismatch).
    pub fn input(&self, pass: &Pass, port: &str) -> Result<&PooledTexture> {
        pass.input(port)
            .map(|t| self.texture(t))
            .ok_or_else(|| RenderError::Gpu(format!("input \"{port}\" is not bound")))
    }
}

/// A node's GPU side.
pub trait NodeExec {
    /// Takes new param values (the kind and ports are unchanged).
    ///
    /// # Errors
    /// When a param cannot be applied (e.g. an input file fails to load).
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()>;

    /// Forgets history kept across frames (progressive accumulation restarts).
    fn reset(&mut self) {}

    /// Records this frame's GPU work.
    ///
    /// # Errors
    /// When recording fails.
    fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        pass: &Pass,
        io: &FrameIo<'_>,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()>;

    /// Lines describing how the node was set up (shader specialization and such).
    fn notes(&self) -> Vec<String> {
        Vec::new()
    }

    /// The node's counters since its last reset (may read back from the GPU).
    ///
    /// # Errors
    /// When the readback fails.
    fn counters(&mut self, _ctx: &GpuContext) -> Result<Vec<Counter>> {
        Ok(Vec::new())
    }

    /// Runs after the frame's GPU work finished; returns files written.
    ///
    /// # Errors
    /// When writing results fails.
    fn finish(&mut self, _ctx: &GpuContext, _pass: &Pass) -> Result<Vec<PathBuf>> {
        Ok(Vec::new())
    }
}

/// Memory a node allocates for itself, outside the plan's textures (history, scratch
/// images, depth attachments), in bytes with what it is; `None` for nodes that own none.
/// The CLI's `plan` prints it beside the plan's textures.
pub fn owned_memory(pass: &Pass) -> Option<(u64, String)> {
    let px = pass.extent.pixels();
    match pass.kind {
        "Accumulate" => {
            let buffers = if pass.output("variance").is_some() {
                3
            } else {
                2
            };
            Some((
                buffers * 16 * px,
                format!(
                    "{buffers} history buffers of 16 B per pixel (sum, compensation{})",
                    if buffers == 3 { ", second moment" } else { "" }
                ),
            ))
        }
        "Denoise" => {
            let n = u32::try_from(pass.params.int("iterations")).unwrap_or(1);
            let bytes = denoise::scratch_bytes(pass.extent, n);
            let what = if n > 1 {
                "2 rgba32f ping-pong images"
            } else {
                "1 rgba32f image (demodulated input)"
            };
            Some((bytes, what.to_owned()))
        }
        "GBuffer" => Some((4 * px, "depth attachment (depth32float)".to_owned())),
        _ => None,
    }
}

/// The common shape of a post-processing node: `color` in, `color` out (in `out_format`),
/// one 16-byte uniform block of params; the nodes differ only in their shader and params.
pub(crate) struct ColorFilter {
    kernel: crate::kernel::Kernel,
    params: wgpu::Buffer,
}

impl ColorFilter {
    /// Compiles `shader` (bindings: input texture, output storage texture, uniform).
    ///
    /// # Errors
    /// When the shader does not compile.
    pub(crate) fn new(
        ctx: &GpuContext,
        shader: &str,
        out_format: wgpu::TextureFormat,
    ) -> Result<Self> {
        use crate::kernel::{Binding, Kernel, uniform_buffer};
        let kernel = Kernel::new(
            ctx,
            shader,
            &[
                Binding::Texture,
                Binding::StorageTexture(out_format),
                Binding::Uniform,
            ],
        )?;
        let params = uniform_buffer(ctx, shader, &[0; 16]);
        Ok(Self { kernel, params })
    }

    /// Writes the params block.
    pub(crate) fn set_params(&self, ctx: &GpuContext, bytes: &[u8; 16]) {
        ctx.queue.write_buffer(&self.params, 0, bytes);
    }

    /// Records the pass over `pass`'s `color` ports.
    ///
    /// # Errors
    /// When the input is not bound or the bindings do not match the kernel.
    pub(crate) fn record(
        &self,
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
        self.kernel
            .pass(&pass.node)
            .read(&input.view)
            .write(&io.texture(out).view)
            .uniform(&self.params)
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}

/// Creates the GPU side of the node a pass runs.
///
/// # Errors
/// When the kind has no implementation or its setup fails; the error names the node.
pub fn create(ctx: &GpuContext, pass: &Pass, paths: &Resources) -> Result<Box<dyn NodeExec>> {
    let node: Result<Box<dyn NodeExec>> = match pass.kind {
        "ImageInput" => image_input::ImageInput::new(ctx, pass, paths).map(|n| Box::new(n) as _),
        "Accumulate" => accumulate::Accumulate::new(ctx, pass).map(|n| Box::new(n) as _),
        "Exposure" => exposure::Exposure::new(ctx, pass).map(|n| Box::new(n) as _),
        "Tonemap" => tonemap::Tonemap::new(ctx, pass).map(|n| Box::new(n) as _),
        "PathTrace" => pathtrace::PathTrace::new(ctx, pass, paths).map(|n| Box::new(n) as _),
        "GBuffer" => gbuffer::GBuffer::new(ctx, pass, paths).map(|n| Box::new(n) as _),
        "Denoise" => denoise::Denoise::new(ctx, pass).map(|n| Box::new(n) as _),
        "Output" => output::Output::new(ctx, pass, paths).map(|n| Box::new(n) as _),
        other => Err(RenderError::Unimplemented(other.to_owned())),
    };
    node.map_err(|e| e.in_node(&pass.node))
}

/// Checks that `path` can be written, by creating and removing a temporary file beside it
/// (creating missing folders first), so a long render does not fail at the very end.
///
/// # Errors
/// When the folder cannot be created or written.
pub fn check_writable(path: &Path) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)
        .and_then(|()| {
            tempfile::Builder::new()
                .prefix(".lumagraph-check")
                .tempfile_in(dir)
                .map(|_| ())
        })
        .map_err(|e| RenderError::image(path, format!("cannot write output: {e}")))
}
