//! Flattening a [`Scene`] into a [`GpuScene`]: BVH, reordered primitives, materials,
//! lights with an alias table that picks them half by power, half uniformly (an emissive
//! texture scales a triangle's power by its mean over the triangle; point, spot and
//! directional lights join with their emitted power), camera and settings.

use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;

use crate::bvh::{self, BvhOptions};
use crate::error::{ErrorKind, SceneError};
use crate::file::Environment;
use crate::gpu::{
    ENV_CONSTANT, ENV_MAP, ENV_NONE, ENV_SHOW_BACKGROUND, FEATURE_ENVIRONMENT, FEATURE_LIGHTS,
    FEATURE_MEDIA, FEATURE_METAL, FEATURE_SHAPES, FEATURE_TEXTURES, FEATURE_TRANSMISSION,
    GpuAliasEntry, GpuBvhNode, GpuBvhRecord, GpuCamera, GpuHeader, GpuLight, GpuMaterial,
    GpuSettings, GpuShape, GpuTriShading, GpuTriTexcoords, GpuTriangle, LIGHT_SHAPE,
    LIGHT_TWO_SIDED, MATERIAL_CONDUCTOR, MATERIAL_INDEX_MATCHED, MATERIAL_MEDIUM,
    MATERIAL_SINGLE_SCATTER, MATERIAL_TWO_SIDED, NO_LIGHT, TRI_VERTEX_NORMALS,
};
use crate::scene::{Material, NO_TEXTURE, PunctualLight, Scene};

/// Everything the render crate uploads: one `Vec` per storage buffer, plus small blocks.
/// Arrays may be empty (no shapes, no lights); the uploader pads empty buffers.
#[derive(Clone, Debug, Default)]
pub struct GpuScene {
    /// Counts and scene-wide values.
    pub header: GpuHeader,
    /// The camera.
    pub camera: GpuCamera,
    /// Image size, sampling, environment.
    pub settings: GpuSettings,
    /// BVH nodes, root first (buffer `bvh_nodes`, each node followed by its skip links).
    pub bvh_nodes: Vec<GpuBvhNode>,
    /// For each node and ray octant, where traversal goes after the node's subtree (see
    /// [`crate::bvh`]); same length as `bvh_nodes`.
    pub bvh_skips: Vec<[u32; crate::bvh::BVH_OCTANTS]>,
    /// Triangle intersection data in BVH order (buffer `tri_positions`).
    pub tri_positions: Vec<GpuTriangle>,
    /// Each GPU triangle's corners in BVH order, as the scene gave them (CPU side only: the
    /// host intersector, `lumagraph_render::embree`).
    pub tri_corners: Vec<[[f32; 3]; 3]>,
    /// Triangle shading data, same order (buffer `tri_shading`).
    pub tri_shading: Vec<GpuTriShading>,
    /// Analytic shapes in BVH order (buffer `shapes`).
    pub shapes: Vec<GpuShape>,
    /// Materials, as in [`Scene::materials`] (buffer `materials`).
    pub materials: Vec<GpuMaterial>,
    /// Emissive triangles and spheres (buffer `lights`).
    pub lights: Vec<GpuLight>,
    /// Alias table over `lights` by [`light_selection`] (buffer `light_alias`).
    pub light_alias: Vec<GpuAliasEntry>,
    /// Texture coordinates and tangents per triangle, same order as `tri_positions`; empty
    /// when no material has a texture (buffer `tri_texcoords`).
    pub tri_texcoords: Vec<GpuTriTexcoords>,
    /// Every texture a material uses, in one atlas ([`crate::texture::pack_atlas`]); empty
    /// without textures (the array texture `textures` and buffer `texture_descs`).
    pub atlas: crate::texture::TextureAtlas,
    /// Per texture, whether a material reads it as colour (sRGB), where the atlas has mip
    /// chains ([`crate::texture::pack_atlas_with`], the scene's `texture_mips`); `None`
    /// without them (CPU side only: [`GpuScene::fit_textures`] packs the atlas again).
    pub texture_srgb: Option<Vec<bool>>,
    /// How long packing the atlas took, its mip chains included (CPU side only).
    pub atlas_time: std::time::Duration,
    /// Each texture's channel ranges, in the order of `textures` (CPU side only: the shader
    /// specializer leaves a lobe out only where no texel can produce it).
    pub texture_ranges: Vec<crate::texture::TexelRange>,
    /// Per material, the smallest vertex colour alpha (over 255) of its triangles; 255 where
    /// none has vertex colours (CPU side only: the specializer keeps alpha where it can
    /// cut).
    pub vertex_alpha_min: Vec<u8>,
    /// For each GPU triangle, its index in [`Scene::triangles`] (CPU side only).
    pub tri_source: Vec<u32>,
    /// For each GPU shape (`shapes`), its index in [`Scene::shapes`] (CPU side only).
    pub shape_source: Vec<u32>,
    /// The instances of the scene's instanced meshes, in top-level BVH order (uploaded in
    /// `bvh_nodes` after the nodes, two node slots each: see [`crate::bvh`]). Their meshes'
    /// triangles follow the scene's own ones (the first `tri_source.len()`) in
    /// `tri_positions`, in their meshes' own space.
    pub instances: Vec<crate::gpu::GpuInstance>,
    /// For each instance, its mesh in [`Scene::instanced`] (CPU side only).
    pub instance_mesh: Vec<u32>,
    /// For each instanced mesh, its first triangle in `tri_positions` and its triangle count
    /// (CPU side only: the G-buffer draws each mesh once per instance).
    pub mesh_triangles: Vec<[u32; 2]>,
    /// Triangles the instances place (each instance's mesh counted once per instance;
    /// CPU side only, for what `render` prints).
    pub instanced_triangles: u64,
    /// The environment map's file, when the environment is a map (CPU side only: the
    /// renderer loads it and builds its sampling tables).
    pub environment_map: Option<std::path::PathBuf>,
}

