//! The path tracer's shader features, typed: each [`Feature`] is decided once for a scene,
//! an adapter and a graph ([`Features::decide`]), with the reason for its choice. The WGSL
//! options (`pathtrace/options.wgsl`), the plan's explanation and the node's own choices
//! (host intersection, dispatch sizes) all derive from the one [`Features`] value; no
//! choice is found by its label, which is only what `plan` prints.
//!
//! Leaving a feature out is an optimization and must never change an image: a lobe is left
//! out only where no material can produce it, counting what its textures can do (a
//! metallic-roughness texture can lower a metallic factor of 1 to 0 per texel), from the
//! range of the texels each texture holds.

use lumagraph_scene::{
    ENV_MAP, ENV_NONE, FEATURE_TEXTURES, GpuMaterial, GpuScene, MATERIAL_ALPHA_BLEND,
    MATERIAL_ALPHA_MASK, MATERIAL_INDEX_MATCHED, MATERIAL_MEDIUM,
};

use super::ranges::{MaterialRanges, material_ranges};
use super::{INLINE_MAX_MATERIALS, Intersector, PathTraceOptions, Schedule, codegen};
use crate::intersect::{IntersectorKind, KINDS};

/// The last kind the adapter's choice tries: it traces every scene (a test holds it).
fn last() -> &'static dyn IntersectorKind {
    KINDS[KINDS.len() - 1]
}

/// One part of the path tracer that a shader compiles in or leaves out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    /// Materials and lights (and, with inline intersection, the primitives' shading data)
    /// written into the code.
    InlineData,
    /// Next-event estimation with multiple importance sampling.
    LightSampling,
    /// A non-black environment.
    Environment,
    /// The environment map's importance sampling.
    EnvMapSampling,
    /// Triangle leaves and surfaces.
    Triangles,
    /// Analytic shapes' leaves and surfaces.
    Shapes,
    /// The dielectric specular (GGX) lobe over the diffuse base.
    SpecularLobe,
    /// The metal lobe.
    MetalLobe,
    /// The glass (rough dielectric transmission) lobe.
    GlassLobe,
    /// The energy-preserving Oren–Nayar diffuse base.
    RoughDiffuse,
    /// The clear coat over the lobes (`pathtrace/bsdf/coat.wgsl`).
    Coat,
    /// The sheen under the clear coat (`pathtrace/bsdf/sheen.wgsl`).
    Sheen,
    /// Media inside shapes and index-matched boundaries.
    Media,
    /// The any-hit test of alpha-masked and blended materials, in every intersector.
    Alpha,
    /// Instanced meshes: the WGSL BVH walk has two levels (`pathtrace/intersect/instances.wgsl`).
    Instances,
    /// First-hit albedo, normal and depth.
    FirstHitAovs,
    /// Adaptive sampling's statistics and skipping.
    Adaptive,
    /// UVs, tangents and texture sampling.
    Textures,
    /// Workgroups spread over the image (CPU adapters).
    SpreadWorkgroups,
    /// A lane whose path ended starts its next sample at once (CPU adapters).
    PathRegeneration,
    /// The wavefront: the WGSL shades the paths step by step, as for host intersection, and
    /// a kernel of its own traces each step's rays on the device ([`crate::wavefront`]).
    Wavefront,
}

impl Feature {
    /// Every feature, in the order `plan` lists them.
    pub const ALL: [Self; 21] = [
        Self::InlineData,
        Self::LightSampling,
        Self::Environment,
        Self::EnvMapSampling,
        Self::Triangles,
        Self::Shapes,
        Self::SpecularLobe,
        Self::MetalLobe,
        Self::GlassLobe,
        Self::RoughDiffuse,
        Self::Coat,
        Self::Sheen,
        Self::Media,
        Self::Alpha,
        Self::Instances,
        Self::FirstHitAovs,
        Self::Adaptive,
        Self::Textures,
        Self::SpreadWorkgroups,
        Self::PathRegeneration,
        Self::Wavefront,
    ];

