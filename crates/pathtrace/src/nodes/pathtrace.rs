//! `PathTrace`: the path tracer's node. Each frame adds `samples_per_frame` samples per
//! pixel and writes their mean, through the WGSL megakernel (`shaders/pathtrace/`)
//! specialized to the scene ([`crate::specialize`]), whose rays one of the intersectors
//! traces ([`crate::intersect`]: inline, the binary or 8-wide BVH, ray
//! queries, or the host's Embree through [`crate::host_rays`]).

use lumagraph_graph::Pass;

use wgpu::util::DeviceExt as _;

use lumagraph_graph::TexFormat;
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use lumagraph_render::kernel::{Kernel, uniform_buffer};
use lumagraph_render::shared::{CHUNK_FIRST, CHUNK_LAST, WAVE_FINISH};

use crate::host_rays::HostCounts;
use crate::scene_gpu::SceneBuffers;
use crate::specialize::{Feature, Features};
use lumagraph_render::kernel::PassBuilder;
use lumagraph_render::nodes::{
    Counter, FrameIo, History, NodeExec, NodeImpl, OwnWork, Recording, Resources, View, boxed,
};
use lumagraph_render::pool::{PooledTexture, create};
use lumagraph_render::readback::map_read;

/// `stats` slots: dropped (non-finite) samples, rays traced (low, high 32 bits), samples
/// adaptive sampling took (since the last read); then the wavefront's list counts
/// ([`lumagraph_render::shared::WAVE_COUNTS_AT`]).
const STATS: u64 = 8;

mod adaptive;
mod history;
mod steps;

use adaptive::Adaptive;
use steps::submit_pending;

/// The `PathTrace` kind.
pub(crate) const IMPL: NodeImpl = NodeImpl::new("PathTrace", |ctx, pass, resources| {
    boxed(PathTrace::new(ctx, pass, resources))
})
.with_features(|pass, scene, resources, traits| {
    let options = options(pass, resources, traits);
    let features = crate::specialize::Features::decide(scene, options);
    let refusal = crate::specialize::support::refusal(scene, options, &features);
    lumagraph_render::ShaderChoices {
        lines: features.lines(),
        refusal,
    }
})
.owning(|pass| {
    adaptive_on(pass).then(|| {
        (
            40 * pass.extent.pixels(),
            "adaptive sampling: 40 B per pixel (the sums of two halves of the frames, \
             whether it stopped, the list of pixels still sampling)"
                .to_owned(),
        )
    })
});

/// The shader features of node `id` of `exec`, where it is a `PathTrace` node (tests and
/// tools read the choices here, never from the notes' words).
pub fn features<'a>(exec: &'a lumagraph_render::Executor, id: &str) -> Option<&'a Features> {
    let node = exec.node(id)?;
    <dyn NodeExec as lumagraph_render::AsAny>::as_any(node)
        .downcast_ref::<PathTrace>()
        .map(|p| &p.features)
}

/// Whether `pass` samples adaptively.
fn adaptive_on(pass: &Pass) -> bool {
    pass.params.float("adaptive_error") > 0.0
}

