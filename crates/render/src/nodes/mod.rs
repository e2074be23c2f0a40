//! GPU implementations of the node kinds, one file per kind, each named as in the registry.

pub(crate) mod accumulate;
pub(crate) mod auto_exposure;
pub(crate) mod bloom;
pub(crate) mod blur;
pub(crate) mod denoise;
pub mod difference;
mod image_input;
pub mod lut;
pub(crate) mod multi_layer_output;
pub mod ocio;
pub(crate) mod oidn;
pub mod output;
pub mod post_filter;
pub(crate) mod regression;
pub(crate) mod temporal;
pub(crate) mod tonemap;

use std::any::{Any, TypeId};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use lumagraph_graph::{Extent, Pass, Plan, TextureId};

use crate::context::GpuContext;
use crate::error::{RenderError, Result};
use crate::params::ParamBlock;
use crate::pool::PooledTexture;
use crate::timing::GpuTimer;

/// What nodes read from outside the graph: where relative paths point, and the scene.
#[derive(Clone, Debug, Default)]
pub struct Resources {
    /// Folder input paths are relative to (the graph file's folder).
    pub base_dir: PathBuf,
    /// Folder output paths are relative to; they must stay inside it (see
    /// [`lumagraph_graph::outputs`]) unless `outputs_anywhere` is set.
    pub out_dir: PathBuf,
    /// Write output paths that are absolute or leave `out_dir` as they are, instead of
    /// refusing them (`lumagraph render --allow-outputs-outside`).
    pub outputs_anywhere: bool,
    /// The colour space of the graph's colour images (the plan's; set by the executor).
    pub working_space: lumagraph_graph::WorkingSpace,
    /// The scene, flattened, for nodes that render one.
    pub scene: Option<Arc<lumagraph_scene::GpuScene>>,
    /// What kinds are asked for beyond their nodes' params, a value per type: the path
    /// tracer's `Tracing` (the command line's `--intersector` and `--schedule`, and the
    /// knobs tests and benchmarks turn), read only by the kind that defines the type.
    pub settings: Settings,
    /// What the graph's image-file sources read, per output port, for the sinks that
    /// write it back (filled as they load; see [`crate::image_io::Sources`]).
    pub sources: crate::image_io::Sources,
}

/// Settings of node kinds beyond their nodes' params, one value per type, each read by the
/// kind that defines the type (the frame graph names none of them).
#[derive(Clone, Default)]
pub struct Settings(Vec<(TypeId, &'static str, Arc<dyn Any + Send + Sync>)>);

impl Settings {
    /// The value of type `T`, if one was set.
    pub fn get<T: Any + Send + Sync>(&self) -> Option<&T> {
        self.0
            .iter()
            .find(|(id, _, _)| *id == TypeId::of::<T>())
            .and_then(|(_, _, v)| v.downcast_ref::<T>())
    }

    /// Sets the value of type `T`, replacing the one set before.
    pub fn set<T: Any + Send + Sync>(&mut self, value: T) {
        self.0.retain(|(id, _, _)| *id != TypeId::of::<T>());
        self.0.push((
            TypeId::of::<T>(),
            std::any::type_name::<T>(),
            Arc::new(value),
        ));
    }
}

impl std::fmt::Debug for Settings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.0.iter().map(|(_, name, _)| name))
            .finish()
    }
}

/// An image a sink would write: its pixels and what they are.
#[derive(Clone, Debug)]
pub struct HeldImage {
    /// Rows of `extent.width` pixels of `format`, no padding.
    pub bytes: Vec<u8>,
    /// Storage format.
    pub format: lumagraph_graph::TexFormat,
    /// What it holds.
    pub ty: lumagraph_graph::PortType,
    /// Size.
    pub extent: lumagraph_graph::Extent,
}

/// A one-channel float texture of `extent` holding `value` everywhere, for an optional
/// input left unconnected: made once in `slot`, again when the size changes.
pub(crate) fn constant_r32<'s>(
    ctx: &GpuContext,
    slot: &'s mut Option<PooledTexture>,
    extent: Extent,
    value: f32,
) -> &'s PooledTexture {
    if slot.as_ref().is_none_or(|t| t.extent != extent) {
        let t = crate::pool::create(
            ctx,
            "constant",
            lumagraph_graph::TexFormat::R32Float,
            extent,
        );
        let values = vec![value; extent.pixels() as usize];
        ctx.queue.write_texture(
            t.texture.as_image_copy(),
            bytemuck::cast_slice(&values),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(extent.width * 4),
                rows_per_image: Some(extent.height),
            },
            t.texture.size(),
        );
        *slot = Some(t);
    }
    slot.get_or_insert_with(|| {
        crate::pool::create(
            ctx,
            "constant",
            lumagraph_graph::TexFormat::R32Float,
            extent,
        )
    })
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

