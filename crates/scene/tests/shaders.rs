//! The WGSL mirror of the scene layout and traversal: imports resolved as the project
//! resolves them, validated with naga, struct layouts compared with the Rust structs.

mod common;

use std::mem::{offset_of, size_of};

use lumagraph_scene::{
    GpuAliasEntry, GpuBvhNode, GpuCamera, GpuHeader, GpuLight, GpuMaterial, GpuSettings, GpuShape,
    GpuTexDesc, GpuTriShading, GpuTriTexcoords, GpuTriangle,
};

/// The shader folder, and the generated files the scene crate writes (the dispatches over
/// the kinds of shapes and of lights without area, the `Material` struct).
fn source(name: &str) -> Option<String> {
    if name == lumagraph_scene::shapes::FILE {
        return Some(lumagraph_scene::shapes::wgsl());
    }
    if name == lumagraph_scene::lights::FILE {
        return Some(lumagraph_scene::lights::wgsl());
    }
    if name == lumagraph_scene::lobes::FILE {
        return Some(lumagraph_scene::lobes::wgsl());
    }
    lumagraph_wgsl::from_dir(common::shaders())(name)
}

/// `name` with its imports resolved as the renderer resolves them (`lumagraph-wgsl`), read
/// from the repository's `shaders/` folder.
fn resolve(name: &str) -> String {
    lumagraph_wgsl::resolve(name, &[], &source).unwrap_or_else(|e| panic!("{e}"))
}

fn validate(source: &str, what: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{what}: {}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{what}: {}", e.emit_to_string(source)));
    module
}

const STUB: &str = r#"
const HAS_TRIANGLES: bool = true;
const HAS_SHAPES: bool = true;
const HAS_ALPHA: bool = false;
const HAS_INSTANCES: bool = true;
fn triangle_hit_counts(prim: u32, u: f32, v: f32, ray: Ray) -> bool { return true; }
fn shape_hit_counts(i: u32, ray: Ray) -> bool { return true; }
@group(0) @binding(0) var<storage, read> bvh_nodes: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read> tri_positions: array<TriPositions>;
@group(0) @binding(2) var<storage, read> shapes: array<Shape>;
@group(0) @binding(3) var<storage, read_write> out_hits: array<Hit>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let ray = Ray(vec3<f32>(0.0, 0.0, 4.0), vec3<f32>(0.0, 0.1 * f32(id.x), -1.0));
    var hit = intersect_scene(ray);
    if (occluded(ray, 2.0)) {
        hit.u = -1.0;
    }
    out_hits[id.x] = hit;
    let h2 = intersect_scene_within(ray, 1.0);
    out_hits[id.x + 1u] = h2;
}
"#;

#[test]
fn bvh_wgsl_validates_with_a_stub() {
    let imported = lumagraph_wgsl::imports("pathtrace/intersect/bvh.wgsl", &source).unwrap();
    assert!(imported.iter().any(|f| f == "pathtrace/scene_types.wgsl"));
    let mut src = resolve("pathtrace/intersect/bvh.wgsl");
    src.push_str(STUB);
    validate(&src, "bvh.wgsl + stub");
}

#[test]
fn scene_types_validate_alone() {
    validate(&resolve("pathtrace/scene_types.wgsl"), "scene_types.wgsl");
}

macro_rules! layout {
    ($rust:ty, $wgsl:literal, [$($field:ident),* $(,)?]) => {
        (
            $wgsl,
            size_of::<$rust>(),
            vec![$((stringify!($field), offset_of!($rust, $field))),*],
        )
    };
}

/// `Material`'s layout: its fields as the table declares them (`lumagraph_scene::lobes`),
/// each at its Rust offset.
fn material_layout() -> (&'static str, usize, Vec<(&'static str, usize)>) {
    let fields = GpuMaterial::FIELDS.iter().map(|f| (f.name, f.offset));
    ("Material", size_of::<GpuMaterial>(), fields.collect())
}