/// How a pass's shader is specialized: to the scene unless the resources ask for the
/// general shader, to the kind of adapter, with first-hit AOVs when something reads them.
/// The resources' [`Tracing`](crate::specialize::Tracing)'s `as_gpu_adapter` has it decided as on a GPU adapter. The pass's `intersector`
/// and `schedule` params, where not `auto`, ask for an intersector and a schedule; else
/// its `intersector` and `schedule` (`--intersector`, `--schedule`) do.
fn options(
    pass: &Pass,
    resources: &Resources,
    traits: crate::specialize::AdapterTraits,
) -> crate::specialize::PathTraceOptions {
    use crate::specialize::{Intersector, Schedule, Tracer as _};
    let tracer = resources.tracer();
    let cpu_adapter = traits.cpu && !tracer.as_gpu_adapter;
    let param = |name: &str| {
        if pass.params.has(name) {
            pass.params.str(name).to_owned()
        } else {
            "auto".to_owned()
        }
    };
    // The registry's options are exactly the names, so an unknown one cannot reach here.
    let intersector = match Intersector::from_name(&param("intersector")) {
        Ok(Intersector::AUTO) | Err(_) => tracer.intersector,
        Ok(asked) => asked,
    };
    let schedule = match Schedule::from_name(&param("schedule")) {
        Ok(Schedule::Auto) | Err(_) => tracer.schedule,
        Ok(asked) => asked,
    };
    crate::specialize::PathTraceOptions {
        ray_query_limit: traits
            .ray_query_limit
            .filter(|_| !tracer.as_gpu_adapter || intersector == Intersector::RAY_QUERIES),
        intersector,
        specialize: !tracer.general_shaders,
        cpu_adapter,
        data_in_buffers: tracer.scene_data_in_buffers,
        in_image_order: tracer.workgroups_in_image_order,
        aovs: ["albedo", "normal", "depth"]
            .iter()
            .any(|p| pass.output(p).is_some()),
        adaptive: adaptive_on(pass),
        host_rays: cpu_adapter && crate::embree::Embree::load().is_ok(),
        schedule,
    }
}

/// The shader source and features for `scene` and `options`, or why the intersector or
/// schedule they ask for cannot trace it ([`crate::specialize::support::refusal`]).
fn specialized(
    scene: &lumagraph_scene::GpuScene,
    options: crate::specialize::PathTraceOptions,
) -> Result<(String, Features)> {
    let specialization = crate::specialize::Specialization::new(scene, options);
    if let Some(why) = crate::specialize::support::refusal(scene, options, &specialization.features)
    {
        return Err(RenderError::Unsupported(why));
    }
    Ok((specialization.source()?, specialization.features))
}

lumagraph_render::param_block! {
    /// The path tracer's per-frame uniform block.
    pub(crate) struct Frame in "pathtrace/integrator/pathtrace.wgsl" as "Frame" {
        settings: lumagraph_scene::GpuSettings,
        camera: lumagraph_scene::GpuCamera,
        header: lumagraph_scene::GpuHeader,
        /// Index of this frame's first sample in each pixel's sequence.
        sample_offset: u32,
        samples_per_frame: u32,
        env_width: u32,
        env_height: u32,
        /// Largest channel value one sample may contribute (0: off).
        firefly_clamp: f32,
        /// The `sampler` param's option index.
        sampler: u32,
        /// The `strategy` param's option index.
        strategy: u32,
        /// The `replicates` param: 1 or 2 Sobol replicates, alternating by frame.
        replicates: u32,
        /// The pixels this pass renders: left, top, width and height in the whole image
        /// (all of it unless the render is tiled).
        window: [u32; 4],
        /// The samples of the frame this dispatch traces: from `chunk_first`, `chunk_count`
        /// of them (a frame is traced in several dispatches on CPU adapters, see
        /// [`CPU_SAMPLES_PER_DISPATCH`]).
        chunk_first: u32,
        chunk_count: u32,
        /// `CHUNK_FIRST` | `CHUNK_LAST` (`pathtrace/integrator/pathtrace.wgsl`).
        chunk_flags: u32,
        /// With host intersection or the wavefront: `WAVE_STEP` or `WAVE_FINISH`; the batch
        /// of slots traced: its first, and the slots the `wave` buffer holds; how many of a
        /// step's listed slots `wave_misses` takes (`wave_hits` the rest); with the
        /// wavefront, which of its two lists is the step's ([`crate::wavefront`]).
        wave: u32,
        wave_base: u32,
        wave_capacity: u32,
        wave_split: u32,
        wave_list: u32,
    }
}