/// A value a node measures on its images (an error against a reference, the exposure it
/// chose), read back after a frame: the CLI prints them after a render, the editor shows
/// them beside the preview.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// What is measured (`relmse`, `exposure_ev`).
    pub name: &'static str,
    /// The value.
    pub value: f64,
}

impl Measurement {
    /// A measurement.
    pub fn new(name: &'static str, value: f64) -> Self {
        Self { name, value }
    }
}

impl Resources {
    /// An input path resolved against the base folder.
    pub fn input(&self, p: &str) -> PathBuf {
        self.base_dir.join(p)
    }

    /// An output path resolved against the output folder, inside it unless
    /// `outputs_anywhere` is set ([`lumagraph_graph::outputs::resolve_output`]).
    ///
    /// # Errors
    /// [`RenderError::OutsideOutput`] for a path that leaves the output folder.
    pub fn output(&self, p: &str) -> Result<PathBuf> {
        Ok(lumagraph_graph::outputs::resolve_output(
            &self.out_dir,
            p,
            self.outputs_anywhere,
        )?)
    }

    /// These resources with `value` as the setting of its type ([`Settings`]).
    #[must_use]
    pub fn with<T: Any + Send + Sync>(mut self, value: T) -> Self {
        self.settings.set(value);
        self
    }

    /// The setting of type `T` ([`Settings`]; its default where none was set).
    pub fn setting<T: Any + Send + Sync + Clone + Default>(&self) -> T {
        self.settings.get::<T>().cloned().unwrap_or_default()
    }

    /// These resources with the setting of type `T` changed by `change` (from its default
    /// where none was set).
    #[must_use]
    pub fn with_setting<T: Any + Send + Sync + Clone + Default>(
        mut self,
        change: impl FnOnce(&mut T),
    ) -> Self {
        let mut value = self.setting::<T>();
        change(&mut value);
        self.settings.set(value);
        self
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

/// What recording a pass works with: the device, the frame's command encoder, the frame's
/// textures, and the GPU timer when this frame is timed.
#[derive(Debug)]
pub struct Recording<'r> {
    /// The device and queue.
    pub ctx: &'r GpuContext,
    /// The frame's command encoder.
    pub encoder: &'r mut wgpu::CommandEncoder,
    /// The plan and the textures its ports are bound to.
    pub io: &'r FrameIo<'r>,
    /// Timestamp queries for this pass, when the frame is timed on them.
    pub timer: Option<&'r mut GpuTimer>,
}

/// A [`Recording`] taken apart: device, encoder, textures, timer.
pub type RecordingParts<'r> = (
    &'r GpuContext,
    &'r mut wgpu::CommandEncoder,
    &'r FrameIo<'r>,
    Option<&'r mut GpuTimer>,
);

impl<'r> Recording<'r> {
    /// Its parts, for a `let (ctx, encoder, io, timer) = rec.parts();` line.
    pub fn parts(self) -> RecordingParts<'r> {
        (self.ctx, self.encoder, self.io, self.timer)
    }
}

/// A node's GPU side as [`Any`], so the crate that defines a kind can reach its own node's
/// state through the [`Executor`](crate::Executor) (`Executor::node`); every `'static` type
/// has it.
pub trait AsAny {
    /// This node as [`Any`].
    fn as_any(&self) -> &dyn Any;
}

impl<T: Any> AsAny for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// A node's GPU side.
pub trait NodeExec: AsAny {
    /// Takes new param values (the kind and ports are unchanged).
    ///
    /// # Errors
    /// When a param cannot be applied (e.g. an input file fails to load).
    fn update(&mut self, ctx: &GpuContext, pass: &Pass) -> Result<()>;

    /// Forgets history kept across frames (progressive accumulation restarts).
    fn reset(&mut self) {}