    /// What `plan` and the render's shader line call it: words for people, never looked up
    /// (a test renames every label and checks that no choice changes).
    pub fn label(self) -> &'static str {
        #[cfg(test)]
        if RENAMED.with(std::cell::Cell::get) {
            return Box::leak(format!("feature #{}", self as usize).into_boxed_str());
        }
        match self {
            Self::InlineData => "inline materials and lights",
            Self::LightSampling => "light sampling (NEE + MIS)",
            Self::Environment => "environment",
            Self::EnvMapSampling => "environment map sampling",
            Self::Triangles => "triangle tests",
            Self::Shapes => "shape tests",
            Self::SpecularLobe => "dielectric specular lobe",
            Self::MetalLobe => "metal lobe",
            Self::GlassLobe => "glass lobe",
            Self::RoughDiffuse => "rough diffuse (EON)",
            Self::Coat => "clear coat",
            Self::Sheen => "sheen",
            Self::Media => "participating media",
            Self::Alpha => "alpha (mask, blend)",
            Self::Instances => "instanced meshes (two-level BVH)",
            Self::FirstHitAovs => "first-hit AOVs",
            Self::Adaptive => "adaptive sampling",
            Self::Textures => "material textures",
            Self::SpreadWorkgroups => "spread workgroups",
            Self::PathRegeneration => "path regeneration",
            Self::Wavefront => "wavefront",
        }
    }

    /// The `bool` constant of `pathtrace/options.wgsl` that compiles it in or out; `None`
    /// for the features that choose which files are imported instead (intersection and
    /// scene data, see [`super::Specialization::source`]).
    pub const fn wgsl_const(self) -> Option<&'static str> {
        Some(match self {
            Self::InlineData => return None,
            Self::LightSampling => "HAS_LIGHTS",
            Self::Environment => "HAS_ENVIRONMENT",
            Self::EnvMapSampling => "HAS_ENV_MAP",
            Self::Triangles => "HAS_TRIANGLES",
            Self::Shapes => "HAS_SHAPES",
            Self::SpecularLobe => "HAS_SPECULAR",
            Self::MetalLobe => "HAS_METAL",
            Self::GlassLobe => "HAS_GLASS",
            Self::RoughDiffuse => "HAS_ROUGH_DIFFUSE",
            Self::Coat => "HAS_COAT",
            Self::Sheen => "HAS_SHEEN",
            Self::Media => "HAS_MEDIA",
            Self::Alpha => "HAS_ALPHA",
            Self::Instances => "HAS_INSTANCES",
            Self::FirstHitAovs => "WRITE_AOVS",
            Self::Adaptive => "ADAPTIVE",
            Self::Textures => "HAS_TEXTURES",
            Self::SpreadWorkgroups => "SPREAD_WORKGROUPS",
            Self::PathRegeneration => "REGENERATE_PATHS",
            Self::Wavefront => "WAVEFRONT",
        })
    }
}

/// Whether a feature is compiled in, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decision {
    /// Whether its code is compiled in.
    pub included: bool,
    /// Why, for people.
    pub reason: String,
}

fn decision(included: bool, reason: impl Into<String>) -> Decision {
    Decision {
        included,
        reason: reason.into(),
    }
}

/// Every [`Feature`]'s decision for one shader.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Features {
    /// In [`Feature::ALL`]'s order.
    decisions: Vec<Decision>,
    /// The intersector that traces the scene (never [`Intersector::AUTO`]).
    intersector: Intersector,
    /// Per intersector, in [`KINDS`]' order: why it traces the scene or does not.
    intersectors: Vec<(Intersector, String)>,
}

impl Features {
    /// Decides every feature for `scene` and `options`.
    pub fn decide(scene: &GpuScene, options: PathTraceOptions) -> Self {
        let facts = Facts::new(scene, options);
        Self {
            decisions: Feature::ALL.iter().map(|&f| facts.decide(f)).collect(),
            intersector: facts.kind.intersector(),
            intersectors: facts.intersectors,
        }
    }