/// At most this many samples per pixel in one dispatch on a CPU adapter (llvmpipe), by how
/// the scene is intersected: through the BVH, or inline. llvmpipe ends every loop of a
/// dispatch's invocation, silently, once all its loops together have run 65 535 iterations
/// (`LP_MAX_TGSI_LOOP_ITERATIONS` in Mesa's gallivm), and a BVH path tracer runs one per
/// node visit: on the 81 920-triangle mesh scene, 64 samples in one dispatch already traced
/// 9 % fewer rays (truncated traversals), 32 a few. A frame of more samples is traced in
/// dispatches of at most this many, summed in a buffer, with the same sample indices.
pub(crate) const CPU_SAMPLES_PER_DISPATCH: [u32; 2] = [8, 256];

lumagraph_render::param_block! {
    /// The adaptive sampling pass's params (`pathtrace/integrator/adaptive.wgsl`).
    pub(crate) struct AdaptiveParams in "pathtrace/integrator/adaptive.wgsl" as "Params" {
        size: [u32; 2],
        min_frames: u32,
        error2: f32,
        frames: u32,
        samples_per_frame: u32,
        pad0: u32,
        pad1: u32,
    }
}

/// A storage buffer of `size` bytes that can be cleared and read back.
fn storage(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

pub(crate) struct PathTrace {
    kernel: Kernel,
    scene: std::sync::Arc<lumagraph_scene::GpuScene>,
    /// The camera rendered from: the scene's, until [`View::move_camera`](lumagraph_render::nodes::View::move_camera).
    camera: lumagraph_scene::GpuCamera,
    buffers: SceneBuffers,
    frame: wgpu::Buffer,
    stats: wgpu::Buffer,
    stats_read: wgpu::Buffer,
    samples_per_frame: u32,
    /// Samples per pixel taken since the last reset.
    samples: u32,
    /// Dropped samples and rays since the last reset, read back so far.
    dropped: u64,
    rays: u64,
    /// What the shader compiles in and leaves out, and why.
    features: Features,
    /// Stand-ins for outputs nothing reads (color, albedo, normal, depth, samples).
    unused: [PooledTexture; 5],
    /// GGX albedo tables of the material model.
    ggx_table: wgpu::Buffer,
    /// The environment map and its sampling tables (a 1x1 stand-in without one).
    env: crate::env_map::EnvMap,
    /// Largest channel value a sample may contribute; 0 is off.
    firefly_clamp: f32,
    /// The `sampler` param's option index (`SAMPLER_*` in `pathtrace/integrator/sampler.wgsl`).
    sampler: u32,
    /// `STRATEGY_MIS` (0), `STRATEGY_LIGHT` (1) or `STRATEGY_BSDF` (2) in
    /// `pathtrace/integrator/pathtrace.wgsl`.
    strategy: u32,
    /// Sobol replicates (1 or 2), alternating by frame.
    replicates: u32,
    /// Where the pass's image lies in the whole image (tiled renders).
    origin: [u32; 2],
    adaptive: Adaptive,
    /// Samples adaptive sampling took since the last reset, read back so far.
    adaptive_samples: u64,
    /// Most samples per pixel one dispatch traces (`u32::MAX` on GPU adapters).
    samples_per_dispatch: u32,
    /// Per pixel of the window, the sum of a frame's samples traced so far while it takes
    /// several dispatches (a 16-byte stand-in until one does).
    chunk_sums: wgpu::Buffer,
    /// What traces the rays (the plan's intersector), with its state.
    backend: Box<dyn crate::intersect::Traversal>,
    /// Host intersection's steps and times since the last reset (its rays go to `rays`).
    host_counts: HostCounts,
    /// The `wave` binding's stand-in without host intersection or the wavefront.
    wave_stand_in: wgpu::Buffer,
    /// The wavefront's buffers, where the plan says "wavefront".
    wavefront: Option<crate::wavefront::Wavefront>,
    /// The frame `submit_own` traced in steps, whose finish `record` records.
    traced: Option<Frame>,
}

impl PathTrace {
    pub(crate) fn new(ctx: &GpuContext, pass: &Pass, resources: &Resources) -> Result<Self> {
        let scene = resources.scene.clone().ok_or_else(|| {
            RenderError::Gpu("PathTrace needs a scene (lumagraph render --scene FILE)".into())
        })?;
        let opts = options(pass, resources, ctx.traits());
        let (source, features) = specialized(&scene, opts)?;
        let samples_per_dispatch = if !ctx.is_cpu() {
            u32::MAX
        } else if features.kind().inline() {
            CPU_SAMPLES_PER_DISPATCH[1]
        } else {
            CPU_SAMPLES_PER_DISPATCH[0]
        };
        let (main, entries) = entry_points(&features);
        // The pipelines compile on a thread of their own (a CPU adapter's driver takes most
        // of a second over the path tracer's) while this one builds the intersector (Embree's
        // BVH, for host intersection), loads the environment map and uploads the tables.
        let (kernel, backend, wavefront, env, ggx_table) = std::thread::scope(|s| {
            let kernel = s.spawn(|| {
                Kernel::with_entries(
                    ctx,
                    "pathtrace/integrator/pathtrace.wgsl",
                    &source,
                    main,
                    entries,
                )
            });
            let rest = (|| {
                let backend = features.kind().build(ctx, &scene)?;
                let wavefront = features
                    .on(Feature::Wavefront)
                    .then(|| crate::wavefront::Wavefront::new(ctx));
                let env = match &scene.environment_map {
                    Some(path) => crate::env_map::EnvMap::load(
                        ctx,
                        path,
                        pass.params.str("env_sampling") == "uniform",
                    )?,
                    None => crate::env_map::EnvMap::empty(ctx),
                };
                let ggx_table = crate::bsdf_tables::upload(ctx, features.on(Feature::Sheen));
                Ok::<_, RenderError>((backend, wavefront, env, ggx_table))
            })();
            let kernel = kernel
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            let (backend, wavefront, env, ggx_table) = rest?;
            Ok::<_, RenderError>((kernel?, backend, wavefront, env, ggx_table))
        })?;
        // Outputs nothing reads are bound to 1x1 stand-ins (stores outside them are dropped).
        let one = lumagraph_graph::Extent::new(1, 1);
        let unused = [
            create(ctx, "unused color", TexFormat::Rgba32Float, one),
            create(ctx, "unused albedo", TexFormat::Rgba32Float, one),
            create(ctx, "unused normal", TexFormat::Rgba32Float, one),
            create(ctx, "unused depth", TexFormat::R32Float, one),
            create(ctx, "unused samples", TexFormat::Rgba32Float, one),
        ];
        // The binary BVH's records only where the intersector reads them.
        let binary_bvh = features.kind().reads_binary_bvh(&features);
        let buffers = SceneBuffers::upload_for(ctx, &scene, binary_bvh)?;
        let frame = uniform_buffer(
            ctx,
            "pathtrace frame",
            bytemuck::bytes_of(&Frame::default()),
        );
        let stats = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pathtrace stats"),
            size: STATS * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let stats_read = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pathtrace stats readback"),
            size: STATS * 4,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut node = Self {
            kernel,
            camera: scene.camera,
            scene,
            buffers,
            frame,
            stats,
            stats_read,
            samples_per_frame: 1,
            samples: 0,
            dropped: 0,
            rays: 0,
            features,
            unused,
            ggx_table,
            env,
            firefly_clamp: 0.0,
            sampler: 0,
            strategy: 0,
            replicates: 1,
            origin: [0, 0],
            adaptive: Adaptive::new(ctx)?,
            adaptive_samples: 0,
            host_counts: HostCounts::default(),
            samples_per_dispatch,
            chunk_sums: storage(ctx, "pathtrace chunk sums", 16),
            backend,
            wave_stand_in: storage(ctx, "pathtrace wave stand-in", 16),
            wavefront,
            traced: None,
        };
        node.update(ctx, pass)?;
        Ok(node)
    }

    fn frame(&self, extent: lumagraph_graph::Extent) -> Frame {
        let s = &self.scene;
        Frame {
            settings: s.settings,
            camera: self.camera,
            header: s.header,
            sample_offset: self.samples,
            samples_per_frame: self.samples_per_frame,
            env_width: self.env.width,
            env_height: self.env.height,
            firefly_clamp: self.firefly_clamp,
            sampler: self.sampler,
            strategy: self.strategy,
            // Adaptive sampling estimates the error from two independent halves.
            replicates: if self.adaptive.on() {
                2
            } else {
                self.replicates
            },
            window: [self.origin[0], self.origin[1], extent.width, extent.height],
            chunk_first: 0,
            chunk_count: self.samples_per_frame,
            chunk_flags: CHUNK_FIRST | CHUNK_LAST,
            wave: 0,
            wave_base: 0,
            wave_capacity: 0,
            wave_split: 0,
            wave_list: 0,
        }
    }
}

impl PathTrace {
    /// The views of the color and AOV outputs (1×1 stand-ins for those nothing reads).
    fn views<'a>(&'a self, pass: &Pass, io: &'a FrameIo<'_>) -> [&'a wgpu::TextureView; 4] {
        ["color", "albedo", "normal", "depth"]
            .iter()
            .enumerate()
            .map(|(i, port)| {
                pass.output(port)
                    .map_or(&self.unused[i].view, |t| &io.texture(t).view)
            })
            .collect::<Vec<_>>()
            .try_into()
            .unwrap_or([&self.unused[0].view; 4])
    }

    /// The path tracer's pass with every binding: the output `views` (color, albedo,
    /// normal, depth), the per-pixel `sums` and the host intersection's `wave` buffer.
    fn bind<'a>(
        &'a self,
        name: &'a str,
        [color, albedo, normal, depth]: [&'a wgpu::TextureView; 4],
        sums: &'a wgpu::Buffer,
        wave: &'a wgpu::Buffer,
    ) -> PassBuilder<'a> {
        let b = &self.buffers;
        let pass = self
            .kernel
            .pass(name)
            .write(color)
            .uniform(&self.frame)
            .buffer(self.backend.bvh_nodes().unwrap_or(&b.bvh_nodes))
            .buffer(&b.tri_positions)
            .buffer(&b.tri_shading)
            .buffer(&b.shapes)
            .buffer(&b.materials)
            .buffer(&b.lights)
            .buffer(&b.light_alias)
            .buffer(&self.stats)
            .write(albedo)
            .write(normal)
            .write(depth)
            .buffer(&self.ggx_table)
            .buffer(&self.env.texels)
            .buffer(&self.env.alias)
            .buffer(&b.tri_texcoords)
            .buffer(&b.texture_descs)
            .buffer(&self.adaptive.halves)
            .buffer(&self.adaptive.stopped)
            .buffer(&self.adaptive.active)
            .buffer(sums)
            .buffer(wave)
            .read(&b.textures);
        match self.backend.accel() {
            Some(accel) => pass.accel(&accel.tlas),
            None => pass,
        }
    }

    /// The most steps a frame of paths traced in steps may take (host intersection, the
    /// wavefront): each step takes at most one bounce of one path per slot, or a path's
    /// last shadow ray.
    fn max_steps(&self, frame: &Frame) -> u64 {
        u64::from(frame.samples_per_frame.max(1))
            * (2 * u64::from(self.scene.settings.max_bounces) + 4)
            + 2
    }

    /// Records the pass that writes the pixels' means from a frame's `sums` (and the AOVs)
    /// into the output `views` after its steps, with the steps' `wave` buffer bound.
    fn record_finish(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        pass: &Pass,
        frame: Frame,
        (views, sums, wave): ([&wgpu::TextureView; 4], &wgpu::Buffer, &wgpu::Buffer),
        timer: Option<&mut lumagraph_render::timing::GpuTimer>,
    ) -> Result<()> {
        let f = Frame {
            wave: WAVE_FINISH,
            ..frame
        };
        stage_frame(ctx, encoder, &f, &self.frame);
        self.bind(&pass.node, views, sums, wave)
            .dispatch_2d(ctx, encoder, pass.extent, timer)
    }
}