/// Rec. 709 luminance of linear RGB.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

fn tex16(t: u32) -> u32 {
    if t == NO_TEXTURE || t >= 0xFFFF {
        0xFFFF
    } else {
        t
    }
}

impl From<&Material> for GpuMaterial {
    /// The material as the path tracer reads it.
    fn from(m: &Material) -> Self {
        let mut flags = if m.two_sided { MATERIAL_TWO_SIDED } else { 0 };
        if m.conductor.is_some() {
            flags |= MATERIAL_CONDUCTOR;
        }
        if !m.multiscatter {
            flags |= MATERIAL_SINGLE_SCATTER;
        }
        if m.medium.is_some() {
            flags |= MATERIAL_MEDIUM;
        }
        if m.index_matched {
            flags |= MATERIAL_INDEX_MATCHED;
        }
        let alpha_cutoff = match m.alpha_mode {
            crate::scene::AlphaMode::Opaque => 0.0,
            crate::scene::AlphaMode::Mask { cutoff } => {
                flags |= crate::gpu::MATERIAL_ALPHA_MASK;
                cutoff
            }
            crate::scene::AlphaMode::Blend => {
                flags |= crate::gpu::MATERIAL_ALPHA_BLEND;
                0.0
            }
        };
        let medium = m.medium.unwrap_or(crate::scene::Medium {
            sigma_a: Vec3::ZERO,
            sigma_s: Vec3::ZERO,
            g: 0.0,
        });
        let (eta, k, f_avg) = m.conductor.map_or(([0.0; 3], [0.0; 3], [0.0; 3]), |c| {
            (
                c.eta.to_array(),
                c.k.to_array(),
                c.average_reflectance().to_array(),
            )
        });
        let mut g = GpuMaterial {
            base_color: m.base_color.to_array(),
            emission: m.emission.to_array(),
            metallic: m.metallic,
            ior: m.ior,
            opacity: m.opacity,
            alpha_cutoff,
            tex_base_mr: tex16(m.textures.base_color)
                | (tex16(m.textures.metallic_roughness) << 16),
            tex_emissive_normal: tex16(m.textures.emissive) | (tex16(m.textures.normal) << 16),
            flags,
            normal_scale: m.normal_scale,
            tex_transmission_specular: tex16(m.textures.transmission)
                | (tex16(m.textures.specular) << 16),
            tex_specular_color: tex16(m.textures.specular_color)
                | (tex16(m.textures.clearcoat_normal) << 16),
            tex_coat: tex16(m.textures.clearcoat) | (tex16(m.textures.clearcoat_roughness) << 16),
            tex_sheen: tex16(m.textures.sheen_color) | (tex16(m.textures.sheen_roughness) << 16),
            clearcoat_normal_scale: m.clearcoat_normal_scale,
            eta,
            k,
            f_avg,
            sigma_a: medium.sigma_a.to_array(),
            phase_g: medium.g,
            sigma_s: medium.sigma_s.to_array(),
            ..GpuMaterial::default()
        };
        for p in crate::lobes::PARAMS {
            (p.flatten)(m, &mut g);
        }
        g
    }
}