    /// What a node that follows the view keeps of it (the camera, a tiled render's
    /// window: [`View`]); `None` (the default) for the others, whose history restarts when
    /// the camera moves ([`NodeExec::reset`]).
    fn view(&mut self) -> Option<&mut dyn View> {
        None
    }

    /// A sink's image for a tiled render to read instead of letting the sink write
    /// ([`Sink`]); `None` (the default) for other nodes.
    fn sink(&mut self) -> Option<&mut dyn Sink> {
        None
    }

    /// A node whose frames may include submissions of its own ([`OwnWork`]); `None` (the
    /// default) for the others.
    fn own_work(&mut self) -> Option<&mut dyn OwnWork> {
        None
    }

    /// Records this frame's GPU work.
    ///
    /// # Errors
    /// When recording fails.
    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()>;

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

    /// What the node measured on the last frame it ran (may read back from the GPU); empty
    /// before it ran.
    ///
    /// # Errors
    /// When the readback fails.
    fn measurements(&mut self, _ctx: &GpuContext) -> Result<Vec<Measurement>> {
        Ok(Vec::new())
    }

    /// The history this node keeps across frames (sums of samples, a sample counter), for
    /// checkpoints, partial renders and their merge ([`History`]); `None` (the default)
    /// when it keeps none.
    fn history(&mut self) -> Option<&mut dyn History> {
        None
    }

    /// Runs after the frame's GPU work finished; returns files written.
    ///
    /// # Errors
    /// When writing results fails.
    fn finish(&mut self, _ctx: &GpuContext, _pass: &Pass) -> Result<Vec<PathBuf>> {
        Ok(Vec::new())
    }
}

/// A node that follows the view: nodes that render the scene (`PathTrace`, `GBuffer`) and
/// those that reproject what they keep (`TemporalReuse`). A node has it through
/// [`NodeExec::view`].
pub trait View {
    /// The camera moved to `camera` (the scene is otherwise the same): nodes that render
    /// the scene render from it from the next frame on; a node that can carry its history
    /// into the new view (`TemporalReuse`) keeps it, the others restart it.
    fn move_camera(&mut self, camera: &lumagraph_scene::GpuCamera);

    /// Where the pass's images lie in the whole image, for a node that renders the scene
    /// (a tiled render's window: left and top; the size is the pass's extent).
    fn set_origin(&mut self, _origin: [u32; 2]) {}
}

/// A sink whose image a tiled render reads instead of letting it write
/// ([`crate::Executor::hold_sinks`]). A node has it through [`NodeExec::sink`].
pub trait Sink {
    /// The image the sink writes, as recorded in the last finishing frame (rows of
    /// `extent.width` pixels of `format`, no padding); `None` before one.
    ///
    /// # Errors
    /// When the readback fails.
    fn held_image(&mut self, ctx: &GpuContext) -> Result<Option<HeldImage>>;
}

/// A node whose frame's work may include submissions of its own, which must run after
/// what the graph recorded before the node (a frame traced in steps, each step submitted
/// and waited for; a denoiser on the host). The executor then submits the graph's work so
/// far and calls [`OwnWork::submit_own`] before [`NodeExec::record`], so no node submits
/// from inside `record`. A node has it through [`NodeExec::own_work`].
pub trait OwnWork {
    /// Whether this frame's work includes submissions of its own.
    fn submits_own(&self) -> bool;

    /// This frame's own submissions, before its pass is recorded.
    ///
    /// # Errors
    /// When the work fails.
    fn submit_own(&mut self, ctx: &GpuContext, pass: &Pass, io: &FrameIo<'_>) -> Result<()>;
}

/// The history a progressive node keeps across frames (`Accumulate`'s sums, `PathTrace`'s
/// sample counter): what a checkpoint saves and restores ([`crate::Checkpoint`]), a partial
/// render of a sample range starts from, and a merge of partial renders combines and
/// presents. A node has it through [`NodeExec::history`].
pub trait History {
    /// The history as bytes for a checkpoint. Reads back from the GPU.
    ///
    /// # Errors
    /// When the readback fails.
    fn save_state(&mut self, ctx: &GpuContext) -> Result<Vec<u8>>;

    /// Puts back what [`History::save_state`] returned, so the next frame continues exactly
    /// where the saved one stopped.
    ///
    /// # Errors
    /// When the bytes do not fit this node (another size, a truncated file).
    fn load_state(&mut self, ctx: &GpuContext, pass: &Pass, state: &[u8]) -> Result<()>;

