//! The support matrix: what each intersector (and the wavefront schedule) can trace, as
//! data. The decisions ([`super::features`]) refuse an intersector asked for where the scene
//! has something its column lacks, and a render that asks for it through the `PathTrace`
//! node's `intersector` param or `lumagraph render --intersector` stops with that reason
//! ([`refusal`]). `docs/pathtracer.md` shows the table [`markdown`] writes; a test checks
//! both the page and every cell against the decisions.

use lumagraph_scene::{FEATURE_ALPHA, GpuScene, MATERIAL_INDEX_MATCHED, MATERIAL_MEDIUM};

use super::{
    Feature, Features, INLINE_MAX_PRIMITIVES, INSTANCES_REASON, Intersector, PathTraceOptions,
    Schedule,
};

/// Host intersection's steps keep the bounce in 24 bits of a word (`save_slot` in the shader).
pub const HOST_RAYS_MAX_BOUNCES: u32 = 1 << 24;

/// What a scene or a render has that not every intersector can trace: the matrix's rows,
/// in the order they are checked (the first one a column lacks is the reason given).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    /// The general shader (specialization off).
    GeneralShader,
    /// A GPU adapter (or one decided as a GPU: `Resources::as_gpu_adapter`).
    GpuAdapter,
    /// More than [`INLINE_MAX_PRIMITIVES`] primitives.
    ManyPrimitives,
    /// Analytic shapes, or no triangles at all.
    Shapes,
    /// Instanced meshes (a two-level BVH).
    Instances,
    /// Media inside shapes and index-matched boundaries.
    Media,
    /// Adaptive sampling (`adaptive_error` > 0).
    Adaptive,
    /// At least [`HOST_RAYS_MAX_BOUNCES`] bounces.
    ManyBounces,
    /// Alpha-masked or blended materials.
    Alpha,
    /// First-hit AOVs (albedo, normal, depth) read.
    Aovs,
}

impl Content {
    /// Every row, in the order they are checked.
    pub const ALL: [Self; 10] = [
        Self::GeneralShader,
        Self::GpuAdapter,
        Self::ManyPrimitives,
        Self::Shapes,
        Self::Instances,
        Self::Media,
        Self::Adaptive,
        Self::ManyBounces,
        Self::Alpha,
        Self::Aovs,
    ];

    /// The row's name in the table.
    pub fn label(self) -> &'static str {
        match self {
            Self::GeneralShader => "general shader (specialization off)",
            Self::GpuAdapter => "GPU adapter",
            Self::ManyPrimitives => "more than 64 primitives",
            Self::Shapes => "analytic shapes (or no triangles)",
            Self::Instances => "instanced meshes",
            Self::Media => "participating media",
            Self::Adaptive => "adaptive sampling",
            Self::ManyBounces => "2^24 bounces or more",
            Self::Alpha => "alpha (mask, blend)",
            Self::Aovs => "first-hit AOVs",
        }
    }

    /// Whether `scene`, rendered with `options`, has it.
    pub fn in_scene(self, scene: &GpuScene, options: PathTraceOptions) -> bool {
        match self {
            Self::GeneralShader => !options.specialize,
            Self::GpuAdapter => !options.cpu_adapter,
            Self::ManyPrimitives => {
                scene.tri_positions.len() + scene.shapes.len() > INLINE_MAX_PRIMITIVES
            }
            Self::Shapes => scene.tri_positions.is_empty() || !scene.shapes.is_empty(),
            Self::Instances => !scene.instances.is_empty(),
            Self::Media => scene
                .materials
                .iter()
                .any(|x| x.flags & (MATERIAL_MEDIUM | MATERIAL_INDEX_MATCHED) != 0),
            Self::Adaptive => options.adaptive,
            Self::ManyBounces => scene.settings.max_bounces >= HOST_RAYS_MAX_BOUNCES,
            Self::Alpha => scene.header.features & FEATURE_ALPHA != 0,
            Self::Aovs => options.aovs,
        }
    }
}

/// Who traces the rays: the matrix's columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tracer {
    /// [`Intersector::Inline`].
    Inline,
    /// [`Intersector::Host`] (besides: a CPU adapter with Embree).
    Host,
    /// [`Intersector::BinaryBvh`].
    BinaryBvh,
    /// [`Intersector::WideBvh`].
    WideBvh,
    /// [`Intersector::RayQueries`] (besides: a device with ray queries, within its limits).
    RayQueries,
    /// [`Schedule::Wavefront`] (besides: a WGSL BVH or ray queries intersect).
    Wavefront,
}

const T: bool = true;
const F: bool = false;

/// The support matrix: per column, whether it traces each [`Content::ALL`] row.
pub const MATRIX: [(Tracer, [bool; Content::ALL.len()]); 6] = [
    (Tracer::Inline, [F, T, F, T, F, T, T, T, T, T]),
    (Tracer::Host, [F, F, T, F, T, F, F, F, T, T]),
    (Tracer::BinaryBvh, [T, T, T, T, T, T, T, T, T, T]),
    (Tracer::WideBvh, [F, T, T, T, F, T, T, T, T, T]),
    (Tracer::RayQueries, [F, T, T, T, F, T, T, T, T, T]),
    (Tracer::Wavefront, [F, T, T, F, F, F, F, F, T, T]),
];

impl Tracer {
    /// The column of an intersector (none for [`Intersector::Auto`]).
    pub fn of(intersector: Intersector) -> Option<Self> {
        Some(match intersector {
            Intersector::Auto => return None,
            Intersector::Inline => Self::Inline,
            Intersector::Host => Self::Host,
            Intersector::BinaryBvh => Self::BinaryBvh,
            Intersector::WideBvh => Self::WideBvh,
            Intersector::RayQueries => Self::RayQueries,
        })
    }

