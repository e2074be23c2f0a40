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
            "    r = intersect_triangle(ray.origin, ray.dir, {args}, hit.t);\n    if (r.x != 0.0 && skip_prim != {i}u) {{ hit = Hit({i}u, r.y, r.z, r.w); }}"
        );
        let _ = writeln!(
            any,
            "    if (skip_prim != {i}u && intersect_triangle(ray.origin, ray.dir, {args}, t_max).x != 0.0) {{ return true; }}"
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

/// One feature of the path tracer, compiled in or left out for a scene, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Feature {
    /// What the feature is.
    pub name: &'static str,
    /// Whether its code is compiled in.
    pub included: bool,
    /// Why.
    pub reason: String,
}

fn feature(name: &'static str, included: bool, reason: impl Into<String>) -> Feature {
    Feature {
        name,
        included,
        reason: reason.into(),
    }
}

/// The features of the path tracer for `scene`: what is compiled in, what is left out.
pub fn features(scene: &GpuScene, options: PathTraceOptions) -> Vec<Feature> {
    let all = !options.specialize;
    let m = &scene.materials;
    let count =
        |f: &dyn Fn(&lumagraph_scene::GpuMaterial) -> bool| m.iter().filter(|x| f(x)).count();
    let specular = count(&|x| x.specular > 0.0 && x.metallic < 1.0 && x.transmission < 1.0);
    let metal = count(&|x| x.metallic > 0.0);
    let glass = count(&|x| x.transmission > 0.0 && x.metallic < 1.0);
    let prims = scene.tri_positions.len() + scene.spheres.len();
    let inline = options.specialize && prims <= INLINE_MAX_PRIMITIVES;
    let env = scene.settings.env_kind != lumagraph_scene::ENV_NONE;
    let env_map = scene.settings.env_kind == lumagraph_scene::ENV_MAP;
    let lights = scene.lights.len();
    let textured = scene.header.features & lumagraph_scene::FEATURE_TEXTURES != 0;
    let textured_materials = count(&|x| {
        [
            x.tex_base_mr,
            x.tex_emissive_normal,
            x.tex_transmission_specular,
            x.tex_specular_color,
        ]
        .iter()
        .any(|&t| t & 0xFFFF != 0xFFFF || t >> 16 != 0xFFFF)
    });
    let why = |n: usize, what: &str| {
        if all {
            "general shader (specialization off)".to_owned()
        } else if n > 0 {
            format!("{n} {what}")
        } else {
            format!("no {what}")
        }
    };
    vec![
        feature(
            "BVH traversal",
            !inline,
            if inline {
                format!("{prims} primitives <= {INLINE_MAX_PRIMITIVES}: tested inline")
            } else {
                format!("{} nodes", scene.bvh_nodes.len())
            },
        ),
        feature("inline intersection", inline, format!("{prims} primitives")),
        feature(
            "light sampling (NEE + MIS)",
            all || lights > 0,
            why(lights, "emissive primitives"),
        ),
        feature(
            "environment",
            all || env,
            if env || all {
                "environment not black".to_owned()
            } else {
                "black environment".to_owned()
            },
        ),
        feature(
            "environment map sampling",
            all || env_map,
            if env_map || all {
                "equirectangular map, importance sampled"
            } else {
                "no environment map"
            },
        ),
        feature(
            "dielectric specular lobe",
            all || specular > 0,
            why(specular, "materials with specular > 0"),
        ),
        feature(
            "metal lobe",
            all || metal > 0,
            why(metal, "materials with metallic > 0"),
        ),
        feature(
            "glass lobe",
            all || glass > 0,
            why(glass, "materials with transmission > 0"),
        ),
        feature(
            "first-hit AOVs",
            options.aovs,
            if options.aovs {
                "albedo, normal or depth is read"
            } else {
                "nothing reads albedo, normal or depth"
            },
        ),
        feature(
            "material textures",
            all || textured,
            if all {
                "general shader (specialization off)".to_owned()
            } else if textured {
                format!(
                    "{textured_materials} textured materials, {} KiB of texels",
                    scene.textures.len() * 4 / 1024
                )
            } else {
                "no material has a texture".to_owned()
            },
        ),
    ]
}

/// The path tracer's source for `scene`, specialized where it pays, and a line saying how.
///
/// # Errors
/// When a shader file is missing.
pub fn pathtrace_source(
    scene: &GpuScene,
    options: PathTraceOptions,
) -> crate::Result<(String, String)> {
    let features = features(scene, options);
    let on = |name: &str| features.iter().any(|f| f.name == name && f.included);
    let consts = format!(
        "const WRITE_AOVS: bool = {};\nconst HAS_SPECULAR: bool = {};\nconst HAS_METAL: bool = {};\n\
         const HAS_GLASS: bool = {};\nconst HAS_LIGHTS: bool = {};\nconst HAS_ENVIRONMENT: bool = {};\n\
         const HAS_ENV_MAP: bool = {};\nconst HAS_TEXTURES: bool = {};\n",
        on("first-hit AOVs"),
        on("dielectric specular lobe"),
        on("metal lobe"),
        on("glass lobe"),
        on("light sampling (NEE + MIS)"),
        on("environment"),
        on("environment map sampling"),
        on("material textures"),
    );
    let mut overrides = vec![("pathtrace/options.wgsl", consts)];
    if on("inline intersection")
        && let Some(code) = inline_intersection(scene)
    {
        overrides.push(("pathtrace/intersect.wgsl", code));
    }
    let left_out: Vec<&str> = features
        .iter()
        .filter(|f| !f.included)
        .map(|f| f.name)
        .collect();
    let how = format!(
        "{}; left out: {}",
        if on("inline intersection") {
            "intersection inlined"
        } else {
            "BVH traversal"
        },
        if left_out.is_empty() {
            "nothing".to_owned()
        } else {
            left_out.join(", ")
        }
    );
    let source = crate::shader::resolve_with("pathtrace/pathtrace.wgsl", &overrides)?;
    Ok((source, how))
}