/// The path tracer's entry points for host intersection's steps (see [`WaveStep`]).
const WAVE_ENTRIES: [&str; 3] = ["wave_start", "wave_misses", "wave_hits"];

/// The wavefront's: the steps, and the tracing between them ([`crate::wavefront`]).
const WAVEFRONT_ENTRIES: [&str; 4] = ["wave_start", "wave_misses", "wave_hits", "wave_trace"];

/// The entry points a shader of `features` runs: the kernel's own (`main`, the megakernel;
/// or `wave_finish` for paths traced in steps, whose `main` is then not built), and the
/// others.
fn entry_points(features: &Features) -> (&'static str, &'static [&'static str]) {
    if features.on(Feature::Wavefront) {
        ("wave_finish", &WAVEFRONT_ENTRIES)
    } else if features.kind().host_steps() {
        ("wave_finish", &WAVE_ENTRIES)
    } else {
        ("main", &[])
    }
}

/// Records a copy of `frame` into the uniform buffer `dst` through a staging buffer, in
/// order with the passes recorded around it.
fn stage_frame(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    frame: &Frame,
    dst: &wgpu::Buffer,
) {
    let staging = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pathtrace frame staging"),
            contents: bytemuck::bytes_of(frame),
            usage: wgpu::BufferUsages::COPY_SRC,
        });
    encoder.copy_buffer_to_buffer(&staging, 0, dst, 0, dst.size());
}

