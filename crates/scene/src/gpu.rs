//! The flat, GPU-ready scene: `#[repr(C)]` + [`bytemuck::Pod`] structs laid out exactly as
//! WGSL lays out the structs of `shaders/pathtrace/scene_types.wgsl` in storage buffers
//! (std430-compatible: every `vec3<f32>` starts at a multiple of 16 bytes and is followed
//! by a 4-byte scalar; every struct's size is a multiple of 16 or of 8 for [`GpuAliasEntry`]).
//! A test checks each offset and size against naga's layouter.
//!
//! Intersection data is kept apart from shading data so the traversal loop loads little:
//! [`GpuBvhNode`] (32 B, then one 4-byte skip link of its [`GpuBvhRecord`]) and
//! [`GpuTriangle`] (48 B: a corner and two edges) or the first 32 bytes of [`GpuShape`];
//! normals and material ids live in [`GpuTriShading`], read once per hit.
//!
//! Primitive ids: triangles and shapes are stored in BVH leaf order (see [`crate::bvh`]).
//! A hit's `prim` is the triangle index, or the shape index with [`PRIM_SHAPE`] set.

use bytemuck::{Pod, Zeroable};

/// Set in a hit's `prim` when it is an analytic shape; the low bits are then its index.
pub const PRIM_SHAPE: u32 = 0x8000_0000;
/// A hit's `prim` when nothing was hit.
pub const NO_HIT: u32 = u32::MAX;
/// No light: the value of `light` in [`GpuTriShading`] and [`GpuShape`] for a
/// non-emissive primitive.
pub const NO_LIGHT: u32 = u32::MAX;

/// [`GpuTriShading::flags`]: the normals are interpolated vertex normals (else flat).
pub const TRI_VERTEX_NORMALS: u32 = 1;
/// [`GpuMaterial::flags`]: emission leaves both sides.
pub const MATERIAL_TWO_SIDED: u32 = 1;
/// [`GpuMaterial::flags`]: the metal lobe's Fresnel is the exact conductor one with
/// `eta` and `k` (else Schlick's on `base_color`).
pub const MATERIAL_CONDUCTOR: u32 = 2;
/// [`GpuMaterial::flags`]: no multiple-scattering compensation (the metal lobe's
/// Kulla–Conty term, rough glass's reflections into the surface sent back out).
pub const MATERIAL_SINGLE_SCATTER: u32 = 4;
/// [`GpuMaterial::flags`]: the inside of the material's shapes is a homogeneous medium
/// (`sigma_a`, `sigma_s`, `phase_g`).
pub const MATERIAL_MEDIUM: u32 = 8;
/// [`GpuMaterial::flags`]: no surface: rays cross it unchanged (an index-matched medium
/// boundary).
pub const MATERIAL_INDEX_MATCHED: u32 = 16;
/// [`GpuTriangle::flags`]: the triangle's material is alpha-masked or blended, so its hits
/// take the any-hit test ([`crate::traverse::triangle_hit_counts`]).
pub const TRI_ALPHA: u32 = 1;
/// Material flag: the surface is cut out where its opacity is below `alpha_cutoff`.
pub const MATERIAL_ALPHA_MASK: u32 = 32;
/// Material flag: a ray passes through the surface with probability 1 − opacity.
pub const MATERIAL_ALPHA_BLEND: u32 = 64;
/// [`GpuLight::flags`]: the light is an analytic shape, `prim` its index (else a triangle).
pub const LIGHT_SHAPE: u32 = 1;
/// [`GpuLight::flags`]: emission leaves both sides of the triangle.
pub const LIGHT_TWO_SIDED: u32 = 2;

/// [`GpuSettings::env_kind`]: black environment.
pub const ENV_NONE: u32 = 0;
/// [`GpuSettings::env_kind`]: constant radiance `env_radiance`.
pub const ENV_CONSTANT: u32 = 1;
/// [`GpuSettings::env_kind`]: an equirectangular map (uploaded by the renderer), scaled by
/// `env_radiance`.
pub const ENV_MAP: u32 = 2;
/// [`GpuSettings::env_flags`]: camera rays that miss see the environment.
pub const ENV_SHOW_BACKGROUND: u32 = 1;

/// [`GpuHeader::features`]: the scene has analytic shapes.
pub const FEATURE_SHAPES: u32 = 1;
/// [`GpuHeader::features`]: some material transmits (glass lobe needed).
pub const FEATURE_TRANSMISSION: u32 = 2;
/// [`GpuHeader::features`]: some material has a texture.
pub const FEATURE_TEXTURES: u32 = 4;
/// [`GpuHeader::features`]: the environment is not black.
pub const FEATURE_ENVIRONMENT: u32 = 8;
/// [`GpuHeader::features`]: there are emissive primitives (NEE needed).
pub const FEATURE_LIGHTS: u32 = 16;
/// [`GpuHeader::features`]: some material is metallic.
pub const FEATURE_METAL: u32 = 32;
/// [`GpuHeader::features`]: some material has a medium inside or is index-matched.
pub const FEATURE_MEDIA: u32 = 64;
/// [`GpuHeader::features`]: some material's alpha mode is `Mask` or `Blend`: every
/// intersector applies its any-hit test ([`crate::traverse::triangle_hit_counts`]).
pub const FEATURE_ALPHA: u32 = 128;

