//! The path tracer's intersectors as parts, as shapes and lights are: each is an
//! [`IntersectorKind`] in a file of its own here (with its WGSL under
//! `shaders/pathtrace/intersect/`), listed once in the `intersectors!` line below.
//!
//! A kind says what it can trace (its column of the support matrix,
//! [`crate::specialize::support`]), what the adapter must have for it, whether the adapter's
//! own choice (`auto`) takes it, the WGSL that replaces `pathtrace/intersect.wgsl`, and what
//! it builds for a `PathTrace` node (a [`Traversal`]: a buffer bound in the BVH's slot, an
//! acceleration structure, or the host's own steps). Every kind implements the contract of
//! `shaders/pathtrace/intersect/contract.wgsl` (the closest hit, occlusion up to a distance,
//! the alpha any-hit test); the Rust mirror (`lumagraph_scene::traverse`) follows it on the
//! CPU. Nothing outside this folder names a kind to decide anything: the decisions
//! ([`crate::specialize::Features`]), the support matrix, the node and the plan ask the
//! kinds.

use glam::Vec3;
use lumagraph_scene::GpuScene;

use crate::specialize::{Features, PathTraceOptions, support::Content};
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::Result;

/// Declares the intersector modules and [`KINDS`], in the order the adapter's choice tries
/// them (the first that can trace the scene and whose [`IntersectorKind::auto`] takes it).
macro_rules! intersectors {
    ($($module:ident :: $kind:ident),* $(,)?) => {
        $(pub mod $module;)*
        /// Every intersector, in the order the adapter's choice tries them.
        pub static KINDS: &[&dyn IntersectorKind] = &[$(&$module::$kind),*];
    };
}

// The list: one entry per intersector.
intersectors!(
    inline::Inline,
    host::Host,
    ray_queries::RayQueries,
    wide_bvh::WideBvhKind,
    binary_bvh::BinaryBvh
);

/// One way of intersecting the path tracer's rays. The defaults are those of a WGSL
/// traversal over the scene's buffers that needs nothing of its own.
pub trait IntersectorKind: Sync {
    /// Its handle: its word in the `intersector` param and `--intersector`.
    fn intersector(&self) -> Intersector;

    /// What it is, in the plan's words ("the 8-wide BVH").
    fn describe(&self) -> &'static str;

    /// How the render's shader line says it traces ("8-wide BVH traversal").
    fn how(&self) -> &'static str;

    /// Its column of the support matrix: whether it traces each [`Content::ALL`] row.
    fn traces(&self) -> [bool; Content::ALL.len()];

    /// Why it cannot trace `content` (a row its column lacks), in the plan's words.
    fn lacks(&self, content: Content, scene: &GpuScene) -> String {
        crate::specialize::support::reason(content, scene)
    }

    /// What the adapter or the scene lacks for it beyond the matrix (Embree not found, no
    /// ray queries, a device limit), or `None`.
    fn unavailable(&self, _scene: &GpuScene, _options: PathTraceOptions) -> Option<String> {
        None
    }

    /// Whether the adapter's choice takes it where it can trace the scene: `Ok(why)`, or
    /// `Err(why not)` (the next kind in [`KINDS`] is tried).
    ///
    /// # Errors
    /// Why the adapter's choice passes it over.
    fn auto(&self, scene: &GpuScene, options: PathTraceOptions) -> Result<String, String>;

    /// Why it traces the scene when asked for.
    fn asked(&self, _scene: &GpuScene) -> String {
        "asked for".to_owned()
    }

    /// The WGSL that replaces `pathtrace/intersect.wgsl`, or `None` for that file (the
    /// binary BVH). `alpha`: the any-hit test is compiled in.
    fn wgsl(&self, _scene: &GpuScene, _alpha: bool) -> Option<String> {
        None
    }

    /// A WGSL `enable` directive its code needs.
    fn enable(&self) -> Option<&'static str> {
        None
    }

    /// The `bool` constant of `pathtrace/options.wgsl` that is true where it traces.
    fn wgsl_const(&self) -> Option<&'static str> {
        None
    }

    /// It tests every primitive in code written for the scene: no traversal loop, so the
    /// shader may also hold the primitives' shading data and regenerate paths.
    fn inline(&self) -> bool {
        false
    }

    /// The host traces the rays and the WGSL shades them in steps (`pathtrace/integrator/wave.wgsl`),
    /// between which the host intersects.
    fn host_steps(&self) -> bool {
        false
    }

    /// Why the wavefront (whose `wave_trace` kernel intersects on the device through
    /// `pathtrace/intersect.wgsl`) cannot schedule the paths it traces, if it cannot.
    fn no_wavefront(&self) -> Option<&'static str> {
        None
    }

    /// Whether the shader reads the scene's binary BVH records.
    fn reads_binary_bvh(&self, _features: &Features) -> bool {
        false
    }

    /// What a `PathTrace` node keeps for it, built over `scene`.
    ///
    /// # Errors
    /// When building its structure fails.
    fn build(
        &self,
        _ctx: &GpuContext,
        _scene: &std::sync::Arc<GpuScene>,
    ) -> Result<Box<dyn Traversal>> {
        Ok(nothing())
    }
}