impl NodeExec for PathTrace {
    fn own_work(&mut self) -> Option<&mut dyn OwnWork> {
        Some(self)
    }

    fn view(&mut self) -> Option<&mut dyn View> {
        Some(self)
    }

    fn history(&mut self) -> Option<&mut dyn History> {
        Some(self)
    }

    fn update(&mut self, _ctx: &GpuContext, pass: &Pass) -> Result<()> {
        self.samples_per_frame = u32::try_from(pass.params.int("samples_per_frame")).unwrap_or(1);
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
        let clamp = pass.params.float("firefly_clamp") as f32;
        self.firefly_clamp = clamp;
        self.sampler = lumagraph_render::params::enum_index(pass, "sampler")?;
        self.strategy = lumagraph_render::params::enum_index(pass, "strategy")?;
        self.replicates = u32::try_from(pass.params.int("replicates")).unwrap_or(1);
        #[expect(clippy::cast_possible_truncation, reason = "GPU math is f32")]
        let error = pass.params.float("adaptive_error") as f32;
        self.adaptive.error = error;
        self.adaptive.min_spp = u32::try_from(pass.params.int("adaptive_min_spp")).unwrap_or(16);
        Ok(())
    }

    fn reset(&mut self) {
        self.samples = 0;
        self.dropped = 0;
        self.rays = 0;
        self.adaptive_samples = 0;
        self.host_counts = HostCounts::default();
        self.adaptive.clear = true;
    }