/// A BVH node, 32 bytes. See [`crate::bvh`] for the encoding.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhNode {
    /// Box minimum corner (offset 0).
    pub aabb_min: [f32; 3],
    /// Inner: second child's node index. Leaf: first primitive in its kind's array
    /// (offset 12).
    pub index: u32,
    /// Box maximum corner (offset 16).
    pub aabb_max: [f32; 3],
    /// Bits 0–1 split axis (inner), leaf kind (bit 0: instances, bit 2: shapes, neither:
    /// triangles), bits 3–31 primitive count (0 = inner node) (offset 28).
    pub bits: u32,
}

/// An instance of an instanced mesh as the traversal reads it, 128 bytes: two
/// [`GpuBvhRecord`] slots in the `bvh_nodes` buffer, after the last node (a top-level leaf of
/// instances holds the slot of its first one; see [`crate::bvh`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuInstance {
    /// Object to world, the matrix's first three rows (offset 0).
    pub to_world: [[f32; 4]; 3],
    /// World to object, likewise (offset 48).
    pub to_object: [[f32; 4]; 3],
    /// Its mesh's BVH root node (offset 96).
    pub root: u32,
    /// [`INSTANCE_MIRROR`] (offset 100).
    pub flags: u32,
    /// How much a ray's origin coordinates weigh in the rounding error of the moved ray
    /// (the largest row sum of |`to_object`|'s 3×3 part; offset 104): the boxes of its
    /// mesh grow by `INSTANCE_PAD` × (this × the origin's largest coordinate + `pad_base` +
    /// the moved origin's largest coordinate) (`instance_ray` in `pathtrace/intersect/instances.wgsl`).
    pub pad_scale: f32,
    /// The rest of that bound: `to_object`'s largest translation and the mesh's largest
    /// coordinate (offset 108).
    pub pad_base: f32,
    /// Its index in [`crate::GpuScene::instances`] (offset 112).
    pub index: u32,
    /// Padding to two node records (offset 116).
    pub pad: [u32; 3],
}

/// A hit's instance off instanced meshes (the scene's own primitives).
pub const NO_INSTANCE: u32 = u32::MAX;

/// [`GpuInstance::flags`]: the transform mirrors (a negative determinant); its triangles'
/// corners 1 and 2 are swapped, as in a copy ([`crate::transform_triangle`]).
pub const INSTANCE_MIRROR: u32 = 1;

/// [`GpuHeader::features`]: the scene has instanced meshes (a two-level BVH).
pub const FEATURE_INSTANCES: u32 = 256;

/// A BVH node as the GPU reads it, 64 bytes: the node, then its skip links for the 8 ray
/// octants (see [`crate::bvh`]), so the link a ray needs is in the node's cache line.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBvhRecord {
    /// The node (offset 0).
    pub node: GpuBvhNode,
    /// Where a ray of each octant goes after the node's subtree (offset 32).
    pub skips: [u32; 8],
}

/// A triangle's intersection data, 48 bytes: corner 0 and the two edges from it, as
/// Möller–Trumbore uses them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    /// Corner 0 (offset 0).
    pub v0: [f32; 3],
    /// [`TRI_ALPHA`] (offset 12): read with the corners, so the traversal knows without
    /// another load whether a hit takes the any-hit test.
    pub flags: u32,
    /// Corner 1 − corner 0 (offset 16).
    pub e1: [f32; 3],
    /// Padding (offset 28).
    pub pad1: u32,
    /// Corner 2 − corner 0 (offset 32). The front normal is `e1 × e2`.
    pub e2: [f32; 3],
    /// Padding (offset 44).
    pub pad2: u32,
}

/// A triangle's shading data, 48 bytes, same index as its [`GpuTriangle`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriShading {
    /// Unit shading normal at corner 0 (offset 0); the flat normal without vertex normals.
    pub n0: [f32; 3],
    /// Material index (offset 12).
    pub material: u32,
    /// Unit shading normal at corner 1 (offset 16).
    pub n1: [f32; 3],
    /// Index into the lights, or [`NO_LIGHT`] (offset 28): for MIS when a ray hits it.
    pub light: u32,
    /// Unit shading normal at corner 2 (offset 32).
    pub n2: [f32; 3],
    /// [`TRI_VERTEX_NORMALS`] (offset 44).
    pub flags: u32,
}

