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

use std::fmt::Write as _;

use lumagraph_scene::GpuScene;

/// Scenes with at most this many primitives get inline intersection code.
pub const INLINE_MAX_PRIMITIVES: usize = 64;

fn v3(v: [f32; 3]) -> String {
    format!("vec3<f32>({:?}, {:?}, {:?})", v[0], v[1], v[2])
}

/// The triangles to test inline, in order: `(a, Some(b))` where triangles `a` and `b` are
/// the two halves of a parallelogram, tested as one (`intersect_parallelogram`): `a` is
/// (v0, v0 + e1, v0 + e2) and `b` is (v0, v0 + e2, v0 + e2 - e1), to the rounding of f32, as
/// `quad_triangles` splits a quad whose corners form a parallelogram (every `Quad`,
/// `Rectangle` and `Box` face of the shipped scenes). `(i, None)`: a triangle on its own.
pub fn parallelograms(tris: &[lumagraph_scene::GpuTriangle]) -> Vec<(usize, Option<usize>)> {
    let key = |v0: [f32; 3], e: [f32; 3]| (v0.map(f32::to_bits), e.map(f32::to_bits));
    let by_first_edge: std::collections::HashMap<_, usize> = tris
        .iter()
        .enumerate()
        .map(|(i, t)| (key(t.v0, t.e1), i))
        .collect();
    // The second half of each first half, wherever each is in the list (BVH order).
    let mut second: Vec<Option<usize>> = vec![None; tris.len()];
    let mut paired = vec![false; tris.len()];
    for (a, t) in tris.iter().enumerate() {
        let (e1, e2) = (glam::Vec3::from(t.e1), glam::Vec3::from(t.e2));
        // The second triangle's last corner where the parallelogram's is, within the
        // rounding of the subtraction that made its edge (corners given to 7 or 8 digits
        // rarely make an exact parallelogram in f32).
        let tolerance = 2.0 * f32::EPSILON * e1.abs().max(e2.abs()).max_element();
        let b = by_first_edge.get(&key(t.v0, t.e2)).copied().filter(|&b| {
            b != a
                && !paired[a]
                && !paired[b]
                && (glam::Vec3::from(tris[b].e2) - (e2 - e1))
                    .abs()
                    .max_element()
                    <= tolerance
        });
        if let Some(b) = b {
            (second[a], paired[a], paired[b]) = (Some(b), true, true);
        }
    }
    // Each pair where its first triangle was, every other triangle on its own.
    let mut out = Vec::new();
    for (i, b) in second.iter().enumerate() {
        if b.is_some() || !paired[i] {
            out.push((i, *b));
        }
    }
    out
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
    for (a, b) in parallelograms(tris) {
        let t = &tris[a];
        let args = format!("{}, {}, {}", v3(t.v0), v3(t.e1), v3(t.e2));
        match b {
            None => {
                let _ = writeln!(
                    closest,
                    "    r = intersect_triangle(ray.origin, ray.dir, {args}, hit.t);\n    if (r.x != 0.0 && skip_prim != {a}u) {{ hit = Hit({a}u, r.y, r.z, r.w); }}"
                );
                let _ = writeln!(
                    any,
                    "    if (skip_prim != {a}u && intersect_triangle(ray.origin, ray.dir, {args}, t_max).x != 0.0) {{ return true; }}"
                );
            }
            Some(b) => {
                // Hits with u < 0 are on the second triangle, (v0, v0 + e2, v0 + e2 - e1):
                // its barycentrics are (u + v, -u).
                let _ = writeln!(
                    closest,
                    "    r = intersect_parallelogram(ray.origin, ray.dir, {args}, hit.t);\n    if (r.x != 0.0 && skip_prim != {a}u && skip_prim != {b}u) {{ let second = r.z < 0.0; hit = Hit(select({a}u, {b}u, second), r.y, select(r.z, r.z + r.w, second), select(r.w, -r.z, second)); }}"
                );
                let _ = writeln!(
                    any,
                    "    if (skip_prim != {a}u && skip_prim != {b}u && intersect_parallelogram(ray.origin, ray.dir, {args}, t_max).x != 0.0) {{ return true; }}"
                );
            }
        }
    }
    for (i, s) in spheres.iter().enumerate() {
        let args = format!("{}, {:?}", v3(s.center), s.radius);
        let _ = writeln!(
            closest,
            "    t = intersect_sphere_from({i}u | PRIM_SPHERE, ray.origin, ray.dir, {args}, hit.t);\n    if (t > 0.0) {{ hit = Hit({i}u | PRIM_SPHERE, t, 0.0, 0.0); }}"
        );
        let _ = writeln!(
            any,
            "    if (intersect_sphere_from({i}u | PRIM_SPHERE, ray.origin, ray.dir, {args}, t_max) > 0.0) {{ return true; }}"
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

/// Scenes with at most this many materials (and [`INLINE_MAX_PRIMITIVES`] primitives) get
/// their materials, lights and per-primitive shading data written into the shader.
pub const INLINE_MAX_MATERIALS: usize = 64;

/// WGSL literals for scene values; remembers whether one was not finite (WGSL has no
/// literal for it).
#[derive(Default)]
struct Literals {
    not_finite: std::cell::Cell<bool>,
}

impl Literals {
    /// An f32 literal that parses back to exactly `x` (the shortest round-trip decimal).
    fn f(&self, x: f32) -> String {
        if !x.is_finite() {
            self.not_finite.set(true);
        }
        format!("{x:?}f")
    }

    fn v3(&self, v: [f32; 3]) -> String {
        format!(
            "vec3f({}, {}, {})",
            self.f(v[0]),
            self.f(v[1]),
            self.f(v[2])
        )
    }
}

fn u(x: u32) -> String {
    format!("{x}u")
}

/// WGSL functions returning row `i` of a table as a `ty` struct with fields of `types`:
/// one function per field, which compares `i` with the start of each run of equal values
/// and assigns (a select once compiled: no branch, no memory), so a field equal in every row
/// is a constant. A `const` array indexed at run time would instead be copied to scratch
/// memory per lookup on some drivers (Mesa's was 30x slower); a `switch` over the ids was
/// measured slower than these comparisons on lavapipe.
fn table_fns(name: &str, ty: &str, types: &[&str], rows: &[Vec<String>]) -> String {
    let mut out = String::new();
    let mut args = Vec::new();
    for (k, field_ty) in types.iter().enumerate() {
        let _ = writeln!(out, "fn {name}_{k}(i: u32) -> {field_ty} {{");
        match rows.first() {
            None => {
                let _ = writeln!(out, "    return {field_ty}();");
            }
            Some(first) => {
                let _ = writeln!(out, "    var r = {};", first[k]);
                for (j, row) in rows.iter().enumerate().skip(1) {
                    if row[k] != rows[j - 1][k] {
                        let _ = writeln!(out, "    if i >= {j}u {{ r = {}; }}", row[k]);
                    }
                }
                out.push_str("    return r;\n");
            }
        }
        out.push_str("}\n\n");
        args.push(format!("{name}_{k}(i)"));
    }
    let _ = writeln!(
        out,
        "fn {name}(i: u32) -> {ty} {{\n    return {ty}({});\n}}\n",
        args.join(", ")
    );
    out
}

/// Every material as WGSL literals, field by field.
fn materials_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .materials
        .iter()
        .map(|m| {
            vec![
                l.v3(m.base_color),
                l.f(m.roughness),
                l.v3(m.emission),
                l.f(m.metallic),
                l.f(m.specular),
                l.f(m.specular_tint),
                l.f(m.transmission),
                l.f(m.ior),
                u(m.tex_base_mr),
                u(m.tex_emissive_normal),
                u(m.flags),
                l.f(m.normal_scale),
                u(m.tex_transmission_specular),
                u(m.tex_specular_color),
                l.f(m.diffuse_roughness),
                u(0),
                l.v3(m.eta),
                u(0),
                l.v3(m.k),
                u(0),
                l.v3(m.f_avg),
                u(0),
                l.v3(m.sigma_a),
                l.f(m.phase_g),
                l.v3(m.sigma_s),
                u(0),
            ]
        })
        .collect()
}

/// Every light as WGSL literals.
fn lights_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .lights
        .iter()
        .map(|x| {
            vec![
                l.v3(x.p0),
                u(x.flags),
                l.v3(x.e1),
                u(x.prim),
                l.v3(x.e2),
                l.f(x.area),
                l.v3(x.emission),
                l.f(x.power),
            ]
        })
        .collect()
}

/// The light alias table as WGSL literals.
fn alias_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .light_alias
        .iter()
        .map(|a| vec![l.f(a.prob), u(a.other)])
        .collect()
}