    fn record(&mut self, pass: &Pass, rec: Recording<'_>) -> Result<()> {
        let (ctx, encoder, io, mut timer) = rec.parts();
        let samples = pass.output("samples");
        if samples.is_some() || self.adaptive.on() {
            let view = samples.map_or(&self.unused[4].view, |t| &io.texture(t).view);
            let spf = self.samples_per_frame.max(1);
            self.adaptive.record(
                ctx,
                encoder,
                pass,
                [self.samples / spf, spf],
                view,
                timer.as_deref_mut(),
            )?;
        }
        if self.submits_own() {
            let frame = match self.traced.take() {
                Some(frame) => frame,
                None => {
                    // Recorded without `submit_own`: the graph's work so far first.
                    submit_pending(ctx, encoder);
                    let frame = self.frame(pass.extent);
                    self.trace_steps(ctx, io, pass, frame)?;
                    frame
                }
            };
            self.samples += self.samples_per_frame;
            return self.record_steps_finish(ctx, encoder, io, pass, frame, timer);
        }
        let frame = self.frame(pass.extent);
        self.samples += self.samples_per_frame;
        // The frame's samples in dispatches of at most `samples_per_dispatch` (one on GPU
        // adapters), the partial sums kept per pixel between them.
        let n = self.samples_per_frame.max(1);
        let per_dispatch = self.samples_per_dispatch.clamp(1, n);
        let sums_size = 16 * pass.extent.pixels();
        if per_dispatch < n && self.chunk_sums.size() < sums_size {
            self.chunk_sums = storage(ctx, "pathtrace chunk sums", sums_size);
        }
        let mut first = 0;
        while first < n {
            let count = per_dispatch.min(n - first);
            let chunk = Frame {
                chunk_first: first,
                chunk_count: count,
                chunk_flags: if first == 0 { CHUNK_FIRST } else { 0 }
                    | if first + count == n { CHUNK_LAST } else { 0 },
                ..frame
            };
            // Each dispatch has its own uniform contents: stage them through a copy recorded
            // in order, so many frames can share one submission.
            stage_frame(ctx, encoder, &chunk, &self.frame);
            let views = self.views(pass, io);
            self.bind(&pass.node, views, &self.chunk_sums, &self.wave_stand_in)
                .dispatch_2d(ctx, encoder, pass.extent, timer.as_deref_mut())?;
            first += count;
        }
        Ok(())
    }