/// The light-table entry of a light without area and its emitted power (for selection),
/// as its kind gives it ([`crate::lights::LightKind::power`]; `radius` bounds the scene).
fn punctual_light(l: &PunctualLight, radius: f32) -> (GpuLight, f32) {
    let kind = crate::lights::kind_of(l).expect("a light without area has a kind");
    let power = kind.power(l, radius);
    (GpuLight { power, ..*l }, power)
}

/// Share of light samples spread uniformly over the lights; the rest go by power.
pub const LIGHT_UNIFORM_SHARE: f32 = 0.5;

/// Probability of picking each light for a light sample: `LIGHT_UNIFORM_SHARE` spread
/// evenly, the rest in proportion to the light's power. By power alone, a dim light that
/// is near what it lights (a small lamp beside a large panel) gets too few samples; evenly
/// alone, a large mesh light of many small triangles starves a bright one. Half each is at
/// most twice as noisy as the better of the two for any scene. Mirrored by
/// `light_select_pdf` in `shaders/pathtrace/lights/lights.wgsl`.
pub fn light_selection(powers: &[f32]) -> Vec<f32> {
    let total: f32 = powers.iter().sum();
    let n = powers.len() as f32;
    powers
        .iter()
        .map(|&p| {
            let by_power = if total > 0.0 { p / total } else { 1.0 / n };
            (1.0 - LIGHT_UNIFORM_SHARE) * by_power + LIGHT_UNIFORM_SHARE / n
        })
        .collect()
}

/// Smallest share of its factor's power an emitter with an emissive texture keeps for light
/// selection, so that a footprint whose samples all fall on black texels stays selectable.
pub const MIN_TEXTURED_POWER_SCALE: f32 = 1e-2;

/// How much of the emissive factor's luminance the emissive texture of `m` leaves over a
/// triangle with texture coordinates `uvs` (both sets): the mean of the textured emission
/// over the triangle ([`crate::texture::Texture::triangle_mean`], at the texture's own
/// coordinates) over the factor's luminance, at least [`MIN_TEXTURED_POWER_SCALE`]. Only
/// the selection probability uses it; the light's radiance is still read from the texture
/// at the sampled point, so the estimate stays unbiased whatever the scale.
fn textured_emission_scale(scene: &Scene, m: &Material, uvs: [[glam::Vec2; 3]; 2]) -> f32 {
    let factor = luminance(m.emission);
    let Some(tex) = scene.textures.get(m.textures.emissive as usize) else {
        return 1.0;
    };
    if factor <= 0.0 {
        return 1.0;
    }
    let uv = [0, 1, 2].map(|k| tex.uv([uvs[0][k], uvs[1][k]]));
    let mean = tex.triangle_mean(uv, true).truncate();
    let scale = luminance(m.emission * mean) / factor;
    if scale.is_finite() {
        scale.clamp(MIN_TEXTURED_POWER_SCALE, 1.0)
    } else {
        1.0
    }
}

/// Vose's alias table for the weights `w` (all ≥ 0, sum > 0).
pub fn alias_table(w: &[f32]) -> Vec<GpuAliasEntry> {
    let n = w.len();
    let total: f64 = w.iter().map(|&x| f64::from(x)).sum();
    if n == 0 || total.is_nan() || total <= 0.0 {
        return vec![
            GpuAliasEntry {
                prob: 1.0,
                other: 0
            };
            n
        ];
    }
    let mut scaled: Vec<f64> = w.iter().map(|&x| f64::from(x) * n as f64 / total).collect();
    let mut table: Vec<GpuAliasEntry> = (0..n as u32)
        .map(|i| GpuAliasEntry {
            prob: 1.0,
            other: i,
        })
        .collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        table[s] = GpuAliasEntry {
            prob: scaled[s] as f32,
            other: l as u32,
        };
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    table
}

impl GpuScene {
    /// The GPU camera of `c` over this scene: its aspect from the scene's image size, its
    /// focus distance, with `autofocus`, the distance to what the image center sees (a
    /// moved camera keeps the scene, so the scene's own camera is rebuilt the same way).
    pub fn camera_for(&self, c: &crate::Camera) -> GpuCamera {
        let (right, up, forward) = c.basis();
        let s = self.settings;
        let mut camera = GpuCamera {
            position: c.position.to_array(),
            tan_half_fov: (c.fov_y_deg.to_radians() * 0.5).tan(),
            right: right.to_array(),
            aspect: s.width as f32 / s.height as f32,
            up: up.to_array(),
            aperture_radius: c.aperture_radius,
            forward: forward.to_array(),
            focus_distance: c.focus_distance,
        };
        if c.autofocus {
            let center = crate::traverse::Ray {
                origin: c.position,
                dir: c.forward,
            };
            if let Some(hit) = crate::traverse::intersect(self, &center) {
                camera.focus_distance = hit.t * c.forward.length();
            }
        }
        camera
    }