/// The fields of the 208-byte record that the images were rendered with keep their
/// offsets: a field added to the table goes into padding (`pad*`) or after them.
#[test]
fn material_fields_keep_their_offsets() {
    let pinned: [(&str, usize); 34] = [
        ("base_color", 0),
        ("roughness", 12),
        ("emission", 16),
        ("metallic", 28),
        ("specular", 32),
        ("specular_tint", 36),
        ("transmission", 40),
        ("ior", 44),
        ("tex_base_mr", 48),
        ("tex_emissive_normal", 52),
        ("flags", 56),
        ("normal_scale", 60),
        ("tex_transmission_specular", 64),
        ("tex_specular_color", 68),
        ("diffuse_roughness", 72),
        ("opacity", 76),
        ("eta", 80),
        ("alpha_cutoff", 92),
        ("k", 96),
        ("tex_coat", 108),
        ("f_avg", 112),
        ("tex_sheen", 124),
        ("sigma_a", 128),
        ("phase_g", 140),
        ("sigma_s", 144),
        ("pad5", 156),
        ("sheen_color", 160),
        ("sheen_roughness", 172),
        ("clearcoat", 176),
        ("clearcoat_roughness", 180),
        ("pad6", 184),
        ("pad7", 188),
        ("specular_color", 192),
        ("clearcoat_normal_scale", 204),
    ];
    for (name, offset) in &pinned {
        let now = GpuMaterial::FIELDS.iter().find(|f| f.name == *name);
        let pad = name.starts_with("pad");
        assert!(
            now.map(|f| f.offset) == Some(*offset) || pad,
            "{name}: was at {offset}, now {now:?}"
        );
    }
    assert!(size_of::<GpuMaterial>() >= 208);
}

#[test]
fn wgsl_layouts_match_rust() {
    let expected = [
        layout!(GpuBvhNode, "BvhNode", [aabb_min, index, aabb_max, bits]),
        layout!(GpuTriangle, "TriPositions", [v0, flags, e1, pad1, e2, pad2]),
        layout!(
            GpuTriShading,
            "TriShading",
            [n0, material, n1, light, n2, flags]
        ),
        layout!(
            GpuShape,
            "Shape",
            [center, radius, axis, kind, material, light, pad0, pad1]
        ),
        material_layout(),
        layout!(
            GpuTriTexcoords,
            "TriTexcoords",
            [t0, t1, t2, uv01, uv2, uv1_2, uv1_01, colors, pad0]
        ),
        layout!(GpuTexDesc, "TexDesc", [place, m, offset, uv_set, mips]),
        layout!(
            GpuLight,
            "Light",
            [p0, flags, e1, prim, e2, area, emission, power, params, kind]
        ),
        layout!(GpuAliasEntry, "AliasEntry", [prob, other]),
        layout!(
            GpuCamera,
            "Camera",
            [
                position,
                tan_half_fov,
                right,
                aspect,
                up,
                aperture_radius,
                forward,
                focus_distance
            ]
        ),
        layout!(
            GpuSettings,
            "Settings",
            [
                width,
                height,
                max_bounces,
                spp,
                seed,
                env_kind,
                env_flags,
                env_azimuth,
                env_radiance,
                env_elevation
            ]
        ),
        layout!(
            GpuHeader,
            "SceneHeader",
            [
                num_nodes,
                num_triangles,
                num_shapes,
                num_materials,
                num_lights,
                bvh_depth,
                features,
                total_light_power
            ]
        ),
    ];
    let src = resolve("pathtrace/scene_types.wgsl");
    let module = validate(&src, "scene_types.wgsl");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    for (name, size, fields) in expected {
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no struct {name} in scene_types.wgsl"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{name} is not a struct");
        };
        let wgsl: Vec<_> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
            .collect();
        let rust: Vec<_> = fields.iter().map(|(f, o)| ((*f).to_owned(), *o)).collect();
        assert_eq!(wgsl, rust, "{name}: members and offsets");
        assert_eq!(*span as usize, size, "{name}: size");
        // Array stride in a storage buffer equals the Rust size.
        let stride = layouter[handle].to_stride();
        assert_eq!(stride as usize, size, "{name}: array stride");
    }
}

/// `pathtrace/intersect/instances.wgsl` reads an instance as vec4s of `bvh_nodes`: rows 0-2
/// `to_world`, 3-5 `to_object`, 6 (`root`, `flags`, `pad_scale`, `pad_base`), 7 (`index`); two node
/// records in all.
#[test]
fn instance_records_are_where_instances_wgsl_reads_them() {
    use lumagraph_scene::{GpuBvhRecord, GpuInstance};
    assert_eq!(size_of::<GpuInstance>(), 2 * size_of::<GpuBvhRecord>());
    assert_eq!(offset_of!(GpuInstance, to_world), 0);
    assert_eq!(offset_of!(GpuInstance, to_object), 3 * 16);
    assert_eq!(offset_of!(GpuInstance, root), 6 * 16);
    assert_eq!(offset_of!(GpuInstance, flags), 6 * 16 + 4);
    assert_eq!(offset_of!(GpuInstance, pad_scale), 6 * 16 + 8);
    assert_eq!(offset_of!(GpuInstance, pad_base), 6 * 16 + 12);
    assert_eq!(offset_of!(GpuInstance, index), 7 * 16);
    let src = std::fs::read_to_string(common::shaders().join("pathtrace/intersect/instances.wgsl"))
        .unwrap();
    assert!(src.contains("return bvh_nodes[slot * 4u + 6u];"));
    assert!(src.contains("const INSTANCE_PAD: f32 = 9.536743e-7;"));
}