    /// Starts the history at sample `first` of each pixel's sequence instead of 0, as if
    /// the samples before it had been taken elsewhere: a partial render of a sample range
    /// (`lumagraph render --samples`); `frames` took those samples.
    fn start_at_sample(&mut self, first: u32, frames: u64);

    /// While `present` is set, [`NodeExec::record`] writes the node's outputs from its
    /// history as it stands, adding nothing to it: the outputs of the frame that added the
    /// last sample. A merge of partial renders restores the merged history and presents it.
    fn set_present(&mut self, ctx: &GpuContext, present: bool);

    /// Combines the states ([`History::save_state`]) of several partial renders of disjoint
    /// sample ranges, in sample order, into the state of one render of them all.
    ///
    /// # Errors
    /// When the states do not fit together.
    fn merge_states(&mut self, states: &[&[u8]]) -> Result<Vec<u8>>;
}

/// What a pass of a kind specialized to the scene compiles in and leaves out, with these
/// resources (the intersector and schedule asked for) on an adapter with these traits (a CPU
/// one or a GPU, with or without ray queries); and why the pass would refuse to render, if
/// it would (an intersector or schedule asked for that cannot trace the scene there).
pub type ShaderFeatures =
    fn(&Pass, &lumagraph_scene::GpuScene, &Resources, crate::AdapterTraits) -> ShaderChoices;

/// A pass's shader choices for the scene, as [`ShaderFeatures`] finds them: lines that say
/// what is chosen, compiled in and left out, and why (`lumagraph plan` prints them), and why
/// the pass would refuse to render, if it would.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ShaderChoices {
    /// What is chosen, compiled in and left out, with why, a line each.
    pub lines: Vec<String>,
    /// Why the pass would refuse to render (an intersector or schedule asked for that
    /// cannot trace the scene on this adapter), if it would.
    pub refusal: Option<String>,
}

/// The size of the image a source produces from its params (paths relative to the folder
/// given), or why it cannot tell.
pub type SourceExtent = fn(&Path, &lumagraph_graph::Params) -> std::result::Result<Extent, String>;

/// How a node kind runs: one entry per kind, declared in the kind's own file (`IMPL`; the
/// built-in ones are listed in [`IMPLEMENTATIONS`]) and held with the kind in a
/// [`NodeLibrary`](crate::NodeLibrary). Nothing else in the program matches kind names:
/// what the rest needs to know of a kind is on its registry entry (and copied onto its
/// [`Pass`]) or here.
#[derive(Clone, Copy)]
pub struct NodeImpl {
    /// The registry kind it implements.
    pub kind: &'static str,
    /// Creates the GPU side of a pass of this kind.
    pub create: fn(&GpuContext, &Pass, &Resources) -> Result<Box<dyn NodeExec>>,
    /// Memory it allocates for itself, outside the plan's textures (history, scratch
    /// images, depth attachments), in bytes with what it is; the CLI's `plan` prints it.
    pub owned_memory: fn(&Pass) -> Option<(u64, String)>,
    /// For a source that does not render the scene: the size of the image it produces from
    /// its params (paths relative to the folder given), or why it cannot tell.
    pub source_extent: Option<SourceExtent>,
    /// For a kind whose shader is specialized to the scene: what a pass of it compiles in
    /// and leaves out for `scene` (with the resources given), for `lumagraph plan`.
    /// The adapter's traits say whether it is a CPU one (lavapipe), where other choices
    /// pay, and whether it has ray queries.
    pub features: Option<ShaderFeatures>,
}

impl std::fmt::Debug for NodeImpl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NodeImpl")
            .field("kind", &self.kind)
            .finish_non_exhaustive()
    }
}

impl NodeImpl {
    /// The implementation of `kind` made by `create`: no memory of its own, no source size,
    /// no shader features (the builder methods add them).
    pub const fn new(
        kind: &'static str,
        create: fn(&GpuContext, &Pass, &Resources) -> Result<Box<dyn NodeExec>>,
    ) -> Self {
        Self {
            kind,
            create,
            owned_memory: owns_nothing,
            source_extent: None,
            features: None,
        }
    }

    /// With memory of its own (see [`NodeImpl::owned_memory`]).
    #[must_use]
    pub const fn owning(mut self, owned_memory: fn(&Pass) -> Option<(u64, String)>) -> Self {
        self.owned_memory = owned_memory;
        self
    }