/// An analytic shape ([`crate::Shape`]), 48 bytes: its kind's parameters, then what
/// shading reads.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShape {
    /// Center (offset 0).
    pub center: [f32; 3],
    /// Radius (offset 12).
    pub radius: f32,
    /// Unit axis, or zero (offset 16).
    pub axis: [f32; 3],
    /// Index into [`crate::shapes::KINDS`] (offset 28).
    pub kind: u32,
    /// Material index (offset 32).
    pub material: u32,
    /// Index into the lights, or [`NO_LIGHT`] (offset 36).
    pub light: u32,
    /// Padding (offset 40).
    pub pad0: u32,
    /// Padding (offset 44).
    pub pad1: u32,
}

pub use crate::lobes::GpuMaterial;

/// A triangle's texture coordinates, tangents and vertex colours, 112 bytes, same index as
/// its [`GpuTriangle`]; only filled when some material has a texture or some triangle has
/// vertex colours (else the buffer holds one zeroed entry).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriTexcoords {
    /// Tangent at corner 0: xyz unit, w = ±1 handedness (offset 0).
    pub t0: [f32; 4],
    /// Tangent at corner 1 (offset 16).
    pub t1: [f32; 4],
    /// Tangent at corner 2 (offset 32).
    pub t2: [f32; 4],
    /// UV (set 0) at corner 0 (xy) and corner 1 (zw) (offset 48).
    pub uv01: [f32; 4],
    /// UV (set 0) at corner 2 (offset 64).
    pub uv2: [f32; 2],
    /// The second UV set (glTF `TEXCOORD_1`) at corner 2 (offset 72).
    pub uv1_2: [f32; 2],
    /// The second UV set at corners 0 (xy) and 1 (zw) (offset 80).
    pub uv1_01: [f32; 4],
    /// Vertex colours at the corners, RGBA8 (R in the low byte; RGB sRGB-encoded), white
    /// where the mesh has none (offset 96).
    pub colors: [u32; 3],
    /// Padding (offset 108).
    pub pad0: u32,
}

/// Where a texture's texels are in the atlas and how a material reads them, 48 bytes: the
/// atlas place (x | y << 16 in its page, the page, width | height << 16, flags:
/// [`crate::Texture::flags`]), then the coordinate transform (`uv' = u · m.xy + v · m.zw +
/// offset`) and the coordinate set, and where its mip levels' places are. A mip level's
/// descriptor (after every texture's, [`crate::texture::TextureAtlas::descriptors`]) holds
/// only a place.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexDesc {
    /// Place, page, size and flags (offset 0).
    pub place: [u32; 4],
    /// The transform's matrix by columns (offset 16).
    pub m: [f32; 4],
    /// The transform's offset (offset 32).
    pub offset: [f32; 2],
    /// 0: `TEXCOORD_0`, 1: `TEXCOORD_1` (offset 40).
    pub uv_set: u32,
    /// The index of the descriptor of its mip level 1 (level k at `mips + k − 1`; how many
    /// levels there are is in the flags, [`crate::texture::TEX_MIPS_SHIFT`]), 0 without mip
    /// levels (offset 44).
    pub mips: u32,
}

/// White in [`GpuTriTexcoords::colors`]: the vertex colour of meshes without one.
pub const VERTEX_WHITE: u32 = 0xFFFF_FFFF;

/// A vertex colour as stored (RGBA8, R in the low byte, RGB sRGB-encoded) decoded as a
/// texel is: `vertex_color` in `pathtrace/textures.wgsl`.
pub fn vertex_color(c: u32) -> glam::Vec4 {
    let [r, g, b, a] = c.to_le_bytes().map(|x| f32::from(x) / 255.0);
    let d = crate::texture::srgb_decode;
    glam::Vec4::new(d(r), d(g), d(b), a)
}

impl GpuTriTexcoords {
    /// Both UV sets at barycentrics (`u`, `v`), set 0 in xy and set 1 in zw: `tri_uv` in
    /// `pathtrace/textures.wgsl`.
    pub fn uv(&self, u: f32, v: f32) -> glam::Vec4 {
        use glam::Vec2;
        let w = 1.0 - u - v;
        let set0 = w * Vec2::new(self.uv01[0], self.uv01[1])
            + u * Vec2::new(self.uv01[2], self.uv01[3])
            + v * Vec2::from(self.uv2);
        let set1 = w * Vec2::new(self.uv1_01[0], self.uv1_01[1])
            + u * Vec2::new(self.uv1_01[2], self.uv1_01[3])
            + v * Vec2::from(self.uv1_2);
        set0.extend(set1.x).extend(set1.y)
    }