    /// The `bvh_nodes` buffer: each node with its skip links. An empty scene gets one leaf
    /// over triangle 0, which the zeroed stand-in triangle buffer makes a degenerate
    /// triangle no ray hits, so the traversal needs no special case.
    pub fn bvh_records(&self) -> Vec<GpuBvhRecord> {
        if self.bvh_nodes.is_empty() {
            return vec![GpuBvhRecord {
                node: GpuBvhNode {
                    bits: 1 << crate::bvh::NODE_COUNT_SHIFT,
                    ..GpuBvhNode::default()
                },
                skips: [crate::bvh::BVH_END; crate::bvh::BVH_OCTANTS],
            }];
        }
        let mut records: Vec<GpuBvhRecord> = self
            .bvh_nodes
            .iter()
            .zip(&self.bvh_skips)
            .map(|(&node, &skips)| GpuBvhRecord { node, skips })
            .collect();
        records.extend(
            self.instances
                .iter()
                .flat_map(|i| bytemuck::cast::<_, [GpuBvhRecord; 2]>(*i)),
        );
        records
    }

    /// Bytes of the geometry's GPU buffers: BVH records (with the instances), triangles
    /// (positions, shading data, texture coordinates) and spheres.
    pub fn geometry_bytes(&self) -> u64 {
        let size = |n: usize, each: usize| (n * each) as u64;
        size(
            self.bvh_nodes.len() + 2 * self.instances.len(),
            std::mem::size_of::<GpuBvhRecord>(),
        ) + size(self.tri_positions.len(), std::mem::size_of::<GpuTriangle>())
            + size(self.tri_shading.len(), std::mem::size_of::<GpuTriShading>())
            + size(
                self.tri_texcoords.len(),
                std::mem::size_of::<GpuTriTexcoords>(),
            )
            + size(self.shapes.len(), std::mem::size_of::<GpuShape>())
    }

    /// Instance `k` of a leaf whose `index` is `slot` (its first instance's node slot).
    pub fn instance_at(&self, slot: u32, k: u32) -> &crate::gpu::GpuInstance {
        &self.instances[(slot as usize - self.bvh_nodes.len()) / 2 + k as usize]
    }

    /// Flattens `scene` with the default BVH options.
    ///
    /// # Errors
    /// When the scene has no primitive, more than 2^28 of them, or the BVH is too deep.
    pub fn build(scene: &Scene) -> Result<Self, SceneError> {
        Self::build_with(scene, &BvhOptions::default())
    }

    /// [`GpuScene::build`], and how long building its BVH took (what `render` prints).
    ///
    /// # Errors
    /// As [`GpuScene::build`].
    pub fn build_timed(scene: &Scene) -> Result<(Self, std::time::Duration), SceneError> {
        let mut bvh = std::time::Duration::ZERO;
        let built = Self::build_inner(scene, &BvhOptions::default(), &mut bvh)?;
        Ok((built, bvh))
    }

    /// The texture atlas made again from `textures` (the scene's, from which it was built)
    /// with the largest images halved until it fits `limits`
    /// ([`crate::texture::fit_textures`]); what was made smaller, empty when it fitted
    /// already. `None` when even 1×1 images do not fit; the atlas is then unchanged.
    pub fn fit_textures(
        &mut self,
        textures: &[crate::texture::Texture],
        limits: crate::texture::AtlasLimits,
    ) -> Option<Vec<crate::texture::Downscaled>> {
        if limits.hold(self.atlas.page_size, self.atlas.pages) {
            return Some(Vec::new());
        }
        let srgb = self.texture_srgb.as_deref();
        let (fitted, notes) = crate::texture::fit_textures_with(textures, limits, srgb)?;
        self.atlas = crate::texture::pack_atlas_with(&fitted, srgb);
        Some(notes)
    }

    /// Flattens `scene`.
    ///
    /// # Errors
    /// As [`GpuScene::build`].
    pub fn build_with(scene: &Scene, options: &BvhOptions) -> Result<Self, SceneError> {
        let mut bvh = std::time::Duration::ZERO;
        Self::build_inner(scene, options, &mut bvh)
    }

