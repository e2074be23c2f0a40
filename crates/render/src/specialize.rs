//! Shaders specialized to the scene: code the scene does not need is not compiled.
//!
//! On CPU drivers (lavapipe), every memory load inside the traversal loop is costly, while
//! constants written into the shader are nearly free; on GPUs, tiny scenes gain too. So a
//! scene with few primitives gets an intersection routine that tests every primitive with
//! its coordinates written into the code, replacing `pathtrace/intersect.wgsl` (the BVH
//! traversal over storage buffers) through the import resolver's overrides.

use std::fmt::Write as _;

use lumagraph_scene::GpuScene;

/// Scenes with at most this many primitives get inline intersection code.
pub const INLINE_MAX_PRIMITIVES: usize = 64;

fn v3(v: [f32; 3]) -> String {
    format!("vec3<f32>({:?}, {:?}, {:?})", v[0], v[1], v[2])
}

/// Generated replacement for `pathtrace/intersect.wgsl`, or `None` when the scene is too
/// large to inline.
pub fn inline_intersection(scene: &GpuScene) -> Option<String> {
    let (tris, spheres) = (&scene.tri_positions, &scene.spheres);
    if tris.len() + spheres.len() > INLINE_MAX_PRIMITIVES {
        return None;
    }
    let mut closest = String::new();
    let mut any = String::new();
    for (i, t) in tris.iter().enumerate() {
        let args = format!("{}, {}, {}", v3(t.v0), v3(t.e1), v3(t.e2));
        let _ = writeln!(
            closest,
            "    r = intersect_triangle(ray.origin, ray.dir, {args}, hit.t);\n    if (r.x != 0.0) {{ hit = Hit({i}u, r.y, r.z, r.w); }}"
        );
        let _ = writeln!(
            any,
            "    if (intersect_triangle(ray.origin, ray.dir, {args}, t_max).x != 0.0) {{ return true; }}"
        );
    }
    for (i, s) in spheres.iter().enumerate() {
        let args = format!("{}, {:?}", v3(s.center), s.radius);
        let _ = writeln!(
            closest,
            "    t = intersect_sphere(ray.origin, ray.dir, {args}, hit.t);\n    if (t > 0.0) {{ hit = Hit({i}u | PRIM_SPHERE, t, 0.0, 0.0); }}"
        );
        let _ = writeln!(
            any,
            "    if (intersect_sphere(ray.origin, ray.dir, {args}, t_max) > 0.0) {{ return true; }}"
        );
    }
    Some(format!(
        "// Generated for this scene: {} triangles and {} spheres, tested one by one with their
// coordinates inline (no BVH, no geometry buffers read).
#import \"pathtrace/primitives.wgsl\"

fn intersect_scene_within(ray: Ray, t_max: f32) -> Hit {{
    var hit = Hit(NO_HIT, t_max, 0.0, 0.0);
    var r: vec4<f32>;
    var t: f32;
{closest}    return hit;
}}

fn intersect_scene(ray: Ray) -> Hit {{
    return intersect_scene_within(ray, F32_MAX);
}}

fn occluded(ray: Ray, t_max: f32) -> bool {{
{any}    return false;
}}
",
        tris.len(),
        spheres.len()
    ))
}

/// What the graph needs of the path tracer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathTraceOptions {
    /// Specialize to the scene where it pays (off: the general shader, for benchmarks).
    pub specialize: bool,
    /// Write the first-hit AOVs (albedo, normal, depth): something reads them.
    pub aovs: bool,
}

/// The path tracer's source for `scene`, specialized where it pays, and a line saying how.
///
/// # Errors
/// When a shader file is missing.
pub fn pathtrace_source(
    scene: &GpuScene,
    options: PathTraceOptions,
) -> crate::Result<(String, String)> {
    let mut overrides = vec![(
        "pathtrace/options.wgsl",
        format!("const WRITE_AOVS: bool = {};\n", options.aovs),
    )];
    let inline = if options.specialize {
        inline_intersection(scene)
    } else {
        None
    };
    let how = if let Some(code) = inline {
        overrides.push(("pathtrace/intersect.wgsl", code));
        format!(
            "intersection inlined ({} primitives <= {INLINE_MAX_PRIMITIVES}): BVH traversal left out",
            scene.tri_positions.len() + scene.spheres.len()
        )
    } else {
        format!("BVH traversal ({} nodes)", scene.bvh_nodes.len())
    };
    let how = if options.aovs {
        format!("{how}; first-hit AOVs written")
    } else {
        format!("{how}; AOVs left out (nothing reads them)")
    };
    let source = crate::shader::resolve_with("pathtrace/pathtrace.wgsl", &overrides)?;
    Ok((source, how))
}
