//! Shaders specialized to the scene: code the scene does not need is not compiled.
//!
//! On CPU drivers (lavapipe), every memory load inside the traversal loop is costly, while
//! constants written into the shader are nearly free; on GPUs, tiny scenes gain too. So a
//! scene with few primitives gets an intersection routine that tests every primitive with
//! its coordinates written into the code, replacing `pathtrace/intersect.wgsl` (the BVH
//! traversal over storage buffers) through the import resolver's overrides. Such a scene,
//! unless textured, also gets its materials, lights, light alias table and per-primitive
//! shading data written into the code (`pathtrace/scene_data.wgsl` replaced), so no bounce
//! reads them from memory; the images are bit-identical to reading the buffers.
//!
//! What is compiled in is decided once per shader as typed [`Feature`]s
//! ([`features`]); the generated code is in [`codegen`]. [`Specialization`] holds both and
//! assembles the source.

mod codegen;
mod features;
mod ranges;
pub mod support;

pub use crate::intersect::Intersector;
pub use codegen::{inline_intersection, inline_materials_data, inline_scene_data, parallelograms};
pub use features::{Decision, Feature, Features};

use lumagraph_scene::GpuScene;

/// Scenes with at most this many primitives get inline intersection code.
pub const INLINE_MAX_PRIMITIVES: usize = 64;

/// Scenes with at most this many materials (and [`INLINE_MAX_PRIMITIVES`] primitives) get
/// their materials, lights and per-primitive shading data written into the shader.
pub const INLINE_MAX_MATERIALS: usize = 64;

pub use lumagraph_render::AdapterTraits;

/// How the path tracer's work is laid out on the device.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Schedule {
    /// The adapter decides: on GPU adapters the wavefront for scenes of textured materials
    /// and at least [`WAVEFRONT_MIN_TRIANGLES`] triangles, the megakernel for the others; on
    /// CPU adapters the megakernel (or host intersection's steps). Measured in
    /// `docs/benchmarks.md`.
    #[default]
    Auto,
    /// One invocation traces a pixel's whole paths (`main` in `pathtrace/integrator/pathtrace.wgsl`).
    Megakernel,
    /// The paths of a frame are taken one bounce at a time by small kernels: the steps of
    /// host intersection shade (`pathtrace/integrator/wave.wgsl`) and `wave_trace` traces the rays they
    /// wrote, on the device, between them ([`crate::wavefront`]). For the scenes host
    /// intersection takes (triangles, no media, no adaptive sampling).
    Wavefront,
}

impl Schedule {
    /// What it is, in the plan's words.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Auto => "the adapter's choice",
            Self::Megakernel => "the megakernel",
            Self::Wavefront => "the wavefront",
        }
    }

    /// Every choice, [`Schedule::Auto`] first.
    pub const ALL: [Self; 3] = [Self::Auto, Self::Megakernel, Self::Wavefront];

    /// Its word in the `schedule` param and the `--schedule` option.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Megakernel => "megakernel",
            Self::Wavefront => "wavefront",
        }
    }

    /// The schedule a word names ([`Schedule::name`]).
    ///
    /// # Errors
    /// An unknown word, with the known ones.
    pub fn from_name(name: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|i| i.name() == name)
            .ok_or_else(|| format!("unknown schedule {name:?}: auto, megakernel or wavefront"))
    }
}

/// What a path tracer is asked for beyond its node's params: the intersector and the
/// schedule (the command line's `--intersector` and `--schedule`, a session's options), and
/// the knobs tests and benchmarks turn. It travels in the resources' settings ([`Tracer`]); only
/// `PathTrace` reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tracing {
    /// The intersector ([`Intersector::AUTO`], the default: the scene and the adapter
    /// decide). A `PathTrace` node's `intersector` param, when not `auto`, wins over it. One
    /// that cannot trace the scene is an error when the node is built, never a silent
    /// fallback.
    pub intersector: Intersector,
    /// The schedule ([`Schedule::Auto`], the default: the scene and the adapter decide).
    /// The node's `schedule` param, when not `auto`, wins.
    pub schedule: Schedule,
    /// Use the general shaders even where a scene-specialized one exists (benchmarks).
    pub general_shaders: bool,
    /// In the specialized shader, keep materials, lights and shading data in their storage
    /// buffers even where they could be written into the code (tests and benchmarks).
    pub scene_data_in_buffers: bool,
    /// Decide the shader as a GPU adapter would (no inline intersection, no host, no
    /// spreading of workgroups, ray queries only where `intersector` asks for them) even on
    /// a CPU adapter: tests run what GPUs run on lavapipe.
    pub as_gpu_adapter: bool,
    /// Trace workgroups in image order even on a CPU adapter, where they are otherwise
    /// spread over the image to balance the driver's threads (a test compares the two).
    pub workgroups_in_image_order: bool,
}

