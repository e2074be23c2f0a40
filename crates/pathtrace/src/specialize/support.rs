//! The support matrix: what each intersector (and the wavefront schedule) can trace, as
//! data: a column per intersector, each kind's own ([`crate::intersect::IntersectorKind::traces`]), and the
//! wavefront's. The decisions ([`super::features`]) refuse an intersector asked for where the scene
//! has something its column lacks, and a render that asks for it through the `PathTrace`
//! node's `intersector` param or `lumagraph render --intersector` stops with that reason
//! ([`refusal`]). `docs/pathtracer.md` shows the table [`markdown`] writes; a test checks
//! both the page and every cell against the decisions.

use lumagraph_scene::{FEATURE_ALPHA, GpuScene, MATERIAL_INDEX_MATCHED, MATERIAL_MEDIUM};

use super::{
    Feature, Features, INLINE_MAX_PRIMITIVES, INSTANCES_REASON, Intersector, PathTraceOptions,
    Schedule,
};
use crate::intersect::KINDS;

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

/// Who traces the rays: the matrix's columns, one per intersector
/// ([`crate::intersect::KINDS`], each kind's [`crate::intersect::IntersectorKind::traces`]) and the wavefront.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tracer {
    /// An intersector (never [`Intersector::AUTO`]).
    Intersector(Intersector),
    /// [`Schedule::Wavefront`] (besides: a WGSL BVH or ray queries intersect).
    Wavefront,
}

const T: bool = true;
const F: bool = false;

/// The wavefront's column: its steps shade triangle hits only, and its `wave_trace`
/// intersects through the WGSL the intersector gives it.
const WAVEFRONT: [bool; Content::ALL.len()] = [F, T, T, F, F, F, F, F, T, T];

/// The support matrix: per column, whether it traces each [`Content::ALL`] row.
pub fn matrix() -> Vec<(Tracer, [bool; Content::ALL.len()])> {
    KINDS
        .iter()
        .map(|k| (Tracer::Intersector(k.intersector()), k.traces()))
        .chain([(Tracer::Wavefront, WAVEFRONT)])
        .collect()
}

impl Tracer {
    /// The column of an intersector (none for [`Intersector::AUTO`]).
    pub fn of(intersector: Intersector) -> Option<Self> {
        intersector
            .kind()
            .map(|k| Self::Intersector(k.intersector()))
    }

    /// Whether it traces scenes with `content`.
    pub fn traces(self, content: Content) -> bool {
        match self {
            Self::Intersector(i) => i.kind().is_some_and(|k| k.traces()[content as usize]),
            Self::Wavefront => WAVEFRONT[content as usize],
        }
    }

    /// The column's name in the table (the param's and the option's word).
    pub fn name(self) -> &'static str {
        match self {
            Self::Intersector(i) => i.name(),
            Self::Wavefront => "wavefront (schedule)",
        }
    }

    /// Why it cannot trace `content`, in the decisions' words.
    fn lacks(self, content: Content, scene: &GpuScene) -> String {
        match (self, content) {
            (Self::Intersector(i), _) => match i.kind() {
                Some(k) => k.lacks(content, scene),
                None => reason(content, scene),
            },
            (Self::Wavefront, Content::GeneralShader) => {
                "general shader: the megakernel".to_owned()
            }
            (Self::Wavefront, _) => reason(content, scene),
        }
    }
}

/// Why a column cannot trace `content`, in the decisions' words (what a kind says unless
/// it says more, [`IntersectorKind::lacks`]).
pub(crate) fn reason(content: Content, scene: &GpuScene) -> String {
    match content {
        Content::GeneralShader => "general shader: the binary BVH".to_owned(),
        Content::GpuAdapter => "a GPU adapter".to_owned(),
        Content::ManyPrimitives => format!(
            "{} primitives > {INLINE_MAX_PRIMITIVES}",
            scene.tri_positions.len() + scene.shapes.len()
        ),
        Content::Shapes => {
            "analytic shapes or no triangles: the steps shade triangle hits only".to_owned()
        }
        Content::Instances => INSTANCES_REASON.to_owned(),
        Content::Media => "participating media: shadow rays cross boundaries in WGSL".to_owned(),
        Content::Adaptive => "adaptive sampling: traced in WGSL".to_owned(),
        Content::ManyBounces => format!(
            "{} bounces: a step keeps at most {HOST_RAYS_MAX_BOUNCES}",
            scene.settings.max_bounces
        ),
        Content::Alpha | Content::Aovs => format!("{} not traced", content.label()),
    }
}

/// Why `tracer` cannot trace `scene` with `options`, by the matrix: the first row the scene
/// has that its column lacks.
pub fn cannot_trace(tracer: Tracer, scene: &GpuScene, options: PathTraceOptions) -> Option<String> {
    Content::ALL
        .into_iter()
        .find(|&c| !tracer.traces(c) && c.in_scene(scene, options))
        .map(|c| tracer.lacks(c, scene))
}

/// Why `intersector` cannot trace `scene` with `options` (the matrix, then what the
/// adapter has), or `None` where it can ([`Intersector::AUTO`] always can).
pub fn why_not(
    intersector: Intersector,
    scene: &GpuScene,
    options: PathTraceOptions,
) -> Option<String> {
    let kind = intersector.kind()?;
    cannot_trace(Tracer::Intersector(intersector), scene, options)
        .or_else(|| kind.unavailable(scene, options))
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
    if options.intersector != Intersector::AUTO && chosen != options.intersector {
        return Some(format!(
            "{} was asked for, but {} traces the scene",
            options.intersector.describe(),
            chosen.describe()
        ));
    }
    if options.schedule == Schedule::Wavefront && !features.on(Feature::Wavefront) {
        let hint = if options.intersector == Intersector::AUTO
            && features.kind().no_wavefront().is_some()
        {
            " (the wavefront traces through a WGSL BVH or ray queries: ask for one too)"
        } else {
            ""
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
    let matrix = matrix();
    for (t, _) in &matrix {
        let _ = write!(out, " {} |", t.name());
    }
    out.push_str("\n|---|");
    for _ in &matrix {
        out.push_str("---|");
    }
    out.push('\n');
    for c in Content::ALL {
        let _ = write!(out, "| {} |", c.label());
        for (t, _) in &matrix {
            out.push_str(if t.traces(c) { " yes |" } else { " no |" });
        }
        out.push('\n');
    }
    out
}