    /// Whether `f` is compiled in.
    pub fn on(&self, f: Feature) -> bool {
        self.decisions[f as usize].included
    }

    /// Why `f` is compiled in or left out.
    pub fn reason(&self, f: Feature) -> &str {
        &self.decisions[f as usize].reason
    }

    /// Every feature with its decision, in [`Feature::ALL`]'s order.
    pub fn iter(&self) -> impl Iterator<Item = (Feature, &Decision)> {
        Feature::ALL.into_iter().zip(&self.decisions)
    }

    /// The intersector these features trace with (never [`Intersector::AUTO`]).
    pub fn intersector(&self) -> Intersector {
        self.intersector
    }

    /// Its kind.
    pub fn kind(&self) -> &'static dyn IntersectorKind {
        self.intersector.kind().unwrap_or_else(last)
    }

    /// Why [`Features::intersector`] traces the scene, for the plan.
    pub fn intersector_reason(&self) -> &str {
        self.why(self.intersector)
    }

    /// Why `intersector` traces the scene, or does not (where it cannot, or was passed
    /// over, or another was asked for or chosen before it).
    pub fn why(&self, intersector: Intersector) -> &str {
        self.intersectors
            .iter()
            .find(|(i, _)| *i == intersector)
            .map_or("the adapter's choice", |(_, why)| why.as_str())
    }

    /// Every intersector with why it traces the scene or does not, in [`KINDS`]' order.
    pub fn intersectors(&self) -> impl Iterator<Item = (Intersector, &str)> {
        self.intersectors.iter().map(|(i, why)| (*i, why.as_str()))
    }

    /// The schedule these features lay the paths out with (never [`Schedule::Auto`]).
    pub fn schedule(&self) -> Schedule {
        if self.on(Feature::Wavefront) {
            Schedule::Wavefront
        } else {
            Schedule::Megakernel
        }
    }

    /// The same features with `f` set to `included` (tests compare shaders that differ in
    /// one feature).
    #[must_use]
    pub fn with(mut self, f: Feature, included: bool) -> Self {
        self.decisions[f as usize] = decision(included, "forced");
        self
    }

    /// `pathtrace/options.wgsl` for these features: one `const NAME: bool` for each feature
    /// that has one.
    pub fn wgsl_options(&self) -> String {
        use std::fmt::Write as _;
        let mut out = String::from(
            "// Generated from the shader's features (crates/pathtrace/src/specialize/features.rs).\n",
        );
        for (f, d) in self.iter() {
            if let Some(name) = f.wgsl_const() {
                let _ = writeln!(out, "const {name}: bool = {};", d.included);
            }
        }
        // The intersectors' own constants: true for the one that traces.
        for kind in KINDS {
            if let Some(name) = kind.wgsl_const() {
                let _ = writeln!(
                    out,
                    "const {name}: bool = {};",
                    kind.intersector() == self.intersector
                );
            }
        }
        // Paths traced in steps (`pathtrace/integrator/wave.wgsl`), by either.
        let waves = self.kind().host_steps() || self.on(Feature::Wavefront);
        let _ = writeln!(out, "const WAVES: bool = {waves};");
        out
    }

    /// What `lumagraph plan` prints of these choices, a line each: the intersector and
    /// why (and why not each other one), the schedule and why, then what is compiled in and
    /// what is left out, each with why.
    pub fn lines(&self) -> Vec<String> {
        let mut lines = vec![format!(
            "  intersector: {} ({})",
            self.intersector().name(),
            self.intersector_reason()
        )];
        for (other, why) in self.intersectors() {
            if other != self.intersector() {
                lines.push(format!("    not {}: {why}", other.name()));
            }
        }
        lines.push(format!(
            "  schedule: {} ({})",
            self.schedule().name(),
            self.reason(Feature::Wavefront)
        ));
        for included in [true, false] {
            lines.push(format!(
                "  {}:",
                if included { "compiled in" } else { "left out" }
            ));
            for (f, d) in self.iter().filter(|(_, d)| d.included == included) {
                lines.push(format!("    {:<28} {}", f.label(), d.reason));
            }
        }
        lines
    }

    /// One line for the render's output: how the scene is intersected and where its data
    /// lives, then what is left out.
    pub fn summary(&self) -> String {
        let kind = self.kind();
        let how = match (self.on(Feature::InlineData), kind.inline()) {
            (true, true) => format!("{}, materials and lights inlined", kind.how()),
            (true, false) => format!("{}, materials inlined", kind.how()),
            (false, _) => kind.how().to_owned(),
        };
        let how = if self.on(Feature::Wavefront) {
            format!("{how}, in wavefront steps")
        } else {
            how
        };
        let left_out: Vec<&str> = self
            .iter()
            .filter(|(_, d)| !d.included)
            .map(|(f, _)| f.label())
            .collect();
        format!(
            "{how}; left out: {}",
            if left_out.is_empty() {
                "nothing".to_owned()
            } else {
                left_out.join(", ")
            }
        )
    }
}