/// What an intersector keeps in a `PathTrace` node, and what it binds.
pub trait Traversal: Send + Sync {
    /// A buffer bound in the binary BVH's slot (`bvh_nodes`).
    fn bvh_nodes(&self) -> Option<&wgpu::Buffer> {
        None
    }

    /// The acceleration structure bound for ray queries.
    fn accel(&self) -> Option<&crate::accel::SceneAccel> {
        None
    }

    /// Host intersection's state, where the host traces the rays in steps.
    fn host(&self) -> Option<&crate::host_rays::HostRays> {
        None
    }

    /// The same, to trace with.
    fn host_mut(&mut self) -> Option<&mut crate::host_rays::HostRays> {
        None
    }

    /// What the render prints about it.
    fn note(&self, _scene: &GpuScene) -> Option<String> {
        None
    }
}

/// An intersector that keeps nothing.
struct Nothing;

impl Traversal for Nothing {}

/// What an intersector that keeps nothing keeps.
pub(crate) fn nothing() -> Box<dyn Traversal> {
    Box::new(Nothing)
}

/// An intersector by name: [`Intersector::AUTO`] (the scene and the adapter decide) or one
/// of [`KINDS`] (each defines its constant in its own file, e.g. `Intersector::WIDE_BVH`).
/// This is what the `PathTrace` node's `intersector` param, `lumagraph render
/// --intersector`, a session, a test or a benchmark asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Intersector(&'static str);

impl Default for Intersector {
    fn default() -> Self {
        Self::AUTO
    }
}

impl Intersector {
    /// The scene and the adapter decide: the first of [`KINDS`] that can trace the scene
    /// and that the adapter's choice takes.
    pub const AUTO: Self = Self("auto");

    /// The handle of the kind whose word is `name` (for the kinds' own constants).
    pub(crate) const fn named(name: &'static str) -> Self {
        Self(name)
    }

    /// Its kind (`None` for [`Intersector::AUTO`]).
    pub fn kind(self) -> Option<&'static dyn IntersectorKind> {
        KINDS.iter().copied().find(|k| k.intersector() == self)
    }

    /// Its word in the `intersector` param and the `--intersector` option.
    pub fn name(self) -> &'static str {
        self.0
    }

    /// What it is, in the plan's words.
    pub fn describe(self) -> &'static str {
        self.kind().map_or("the adapter's choice", |k| k.describe())
    }

    /// Every choice, [`Intersector::AUTO`] first.
    pub fn all() -> impl Iterator<Item = Self> {
        std::iter::once(Self::AUTO).chain(KINDS.iter().map(|k| k.intersector()))
    }

    /// The intersector a word names ([`Intersector::name`]).
    ///
    /// # Errors
    /// An unknown word, with the known ones.
    pub fn from_name(name: &str) -> Result<Self, String> {
        Self::all().find(|i| i.name() == name).ok_or_else(|| {
            let known: Vec<&str> = Self::all().map(Self::name).collect();
            format!("unknown intersector {name:?}: {}", known.join(", "))
        })
    }
}

/// A box from `lo` to `hi`, grown by a few ulps of `scale` (the largest magnitude the
/// primitive's inputs have): a point the shader's tests find on the primitive, computed from
/// those inputs with rounding, may lie that far outside the exact box (where a sphere
/// touches a plane through the origin, its box's face is at 0, its computed points not).
fn padded(lo: Vec3, hi: Vec3, scale: f32) -> [f32; 6] {
    let grow = Vec3::splat(scale * (16.0 * f32::EPSILON) + f32::MIN_POSITIVE);
    let (lo, hi) = (lo - grow, hi + grow);
    [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]
}

/// Every triangle's and analytic shape's box (min xyz, max xyz), in the order of
/// `GpuScene::tri_positions` and `GpuScene::shapes`, padded so that any point the WGSL
/// tests find on the primitive lies inside: the inputs of both the device's acceleration
/// structure ([`crate::accel`]) and the wide BVH.
pub fn primitive_boxes(scene: &GpuScene) -> (Vec<[f32; 6]>, Vec<[f32; 6]>) {
    let tris = scene
        .tri_positions
        .iter()
        .map(|t| {
            let v0 = Vec3::from(t.v0);
            let (e1, e2) = (Vec3::from(t.e1), Vec3::from(t.e2));
            let (v1, v2) = (v0 + e1, v0 + e2);
            let scale = [v0, v1, v2, e1, e2]
                .iter()
                .map(|v| v.abs().max_element())
                .fold(0.0f32, f32::max);
            padded(v0.min(v1).min(v2), v0.max(v1).max(v2), scale)
        })
        .collect();
    let shapes = scene
        .shapes
        .iter()
        .map(|s| {
            let [lo, hi] = lumagraph_scene::shapes::KINDS[s.kind as usize].bounds(s);
            padded(lo, hi, lo.abs().max(hi.abs()).max_element())
        })
        .collect();
    (tris, shapes)
}