    fn build_inner(
        scene: &Scene,
        options: &BvhOptions,
        bvh_time: &mut std::time::Duration,
    ) -> Result<Self, SceneError> {
        let unique: usize = scene.instanced.iter().map(|m| m.triangles.len()).sum();
        let total = scene.triangles.len() + unique + scene.shapes.len();
        if total >= 1 << 28 {
            return Err(SceneError::new(ErrorKind::TooManyPrimitives(total)));
        }
        if total == 0 {
            return Err(SceneError::new(ErrorKind::BadValue {
                field: "shapes",
                message: "the scene has no triangle or analytic shape".to_owned(),
            }));
        }
        let tri_boxes: Vec<Aabb> = scene.triangles.iter().map(triangle_box).collect();
        let shape_boxes: Vec<Aabb> = scene
            .shapes
            .iter()
            .map(|s| {
                let [lo, hi] = s.kind().bounds(&s.record());
                Aabb::new(lo.into(), hi.into())
            })
            .collect();
        let bvh_started = std::time::Instant::now();
        // One BVH per mesh, in its own space; its root's box is the mesh's.
        let meshes: Vec<bvh::FlatBvh> = scene
            .instanced
            .iter()
            .map(|m| {
                let boxes: Vec<Aabb> = m.triangles.iter().map(triangle_box).collect();
                bvh::build(&boxes, &[], &[], options)
            })
            .collect::<Result<_, _>>()?;
        // Each instance's box: its mesh's box, transformed.
        let mut placed = Vec::new();
        let mut instance_boxes = Vec::new();
        for (mesh, (m, flat)) in scene.instanced.iter().zip(&meshes).enumerate() {
            let root = flat.nodes.first().map_or_else(Aabb::empty, |n| {
                Aabb::new(Vec3A::from(n.aabb_min), Vec3A::from(n.aabb_max))
            });
            for t in &m.transforms {
                placed.push((mesh as u32, *t));
                instance_boxes.push(transformed_box(&root, t));
            }
        }
        let flat = bvh::build(&tri_boxes, &shape_boxes, &instance_boxes, options)?;
        *bvh_time = bvh_started.elapsed();

        let mut out = Self {
            materials: scene.materials.iter().map(GpuMaterial::from).collect(),
            bvh_nodes: flat.nodes,
            bvh_skips: flat.skips,
            tri_source: flat.tri_order,
            shape_source: flat.shape_order,
            environment_map: match &scene.environment {
                Environment::Map { path, .. } => Some(path.into()),
                _ => None,
            },
            ..Self::default()
        };
        let textured = surface_attributes(scene);
        check_textures(scene)?;
        if textured {
            let packing = std::time::Instant::now();
            out.texture_srgb = scene.settings.texture_mips.then(|| texture_srgb(scene));
            out.atlas =
                crate::texture::pack_atlas_with(&scene.textures, out.texture_srgb.as_deref());
            out.atlas_time = packing.elapsed();
            out.texture_ranges = scene
                .textures
                .iter()
                .map(crate::texture::Texture::range)
                .collect();
        }
        out.vertex_alpha_min = vec![u8::MAX; scene.materials.len()];
        for t in scene
            .triangles
            .iter()
            .chain(scene.instanced.iter().flat_map(|m| &m.triangles))
        {
            if let (Some(c), Some(min)) =
                (t.colors, out.vertex_alpha_min.get_mut(t.material as usize))
            {
                *min = c.iter().fold(*min, |m, c| m.min(c[3]));
            }
        }
        let mut weights = Vec::new();
        let order = std::mem::take(&mut out.tri_source);
        out.push_triangles(scene, &scene.triangles, &order, textured, &mut weights);
        out.tri_source = order;
        out.push_shapes(scene, &mut weights);
        let depth = out.push_instances(scene, meshes, &placed, &flat.instance_order, textured);
        let radius = out.bvh_nodes.first().map_or(1.0, |root| {
            0.5 * (Vec3::from(root.aabb_max) - Vec3::from(root.aabb_min)).length()
        });
        for l in &scene.lights {
            let (light, power) = punctual_light(l, radius);
            weights.push(power);
            out.lights.push(light);
        }
        out.light_alias = alias_table(&light_selection(&weights));
        out.header = header(scene, &out, flat.depth.max(depth), weights.iter().sum());
        out.settings = settings(scene);
        out.camera = out.camera_for(&scene.camera);
        Ok(out)
    }