/// The path tracer's [`Tracing`] in a node's [`Resources`](lumagraph_render::Resources)
/// (a [`Settings`](lumagraph_render::Settings) value).
pub trait Tracer {
    /// What the path tracer is asked for (the default where nothing was set).
    fn tracer(&self) -> Tracing;
    /// These resources with what the path tracer is asked for changed by `change`.
    #[must_use]
    fn tracing(self, change: impl FnOnce(&mut Tracing)) -> Self;
}

impl Tracer for lumagraph_render::Resources {
    fn tracer(&self) -> Tracing {
        self.setting::<Tracing>()
    }

    fn tracing(self, change: impl FnOnce(&mut Tracing)) -> Self {
        self.with_setting(change)
    }
}

/// What the graph needs of the path tracer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathTraceOptions {
    /// Specialize to the scene where it pays (off: the general shader, for benchmarks).
    pub specialize: bool,
    /// Whether the shader runs on a CPU adapter (lavapipe): there, small scenes are
    /// intersected inline, with their data written into the code (loads in loops are what
    /// llvmpipe pays most for); on a GPU the BVH is faster than testing every primitive
    /// (2.6-3.6× on 64 spheres on an H100, `docs/benchmarks.md`), so it always traverses it.
    pub cpu_adapter: bool,
    /// Write the first-hit AOVs (albedo, normal, depth): something reads them.
    pub aovs: bool,
    /// Adaptive sampling (`adaptive_error` > 0): per-pixel statistics and skipping.
    pub adaptive: bool,
    /// With `specialize`, keep materials, lights and shading data in their storage buffers
    /// even where the scene is small enough to write them into the shader (tests and
    /// benchmarks compare the two; images are bit-identical).
    pub data_in_buffers: bool,
    /// On a CPU adapter, trace workgroups in image order instead of spreading them over the
    /// image (the images are bit-identical; a test compares the two).
    pub in_image_order: bool,
    /// On a CPU adapter, whether the host can intersect the path tracer's rays (Embree was
    /// found, [`crate::embree`]): the scene's rays are then traced there when the BVH would
    /// be traversed, and the scene allows (see [`features`]).
    pub host_rays: bool,
    /// Where the device has ray queries ([`crate::accel`]): the most primitives one of its
    /// acceleration structures holds. GPU adapters trace through them wherever the scene
    /// would otherwise traverse the BVH in WGSL.
    pub ray_query_limit: Option<u32>,
    /// The intersector asked for (the `intersector` param, `--intersector`, tests,
    /// benchmarks), or [`Intersector::AUTO`]: the scene and the adapter decide. One that
    /// cannot trace the scene ([`support::why_not`]) is decided as `AUTO`; the node refuses
    /// to render then ([`support::refusal`]).
    pub intersector: Intersector,
    /// The schedule asked for (the `schedule` param, `--schedule`, tests, benchmarks), or
    /// [`Schedule::Auto`].
    pub schedule: Schedule,
}

/// A path tracer shader specialized to one scene, adapter and graph: its features, decided
/// once, and the code written for the scene where the features ask for it.
#[derive(Clone, Debug)]
pub struct Specialization {
    /// What is compiled in and left out, and why.
    pub features: Features,
    /// Replaces `pathtrace/intersect.wgsl`: the intersector's own code
    /// ([`crate::intersect::IntersectorKind::wgsl`]).
    intersection: Option<String>,
    /// Replaces `pathtrace/scene_data.wgsl` ([`Feature::InlineData`]).
    scene_data: Option<String>,
    /// Replaces `pathtrace/shapes.wgsl` with the dispatch over the kinds of shapes the
    /// scene has (specialized shaders only).
    shapes: Option<String>,
    /// Replaces `pathtrace/light_kinds.wgsl` with the dispatch over the kinds of lights
    /// without area the scene has (specialized shaders only).
    light_kinds: Option<String>,
}

