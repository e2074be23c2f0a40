//! Analytic shapes, each kind one part: its Rust side in `shapes/<kind>.rs` (bounds, the
//! CPU mirror of its ray test, its area, a hull for rasterizers, its Mitsuba 3 form) and
//! its WGSL side in `shaders/pathtrace/shapes/<kind>.wgsl` (`<kind>_intersect`,
//! `<kind>_normal`, `<kind>_sample`, `<kind>_pdf`). [`KINDS`] lists them, once: a shape's
//! kind is its index there, and the WGSL that calls a kind by its index,
//! `pathtrace/shapes.wgsl`, is written from the list ([`wgsl`]), not kept on disk.
//!
//! Every intersector reaches a shape through that one file: the BVHs, the device's ray
//! queries and the inline code call `shape_intersect` on a candidate (`candidates.wgsl`),
//! the surface and the light code `shape_normal`, `shape_sample` and `shape_pdf`; the CPU
//! mirror ([`crate::traverse`]), the BVH builders and the G-buffer raster call
//! [`ShapeKind`]. Adding a kind: its two files, a line in [`KINDS`] and its variant in the
//! scene format ([`crate::file::ShapeDesc`]).

mod disk;
mod sphere;

use std::fmt::Write as _;

use glam::Vec3;

use crate::gpu::GpuShape;

/// What the Rust side knows of a kind of shape. The parameters are a [`GpuShape`]'s:
/// `center`, `radius` and `axis`, which each kind reads its own way.
pub trait ShapeKind: Sync {
    /// Its name: the scene format's word, in lowercase, its WGSL file's name and its WGSL
    /// functions' prefix.
    fn name(&self) -> &'static str;
    /// Whether it encloses a volume: only a closed shape can bound a medium.
    fn closed(&self) -> bool;
    /// Its box, min then max, holding every point its ray test can return.
    fn bounds(&self, s: &GpuShape) -> [Vec3; 2];
    /// Its surface area.
    fn area(&self, s: &GpuShape) -> f32;
    /// The ray's nearest hit with `0 < t < t_max`: the CPU mirror of `<kind>_intersect`
    /// for a ray that does not leave it.
    fn intersect(&self, s: &GpuShape, origin: Vec3, dir: Vec3, t_max: f32) -> Option<f32>;
    /// The unit geometric normal, front side, at `p` on the shape: the CPU mirror of
    /// `<kind>_normal`.
    fn normal(&self, s: &GpuShape, p: Vec3) -> Vec3;
    /// Triangles whose projection covers the shape's from any viewpoint, `segments` around
    /// (the G-buffer rasterizes them and intersects the shape itself per fragment).
    fn hull(&self, s: &GpuShape, segments: u32) -> Vec<[Vec3; 3]>;
    /// Its Mitsuba 3 plugin dictionary without BSDF or emitter, as JSON (`type`, and
    /// `to_world` as a row-major 4×4 matrix where it has one).
    fn mitsuba(&self, s: &GpuShape) -> serde_json::Value;
}

/// [`crate::Shape::kind`] of a sphere.
pub const SPHERE: u32 = 0;
/// [`crate::Shape::kind`] of a disk.
pub const DISK: u32 = 1;

/// Every kind of shape, by its index. The first is what the WGSL dispatch falls back to.
pub static KINDS: [&dyn ShapeKind; 2] = [&sphere::Sphere, &disk::Disk];

/// The kind named `name` (the scene format's word, any case).
pub fn kind_named(name: &str) -> Option<u32> {
    KINDS
        .iter()
        .position(|k| k.name().eq_ignore_ascii_case(name))
        .map(|i| i as u32)
}

/// The kinds of `all` that `present` keeps, with their indices, or all of them where it
/// keeps none (a generated dispatch always has a kind to fall back on).
pub(crate) fn kinds_present<T: ?Sized>(
    all: &[&'static T],
    present: impl Fn(u32) -> bool,
) -> Vec<(u32, &'static T)> {
    let indexed = || (0..all.len() as u32).map(|i| (i, all[i as usize]));
    let kinds: Vec<_> = indexed().filter(|&(i, _)| present(i)).collect();
    if kinds.is_empty() {
        indexed().collect()
    } else {
        kinds
    }
}

/// The name shaders import the dispatch by.
pub const FILE: &str = "pathtrace/shapes.wgsl";

/// The dispatch, `pathtrace/shapes.wgsl`: an import of every kind's file, its index as a
/// constant `SHAPE_<NAME>`, and `shape_intersect`, `shape_normal`, `shape_sample` and
/// `shape_pdf` calling the kind of the shape they are given.
pub fn wgsl() -> String {
    wgsl_for(|_| true)
}

/// [`wgsl`] for the kinds `present` says a scene has, the others left out (every kind if
/// it has none): a scene of spheres compiles no branch on the kind at all. The path tracer's
/// specialization writes it for its scene; leaving a kind out never changes an image, as the
/// scene has no shape of it.
pub fn wgsl_for(present: impl Fn(u32) -> bool) -> String {
    let kinds = kinds_present(&KINDS, present);
    let mut out = String::from(
        "// Generated from crates/scene/src/shapes/mod.rs (`KINDS`): calls each analytic \
         shape's\n// functions by its kind. Not a file on disk.\n",
    );
    for (_, k) in &kinds {
        let _ = writeln!(out, "#import \"pathtrace/shapes/{}.wgsl\"", k.name());
    }
    for (i, k) in KINDS.iter().enumerate() {
        let _ = writeln!(out, "const SHAPE_{}: u32 = {i}u;", k.name().to_uppercase());
    }
    let dispatch = |out: &mut String, doc: &str, sig: &str, call: &str| {
        let _ = writeln!(out, "\n// {doc}\nfn shape_{sig} {{");
        for (i, k) in kinds.iter().skip(1) {
            let _ = writeln!(
                out,
                "    if s.kind == {i}u {{\n        return {}_{call};\n    }}",
                k.name()
            );
        }
        let _ = writeln!(out, "    return {}_{call};\n}}", kinds[0].1.name());
    };
    dispatch(
        &mut out,
        "The hit of shape `prim` (its index | PRIM_SHAPE), `s`, nearest along `ray` in (0, \
         t_max), or -1;\n// a ray leaving it (`skip_prim`) follows the kind's rules.",
        "intersect(prim: u32, s: Shape, ray: Ray, t_max: f32) -> f32",
        "intersect(prim, s, ray, t_max)",
    );
    dispatch(
        &mut out,
        "The unit geometric normal, front side, at `p` on `s`.",
        "normal(s: Shape, p: vec3f) -> vec3f",
        "normal(s, p)",
    );
    dispatch(
        &mut out,
        "A point of `s` sampled as seen from `x` with the random numbers `u` (only the front \
         side lit\n// unless `two_sided`).",
        "sample(s: Shape, x: vec3f, u: vec2f, two_sided: bool) -> ShapeSample",
        "sample(s, x, u, two_sided)",
    );
    dispatch(
        &mut out,
        "The solid-angle pdf, as (numerator, denominator), with which `shape_sample` from `x` \
         gives `y`.",
        "pdf(s: Shape, x: vec3f, y: vec3f) -> vec2f",
        "pdf(s, x, y)",
    );
    out
}