    /// Appends each instanced mesh's BVH after the nodes (its indices moved to where it
    /// lands) and its triangles after the triangles, then the instances in top-level order,
    /// and makes the top level's instance leaves point at their first instance's node slot;
    /// returns the deepest mesh BVH's depth.
    fn push_instances(
        &mut self,
        scene: &Scene,
        meshes: Vec<bvh::FlatBvh>,
        placed: &[(u32, glam::Mat4)],
        order: &[u32],
        textured: bool,
    ) -> usize {
        let mut roots = Vec::with_capacity(meshes.len());
        let mut depth = 0;
        for (m, flat) in scene.instanced.iter().zip(meshes) {
            let node_base = self.bvh_nodes.len() as u32;
            let tri_base = self.tri_positions.len() as u32;
            roots.push(node_base);
            depth = depth.max(flat.depth);
            self.bvh_nodes.extend(flat.nodes.iter().map(|n| GpuBvhNode {
                index: n.index
                    + if n.bits >> bvh::NODE_COUNT_SHIFT == 0 {
                        node_base
                    } else {
                        tri_base
                    },
                ..*n
            }));
            self.bvh_skips.extend(
                flat.skips
                    .iter()
                    .map(|s| s.map(|k| if k == bvh::BVH_END { k } else { k + node_base })),
            );
            // Instanced meshes never emit (`Scene::apply_instancing` copies those that do).
            self.push_triangles(
                scene,
                &m.triangles,
                &flat.tri_order,
                textured,
                &mut Vec::new(),
            );
            self.mesh_triangles
                .push([tri_base, m.triangles.len() as u32]);
            self.instanced_triangles += m.copies();
        }
        let first_slot = self.bvh_nodes.len() as u32;
        for n in &mut self.bvh_nodes[..roots.first().map_or(0, |&r| r as usize)] {
            if n.bits >> bvh::NODE_COUNT_SHIFT != 0 && n.bits & bvh::NODE_INSTANCES != 0 {
                n.index = first_slot + 2 * n.index;
            }
        }
        for (k, &i) in order.iter().enumerate() {
            let (mesh, to_world) = placed[i as usize];
            let to_object = to_world.as_dmat4().inverse().as_mat4();
            let rows = |m: glam::Mat4| {
                let t = m.transpose();
                [
                    t.x_axis.to_array(),
                    t.y_axis.to_array(),
                    t.z_axis.to_array(),
                ]
            };
            let object = rows(to_object);
            let pad_scale = object
                .iter()
                .map(|r| r[0].abs() + r[1].abs() + r[2].abs())
                .fold(0.0f32, f32::max);
            let root = &self.bvh_nodes[roots[mesh as usize] as usize];
            let extent = Vec3::from(root.aabb_min)
                .abs()
                .max(Vec3::from(root.aabb_max).abs())
                .max_element();
            let translation = object.iter().map(|r| r[3].abs()).fold(0.0f32, f32::max);
            self.instances.push(crate::gpu::GpuInstance {
                to_world: rows(to_world),
                to_object: object,
                root: roots[mesh as usize],
                flags: if to_world.determinant() < 0.0 {
                    crate::gpu::INSTANCE_MIRROR
                } else {
                    0
                },
                pad_scale,
                pad_base: translation + extent,
                index: k as u32,
                pad: [0; 3],
            });
            self.instance_mesh.push(mesh);
        }
        depth
    }

