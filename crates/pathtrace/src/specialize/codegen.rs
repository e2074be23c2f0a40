//! Code written for one scene: intersection routines that test every primitive with its
//! coordinates in the code, and materials, lights and shading data returned by id with their
//! values in the code (replacing `pathtrace/intersect.wgsl` and `pathtrace/scene_data.wgsl`
//! through the import resolver's overrides). Which scenes get it is decided in
//! [`super::features`].

use std::fmt::Write as _;

use lumagraph_scene::lobes::Value;
use lumagraph_scene::{GpuMaterial, GpuScene};

use super::{INLINE_MAX_MATERIALS, INLINE_MAX_PRIMITIVES};

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
/// large to inline. With `alpha` ([`super::Feature::Alpha`]), the primitives of alpha-masked
/// or blended materials take the any-hit test.
pub fn inline_intersection(scene: &GpuScene, alpha: bool) -> Option<String> {
    let (tris, shapes) = (&scene.tri_positions, &scene.shapes);
    if tris.len() + shapes.len() > INLINE_MAX_PRIMITIVES {
        return None;
    }
    // Primitives of alpha-masked or blended materials take the any-hit test
    // (`triangle_hit_counts`, `shape_hit_counts` in pathtrace/intersect/alpha.wgsl), each triangle
    // on its own.
    let alpha_material = |m: u32| {
        alpha
            && scene.materials[m as usize].flags
                & (lumagraph_scene::MATERIAL_ALPHA_MASK | lumagraph_scene::MATERIAL_ALPHA_BLEND)
                != 0
    };
    let alpha_tri = |i: usize| alpha_material(scene.tri_shading[i].material);
    let mut closest = String::new();
    let mut any = String::new();
    let single = |a: usize, closest: &mut String, any: &mut String| {
        let t = &tris[a];
        let args = format!("{}, {}, {}", v3(t.v0), v3(t.e1), v3(t.e2));
        let test = if alpha_tri(a) {
            format!(" && triangle_hit_counts({a}u, r.z, r.w, ray)")
        } else {
            String::new()
        };
        let _ = writeln!(
            closest,
            "    r = intersect_triangle(ray.origin, ray.dir, {args}, hit.t);\n    if (r.x != 0.0 && skip_prim != {a}u{test}) {{ hit = Hit({a}u, r.y, r.z, r.w, NO_INSTANCE); }}"
        );
        let _ = writeln!(
            any,
            "    r = intersect_triangle(ray.origin, ray.dir, {args}, t_max);\n    if (skip_prim != {a}u && r.x != 0.0{test}) {{ return true; }}"
        );
    };
    for (a, b) in parallelograms(tris) {
        let t = &tris[a];
        let args = format!("{}, {}, {}", v3(t.v0), v3(t.e1), v3(t.e2));
        match b {
            Some(b) if !alpha_tri(a) && !alpha_tri(b) => {
                // Hits with u < 0 are on the second triangle, (v0, v0 + e2, v0 + e2 - e1):
                // its barycentrics are (u + v, -u).
                let _ = writeln!(
                    closest,
                    "    r = intersect_parallelogram(ray.origin, ray.dir, {args}, hit.t);\n    if (r.x != 0.0 && skip_prim != {a}u && skip_prim != {b}u) {{ let second = r.z < 0.0; hit = Hit(select({a}u, {b}u, second), r.y, select(r.z, r.z + r.w, second), select(r.w, -r.z, second), NO_INSTANCE); }}"
                );
                let _ = writeln!(
                    any,
                    "    if (skip_prim != {a}u && skip_prim != {b}u && intersect_parallelogram(ray.origin, ray.dir, {args}, t_max).x != 0.0) {{ return true; }}"
                );
            }
            Some(b) => {
                single(a, &mut closest, &mut any);
                single(b, &mut closest, &mut any);
            }
            None => single(a, &mut closest, &mut any),
        }
    }
    // Each shape through its kind's own test (the dispatch's choice made here).
    for (i, s) in shapes.iter().enumerate() {
        let kind = lumagraph_scene::shapes::KINDS[s.kind as usize].name();
        let args = format!(
            "Shape({}, {:?}, {}, {}u, 0u, 0u, 0u, 0u)",
            v3(s.center),
            s.radius,
            v3(s.axis),
            s.kind
        );
        let test = if alpha_material(s.material) {
            format!(" && shape_hit_counts({i}u, ray)")
        } else {
            String::new()
        };
        let _ = writeln!(
            closest,
            "    t = {kind}_intersect({i}u | PRIM_SHAPE, {args}, ray, hit.t);\n    if (t > 0.0{test}) {{ hit = Hit({i}u | PRIM_SHAPE, t, 0.0, 0.0, NO_INSTANCE); }}"
        );
        let _ = writeln!(
            any,
            "    if ({kind}_intersect({i}u | PRIM_SHAPE, {args}, ray, t_max) > 0.0{test}) {{ return true; }}"
        );
    }
    Some(format!(
        "// Generated for this scene: {} triangles and {} analytic shapes, tested one by one with
// their coordinates inline (no BVH, no geometry buffers read).
#import \"pathtrace/intersect/primitives.wgsl\"
#import \"pathtrace/shapes.wgsl\"

fn intersect_scene_within(ray: Ray, t_max: f32) -> Hit {{
    var hit = Hit(NO_HIT, t_max, 0.0, 0.0, NO_INSTANCE);
    var r: vec4<f32>;
    var t: f32;
{closest}    return hit;
}}

fn intersect_scene(ray: Ray) -> Hit {{
    return intersect_scene_within(ray, F32_MAX);
}}

fn occluded(ray: Ray, t_max: f32) -> bool {{
    var r: vec4<f32>;
{any}    return false;
}}
",
        tris.len(),
        shapes.len()
    ))
}

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

