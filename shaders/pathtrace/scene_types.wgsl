// Scene structs shared by the path tracer, mirroring crates/scene/src/gpu.rs field by
// field (same names, same offsets; a test in crates/scene checks them with naga).
// Padding is explicit so the layout reads the same in both languages.

// A hit's `prim` has this bit set for analytic shapes; the low bits index `shapes`.
const PRIM_SHAPE: u32 = 0x80000000u;
// A hit's `prim` when nothing was hit.
const NO_HIT: u32 = 0xffffffffu;
// A hit's `inst` off instanced meshes.
const NO_INSTANCE: u32 = 0xffffffffu;
// `light` of a primitive that does not emit.
const NO_LIGHT: u32 = 0xffffffffu;

const TRI_VERTEX_NORMALS: u32 = 1u;
const MATERIAL_TWO_SIDED: u32 = 1u;
const MATERIAL_CONDUCTOR: u32 = 2u;
const MATERIAL_SINGLE_SCATTER: u32 = 4u;
const MATERIAL_MEDIUM: u32 = 8u;
const MATERIAL_INDEX_MATCHED: u32 = 16u;
// The surface is cut out where its opacity is below `alpha_cutoff` (alpha.wgsl); a ray passes
// through it with probability 1 - opacity.
const MATERIAL_ALPHA_MASK: u32 = 32u;
const MATERIAL_ALPHA_BLEND: u32 = 64u;
// TriPositions::flags: the triangle's material is alpha-masked or blended.
const TRI_ALPHA: u32 = 1u;
const LIGHT_SHAPE: u32 = 1u;
const LIGHT_TWO_SIDED: u32 = 2u;
const ENV_NONE: u32 = 0u;
const ENV_CONSTANT: u32 = 1u;
const ENV_MAP: u32 = 2u;
const ENV_SHOW_BACKGROUND: u32 = 1u;

const FEATURE_SHAPES: u32 = 1u;
const FEATURE_TRANSMISSION: u32 = 2u;
const FEATURE_TEXTURES: u32 = 4u;
const FEATURE_ENVIRONMENT: u32 = 8u;
const FEATURE_LIGHTS: u32 = 16u;
const FEATURE_METAL: u32 = 32u;
const FEATURE_MEDIA: u32 = 64u;
const FEATURE_ALPHA: u32 = 128u;
const FEATURE_INSTANCES: u32 = 256u;
// An instance's flags: its transform mirrors (a negative determinant).
const INSTANCE_MIRROR: u32 = 1u;

// BVH node, 32 bytes. Depth-first order: an inner node's first child is the next node.
//   bits 0-1: split axis (inner); leaf kind: bit 0 instances (NODE_INSTANCES), bit 2 shapes,
//   neither triangles;
//   bits 3-31: primitive count (0 = inner node).
//   index: inner = second child's node index; leaf = first primitive in its kind's array.
struct BvhNode {
    aabb_min: vec3<f32>,
    index: u32,
    aabb_max: vec3<f32>,
    bits: u32,
}

const NODE_SHAPES: u32 = 4u;
const NODE_INSTANCES: u32 = 1u;
const NODE_COUNT_SHIFT: u32 = 3u;

// Triangle intersection data, 48 bytes: corner 0 and the edges to corners 1 and 2.
struct TriPositions {
    v0: vec3<f32>,
    // TRI_ALPHA: the triangle's material takes the any-hit test (alpha.wgsl).
    flags: u32,
    e1: vec3<f32>,
    pad1: u32,
    e2: vec3<f32>,
    pad2: u32,
}

// Triangle shading data, 48 bytes, same index as TriPositions.
struct TriShading {
    n0: vec3<f32>,
    material: u32,
    n1: vec3<f32>,
    light: u32,
    n2: vec3<f32>,
    flags: u32,
}

// Analytic shape (crates/scene/src/shapes/), 48 bytes: its kind's parameters (`center`,
// `radius`, `axis`), then what shading reads.
struct Shape {
    center: vec3<f32>,
    radius: f32,
    axis: vec3<f32>,
    kind: u32,
    material: u32,
    light: u32,
    pad0: u32,
    pad1: u32,
}