/// What the decisions are made from, worked out once.
struct Facts<'a> {
    scene: &'a GpuScene,
    options: PathTraceOptions,
    /// The general shader: everything compiled in.
    all: bool,
    /// The intersector that traces the scene.
    kind: &'static dyn IntersectorKind,
    /// Per intersector, why it traces the scene or does not.
    intersectors: Vec<(Intersector, String)>,
    inline_data: bool,
    textured: bool,
    materials: Vec<MaterialRanges>,
}

/// The intersector that traces `scene` with `options`, and why each kind does or does not:
/// the one asked for where it can trace the scene ([`super::support::why_not`]), else the
/// first of [`KINDS`] that can and that the adapter's choice takes
/// ([`IntersectorKind::auto`]).
fn choose(
    scene: &GpuScene,
    options: PathTraceOptions,
) -> (&'static dyn IntersectorKind, Vec<(Intersector, String)>) {
    let cannot = |i| super::support::why_not(i, scene, options);
    let asked =
        Some(options.intersector).filter(|&i| i != Intersector::AUTO && cannot(i).is_none());
    let mut chosen: Option<&'static dyn IntersectorKind> = None;
    let mut reasons = Vec::with_capacity(KINDS.len());
    for &kind in KINDS {
        let i = kind.intersector();
        let why = match (cannot(i), chosen, asked) {
            (Some(why), _, _) => why,
            (None, Some(c), _) => format!("{} traces the scene", c.describe()),
            (None, None, Some(a)) if a == i => {
                chosen = Some(kind);
                kind.asked(scene)
            }
            (None, None, Some(a)) => format!("{} asked for", a.describe()),
            (None, None, None) => match kind.auto(scene, options) {
                Ok(why) => {
                    chosen = Some(kind);
                    why
                }
                Err(why) => why,
            },
        };
        reasons.push((i, why));
    }
    (chosen.unwrap_or_else(last), reasons)
}

impl<'a> Facts<'a> {
    fn new(scene: &'a GpuScene, options: PathTraceOptions) -> Self {
        let (kind, intersectors) = choose(scene, options);
        let textured = scene.header.features & FEATURE_TEXTURES != 0;
        // Small scenes have all their data written into the code; larger ones on a CPU
        // adapter their materials (and few lights), the primitives' data staying in buffers.
        let inline_data = options.specialize
            && options.cpu_adapter
            && !options.data_in_buffers
            && !textured
            && scene.materials.len() <= INLINE_MAX_MATERIALS
            && codegen::inlinable(scene, kind.inline());
        Self {
            scene,
            options,
            all: !options.specialize,
            kind,
            intersectors,
            inline_data,
            textured,
            materials: scene
                .materials
                .iter()
                .enumerate()
                .map(|(i, m)| material_ranges(scene, i, m))
                .collect(),
        }
    }

    /// How many materials can do what `f` says (over all their texels).
    fn count(&self, f: impl Fn(&MaterialRanges, &GpuMaterial) -> bool) -> usize {
        self.materials
            .iter()
            .zip(&self.scene.materials)
            .filter(|(r, m)| f(r, m))
            .count()
    }