impl Specialization {
    /// Decides the features for `scene` and `options` and writes the code they ask for.
    pub fn new(scene: &GpuScene, options: PathTraceOptions) -> Self {
        let shapes = options.specialize.then(|| {
            lumagraph_scene::shapes::wgsl_for(|k| scene.shapes.iter().any(|s| s.kind == k))
        });
        let light_kinds = options.specialize.then(|| {
            lumagraph_scene::lights::wgsl_for(|k| scene.lights.iter().any(|l| l.kind == k + 1))
        });
        let features = Features::decide(scene, options);
        let kind = features.kind();
        let inline = kind.inline();
        let intersection = kind.wgsl(scene, features.on(Feature::Alpha));
        let scene_data = if !features.on(Feature::InlineData) {
            None
        } else if inline {
            inline_scene_data(scene)
        } else {
            inline_materials_data(scene)
        };
        Self {
            features,
            intersection,
            scene_data,
            shapes,
            light_kinds,
        }
    }

    /// The path tracer's source: `pathtrace/integrator/pathtrace.wgsl` with the options file written
    /// from the features and the generated files in place of the ones they replace.
    ///
    /// # Errors
    /// When a shader file is missing.
    pub fn source(&self) -> lumagraph_render::Result<String> {
        let mut overrides = vec![("pathtrace/options.wgsl", self.features.wgsl_options())];
        if let Some(code) = &self.intersection {
            overrides.push(("pathtrace/intersect.wgsl", code.clone()));
        }
        if let Some(code) = &self.scene_data {
            overrides.push(("pathtrace/scene_data.wgsl", code.clone()));
        }
        if let Some(code) = &self.shapes {
            overrides.push((lumagraph_scene::shapes::FILE, code.clone()));
        }
        if let Some(code) = &self.light_kinds {
            overrides.push((lumagraph_scene::lights::FILE, code.clone()));
        }
        let source = lumagraph_render::shader::resolve_with(
            "pathtrace/integrator/pathtrace.wgsl",
            &overrides,
        )?;
        // An `enable` directive comes before any declaration.
        Ok(match self.features.kind().enable() {
            Some(extension) => format!("enable {extension};\n{source}"),
            None => source,
        })
    }
}

/// Why materials, lights and shading data are (or are not) written into the shader.
fn inline_data_reason(
    scene: &GpuScene,
    options: PathTraceOptions,
    included: bool,
    all: bool,
) -> String {
    let m = scene.materials.len();
    let lights = scene.lights.len();
    let prims = scene.tri_positions.len() + scene.shapes.len();
    let textured = scene.header.features & lumagraph_scene::FEATURE_TEXTURES != 0;
    if included && all {
        format!("{m} materials, {lights} lights, {prims} primitives' shading data")
    } else if included && lights <= INLINE_MAX_MATERIALS {
        format!(
            "{m} materials, {lights} lights ({prims} primitives > {INLINE_MAX_PRIMITIVES}: \
             their data read from buffers)"
        )
    } else if included {
        format!("{m} materials ({lights} lights and {prims} primitives: read from buffers)")
    } else if !options.specialize {
        "general shader (specialization off)".to_owned()
    } else if !options.cpu_adapter {
        "a GPU adapter: read from buffers, with BVH traversal".to_owned()
    } else if options.data_in_buffers {
        "forced off: read from buffers".to_owned()
    } else if textured {
        "textured materials: read from buffers".to_owned()
    } else if m > INLINE_MAX_MATERIALS {
        format!("{m} materials > {INLINE_MAX_MATERIALS}: read from buffers")
    } else {
        "a value is not finite: read from buffers".to_owned()
    }
}

/// How many of the scene's materials have a texture.
fn textured_materials(scene: &GpuScene) -> usize {
    scene
        .materials
        .iter()
        .filter(|x| {
            [
                x.tex_base_mr,
                x.tex_emissive_normal,
                x.tex_transmission_specular,
                x.tex_specular_color,
            ]
            .iter()
            .any(|&t| t & 0xFFFF != 0xFFFF || t >> 16 != 0xFFFF)
        })
        .count()
}