    /// Appends `triangles` in the order `order` (BVH order): intersection data, shading
    /// data, texture coordinates (when `textured`), and a light for each emissive one (its
    /// power pushed to `weights`).
    fn push_triangles(
        &mut self,
        scene: &Scene,
        triangles: &[crate::scene::Triangle],
        order: &[u32],
        textured: bool,
        weights: &mut Vec<f32>,
    ) {
        for &src in order {
            let i = self.tri_positions.len();
            let t = &triangles[src as usize];
            let [p0, p1, p2] = t.positions;
            let (e1, e2) = (p1 - p0, p2 - p0);
            let alpha =
                scene.materials[t.material as usize].alpha_mode != crate::scene::AlphaMode::Opaque;
            self.tri_positions.push(GpuTriangle {
                v0: p0.to_array(),
                flags: if alpha { crate::gpu::TRI_ALPHA } else { 0 },
                e1: e1.to_array(),
                e2: e2.to_array(),
                ..GpuTriangle::default()
            });
            self.tri_corners
                .push([p0.to_array(), p1.to_array(), p2.to_array()]);
            let flat_n = e1.cross(e2).normalize();
            let ns = t.normals.unwrap_or([flat_n; 3]);
            let m = &scene.materials[t.material as usize];
            if textured {
                let uv = t.uvs.unwrap_or([glam::Vec2::ZERO; 3]);
                let uv1 = t.uvs1.unwrap_or([glam::Vec2::ZERO; 3]);
                // Generated tangents follow the normal map's own coordinates: its set,
                // through its transform.
                let tan = t.tangents.unwrap_or_else(|| {
                    let normal_uv = scene
                        .textures
                        .get(m.textures.normal as usize)
                        .map_or(uv, |tex| [0, 1, 2].map(|k| tex.uv([uv[k], uv1[k]])));
                    crate::texture::triangle_tangents(t.positions, ns, normal_uv)
                });
                let colors = t
                    .colors
                    .map_or([crate::gpu::VERTEX_WHITE; 3], |c| c.map(u32::from_le_bytes));
                self.tri_texcoords.push(GpuTriTexcoords {
                    t0: tan[0].to_array(),
                    t1: tan[1].to_array(),
                    t2: tan[2].to_array(),
                    uv01: [uv[0].x, uv[0].y, uv[1].x, uv[1].y],
                    uv2: uv[2].to_array(),
                    uv1_2: uv1[2].to_array(),
                    uv1_01: [uv1[0].x, uv1[0].y, uv1[1].x, uv1[1].y],
                    colors,
                    pad0: 0,
                });
            }
            let mut light = NO_LIGHT;
            if m.is_emissive() {
                light = self.lights.len() as u32;
                let area = t.area();
                let sides = if m.two_sided { 2.0 } else { 1.0 };
                let mut power = luminance(m.emission) * area * std::f32::consts::PI * sides;
                if textured && m.textures.emissive != NO_TEXTURE {
                    let uv = t.uvs.unwrap_or([glam::Vec2::ZERO; 3]);
                    let uv1 = t.uvs1.unwrap_or([glam::Vec2::ZERO; 3]);
                    power *= textured_emission_scale(scene, m, [uv, uv1]);
                }
                weights.push(power);
                self.lights.push(GpuLight {
                    p0: p0.to_array(),
                    flags: if m.two_sided { LIGHT_TWO_SIDED } else { 0 },
                    e1: e1.to_array(),
                    prim: i as u32,
                    e2: e2.to_array(),
                    area,
                    emission: m.emission.to_array(),
                    power,
                    ..GpuLight::default()
                });
            }
            self.tri_shading.push(GpuTriShading {
                n0: ns[0].to_array(),
                material: t.material,
                n1: ns[1].to_array(),
                light,
                n2: ns[2].to_array(),
                flags: if t.normals.is_some() {
                    TRI_VERTEX_NORMALS
                } else {
                    0
                },
            });
        }
    }

    /// Appends the shapes in BVH order, and a light for each emissive one (its power
    /// pushed to `weights`).
    fn push_shapes(&mut self, scene: &Scene, weights: &mut Vec<f32>) {
        for (i, &src) in self.shape_source.iter().enumerate() {
            let s = &scene.shapes[src as usize];
            let record = s.record();
            let m = &scene.materials[s.material as usize];
            let mut light = NO_LIGHT;
            if m.is_emissive() {
                light = self.lights.len() as u32;
                let area = s.kind().area(&record);
                // A closed shape is seen from outside only; an open one from its front, or
                // both sides.
                let sides = if m.two_sided && !s.kind().closed() {
                    2.0
                } else {
                    1.0
                };
                let power = luminance(m.emission) * area * std::f32::consts::PI * sides;
                weights.push(power);
                self.lights.push(GpuLight {
                    flags: LIGHT_SHAPE | if m.two_sided { LIGHT_TWO_SIDED } else { 0 },
                    prim: i as u32,
                    area,
                    emission: m.emission.to_array(),
                    power,
                    ..GpuLight::default()
                });
            }
            self.shapes.push(GpuShape { light, ..record });
        }
    }
}

fn triangle_box(t: &crate::scene::Triangle) -> Aabb {
    Aabb::from_points(&t.positions.map(Vec3A::from))
}

/// The box around `b`'s corners moved by `m`.
fn transformed_box(b: &Aabb, m: &glam::Mat4) -> Aabb {
    let mut out = Aabb::empty();
    for k in 0..8 {
        let corner = Vec3A::new(
            if k & 1 == 0 { b.min.x } else { b.max.x },
            if k & 2 == 0 { b.min.y } else { b.max.y },
            if k & 4 == 0 { b.min.z } else { b.max.z },
        );
        out = out.union(&Aabb::from_points(&[Vec3A::from(
            m.transform_point3(corner.into()),
        )]));
    }
    out
}