    /// `n` things that need a feature, or the general shader's reason.
    fn needed(&self, n: usize, what: &str) -> Decision {
        if self.all {
            decision(true, "general shader (specialization off)")
        } else if n > 0 {
            decision(true, format!("{n} {what}"))
        } else {
            decision(false, format!("no {what}"))
        }
    }

    /// A lobe or layer of the material model: needed where some material can produce it,
    /// counting what its textures can do.
    fn lobe(&self, f: Feature) -> Decision {
        match f {
            Feature::SpecularLobe => self.needed(
                self.count(|r, _| {
                    r.specular.max > 0.0 && r.metallic.min < 1.0 && r.transmission.min < 1.0
                }),
                "materials with specular > 0",
            ),
            Feature::MetalLobe => self.needed(
                self.count(|r, _| r.metallic.max > 0.0),
                "materials with metallic > 0",
            ),
            Feature::GlassLobe => self.needed(
                self.count(|r, _| r.transmission.max > 0.0 && r.metallic.min < 1.0),
                "materials with transmission > 0",
            ),
            Feature::RoughDiffuse => self.needed(
                self.count(|r, m| {
                    m.diffuse_roughness > 0.0 && r.metallic.min < 1.0 && r.transmission.min < 1.0
                }),
                "materials with diffuse_roughness > 0",
            ),
            // Textures multiply the factors: a factor of 0 is none at every texel.
            Feature::Coat => self.needed(
                self.count(|_, m| m.clearcoat > 0.0),
                "materials with a clear coat",
            ),
            Feature::Sheen => self.needed(
                self.count(|_, m| m.sheen_color.iter().any(|&c| c > 0.0)),
                "materials with a sheen",
            ),
            _ => unreachable!("{f:?} is not a lobe"),
        }
    }

    fn decide(&self, f: Feature) -> Decision {
        let s = self.scene;
        match f {
            Feature::InlineData => decision(
                self.inline_data,
                super::inline_data_reason(s, self.options, self.inline_data, self.kind.inline()),
            ),
            Feature::LightSampling => self.needed(s.lights.len(), "emissive primitives"),
            Feature::Environment => {
                let env = self.all || s.settings.env_kind != ENV_NONE;
                decision(
                    env,
                    if env {
                        "environment not black"
                    } else {
                        "black environment"
                    },
                )
            }
            Feature::EnvMapSampling => {
                let map = self.all || s.settings.env_kind == ENV_MAP;
                decision(
                    map,
                    if map {
                        "equirectangular map, importance sampled"
                    } else {
                        "no environment map"
                    },
                )
            }
            Feature::Triangles => self.needed(s.tri_positions.len(), "triangles"),
            Feature::Shapes => self.needed(s.shapes.len(), "analytic shapes"),
            Feature::SpecularLobe
            | Feature::MetalLobe
            | Feature::GlassLobe
            | Feature::RoughDiffuse
            | Feature::Coat
            | Feature::Sheen => self.lobe(f),
            Feature::Alpha => self.needed(
                self.count(|r, m| {
                    (m.flags & MATERIAL_ALPHA_MASK != 0 && r.opacity.min < m.alpha_cutoff)
                        || (m.flags & MATERIAL_ALPHA_BLEND != 0 && r.opacity.min < 1.0)
                }),
                "materials that can be cut out (alpha mask) or seen through (alpha blend)",
            ),
            Feature::Instances => self.needed(s.instances.len(), "instances"),
            Feature::Media => self.needed(
                self.count(|_, m| m.flags & (MATERIAL_MEDIUM | MATERIAL_INDEX_MATCHED) != 0),
                "materials with a medium inside or an index-matched boundary",
            ),
            Feature::FirstHitAovs => decision(
                self.options.aovs,
                if self.options.aovs {
                    "albedo, normal or depth is read"
                } else {
                    "nothing reads albedo, normal or depth"
                },
            ),
            Feature::Adaptive => decision(
                self.options.adaptive,
                if self.options.adaptive {
                    "adaptive_error > 0"
                } else {
                    "adaptive_error is 0"
                },
            ),
            Feature::Textures => decision(
                self.all || self.textured,
                super::textures_reason(s, self.all),
            ),
            Feature::SpreadWorkgroups => {
                let o = self.options;
                decision(
                    o.cpu_adapter && !o.in_image_order,
                    if !o.cpu_adapter {
                        "a GPU adapter: workgroups in image order"
                    } else if o.in_image_order {
                        "image order asked for"
                    } else {
                        "a CPU adapter: each driver thread takes one contiguous range of workgroups"
                    },
                )
            }
            Feature::PathRegeneration => decision(
                self.options.cpu_adapter && self.kind.inline(),
                if !self.options.cpu_adapter {
                    "a GPU adapter: one bounce loop per sample"
                } else if self.kind.inline() {
                    "a CPU adapter: a SIMD lane whose path ended starts its next sample at once"
                } else {
                    "BVH traversal: no gain measured on a CPU adapter"
                },
            ),
            Feature::Wavefront => super::wavefront_decision(s, self.options, self.kind),
        }
    }
}