#[test]
fn wgsl_constants_match_rust() {
    let src =
        std::fs::read_to_string(common::shaders().join("pathtrace/intersect/bvh.wgsl")).unwrap();
    let end = format!("const BVH_END: u32 = {:#x}u;", lumagraph_scene::BVH_END);
    assert!(src.contains(&end), "bvh.wgsl must declare `{end}`");
    let types =
        std::fs::read_to_string(common::shaders().join("pathtrace/scene_types.wgsl")).unwrap();
    for (name, value) in [
        ("PRIM_SHAPE", lumagraph_scene::PRIM_SHAPE),
        ("NO_HIT", lumagraph_scene::NO_HIT),
        ("NO_LIGHT", lumagraph_scene::NO_LIGHT),
        ("NODE_SHAPES", lumagraph_scene::bvh::NODE_SHAPES),
        ("NODE_INSTANCES", lumagraph_scene::bvh::NODE_INSTANCES),
        ("NO_INSTANCE", lumagraph_scene::NO_INSTANCE),
        ("INSTANCE_MIRROR", lumagraph_scene::INSTANCE_MIRROR),
        ("FEATURE_INSTANCES", lumagraph_scene::FEATURE_INSTANCES),
        ("NODE_COUNT_SHIFT", lumagraph_scene::bvh::NODE_COUNT_SHIFT),
        ("LIGHT_SHAPE", lumagraph_scene::LIGHT_SHAPE),
        ("LIGHT_TWO_SIDED", lumagraph_scene::LIGHT_TWO_SIDED),
        ("MATERIAL_TWO_SIDED", lumagraph_scene::MATERIAL_TWO_SIDED),
        ("TRI_VERTEX_NORMALS", lumagraph_scene::TRI_VERTEX_NORMALS),
        ("ENV_NONE", lumagraph_scene::ENV_NONE),
        ("ENV_CONSTANT", lumagraph_scene::ENV_CONSTANT),
        ("ENV_MAP", lumagraph_scene::ENV_MAP),
        ("ENV_SHOW_BACKGROUND", lumagraph_scene::ENV_SHOW_BACKGROUND),
        ("FEATURE_SHAPES", lumagraph_scene::FEATURE_SHAPES),
        (
            "FEATURE_TRANSMISSION",
            lumagraph_scene::FEATURE_TRANSMISSION,
        ),
        ("FEATURE_TEXTURES", lumagraph_scene::FEATURE_TEXTURES),
        ("FEATURE_ENVIRONMENT", lumagraph_scene::FEATURE_ENVIRONMENT),
        ("FEATURE_LIGHTS", lumagraph_scene::FEATURE_LIGHTS),
        ("FEATURE_METAL", lumagraph_scene::FEATURE_METAL),
        ("FEATURE_MEDIA", lumagraph_scene::FEATURE_MEDIA),
        ("FEATURE_ALPHA", lumagraph_scene::FEATURE_ALPHA),
        ("MATERIAL_CONDUCTOR", lumagraph_scene::MATERIAL_CONDUCTOR),
        ("MATERIAL_MEDIUM", lumagraph_scene::MATERIAL_MEDIUM),
        (
            "MATERIAL_INDEX_MATCHED",
            lumagraph_scene::MATERIAL_INDEX_MATCHED,
        ),
        ("MATERIAL_ALPHA_MASK", lumagraph_scene::MATERIAL_ALPHA_MASK),
        (
            "MATERIAL_ALPHA_BLEND",
            lumagraph_scene::MATERIAL_ALPHA_BLEND,
        ),
    ] {
        let dec = format!("const {name}: u32 = {value}u;");
        let hex = format!("const {name}: u32 = {value:#x}u;");
        assert!(
            types.contains(&dec) || types.contains(&hex),
            "scene_types.wgsl must declare `{dec}` (or in hex)"
        );
    }
}