/// Every triangle's intersection data as WGSL literals.
fn positions_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .tri_positions
        .iter()
        .map(|t| vec![l.v3(t.v0), u(0), l.v3(t.e1), u(0), l.v3(t.e2), u(0)])
        .collect()
}

/// Every triangle's shading data as WGSL literals; normals only with `TRI_VERTEX_NORMALS`
/// (else zeros, which make longer runs).
fn shading_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .tri_shading
        .iter()
        .map(|t| {
            let smooth = t.flags & lumagraph_scene::TRI_VERTEX_NORMALS != 0;
            let n = |v: [f32; 3]| {
                if smooth {
                    l.v3(v)
                } else {
                    "vec3f()".to_owned()
                }
            };
            vec![
                n(t.n0),
                u(t.material),
                n(t.n1),
                u(t.light),
                n(t.n2),
                u(t.flags),
            ]
        })
        .collect()
}

/// Every sphere as WGSL literals.
fn spheres_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .spheres
        .iter()
        .map(|s| {
            vec![
                l.v3(s.center),
                l.f(s.radius),
                u(s.material),
                u(s.light),
                u(0),
                u(0),
            ]
        })
        .collect()
}

/// Generated replacement for `pathtrace/scene_data.wgsl`: materials, lights, the light
/// alias table and every primitive's position and shading data written into the code and
/// returned by id, or `None` when the scene is too large ([`INLINE_MAX_PRIMITIVES`],
/// [`INLINE_MAX_MATERIALS`]), textured (texture lookups read their buffers anyway), or holds
/// a value that is not finite.
pub fn inline_scene_data(scene: &GpuScene) -> Option<String> {
    if scene.tri_positions.len() + scene.spheres.len() > INLINE_MAX_PRIMITIVES
        || scene.materials.len() > INLINE_MAX_MATERIALS
        || scene.header.features & lumagraph_scene::FEATURE_TEXTURES != 0
    {
        return None;
    }
    let l = Literals::default();
    let (f3, f1, u1) = ("vec3f", "f32", "u32");
    let materials = materials_rows(scene, &l);
    let lights = lights_rows(scene, &l);
    let alias = alias_rows(scene, &l);
    let positions = positions_rows(scene, &l);
    let shading = shading_rows(scene, &l);
    let spheres = spheres_rows(scene, &l);
    if l.not_finite.get() {
        return None;
    }
    let material_types = [
        f3, f1, f3, f1, f1, f1, f1, f1, u1, u1, u1, f1, u1, u1, f1, u1, f3, u1, f3, u1, f3, u1, f3,
        f1, f3, u1,
    ];
    Some(format!(
        "// Generated for this scene: {} materials, {} lights, {} triangles and {} spheres,
// returned by id with their values in the code (no material, light or shading buffer read).
#import \"pathtrace/scene_types.wgsl\"

{}{}{}{}{}{}",
        materials.len(),
        lights.len(),
        positions.len(),
        spheres.len(),
        table_fns("scene_material", "Material", &material_types, &materials),
        table_fns(
            "scene_light",
            "Light",
            &[f3, u1, f3, u1, f3, f1, f3, f1],
            &lights
        ),
        table_fns("scene_light_alias", "AliasEntry", &[f1, u1], &alias),
        table_fns(
            "scene_tri_positions",
            "TriPositions",
            &[f3, u1, f3, u1, f3, u1],
            &positions
        ),
        table_fns(
            "scene_tri_shading",
            "TriShading",
            &[f3, u1, f3, u1, f3, u1],
            &shading
        ),
        table_fns(
            "scene_sphere",
            "Sphere",
            &[f3, f1, u1, u1, u1, u1],
            &spheres
        ),
    ))
}