#[cfg(test)]
thread_local! {
    /// Set by a test: every label is then another word.
    static RENAMED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
mod tests {
    use super::{Feature, Features, RENAMED};
    use crate::specialize::{Intersector, PathTraceOptions, Schedule, Specialization};
    use lumagraph_scene::{GpuScene, Scene};

    /// Every label renamed, the features of scenes of every kind under every set of
    /// options decide the same (each feature's decision, the WGSL options, the whole
    /// shader source), while the plan's words do change: nothing is found by its label.
    #[test]
    fn no_choice_depends_on_a_label() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let mut compared = 0;
        for rel in [
            "assets/cornell.ron",
            "assets/cornell_spheres.ron",
            "assets/furnace_materials.ron",
            "tests/scenes/mesh_env.ron",
            "tests/scenes/media_scattering.ron",
            "tests/scenes/env_map.ron",
            "tests/scenes/disk.ron",
            "tests/scenes/instances.ron",
        ] {
            let scene = GpuScene::build(&Scene::load(&root.join(rel)).unwrap()).unwrap();
            for bits in 0..64_u32 {
                for intersector in [
                    Intersector::AUTO,
                    Intersector::INLINE,
                    Intersector::HOST,
                    Intersector::BINARY_BVH,
                    Intersector::WIDE_BVH,
                    Intersector::RAY_QUERIES,
                ] {
                    let options = PathTraceOptions {
                        specialize: bits & 1 != 0,
                        cpu_adapter: bits & 2 != 0,
                        aovs: bits & 4 != 0,
                        adaptive: bits & 8 != 0,
                        host_rays: bits & 16 != 0,
                        ray_query_limit: (bits & 32 != 0).then_some(1 << 24),
                        intersector,
                        schedule: if bits % 3 == 0 {
                            Schedule::Wavefront
                        } else {
                            Schedule::Auto
                        },
                        ..PathTraceOptions::default()
                    };
                    let decide = |renamed: bool| {
                        RENAMED.with(|r| r.set(renamed));
                        let f = Features::decide(&scene, options);
                        let source = Specialization::new(&scene, options).source().unwrap();
                        let words = f.summary();
                        RENAMED.with(|r| r.set(false));
                        (f, source, words)
                    };
                    let (a, source_a, words_a) = decide(false);
                    let (b, source_b, words_b) = decide(true);
                    for f in Feature::ALL {
                        assert_eq!(a.on(f), b.on(f), "{rel} {options:?}: {f:?}");
                    }
                    assert_eq!(a.wgsl_options(), b.wgsl_options(), "{rel} {options:?}");
                    assert!(
                        source_a == source_b,
                        "{rel} {options:?}: the shader differs"
                    );
                    assert_ne!(words_a, words_b, "{rel}: the labels were not renamed");
                    compared += 1;
                }
            }
        }
        assert_eq!(compared, 8 * 64 * 6);
    }
}