    /// The vertex colour at barycentrics (`u`, `v`), each corner decoded as a texel is, and
    /// exactly white where all three are: `tri_color` in `pathtrace/textures.wgsl`.
    pub fn color(&self, u: f32, v: f32) -> glam::Vec4 {
        if self.colors == [VERTEX_WHITE; 3] {
            return glam::Vec4::ONE;
        }
        let [c0, c1, c2] = self.colors.map(vertex_color);
        (1.0 - u - v) * c0 + u * c1 + v * c2
    }
}

/// An emitter, 80 bytes: an emissive triangle or shape, or a light without area of a kind
/// in [`crate::lights::KINDS`] (`kind`), which reads the fields as its file says.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// Triangle corner 0; zero for a shape, whose sampling reads the shape; a light
    /// without area's position (offset 0).
    pub p0: [f32; 3],
    /// [`LIGHT_SHAPE`], [`LIGHT_TWO_SIDED`] (offset 12).
    pub flags: u32,
    /// Triangle edge 1; a light without area's unit axis, its frame's z (offset 16).
    pub e1: [f32; 3],
    /// The primitive: triangle index, or shape index (offset 28).
    pub prim: u32,
    /// Triangle edge 2; a light without area's frame's unit x (offset 32).
    pub e2: [f32; 3],
    /// Emitting area (offset 44).
    pub area: f32,
    /// Emitted radiance, linear RGB; a light without area's intensity or irradiance (offset
    /// 48).
    pub emission: [f32; 3],
    /// Emitted power for selection: luminance(emission) × area × π (× 2 if two-sided), × the
    /// emissive texture's mean over the triangle when it has one (offset 60). Selection
    /// probability: [`crate::light_selection`], half power / `GpuHeader::total_light_power`,
    /// half 1 / `num_lights`.
    pub power: f32,
    /// A light without area's own numbers (offset 64).
    pub params: [f32; 3],
    /// 0: an emissive triangle or shape; else a light without area, of kind
    /// `crate::lights::KINDS[kind - 1]` (offset 76).
    pub kind: u32,
}

/// One entry of the light alias table (Vose), 8 bytes: pick `i` uniformly, keep it with
/// probability `prob`, else take `other`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuAliasEntry {
    /// Probability of keeping this entry (offset 0).
    pub prob: f32,
    /// The other light of this bucket (offset 4).
    pub other: u32,
}

/// The camera, 64 bytes. A pixel's ray direction, for image coordinates `(x, y)` in
/// [0, 1]² (y down): `forward + (2x − 1)·tan_half_fov·aspect·right − (2y − 1)·tan_half_fov·up`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    /// Eye position (offset 0).
    pub position: [f32; 3],
    /// tan(vertical fov / 2) (offset 12).
    pub tan_half_fov: f32,
    /// Unit right vector: image x grows along it (offset 16).
    pub right: [f32; 3],
    /// Width / height (offset 28).
    pub aspect: f32,
    /// Unit up vector: image y grows along its opposite (offset 32).
    pub up: [f32; 3],
    /// Lens radius, 0 for a pinhole (offset 44).
    pub aperture_radius: f32,
    /// Unit view direction (offset 48).
    pub forward: [f32; 3],
    /// Distance to the plane in focus, along `forward` (offset 60).
    pub focus_distance: f32,
}

/// Render settings and environment, 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSettings {
    /// Image width (offset 0).
    pub width: u32,
    /// Image height (offset 4).
    pub height: u32,
    /// Most scattering events per path (offset 8).
    pub max_bounces: u32,
    /// Samples per pixel (offset 12).
    pub spp: u32,
    /// Random seed (offset 16).
    pub seed: u32,
    /// [`ENV_NONE`], [`ENV_CONSTANT`] or [`ENV_MAP`] (offset 20).
    pub env_kind: u32,
    /// [`ENV_SHOW_BACKGROUND`] (offset 24).
    pub env_flags: u32,
    /// Map rotation about the up axis, radians (offset 28).
    pub env_azimuth: f32,
    /// Constant environment radiance, or the map's scale, linear RGB (offset 32).
    pub env_radiance: [f32; 3],
    /// Map tilt about the x axis, radians (offset 44).
    pub env_elevation: f32,
}

/// Counts and scene-wide values, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuHeader {
    /// BVH nodes (offset 0).
    pub num_nodes: u32,
    /// Triangles (offset 4).
    pub num_triangles: u32,
    /// Analytic shapes (offset 8).
    pub num_shapes: u32,
    /// Materials (offset 12).
    pub num_materials: u32,
    /// Lights, and alias table entries (offset 16).
    pub num_lights: u32,
    /// Most inner nodes above a leaf; the traversal stack needs this many entries
    /// (offset 20).
    pub bvh_depth: u32,
    /// `FEATURE_*` bits: what the shader can leave out (offset 24).
    pub features: u32,
    /// Sum of the lights' `power` (offset 28).
    pub total_light_power: f32,
}