    /// Whether it traces scenes with `content`.
    pub fn traces(self, content: Content) -> bool {
        let row = MATRIX
            .iter()
            .find(|(t, _)| *t == self)
            .map_or(&[F; Content::ALL.len()], |(_, row)| row);
        row[content as usize]
    }

    /// The column's name in the table (the param's and the option's word).
    pub fn name(self) -> &'static str {
        match self {
            Self::Inline => "inline",
            Self::Host => "host",
            Self::BinaryBvh => "binary",
            Self::WideBvh => "wide",
            Self::RayQueries => "rays",
            Self::Wavefront => "wavefront (schedule)",
        }
    }
}

/// Why `tracer` cannot trace `content`, in the decisions' words.
fn reason(tracer: Tracer, content: Content, scene: &GpuScene) -> String {
    match (content, tracer) {
        (Content::GeneralShader, Tracer::RayQueries) => "general shader: WGSL BVH".to_owned(),
        (Content::GeneralShader, Tracer::Wavefront) => "general shader: the megakernel".to_owned(),
        (Content::GeneralShader | Content::GpuAdapter, Tracer::Host) => {
            "a GPU adapter or the general shader: traced in WGSL".to_owned()
        }
        (Content::GeneralShader, _) => "general shader: the binary BVH".to_owned(),
        (Content::GpuAdapter, _) => "a GPU adapter".to_owned(),
        (Content::ManyPrimitives, _) => format!(
            "{} primitives > {INLINE_MAX_PRIMITIVES}",
            scene.tri_positions.len() + scene.shapes.len()
        ),
        (Content::Shapes, _) => {
            "analytic shapes or no triangles: the steps shade triangle hits only".to_owned()
        }
        (Content::Instances, _) => INSTANCES_REASON.to_owned(),
        (Content::Media, _) => {
            "participating media: shadow rays cross boundaries in WGSL".to_owned()
        }
        (Content::Adaptive, _) => "adaptive sampling: traced in WGSL".to_owned(),
        (Content::ManyBounces, _) => format!(
            "{} bounces: a step keeps at most {HOST_RAYS_MAX_BOUNCES}",
            scene.settings.max_bounces
        ),
        (Content::Alpha | Content::Aovs, _) => format!("{} not traced", content.label()),
    }
}

/// Why `tracer` cannot trace `scene` with `options`, by the matrix: the first row the scene
/// has that its column lacks.
pub fn cannot_trace(tracer: Tracer, scene: &GpuScene, options: PathTraceOptions) -> Option<String> {
    Content::ALL
        .into_iter()
        .find(|&c| !tracer.traces(c) && c.in_scene(scene, options))
        .map(|c| reason(tracer, c, scene))
}

/// Why `intersector` cannot trace `scene` with `options` (the matrix, then what the
/// adapter has), or `None` where it can ([`Intersector::Auto`] always can).
pub fn why_not(
    intersector: Intersector,
    scene: &GpuScene,
    options: PathTraceOptions,
) -> Option<String> {
    let tracer = Tracer::of(intersector)?;
    if let Some(why) = cannot_trace(tracer, scene, options) {
        return Some(why);
    }
    match tracer {
        Tracer::Host if !options.host_rays => Some(format!(
            "no host intersector: {}",
            super::host_rays_unavailable()
        )),
        Tracer::RayQueries => match options.ray_query_limit {
            None => Some(
                "the device has no ray queries (or they were turned off: LUMAGRAPH_RAY_QUERY=off)"
                    .to_owned(),
            ),
            Some(most) => crate::accel::unsupported(scene, most),
        },
        _ => None,
    }
}

/// Why the intersector or schedule `options` ask for cannot be what `features` (decided
/// from them) trace `scene` with, or `None` where both are honoured (or left to the
/// adapter): a render that asks for one it cannot have stops with this.
pub fn refusal(scene: &GpuScene, options: PathTraceOptions, features: &Features) -> Option<String> {
    if let Some(why) = why_not(options.intersector, scene, options) {
        return Some(format!(
            "the intersector asked for, {}, cannot trace this scene here: {why}",
            options.intersector.describe()
        ));
    }
    let chosen = features.intersector();
    if options.intersector != Intersector::Auto && chosen != options.intersector {
        return Some(format!(
            "{} was asked for, but {} traces the scene",
            options.intersector.describe(),
            chosen.describe()
        ));
    }
    if options.schedule == Schedule::Wavefront && !features.on(Feature::Wavefront) {
        let hint = match chosen {
            Intersector::Inline | Intersector::Host if options.intersector == Intersector::Auto => {
                " (the wavefront traces through a WGSL BVH or ray queries: ask for one too)"
            }
            _ => "",
        };
        return Some(format!(
            "the wavefront was asked for, but cannot take this scene here: {}{hint}",
            features.reason(Feature::Wavefront)
        ));
    }
    None
}

/// The matrix as a Markdown table: a row per [`Content`], a column per [`Tracer`].
pub fn markdown() -> String {
    use std::fmt::Write as _;
    let mut out = String::from("| the scene or render has |");
    for (t, _) in MATRIX {
        let _ = write!(out, " {} |", t.name());
    }
    out.push_str("\n|---|");
    for _ in MATRIX {
        out.push_str("---|");
    }
    out.push('\n');
    for c in Content::ALL {
        let _ = write!(out, "| {} |", c.label());
        for (t, _) in MATRIX {
            out.push_str(if t.traces(c) { " yes |" } else { " no |" });
        }
        out.push('\n');
    }
    out
}