// A point sampled on a shape as seen from a shading point: the unit direction to it, its
// distance, the solid-angle pdf as (numerator, denominator) (numerator 0: no sample), and
// how far a shadow ray stops short of it.
struct ShapeSample {
    wi: vec3f,
    dist: f32,
    pdf: vec2f,
    margin: f32,
}

// Material: generated from crates/scene/src/lobes/table.rs, the same rows as GpuMaterial.
#import "pathtrace/material.wgsl"

// A triangle's tangents (xyz, w = handedness), UVs (two sets) and vertex colours (RGBA8, R in
// the low byte, RGB sRGB-encoded; white without) at its corners, 112 bytes, same index as
// TriPositions; only present when some material has a texture or some triangle a colour.
struct TriTexcoords {
    t0: vec4<f32>,
    t1: vec4<f32>,
    t2: vec4<f32>,
    uv01: vec4<f32>,
    uv2: vec2<f32>,
    uv1_2: vec2<f32>,
    uv1_01: vec4<f32>,
    colors: vec3<u32>,
    pad0: u32,
}

// Where a texture's texels are in the atlas (x | y << 16 of its corner in its page, the page,
// width | height << 16, flags) and how a material reads it: coordinate set `uv_set` through
// uv' = u * m.xy + v * m.zw + offset (KHR_texture_transform), 48 bytes.
struct TexDesc {
    place: vec4<u32>,
    m: vec4<f32>,
    offset: vec2<f32>,
    uv_set: u32,
    // Its mip level 1's descriptor (level k at mips + k - 1; TEX_MIPS_SHIFT: how many).
    mips: u32,
}

// Emissive triangle (p0, e1, e2) or analytic shape (LIGHT_SHAPE: `prim`), kind 0, 80 bytes;
// or a light without area, of kind LIGHT_<NAME> (pathtrace/light_kinds.wgsl, generated from
// crates/scene/src/lights/): position p0, unit axis e1, frame x e2, intensity or irradiance
// in `emission`, its own numbers in `params`, as pathtrace/lights/<name>.wgsl reads them.
// Selection probability: half power / SceneHeader.total_light_power, half 1 / num_lights.
struct Light {
    p0: vec3<f32>,
    flags: u32,
    e1: vec3<f32>,
    prim: u32,
    e2: vec3<f32>,
    area: f32,
    emission: vec3<f32>,
    power: f32,
    params: vec3<f32>,
    kind: u32,
}

// Alias table entry over the lights (Vose), 8 bytes.
struct AliasEntry {
    prob: f32,
    other: u32,
}

// Camera, 64 bytes. Direction for image coordinates (x, y) in [0,1]^2, y down:
// forward + (2x - 1) * tan_half_fov * aspect * right - (2y - 1) * tan_half_fov * up.
struct Camera {
    position: vec3<f32>,
    tan_half_fov: f32,
    right: vec3<f32>,
    aspect: f32,
    up: vec3<f32>,
    aperture_radius: f32,
    forward: vec3<f32>,
    focus_distance: f32,
}

// Render settings and environment, 48 bytes.
struct Settings {
    width: u32,
    height: u32,
    max_bounces: u32,
    spp: u32,
    seed: u32,
    env_kind: u32,
    env_flags: u32,
    env_azimuth: f32,
    env_radiance: vec3<f32>,
    env_elevation: f32,
}

// Counts and scene-wide values, 32 bytes.
struct SceneHeader {
    num_nodes: u32,
    num_triangles: u32,
    num_shapes: u32,
    num_materials: u32,
    num_lights: u32,
    bvh_depth: u32,
    features: u32,
    total_light_power: f32,
}

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// prim: triangle index, or shape index | PRIM_SHAPE, or NO_HIT.
// u, v: barycentric weights of corners 1 and 2 (0 for shapes).
// inst: the instance whose mesh the triangle is of (its node slot in `bvh_nodes`,
// instances.wgsl), or NO_INSTANCE for the scene's own primitives.
struct Hit {
    prim: u32,
    t: f32,
    u: f32,
    v: f32,
    inst: u32,
}