    fn notes(&self) -> Vec<String> {
        let mut notes = vec![format!("shader: {}", self.features.summary())];
        notes.extend(self.backend.note(&self.scene));
        if self.firefly_clamp > 0.0 {
            notes.push(format!(
                "firefly clamp ON: each sample's channels are scaled to at most {} (biased: energy is lost)",
                self.firefly_clamp
            ));
        }
        notes
    }

    fn counters(&mut self, ctx: &GpuContext) -> Result<Vec<Counter>> {
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("stats"),
            });
        encoder.copy_buffer_to_buffer(&self.stats, 0, &self.stats_read, 0, STATS * 4);
        encoder.clear_buffer(&self.stats, 0, None);
        ctx.queue.submit([encoder.finish()]);
        let v: Vec<u32> = map_read(
            ctx,
            &self.stats_read,
            STATS * 4,
            bytemuck::pod_collect_to_vec,
        )?;
        self.dropped += u64::from(v[0]);
        self.rays += u64::from(v[1]) | (u64::from(v[2]) << 32);
        if let Some(host) = self.backend.host_mut() {
            self.host_counts += host.take_counts();
            self.rays += std::mem::take(&mut self.host_counts.rays);
        }
        self.adaptive_samples += u64::from(v[3]);
        let mut counters = vec![
            Counter::new("samples_per_pixel", u64::from(self.samples)),
            Counter::new("dropped_samples", self.dropped),
            Counter::new("rays", self.rays),
        ];
        if self.backend.host().is_some() {
            let h = self.host_counts;
            counters.extend([
                Counter::new("host_steps", h.steps),
                Counter::new("host_wait_ns", h.wait_ns),
                Counter::new("host_embree_ns", h.embree_ns),
                Counter::new("host_other_ns", h.other_ns),
            ]);
        }
        if self.adaptive.on() {
            counters.push(Counter::new("adaptive_samples", self.adaptive_samples));
        }
        Ok(counters)
    }
}

impl OwnWork for PathTrace {
    fn submits_own(&self) -> bool {
        self.backend.host().is_some() || self.wavefront.is_some()
    }

    fn submit_own(&mut self, ctx: &GpuContext, pass: &Pass, io: &FrameIo<'_>) -> Result<()> {
        let frame = self.frame(pass.extent);
        self.trace_steps(ctx, io, pass, frame)?;
        self.traced = Some(frame);
        Ok(())
    }
}

impl View for PathTrace {
    fn set_origin(&mut self, origin: [u32; 2]) {
        self.origin = origin;
    }

    fn move_camera(&mut self, camera: &lumagraph_scene::GpuCamera) {
        self.camera = *camera;
        self.reset();
    }
}