    /// A source telling its image size from its params.
    #[must_use]
    pub const fn sized_by(mut self, source_extent: SourceExtent) -> Self {
        self.source_extent = Some(source_extent);
        self
    }

    /// With shader features to list for a scene.
    #[must_use]
    pub const fn with_features(mut self, features: ShaderFeatures) -> Self {
        self.features = Some(features);
        self
    }
}

/// [`NodeImpl::owned_memory`] of a kind that owns no memory.
fn owns_nothing(_: &Pass) -> Option<(u64, String)> {
    None
}

/// Boxes a node's GPU side for [`NodeImpl::create`].
///
/// # Errors
/// `node`'s error, unchanged.
pub fn boxed<N: NodeExec + 'static>(node: Result<N>) -> Result<Box<dyn NodeExec>> {
    node.map(|n| Box::new(n) as Box<dyn NodeExec>)
}

/// Every built-in kind with an implementation of its own; with the generic post filters
/// ([`post_filter`]) they are exactly the built-in registry's kinds (a test checks it).
/// [`NodeLibrary::frame_graph`](crate::NodeLibrary::frame_graph) holds them.
pub static IMPLEMENTATIONS: &[NodeImpl] = &[
    image_input::IMPL,
    multi_layer_output::IMPL,
    ocio::COLOR_SPACE,
    ocio::DISPLAY_VIEW,
    accumulate::IMPL,
    temporal::IMPL,
    denoise::IMPL,
    regression::IMPL,
    oidn::IMPL,
    blur::IMPL,
    bloom::IMPL,
    lut::IMPL,
    difference::IMPL,
    auto_exposure::IMPL,
    tonemap::IMPL,
    output::IMPL,
];

/// The pass of a post-processing node: its inputs in declaration order (each a texture
/// binding; an unconnected optional input gets a 1×1 texture of zeros), a bilinear sampler
/// when the shader declares one (`shaders/post/resample.wgsl`), its outputs in declaration
/// order (each a storage texture of the size the port's rule gives; an output nothing reads
/// gets a 1×1 stand-in, so stores there are dropped), one uniform param block (none when the kind has nothing to pass). The dispatch
/// covers the first output's size.
pub(crate) struct FilterPass {
    kernel: crate::kernel::Kernel,
    params: wgpu::Buffer,
    sampler: Option<wgpu::Sampler>,
    /// 1×1 stand-ins for unbound ports, by format, made when first needed.
    stand_ins: Vec<(lumagraph_graph::TexFormat, PooledTexture)>,
}

impl FilterPass {
    /// Compiles `shader` (bindings: input texture, output storage texture, uniform) with its
    /// param block holding `params`.
    ///
    /// # Errors
    /// When the shader does not compile.
    pub(crate) fn new(
        ctx: &GpuContext,
        shader: &lumagraph_graph::registry::Shader,
        params: &[u8],
    ) -> Result<Self> {
        use crate::kernel::{Binding, Kernel, linear_sampler, uniform_buffer};
        use lumagraph_graph::registry::Shader;
        let kernel = match shader {
            Shader::File(name) => Kernel::new(ctx, name)?,
            Shader::Generated(g) => Kernel::from_source(ctx, &g.label, &g.text)?,
        };
        let sampler = kernel
            .bindings()
            .contains(&Binding::Sampler)
            .then(|| linear_sampler(ctx));
        Ok(Self {
            kernel,
            params: uniform_buffer(ctx, shader.label(), params),
            sampler,
            stand_ins: Vec::new(),
        })
    }

    /// Writes the param block.
    pub(crate) fn set_params(&self, ctx: &GpuContext, params: &[u8]) {
        ctx.queue.write_buffer(&self.params, 0, params);
    }

    /// Makes the 1×1 stand-ins `pass` needs (zeros: GPU textures start cleared).
    fn make_stand_ins(&mut self, ctx: &GpuContext, pass: &Pass) {
        let missing_inputs = pass
            .kind
            .inputs
            .iter()
            .filter(|i| pass.input(i.name).is_none())
            .map(|_| lumagraph_graph::TexFormat::Rgba32Float);
        let missing_outputs = pass
            .kind
            .outputs
            .iter()
            .filter(|o| pass.output(o.name).is_none())
            .map(|o| o.ty.format());
        for format in missing_inputs.chain(missing_outputs) {
            if !self.stand_ins.iter().any(|(f, _)| *f == format) {
                let t = crate::pool::create(
                    ctx,
                    "unbound port",
                    format,
                    lumagraph_graph::Extent::new(1, 1),
                );
                self.stand_ins.push((format, t));
            }
        }
    }