/// The WGSL types of [`materials_rows`]'s fields, in order (`Material`, written from the
/// same table: [`lumagraph_scene::lobes`]).
fn material_types() -> Vec<&'static str> {
    GpuMaterial::FIELDS.iter().map(|f| f.wgsl).collect()
}

/// The WGSL types of [`lights_rows`]'s fields, in order (`Light` in
/// `pathtrace/scene_types.wgsl`).
const LIGHT_TYPES: [&str; 10] = [
    "vec3f", "u32", "vec3f", "u32", "vec3f", "f32", "vec3f", "f32", "vec3f", "u32",
];

/// Every material as WGSL literals, field by field.
fn materials_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .materials
        .iter()
        .map(|m| {
            m.values()
                .into_iter()
                .map(|v| match v {
                    Value::F32(x) => l.f(x),
                    Value::U32(x) => u(x),
                    Value::Vec3f(x) => l.v3(x),
                })
                .collect()
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
                l.v3(x.params),
                u(x.kind),
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
        .map(|t| vec![l.v3(t.v0), u(t.flags), l.v3(t.e1), u(0), l.v3(t.e2), u(0)])
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

/// Every shape as WGSL literals.
fn shapes_rows(scene: &GpuScene, l: &Literals) -> Vec<Vec<String>> {
    scene
        .shapes
        .iter()
        .map(|s| {
            vec![
                l.v3(s.center),
                l.f(s.radius),
                l.v3(s.axis),
                u(s.kind),
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
    if scene.tri_positions.len() + scene.shapes.len() > INLINE_MAX_PRIMITIVES
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
    let shapes = shapes_rows(scene, &l);
    if l.not_finite.get() {
        return None;
    }
    Some(format!(
        "// Generated for this scene: {} materials, {} lights, {} triangles and {} shapes,
// returned by id with their values in the code (no material, light or shading buffer read).
#import \"pathtrace/scene_types.wgsl\"

{}{}{}{}{}{}",
        materials.len(),
        lights.len(),
        positions.len(),
        shapes.len(),
        table_fns("scene_material", "Material", &material_types(), &materials),
        table_fns("scene_light", "Light", &LIGHT_TYPES, &lights),
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
            "scene_shape",
            "Shape",
            &[f3, f1, f3, u1, u1, u1, u1, u1],
            &shapes
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
    let (f1, u1) = ("f32", "u32");
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
    let light_fns = if few_lights {
        format!(
            "{}{}",
            table_fns("scene_light", "Light", &LIGHT_TYPES, &lights),
            table_fns("scene_light_alias", "AliasEntry", &[f1, u1], &alias)
        )
    } else {
        "fn scene_light(id: u32) -> Light {\n    return lights[id];\n}\n\n\
         fn scene_light_alias(i: u32) -> AliasEntry {\n    return light_alias[i];\n}\n\n"
            .to_owned()
    };
    Some(format!(
        "// Generated for this scene: {} materials{} returned by id with their values in the
// code; the {} triangles' and {} shapes' data read from their buffers.
#import \"pathtrace/scene_types.wgsl\"

{}{light_fns}fn scene_tri_positions(i: u32) -> TriPositions {{
    return tri_positions[i];
}}

fn scene_tri_shading(i: u32) -> TriShading {{
    return tri_shading[i];
}}

fn scene_shape(i: u32) -> Shape {{
    return shapes[i];
}}
",
        materials.len(),
        if few_lights {
            format!(" and {} lights", lights.len())
        } else {
            String::new()
        },
        scene.tri_positions.len(),
        scene.shapes.len(),
        table_fns("scene_material", "Material", &material_types(), &materials),
    ))
}

/// Whether the scene's data can be written into the code: every value finite (WGSL has no
/// literal for the others). `inline`: with the primitives' data ([`inline_scene_data`]),
/// else materials and lights only ([`inline_materials_data`]).
pub(super) fn inlinable(scene: &GpuScene, inline: bool) -> bool {
    let l = Literals::default();
    materials_rows(scene, &l);
    if inline || scene.lights.len() <= INLINE_MAX_MATERIALS {
        lights_rows(scene, &l);
        alias_rows(scene, &l);
    }
    if inline {
        positions_rows(scene, &l);
        shading_rows(scene, &l);
        shapes_rows(scene, &l);
    }
    !l.not_finite.get()
}