/// Refuses more textures than the GPU layout can index and materials that use a texture
/// the scene does not have.
/// Whether the shader reads per-triangle attributes beyond normals: some material has a
/// texture or some triangle has vertex colours ([`GpuScene::tri_texcoords`],
/// [`FEATURE_TEXTURES`]).
fn surface_attributes(scene: &Scene) -> bool {
    scene.materials.iter().any(|m| m.textures.any())
        || scene
            .triangles
            .iter()
            .chain(scene.instanced.iter().flat_map(|m| &m.triangles))
            .any(|t| t.colors.is_some())
}

/// Per texture of `scene`, whether some material reads it as colour: its base colour,
/// emission, specular colour or sheen colour (sRGB-encoded slots).
fn texture_srgb(scene: &Scene) -> Vec<bool> {
    let mut srgb = vec![false; scene.textures.len()];
    for m in &scene.materials {
        let t = &m.textures;
        for id in [t.base_color, t.emissive, t.specular_color, t.sheen_color] {
            if let Some(s) = srgb.get_mut(id as usize) {
                *s = true;
            }
        }
    }
    srgb
}

fn check_textures(scene: &Scene) -> Result<(), SceneError> {
    if scene.textures.len() >= 0xFFFF {
        return Err(SceneError::new(ErrorKind::BadValue {
            field: "textures",
            message: format!("{} textures; at most 65534", scene.textures.len()),
        }));
    }
    for m in &scene.materials {
        if let Some(&t) = m
            .textures
            .all()
            .iter()
            .find(|&&t| t != NO_TEXTURE && t as usize >= scene.textures.len())
        {
            return Err(SceneError::new(ErrorKind::BadValue {
                field: "textures",
                message: format!(
                    "material \"{}\" uses texture {t} of {}",
                    m.name,
                    scene.textures.len()
                ),
            }));
        }
    }
    Ok(())
}

fn header(scene: &Scene, g: &GpuScene, depth: usize, total_power: f32) -> GpuHeader {
    let mut features = 0;
    if !g.shapes.is_empty() {
        features |= FEATURE_SHAPES;
    }
    if !g.lights.is_empty() {
        features |= FEATURE_LIGHTS;
    }
    if scene.materials.iter().any(|m| m.transmission > 0.0) {
        features |= FEATURE_TRANSMISSION;
    }
    if scene.materials.iter().any(|m| m.metallic > 0.0) {
        features |= FEATURE_METAL;
    }
    if surface_attributes(scene) {
        features |= FEATURE_TEXTURES;
    }
    if scene
        .materials
        .iter()
        .any(|m| m.alpha_mode != crate::scene::AlphaMode::Opaque)
    {
        features |= crate::gpu::FEATURE_ALPHA;
    }
    if scene
        .materials
        .iter()
        .any(|m| m.medium.is_some() || m.index_matched)
    {
        features |= FEATURE_MEDIA;
    }
    if !g.instances.is_empty() {
        features |= crate::gpu::FEATURE_INSTANCES;
    }
    let lit = match &scene.environment {
        Environment::Constant(c) => c.iter().any(|&x| x > 0.0),
        Environment::Map { intensity, .. } => *intensity > 0.0,
        _ => false,
    };
    if lit {
        features |= FEATURE_ENVIRONMENT;
    }
    GpuHeader {
        num_nodes: g.bvh_nodes.len() as u32,
        num_triangles: g.tri_positions.len() as u32,
        num_shapes: g.shapes.len() as u32,
        num_materials: g.materials.len() as u32,
        num_lights: g.lights.len() as u32,
        bvh_depth: depth as u32,
        features,
        total_light_power: total_power,
    }
}

fn settings(scene: &Scene) -> GpuSettings {
    let s = scene.settings;
    let mut g = GpuSettings {
        width: s.width,
        height: s.height,
        max_bounces: s.max_bounces,
        spp: s.spp,
        seed: s.seed,
        ..GpuSettings::default()
    };
    match &scene.environment {
        Environment::Constant(c) => {
            g.env_kind = ENV_CONSTANT;
            g.env_radiance = *c;
            g.env_flags = ENV_SHOW_BACKGROUND;
        }
        Environment::Map {
            intensity,
            azimuth,
            elevation,
            show_background,
            ..
        } => {
            g.env_kind = ENV_MAP;
            g.env_radiance = [*intensity; 3];
            g.env_azimuth = azimuth.to_radians();
            g.env_elevation = elevation.to_radians();
            g.env_flags = if *show_background {
                ENV_SHOW_BACKGROUND
            } else {
                0
            };
        }
        _ => g.env_kind = ENV_NONE,
    }
    g
}