/// Generated replacement for `pathtrace/scene_data.wgsl` for scenes whose primitives are
/// too many to write into the code: the materials, and the lights and their alias table
/// where there are at most [`INLINE_MAX_MATERIALS`] of them, written into the code; the
/// primitives' positions and shading data read from their buffers. `None` where
/// [`inline_scene_data`] would also refuse the materials (too many, textured, a value not
/// finite).
pub fn inline_materials_data(scene: &GpuScene) -> Option<String> {
    if scene.materials.len() > INLINE_MAX_MATERIALS
        || scene.header.features & lumagraph_scene::FEATURE_TEXTURES != 0
    {
        return None;
    }
    let l = Literals::default();
    let (f3, f1, u1) = ("vec3f", "f32", "u32");
    let materials = materials_rows(scene, &l);
    let few_lights = scene.lights.len() <= INLINE_MAX_MATERIALS;
    let (lights, alias) = if few_lights {
        (lights_rows(scene, &l), alias_rows(scene, &l))
    } else {
        (Vec::new(), Vec::new())
    };
    if l.not_finite.get() {
        return None;
    }
    let material_types = [
        f3, f1, f3, f1, f1, f1, f1, f1, u1, u1, u1, f1, u1, u1, f1, u1, f3, u1, f3, u1, f3, u1, f3,
        f1, f3, u1,
    ];
    let light_fns = if few_lights {
        format!(
            "{}{}",
            table_fns(
                "scene_light",
                "Light",
                &[f3, u1, f3, u1, f3, f1, f3, f1],
                &lights
            ),
            table_fns("scene_light_alias", "AliasEntry", &[f1, u1], &alias)
        )
    } else {
        "fn scene_light(id: u32) -> Light {\n    return lights[id];\n}\n\n\
         fn scene_light_alias(i: u32) -> AliasEntry {\n    return light_alias[i];\n}\n\n"
            .to_owned()
    };
    Some(format!(
        "// Generated for this scene: {} materials{} returned by id with their values in the
// code; the {} triangles' and {} spheres' data read from their buffers.
#import \"pathtrace/scene_types.wgsl\"

{}{light_fns}fn scene_tri_positions(i: u32) -> TriPositions {{
    return tri_positions[i];
}}

fn scene_tri_shading(i: u32) -> TriShading {{
    return tri_shading[i];
}}

fn scene_sphere(i: u32) -> Sphere {{
    return spheres[i];
}}
",
        materials.len(),
        if few_lights {
            format!(" and {} lights", lights.len())
        } else {
            String::new()
        },
        scene.tri_positions.len(),
        scene.spheres.len(),
        table_fns("scene_material", "Material", &material_types, &materials),
    ))
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
    /// found, [`crate::embree`]) and may: the scene's rays are then traced there when the
    /// BVH would be traversed, and the scene allows (see [`features`]).
    pub host_rays: bool,
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

/// Why materials, lights and shading data are (or are not) written into the shader.
fn inline_intersection_reason(scene: &GpuScene, inline: bool) -> String {
    let prims = scene.tri_positions.len() + scene.spheres.len();
    let pairs = if inline {
        parallelograms(&scene.tri_positions)
            .iter()
            .filter(|(_, b)| b.is_some())
            .count()
    } else {
        0
    };
    if pairs > 0 {
        format!("{prims} primitives, {pairs} parallelograms of 2 triangles tested as one")
    } else {
        format!("{prims} primitives")
    }
}

fn inline_data_reason(
    scene: &GpuScene,
    options: PathTraceOptions,
    included: bool,
    all: bool,
) -> String {
    let m = scene.materials.len();
    let lights = scene.lights.len();
    let prims = scene.tri_positions.len() + scene.spheres.len();
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

/// Why texture sampling is (or is not) compiled in.
fn textures_reason(scene: &GpuScene, all: bool) -> String {
    let textured_materials = scene
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
        .count();
    if all {
        "general shader (specialization off)".to_owned()
    } else if textured_materials > 0 {
        format!(
            "{textured_materials} textured materials, {} KiB of texels",
            scene.textures.len() * 4 / 1024
        )
    } else {
        "no material has a texture".to_owned()
    }
}

/// The features of the path tracer for `scene`: what is compiled in, what is left out.
pub fn features(scene: &GpuScene, options: PathTraceOptions) -> Vec<Feature> {
    let all = !options.specialize;
    let m = &scene.materials;
    let prims = scene.tri_positions.len() + scene.spheres.len();
    let inline = options.specialize && options.cpu_adapter && prims <= INLINE_MAX_PRIMITIVES;
    let env = scene.settings.env_kind != lumagraph_scene::ENV_NONE;
    let env_map = scene.settings.env_kind == lumagraph_scene::ENV_MAP;
    let lights = scene.lights.len();
    let textured = scene.header.features & lumagraph_scene::FEATURE_TEXTURES != 0;
    // Small scenes have all their data written into the code; larger ones on a CPU adapter
    // their materials (and few lights), the primitives' data staying in buffers.
    let inline_data = options.specialize
        && options.cpu_adapter
        && !options.data_in_buffers
        && !textured
        && m.len() <= INLINE_MAX_MATERIALS
        && if inline {
            inline_scene_data(scene).is_some()
        } else {
            inline_materials_data(scene).is_some()
        };
    let mut out = vec![
        feature(
            "BVH traversal",
            !inline,
            if inline {
                format!("{prims} primitives <= {INLINE_MAX_PRIMITIVES}: tested inline")
            } else if options.specialize && !options.cpu_adapter && prims <= INLINE_MAX_PRIMITIVES {
                format!(
                    "{} nodes (a GPU adapter: faster than testing the {prims} primitives inline)",
                    scene.bvh_nodes.len()
                )
            } else {
                format!("{} nodes", scene.bvh_nodes.len())
            },
        ),
        feature(
            "inline intersection",
            inline,
            inline_intersection_reason(scene, inline),
        ),
        feature(
            "inline materials and lights",
            inline_data,
            inline_data_reason(scene, options, inline_data, inline),
        ),
        feature(
            "light sampling (NEE + MIS)",
            all || lights > 0,
            why(all, lights, "emissive primitives"),
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
    ];
    let (triangles, spheres) = (scene.tri_positions.len(), scene.spheres.len());
    out.extend([
        feature(
            "triangle tests",
            all || triangles > 0,
            why(all, triangles, "triangles"),
        ),
        feature(
            "sphere tests",
            all || spheres > 0,
            why(all, spheres, "spheres"),
        ),
    ]);
    out.extend(material_features(m, all));
    out.extend([
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
            "adaptive sampling",
            options.adaptive,
            if options.adaptive {
                "adaptive_error > 0"
            } else {
                "adaptive_error is 0"
            },
        ),
        feature(
            "material textures",
            all || textured,
            textures_reason(scene, all),
        ),
    ]);
    out.extend(cpu_features(options, inline));
    out.push(host_rays_feature(scene, options, inline));
    out
}

/// Whether the host intersects the rays (`HOST_RAYS`), and why (not).
fn host_rays_feature(scene: &GpuScene, options: PathTraceOptions, inline: bool) -> Feature {
    let media = scene.materials.iter().any(|x| {
        x.flags & (lumagraph_scene::MATERIAL_MEDIUM | lumagraph_scene::MATERIAL_INDEX_MATCHED) != 0
    });
    let (included, reason) = if !options.cpu_adapter || !options.specialize {
        (
            false,
            "a GPU adapter or the general shader: traced in WGSL".to_owned(),
        )
    } else if inline {
        (false, "intersected inline".to_owned())
    } else if !options.host_rays {
        (
            false,
            format!("no host intersector: {}", host_rays_unavailable()),
        )
    } else if scene.tri_positions.is_empty() || !scene.spheres.is_empty() {
        (
            false,
            "spheres or no triangles: the host intersects triangles only".to_owned(),
        )
    } else if media {
        (
            false,
            "participating media: shadow rays cross boundaries in WGSL".to_owned(),
        )
    } else if options.adaptive {
        (false, "adaptive sampling: traced in WGSL".to_owned())
    } else if scene.settings.max_bounces >= HOST_RAYS_MAX_BOUNCES {
        (
            false,
            format!(
                "{} bounces: a step keeps at most {HOST_RAYS_MAX_BOUNCES}",
                scene.settings.max_bounces
            ),
        )
    } else {
        (
            true,
            format!(
                "a CPU adapter: {} intersects the {} triangles on the host's threads, the WGSL shades",
                crate::embree::Embree::load().map_or_else(|e| e, |e| e.version()),
                scene.tri_positions.len()
            ),
        )
    };
    feature("host intersection", included, reason)
}

/// Why the host intersector is not used, for the plan.
/// Host intersection's steps keep the bounce in 24 bits of a word (`save_slot` in the shader).
const HOST_RAYS_MAX_BOUNCES: u32 = 1 << 24;

fn host_rays_unavailable() -> String {
    match crate::embree::Embree::load() {
        Ok(_) => "WGSL intersection asked for".to_owned(),
        Err(e) => e,
    }
}

/// How the work is laid out for a CPU adapter's driver threads and SIMD lanes.
fn cpu_features(options: PathTraceOptions, inline: bool) -> [Feature; 2] {
    [
        feature(
            "spread workgroups",
            options.cpu_adapter && !options.in_image_order,
            if !options.cpu_adapter {
                "a GPU adapter: workgroups in image order"
            } else if options.in_image_order {
                "image order asked for"
            } else {
                "a CPU adapter: each driver thread takes one contiguous range of workgroups"
            },
        ),
        feature(
            "path regeneration",
            options.cpu_adapter && inline,
            if !options.cpu_adapter {
                "a GPU adapter: one bounce loop per sample"
            } else if inline {
                "a CPU adapter: a SIMD lane whose path ended starts its next sample at once"
            } else {
                "BVH traversal: no gain measured on a CPU adapter"
            },
        ),
    ]
}

/// `n` things that need a feature, or the general shader's reason.
fn why(all: bool, n: usize, what: &str) -> String {
    if all {
        "general shader (specialization off)".to_owned()
    } else if n > 0 {
        format!("{n} {what}")
    } else {
        format!("no {what}")
    }
}

/// The lobes and media some material of the scene uses (all of them without `specialize`).
fn material_features(m: &[lumagraph_scene::GpuMaterial], all: bool) -> Vec<Feature> {
    let count =
        |f: &dyn Fn(&lumagraph_scene::GpuMaterial) -> bool| m.iter().filter(|x| f(x)).count();
    let specular = count(&|x| x.specular > 0.0 && x.metallic < 1.0 && x.transmission < 1.0);
    let metal = count(&|x| x.metallic > 0.0);
    let glass = count(&|x| x.transmission > 0.0 && x.metallic < 1.0);
    let rough_diffuse =
        count(&|x| x.diffuse_roughness > 0.0 && x.metallic < 1.0 && x.transmission < 1.0);
    let media = count(&|x| {
        x.flags & (lumagraph_scene::MATERIAL_MEDIUM | lumagraph_scene::MATERIAL_INDEX_MATCHED) != 0
    });
    let why = |n: usize, what: &str| why(all, n, what);
    vec![
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
            "rough diffuse (EON)",
            all || rough_diffuse > 0,
            why(rough_diffuse, "materials with diffuse_roughness > 0"),
        ),
        feature(
            "participating media",
            all || media > 0,
            why(
                media,
                "materials with a medium inside or an index-matched boundary",
            ),
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
        "const WRITE_AOVS: bool = {};\nconst ADAPTIVE: bool = {};\nconst SPREAD_WORKGROUPS: bool = {};\nconst REGENERATE_PATHS: bool = {};\nconst HAS_TRIANGLES: bool = {};\nconst HAS_SPHERES: bool = {};\nconst HAS_SPECULAR: bool = {};\nconst HAS_METAL: bool = {};\n\
         const HAS_GLASS: bool = {};\nconst HAS_LIGHTS: bool = {};\nconst HAS_ENVIRONMENT: bool = {};\n\
         const HAS_ENV_MAP: bool = {};\nconst HAS_TEXTURES: bool = {};\nconst HAS_ROUGH_DIFFUSE: bool = {};\n\
         const HAS_MEDIA: bool = {};\nconst HOST_RAYS: bool = {};\n",
        on("first-hit AOVs"),
        on("adaptive sampling"),
        on("spread workgroups"),
        on("path regeneration"),
        on("triangle tests"),
        on("sphere tests"),
        on("dielectric specular lobe"),
        on("metal lobe"),
        on("glass lobe"),
        on("light sampling (NEE + MIS)"),
        on("environment"),
        on("environment map sampling"),
        on("material textures"),
        on("rough diffuse (EON)"),
        on("participating media"),
        on("host intersection"),
    );
    let mut overrides = vec![("pathtrace/options.wgsl", consts)];
    if on("inline intersection")
        && let Some(code) = inline_intersection(scene)
    {
        overrides.push(("pathtrace/intersect.wgsl", code));
    }
    if on("inline materials and lights") {
        let code = if on("inline intersection") {
            inline_scene_data(scene)
        } else {
            inline_materials_data(scene)
        };
        if let Some(code) = code {
            overrides.push(("pathtrace/scene_data.wgsl", code));
        }
    }
    let left_out: Vec<&str> = features
        .iter()
        .filter(|f| !f.included)
        .map(|f| f.name)
        .collect();
    let how = format!(
        "{}; left out: {}",
        if on("inline materials and lights") && on("inline intersection") {
            "intersection inlined, materials and lights inlined"
        } else if on("host intersection") && on("inline materials and lights") {
            "rays intersected on the host, materials inlined"
        } else if on("host intersection") {
            "rays intersected on the host"
        } else if on("inline materials and lights") {
            "BVH traversal, materials inlined"
        } else if on("inline intersection") {
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