    /// Records the pass over `pass`'s ports.
    ///
    /// # Errors
    /// When a required input is not bound or the bindings do not match the kernel.
    pub(crate) fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, timer) = rec.parts();
        let Some(size) = pass
            .kind
            .outputs
            .iter()
            .find_map(|o| pass.output(o.name))
            .map(|t| io.plan.texture(t).extent)
        else {
            return Ok(());
        };
        self.make_stand_ins(ctx, pass);
        let stand_in = |format| {
            self.stand_ins
                .iter()
                .find(|(f, _)| *f == format)
                .map(|(_, t)| &t.view)
                .ok_or_else(|| RenderError::Gpu("no stand-in texture".into()))
        };
        let mut builder = self.kernel.pass(&pass.node);
        for i in &pass.kind.inputs {
            builder = match pass.input(i.name) {
                Some(t) => builder.read(&io.texture(t).view),
                None if i.optional => {
                    builder.read(stand_in(lumagraph_graph::TexFormat::Rgba32Float)?)
                }
                None => builder.read(&io.input(pass, i.name)?.view),
            };
        }
        if let Some(sampler) = &self.sampler {
            builder = builder.sampler(sampler);
        }
        for o in &pass.kind.outputs {
            builder = match pass.output(o.name) {
                Some(t) => builder.write(&io.texture(t).view),
                None => builder.write(stand_in(o.ty.format())?),
            };
        }
        if self.kernel.bindings().last() == Some(&crate::kernel::Binding::Uniform) {
            builder = builder.uniform(&self.params);
        }
        builder.dispatch_2d(ctx, encoder, size, timer)
    }
}

/// A [`FilterPass`] whose params are the block `P` (which names the shader).
pub(crate) struct ColorFilter<P: ParamBlock> {
    pass: FilterPass,
    block: std::marker::PhantomData<P>,
}

impl<P: ParamBlock> ColorFilter<P> {
    /// Compiles the shader of `P`.
    ///
    /// # Errors
    /// When the shader does not compile.
    pub(crate) fn new(ctx: &GpuContext) -> Result<Self> {
        Ok(Self {
            pass: FilterPass::new(
                ctx,
                &lumagraph_graph::registry::Shader::File(P::LAYOUT.shader),
                bytemuck::bytes_of(&P::zeroed()),
            )?,
            block: std::marker::PhantomData,
        })
    }

    /// Writes the param block.
    pub(crate) fn set_params(&self, ctx: &GpuContext, params: &P) {
        self.pass.set_params(ctx, bytemuck::bytes_of(params));
    }

    /// Records the pass (see [`FilterPass::record`]).
    ///
    /// # Errors
    /// As [`FilterPass::record`].
    pub(crate) fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        self.pass.record(pass, rec)
    }
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

#[cfg(test)]
mod post_filter_tests {
    /// Every generic post filter's shader keeps the contract (bindings, output format,
    /// `Params` = the node's params by name, in order, as packed).
    #[test]
    fn every_post_filter_shader_matches_its_registry_entry() {
        let registry = lumagraph_graph::Registry::with_builtins();
        let filters: Vec<_> = registry
            .kinds()
            .iter()
            .filter(|k| k.shader.is_some())
            .collect();
        assert!(filters.len() >= 2);
        let failures: Vec<String> = filters
            .iter()
            .filter_map(|k| super::post_filter::check(k).err())
            .collect();
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    /// A shader whose `Params` differs from the node's params is caught: the contract test
    /// fails on a kind pointed at another filter's shader.
    #[test]
    fn a_shader_that_does_not_match_its_params_is_caught() {
        let registry = lumagraph_graph::Registry::with_builtins();
        let mut vignette = lumagraph_graph::NodeKind::clone(registry.get("Vignette").unwrap());
        vignette.shader = Some(lumagraph_graph::registry::Shader::File(
            "post/exposure.wgsl",
        ));
        let e = super::post_filter::check(&vignette).unwrap_err();
        assert!(
            e.contains("struct Params has") && e.contains("strength"),
            "{e}"
        );
    }
}