/// Why texture sampling and vertex colours are (or are not) compiled in.
fn textures_reason(scene: &GpuScene, all: bool) -> String {
    let textured_materials = textured_materials(scene);
    if all {
        "general shader (specialization off)".to_owned()
    } else if textured_materials > 0 {
        format!(
            "{textured_materials} textured materials, {} KiB of texels in {} atlas pages of {}x{}",
            scene.atlas.bytes() / 1024,
            scene.atlas.pages,
            scene.atlas.page_size,
            scene.atlas.page_size
        )
    } else if scene.header.features & lumagraph_scene::FEATURE_TEXTURES != 0 {
        "vertex colours (no material has a texture)".to_owned()
    } else {
        "no material has a texture or vertex colours".to_owned()
    }
}

/// Why only the binary WGSL BVH and host intersection trace a scene with instanced meshes:
/// the others (inline code, the 8-wide BVH, ray queries and the wavefront's step records)
/// take flat scenes only so far.
pub const INSTANCES_REASON: &str = "instanced meshes: the binary WGSL BVH walks the two levels, host intersection places them in Embree (the other intersectors take flat scenes only)";

/// GPU adapters step scenes of at least this many triangles with textured materials as a
/// wavefront: the one scene it measured faster on (Sponza, 262 087 triangles, 24 textured
/// materials) has both; a 1.3 M-triangle mesh without textures and a 12-triangle textured
/// box traced faster through the megakernel (`docs/benchmarks.md`).
pub const WAVEFRONT_MIN_TRIANGLES: usize = 100_000;

/// Why a GPU adapter schedules such scenes as a wavefront unless asked otherwise.
const GPU_WAVEFRONT_REASON: &str = "a GPU adapter, textured materials and a large BVH: the \
     wavefront measured 1.11x the megakernel's paths/s on Sponza on an NVIDIA H200 \
     (--schedule megakernel asks for the megakernel)";

/// Why a GPU adapter keeps the megakernel for the other scenes.
const GPU_MEGAKERNEL_REASON: &str = "the megakernel measured 1.8x the wavefront's paths/s on \
     the Cornell box, 1.7x on a 1.3 M-triangle mesh and 6.7x on a textured 12-triangle box on \
     an NVIDIA H200 (--schedule wavefront asks for the wavefront)";

/// Whether the wavefront schedules the paths (`WAVEFRONT`), and why (not): where asked
/// for, or on a GPU adapter for large scenes with textured materials
/// ([`WAVEFRONT_MIN_TRIANGLES`]), wherever its steps can trace the scene.
fn wavefront_decision(
    scene: &GpuScene,
    options: PathTraceOptions,
    kind: &dyn crate::intersect::IntersectorKind,
) -> Decision {
    let wanted = match options.schedule {
        Schedule::Megakernel => Err("the megakernel asked for".to_owned()),
        Schedule::Wavefront => Ok("asked for"),
        Schedule::Auto if options.cpu_adapter => Err(
            "a CPU adapter: the megakernel, or the host's steps (the wavefront measured 0.5x \
             the megakernel on lavapipe; --schedule wavefront asks for it)"
                .to_owned(),
        ),
        Schedule::Auto if textured_materials(scene) == 0 => {
            Err(format!("no textured material: {GPU_MEGAKERNEL_REASON}"))
        }
        Schedule::Auto if scene.tri_positions.len() < WAVEFRONT_MIN_TRIANGLES => Err(format!(
            "{} triangles < {WAVEFRONT_MIN_TRIANGLES}: {GPU_MEGAKERNEL_REASON}",
            scene.tri_positions.len()
        )),
        Schedule::Auto => Ok(GPU_WAVEFRONT_REASON),
    };
    let (included, reason) = match (wanted, kind.no_wavefront()) {
        (Err(why), _) => (false, why),
        (Ok(_), _) if !options.specialize => (false, "general shader: the megakernel".to_owned()),
        (Ok(_), Some(no)) => (false, no.to_owned()),
        (Ok(why), None) => {
            match support::cannot_trace(support::Tracer::Wavefront, scene, options) {
                Some(cannot) => (false, format!("{cannot}: the megakernel")),
                None => (true, why.to_owned()),
            }
        }
    };
    Decision { included, reason }
}
