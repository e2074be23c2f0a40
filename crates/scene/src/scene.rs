//! The resolved scene on the CPU: world-space triangles and spheres, materials by index,
//! a camera, the environment and render settings. Loaders fill it in; [`crate::GpuScene`]
//! flattens it for the GPU.

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::error::{ErrorKind, SceneError};
use crate::file::{Environment, RenderSettings};

/// No texture.
pub const NO_TEXTURE: u32 = u32::MAX;

/// Texture indices of a material, into [`Scene::textures`] (an importer's own list before
/// the scene merges them); [`NO_TEXTURE`] when absent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialTextures {
    /// glTF `baseColorTexture`.
    pub base_color: u32,
    /// glTF `metallicRoughnessTexture`.
    pub metallic_roughness: u32,
    /// glTF `emissiveTexture`.
    pub emissive: u32,
    /// glTF `normalTexture`.
    pub normal: u32,
    /// `KHR_materials_transmission` `transmissionTexture` (R).
    pub transmission: u32,
    /// `KHR_materials_specular` `specularTexture` (A).
    pub specular: u32,
    /// `KHR_materials_specular` `specularColorTexture` (RGB, sRGB).
    pub specular_color: u32,
    /// `KHR_materials_clearcoat` `clearcoatTexture` (R).
    pub clearcoat: u32,
    /// `KHR_materials_clearcoat` `clearcoatRoughnessTexture` (G).
    pub clearcoat_roughness: u32,
    /// `KHR_materials_sheen` `sheenColorTexture` (RGB, sRGB).
    pub sheen_color: u32,
    /// `KHR_materials_sheen` `sheenRoughnessTexture` (A).
    pub sheen_roughness: u32,
    /// `KHR_materials_clearcoat` `clearcoatNormalTexture` (the coat's own normal map, in the
    /// base's tangent frame).
    pub clearcoat_normal: u32,
}

impl Default for MaterialTextures {
    fn default() -> Self {
        Self {
            base_color: NO_TEXTURE,
            metallic_roughness: NO_TEXTURE,
            emissive: NO_TEXTURE,
            normal: NO_TEXTURE,
            transmission: NO_TEXTURE,
            specular: NO_TEXTURE,
            specular_color: NO_TEXTURE,
            clearcoat: NO_TEXTURE,
            clearcoat_roughness: NO_TEXTURE,
            sheen_color: NO_TEXTURE,
            sheen_roughness: NO_TEXTURE,
            clearcoat_normal: NO_TEXTURE,
        }
    }
}

impl MaterialTextures {
    /// Whether any texture is set.
    pub fn any(&self) -> bool {
        self.all().iter().any(|&t| t != NO_TEXTURE)
    }

    /// Every slot, in declaration order.
    pub fn all(&self) -> [u32; 12] {
        [
            self.base_color,
            self.metallic_roughness,
            self.emissive,
            self.normal,
            self.transmission,
            self.specular,
            self.specular_color,
            self.clearcoat,
            self.clearcoat_roughness,
            self.sheen_color,
            self.sheen_roughness,
            self.clearcoat_normal,
        ]
    }

    /// The slots' names, in declaration order (as [`Self::all`] gives them).
    pub const NAMES: [&'static str; 12] = [
        "base_color",
        "metallic_roughness",
        "emissive",
        "normal",
        "transmission",
        "specular",
        "specular_color",
        "clearcoat",
        "clearcoat_roughness",
        "sheen_color",
        "sheen_roughness",
        "clearcoat_normal",
    ];

    /// Every slot, mutably, in declaration order.
    pub fn all_mut(&mut self) -> [&mut u32; 12] {
        [
            &mut self.base_color,
            &mut self.metallic_roughness,
            &mut self.emissive,
            &mut self.normal,
            &mut self.transmission,
            &mut self.specular,
            &mut self.specular_color,
            &mut self.clearcoat,
            &mut self.clearcoat_roughness,
            &mut self.sheen_color,
            &mut self.sheen_roughness,
            &mut self.clearcoat_normal,
        ]
    }
}

/// Leaves out of `textures` (a mesh's, by index) those none of `materials` reads, keeping
/// the others in their order, and moves the materials' indices along (`diffuse: true`
/// reduces materials and then drops what they no longer read).
pub(crate) fn keep_read_textures<T>(materials: &mut [Material], textures: Vec<T>) -> Vec<T> {
    let mut index = vec![NO_TEXTURE; textures.len()];
    for m in materials.iter() {
        for t in m.textures.all() {
            if t != NO_TEXTURE {
                index[t as usize] = 0;
            }
        }
    }
    let mut kept = Vec::new();
    for (i, t) in textures.into_iter().enumerate() {
        if index[i] != NO_TEXTURE {
            index[i] = kept.len() as u32;
            kept.push(t);
        }
    }
    for m in materials {
        for t in m.textures.all_mut() {
            if *t != NO_TEXTURE {
                *t = index[*t as usize];
            }
        }
    }
    kept
}

/// The scene's material, its lobe parameters' fields from `lobe_params!`
/// ([`crate::lobes`]), and [`Material::named`], which gives every field the file format's
/// default.
macro_rules! material {
    ({ $($field:tt)* } { $($named:tt)* } { $($default:tt)* } $(
        $(#[doc = $doc:literal])*
        $lobe:ident . $name:ident : $kind:ident = $value:expr, $check:ident,
        $label:literal, $tip:literal, $max:literal;
    )*) => {
        /// A material, with the parameters of the path tracer's BSDF.
        #[derive(Clone, Debug, PartialEq)]
        pub struct Material {
            $($field)*
            $( $(#[doc = $doc])* pub $name: crate::lobes::scene_ty!($kind), )*
        }

        impl Material {
            /// A material with the file format's defaults and the given name.
            $($named)* {
                Self {
                    $($default)*
                    $( $name: crate::lobes::scene_value!($kind, $value), )*
                }
            }
        }
    };
}

crate::lobes::lobe_params!(material! {
    /// Name, for messages (`"white"`, or `"<shape>/<material>"` for imported ones).
    pub name: String,
    /// Diffuse albedo or metal reflectance, linear RGB.
    pub base_color: Vec3,
    /// Emitted radiance, linear RGB.
    pub emission: Vec3,
    /// 0 dielectric, 1 metal.
    pub metallic: f32,
    /// Index of refraction.
    pub ior: f32,
    /// Emission leaves both sides (default: front only).
    pub two_sided: bool,
    /// Texture indices into [`Scene::textures`]; each texture multiplies its factor.
    pub textures: MaterialTextures,
    /// glTF `normalTexture.scale`: the tangent-space x and y of the normal map are scaled
    /// by it.
    pub normal_scale: f32,
    /// The same for the clear coat's own normal map (`clearcoatNormalTexture.scale`).
    pub clearcoat_normal_scale: f32,
    /// A conductor's complex index of refraction: the metal lobe's Fresnel is the exact
    /// conductor one instead of Schlick's on `base_color` (which then holds its
    /// normal-incidence reflectance, for albedo outputs).
    pub conductor: Option<crate::conductor::Conductor>,
    /// Compensate the energy single-scattering microfacet lobes lose (default true).
    pub multiscatter: bool,
    /// The homogeneous medium inside the shapes of this material (absorbing glass, or a
    /// scattering medium), if any.
    pub medium: Option<Medium>,
    /// No surface: rays cross it unchanged (the index-matched boundary of a `medium`,
    /// Mitsuba's `null` BSDF).
    pub index_matched: bool,
    /// Opacity in [0, 1], times the base colour texture's alpha; used as `alpha_mode` says.
    pub opacity: f32,
    /// How the opacity is used.
    pub alpha_mode: AlphaMode,
} {
    pub fn named(name: impl Into<String>) -> Self
} {
    name: name.into(),
    base_color: Vec3::splat(0.8),
    emission: Vec3::ZERO,
    metallic: 0.0,
    ior: 1.5,
    two_sided: false,
    textures: MaterialTextures::default(),
    normal_scale: 1.0,
    clearcoat_normal_scale: 1.0,
    conductor: None,
    multiscatter: true,
    medium: None,
    index_matched: false,
    opacity: 1.0,
    alpha_mode: AlphaMode::Opaque,
});

/// How a material's opacity is used (glTF `alphaMode`): every intersector (and the G-buffer
/// raster) applies it to the rays that reach the surface, camera and shadow rays alike.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Opacity is ignored: the surface is solid.
    #[default]
    Opaque,
    /// The surface is cut out where its opacity is below `cutoff`.
    Mask {
        /// In [0, 1].
        cutoff: f32,
    },
    /// Stochastic transparency: a ray passes through with probability 1 − opacity.
    Blend,
}

/// A homogeneous participating medium: coefficients per unit length of the scene, linear RGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    /// Absorption coefficient `σ_a`.
    pub sigma_a: Vec3,
    /// Scattering coefficient `σ_s`.
    pub sigma_s: Vec3,
    /// Henyey–Greenstein asymmetry g in (−1, 1): > 0 scatters forward.
    pub g: f32,
}

impl Medium {
    /// The absorbing medium of glTF's `KHR_materials_volume`: white light turns into
    /// `color` after `distance` (`σ_a = −ln(color) / distance`); none for an infinite distance
    /// or a white color.
    pub fn attenuation(color: Vec3, distance: f32) -> Option<Self> {
        if !distance.is_finite() || color.min_element() >= 1.0 {
            return None;
        }
        let sigma_a = Vec3::new(
            -color.x.max(1e-30).ln(),
            -color.y.max(1e-30).ln(),
            -color.z.max(1e-30).ln(),
        )
        .max(Vec3::ZERO)
            / distance;
        Some(Self {
            sigma_a,
            sigma_s: Vec3::ZERO,
            g: 0.0,
        })
    }
}

impl Material {
    /// The material reduced to a Lambertian diffuse of its base colour: the base colour
    /// factor and texture, opacity, alpha mode, emission (factor and texture) and two-sidedness
    /// kept, every other lobe, texture and medium left out (a `Mesh`'s `diffuse: true`).
    #[must_use]
    pub fn as_diffuse(&self) -> Self {
        Self {
            textures: MaterialTextures {
                base_color: self.textures.base_color,
                emissive: self.textures.emissive,
                ..MaterialTextures::default()
            },
            specular: 0.0,
            opacity: self.opacity,
            alpha_mode: self.alpha_mode,
            emission: self.emission,
            two_sided: self.two_sided,
            base_color: self.base_color,
            ..Self::named(self.name.clone())
        }
    }

    /// Whether it emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// A perspective camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Up hint (not necessarily orthogonal to `forward`).
    pub up: Vec3,
    /// Full vertical field of view, degrees.
    pub fov_y_deg: f32,
    /// Lens radius; 0 is a pinhole.
    pub aperture_radius: f32,
    /// Distance to the plane in focus.
    pub focus_distance: f32,
    /// Focus on the first surface through the image center (set when the scene is flattened).
    pub autofocus: bool,
}

impl Camera {
    /// The orthonormal basis `(right, up, forward)`: image x grows along `right`, image y
    /// grows along `-up` (Mitsuba's convention).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = self.forward.normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        (right, up, forward)
    }
}

/// A world-space triangle. The front side is the one from which the corners appear
/// counter-clockwise (geometric normal `(p1 - p0) × (p2 - p0)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// Corners.
    pub positions: [Vec3; 3],
    /// Unit shading normals at the corners, when the source had them.
    pub normals: Option<[Vec3; 3]>,
    /// Texture coordinates (glTF `TEXCOORD_0`) at the corners, when the source had them.
    pub uvs: Option<[Vec2; 3]>,
    /// The second set of texture coordinates (glTF `TEXCOORD_1`), read by textures whose
    /// `uv_set` is 1 ([`crate::texture::Texture::uv_set`]).
    pub uvs1: Option<[Vec2; 3]>,
    /// Vertex colours (glTF `COLOR_0`), multiplying the base colour and the opacity: RGB
    /// sRGB-encoded and alpha linear, 8 bits a channel, as texels are (decoded as a texel
    /// is, then interpolated across the triangle).
    pub colors: Option<[[u8; 4]; 3]>,
    /// Tangents at the corners (glTF `TANGENT`: xyz along +U, w = ±1 the handedness of the
    /// bitangent `w · normal × tangent`), when the source had them; else they are generated
    /// when the scene is flattened (see [`crate::texture::triangle_tangents`]).
    pub tangents: Option<[Vec4; 3]>,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

impl Triangle {
    /// The unnormalized geometric normal; its length is twice the area.
    pub fn cross(&self) -> Vec3 {
        let [p0, p1, p2] = self.positions;
        (p1 - p0).cross(p2 - p0)
    }

    /// Area.
    pub fn area(&self) -> f32 {
        0.5 * self.cross().length()
    }

    /// Unit geometric (front) normal.
    pub fn normal(&self) -> Vec3 {
        self.cross().normalize()
    }
}

/// An analytic shape: a kind of [`crate::shapes::KINDS`] and the parameters every kind
/// reads its own way (a sphere its `center` and `radius`; a disk also its front normal,
/// `axis`). Each kind is one file, `crates/scene/src/shapes/<kind>.rs`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    /// Index into [`crate::shapes::KINDS`].
    pub kind: u32,
    /// Center.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
    /// Unit axis (a disk's front normal); zero where the kind has none.
    pub axis: Vec3,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

impl Shape {
    /// A sphere.
    pub fn sphere(center: Vec3, radius: f32, material: u32) -> Self {
        Self {
            kind: crate::shapes::SPHERE,
            center,
            radius,
            axis: Vec3::ZERO,
            material,
        }
    }

    /// Its kind's code.
    pub fn kind(&self) -> &'static dyn crate::shapes::ShapeKind {
        crate::shapes::KINDS[self.kind as usize]
    }

    /// Its GPU record, without a light.
    pub fn record(&self) -> crate::gpu::GpuShape {
        crate::gpu::GpuShape {
            center: self.center.to_array(),
            radius: self.radius,
            axis: self.axis.to_array(),
            kind: self.kind,
            material: self.material,
            light: crate::gpu::NO_LIGHT,
            ..crate::gpu::GpuShape::default()
        }
    }
}

/// A light without area: it lights the scene through light sampling only and is never hit.
/// Its record is its GPU record, of a kind in [`crate::lights::KINDS`] (`kind` is the index
/// + 1), which reads its fields its own way; [`crate::GpuScene::build`] sets its `power`.
pub type PunctualLight = crate::gpu::GpuLight;

/// What loading left out or changed, never fatal.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// Triangles dropped because their area is zero (collinear or repeated corners).
    pub degenerate_triangles: usize,
    /// Triangles dropped because a corner is NaN or infinite.
    pub non_finite_triangles: usize,
    /// Triangles whose vertex normals were unusable and replaced by the flat normal.
    pub replaced_normals: usize,
    /// Other warnings, one line each.
    pub warnings: Vec<String>,
}

impl LoadReport {
    /// Whether nothing was dropped or changed.
    pub fn is_clean(&self) -> bool {
        *self == Self::default()
    }

    /// Every warning, one line each: the dropped and repaired triangles counted, then the
    /// others (what `lumagraph render` and a session print as `scene warning: …`).
    pub fn lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.degenerate_triangles + self.non_finite_triangles + self.replaced_normals > 0 {
            out.push(format!(
                "dropped {} zero-area and {} non-finite triangles, replaced {} unusable normals",
                self.degenerate_triangles, self.non_finite_triangles, self.replaced_normals
            ));
        }
        out.extend(self.warnings.iter().cloned());
        out
    }

    /// Adds the counts and warnings of `other`.
    pub fn merge(&mut self, other: Self) {
        self.degenerate_triangles += other.degenerate_triangles;
        self.non_finite_triangles += other.non_finite_triangles;
        self.replaced_normals += other.replaced_normals;
        self.warnings.extend(other.warnings);
    }
}

/// The resolved scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Materials; triangles and shapes index into this.
    pub materials: Vec<Material>,
    /// World-space triangles.
    pub triangles: Vec<Triangle>,
    /// Meshes placed several times, stored once each (the render settings' `instancing` decides which
    /// stay so and which become copies in `triangles`).
    pub instanced: Vec<InstancedMesh>,
    /// Analytic shapes (spheres, disks, …).
    pub shapes: Vec<Shape>,
    /// Point, spot and directional lights.
    pub lights: Vec<PunctualLight>,
    /// Decoded textures; materials index into this.
    pub textures: Vec<crate::texture::Texture>,
    /// What rays leaving the scene see.
    pub environment: Environment,
    /// Image size and sampling.
    pub settings: RenderSettings,
    /// What loading dropped or changed.
    pub report: LoadReport,
    /// How long loading took.
    pub stats: LoadStats,
}

/// A mesh placed several times: its triangles stored once, in its own (object) space, and
/// one transform (object to world) per placement. The GPU traverses it as a bottom-level
/// BVH under the instances' top-level one, so memory grows with the unique triangles.
#[derive(Clone, Debug, Default)]
pub struct InstancedMesh {
    /// For messages: the file and mesh it came from.
    pub name: String,
    /// Object-space triangles.
    pub triangles: Vec<Triangle>,
    /// Object to world, one per instance.
    pub transforms: Vec<Mat4>,
}

impl InstancedMesh {
    /// Triangles its copies would store.
    pub fn copies(&self) -> u64 {
        self.triangles.len() as u64 * self.transforms.len() as u64
    }
}

/// The most triangles copies of instanced meshes may make (instancing `Off`, or a mesh
/// that must be copied): each copy stores its triangles, so a file instancing a large mesh
/// many times gets an error naming the mesh rather than exhausting memory.
pub const MAX_INSTANCED_TRIANGLES: u64 = 50_000_000;

/// With instancing `Auto`, instanced meshes whose copies add up to at most this many
/// triangles are copied: the flat scene is faster to trace (every intersector takes it,
/// and on CPU adapters the faster ones take only flat scenes) and costs at most about
/// 0.8 GB at the GPU's ~200 bytes a triangle.
pub const AUTO_FLATTEN_MAX_TRIANGLES: u64 = 4_000_000;

/// Whether meshes placed several times stay instances (stored once) or become copies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
pub enum Instancing {
    /// Copies where they add up to at most [`AUTO_FLATTEN_MAX_TRIANGLES`], else instances.
    #[default]
    Auto,
    /// Instances, always (except meshes with emissive materials: emitters are copied).
    On,
    /// Copies, always ([`MAX_INSTANCED_TRIANGLES`] at most).
    Off,
}

/// How long loading a scene took, and its texture decoding within that (what `render`
/// prints).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LoadStats {
    /// Reading the scene file, its meshes and their textures.
    pub total: std::time::Duration,
    /// Decoding the texture images (part of `total`).
    pub decode: crate::import::DecodeStats,
}

impl Scene {
    /// Applies `instancing`: the instanced meshes that are to be copies are copied into
    /// [`Scene::triangles`] (in world space), the others stay. Meshes with an emissive
    /// material are always copied: emitters are sampled as world-space triangles.
    ///
    /// # Errors
    /// [`ErrorKind::TooManyInstancedTriangles`] where the copies would exceed
    /// [`MAX_INSTANCED_TRIANGLES`].
    pub fn apply_instancing(&mut self, instancing: Instancing) -> Result<(), SceneError> {
        // An instance whose transform cannot be inverted (a zero scale) or is not finite
        // places nothing a ray could hit (its copies' triangles would be dropped as
        // degenerate): it is dropped, and said; so is a mesh left with no triangle.
        for m in &mut self.instanced {
            let before = m.transforms.len();
            m.transforms.retain(|t| {
                let det = t.determinant();
                t.is_finite() && det != 0.0 && det.is_finite()
            });
            if m.transforms.len() < before {
                self.report.warnings.push(format!(
                    "{}: {} of its {before} instances dropped: their transform is singular or \
                     not finite",
                    m.name,
                    before - m.transforms.len()
                ));
            }
        }
        self.instanced
            .retain(|m| !m.triangles.is_empty() && !m.transforms.is_empty());
        let all: u64 = self.instanced.iter().map(InstancedMesh::copies).sum();
        let keep = match instancing {
            Instancing::On => true,
            Instancing::Off => false,
            Instancing::Auto => all > AUTO_FLATTEN_MAX_TRIANGLES,
        };
        let materials = &self.materials;
        let emits = |m: &InstancedMesh| {
            m.triangles.iter().any(|t| {
                materials
                    .get(t.material as usize)
                    .is_some_and(Material::is_emissive)
            })
        };
        let (copy, stay): (Vec<_>, Vec<_>) = std::mem::take(&mut self.instanced)
            .into_iter()
            .partition(|m| !keep || emits(m));
        copy_instances(&copy, &mut self.triangles, &mut self.report)?;
        self.instanced = stay;
        Ok(())
    }

    /// Turns the scene into a white furnace: every material's albedo (base colour, its
    /// texture and a conductor's reflectance) is 1 and nothing emits; the lights are
    /// removed and a constant environment of radiance 1 lights everything. An
    /// energy-conserving, energy-preserving material then looks like the background
    /// (radiance 1) wherever the path depth suffices; what is darker loses energy, what is
    /// brighter creates it. Roughness, metalness, transmission and normal maps are kept.
    pub fn make_furnace(&mut self) {
        for m in &mut self.materials {
            m.base_color = Vec3::ONE;
            m.emission = Vec3::ZERO;
            m.textures.base_color = NO_TEXTURE;
            m.textures.emissive = NO_TEXTURE;
            m.textures.specular_color = NO_TEXTURE;
            m.conductor = None;
        }
        self.lights.clear();
        self.environment = Environment::Constant([1.0; 3]);
    }
}

/// Appends the copies of `meshes`, every instance's triangles in world space.
///
/// # Errors
/// [`ErrorKind::TooManyInstancedTriangles`] where they would exceed
/// [`MAX_INSTANCED_TRIANGLES`] (nothing is appended then).
pub(crate) fn copy_instances(
    meshes: &[InstancedMesh],
    out: &mut Vec<Triangle>,
    report: &mut LoadReport,
) -> Result<(), SceneError> {
    let copies: u64 = meshes.iter().map(InstancedMesh::copies).sum();
    if copies > MAX_INSTANCED_TRIANGLES {
        let largest = meshes
            .iter()
            .max_by_key(|m| m.copies())
            .expect("copies > 0");
        return Err(SceneError::new(ErrorKind::TooManyInstancedTriangles(
            Box::new(crate::error::InstancedCopies {
                mesh: largest.name.clone(),
                instances: largest.transforms.len(),
                triangles: largest.triangles.len(),
                total: copies,
                max: MAX_INSTANCED_TRIANGLES,
            }),
        )));
    }
    out.reserve(copies as usize);
    for m in meshes {
        for t in &m.transforms {
            for tri in &m.triangles {
                push_triangle(out, report, transform_triangle(t, tri));
            }
        }
    }
    Ok(())
}

/// Checks a triangle and appends it, or counts it as dropped in `report`.
///
/// Dropped: any corner NaN or infinite; zero area (the corners are collinear to within
/// 1e-10 of the edge lengths' product). Vertex normals that are not finite or zero are
/// replaced by the flat normal; the others are normalized. Texture coordinates or tangents
/// that are not finite are dropped (tangents are then generated).
pub fn push_triangle(out: &mut Vec<Triangle>, report: &mut LoadReport, mut tri: Triangle) {
    if !tri.positions.iter().all(|p| p.is_finite()) {
        report.non_finite_triangles += 1;
        return;
    }
    let [p0, p1, p2] = tri.positions;
    let (e1, e2) = (p1 - p0, p2 - p0);
    let n = e1.cross(e2).length();
    if !(n > 1e-10 * e1.length() * e2.length() && n.is_finite() && n > 0.0) {
        report.degenerate_triangles += 1;
        return;
    }
    if let Some(normals) = tri.normals {
        let ok = normals
            .iter()
            .all(|n| n.is_finite() && n.length_squared() > 1e-20);
        if ok {
            tri.normals = Some(normals.map(Vec3::normalize));
        } else {
            report.replaced_normals += 1;
            tri.normals = None;
        }
    }
    if tri
        .uvs
        .is_some_and(|uvs| !uvs.iter().all(|uv| uv.is_finite()))
    {
        tri.uvs = None;
    }
    if tri
        .uvs1
        .is_some_and(|uvs| !uvs.iter().all(|uv| uv.is_finite()))
    {
        tri.uvs1 = None;
    }
    if tri.tangents.is_some_and(|ts| {
        !ts.iter()
            .all(|t| t.is_finite() && t.truncate().length_squared() > 1e-20)
    }) {
        tri.tangents = None;
    }
    out.push(tri);
}

/// Applies `m` to a triangle: positions as points, normals by the inverse transpose;
/// swaps two corners when `m` mirrors (negative determinant) so the front side follows
/// the transformed normals, as glTF and Mitsuba do. Tangents transform as vectors; a
/// mirror flips their handedness.
pub fn transform_triangle(m: &Mat4, tri: &Triangle) -> Triangle {
    let normal_m = m.inverse().transpose();
    let mirror = m.determinant() < 0.0;
    let mut positions = tri.positions.map(|p| m.transform_point3(p));
    let mut normals = tri
        .normals
        .map(|ns| ns.map(|n| normal_m.transform_vector3(n)));
    let mut uvs = tri.uvs;
    let mut uvs1 = tri.uvs1;
    let mut colors = tri.colors;
    let mut tangents = tri.tangents.map(|ts| {
        ts.map(|t| {
            let w = if mirror { -t.w } else { t.w };
            m.transform_vector3(t.truncate()).extend(w)
        })
    });
    if mirror {
        positions.swap(1, 2);
        if let Some(ns) = normals.as_mut() {
            ns.swap(1, 2);
        }
        if let Some(uv) = uvs.as_mut() {
            uv.swap(1, 2);
        }
        if let Some(uv) = uvs1.as_mut() {
            uv.swap(1, 2);
        }
        if let Some(c) = colors.as_mut() {
            c.swap(1, 2);
        }
        if let Some(ts) = tangents.as_mut() {
            ts.swap(1, 2);
        }
    }
    Triangle {
        positions,
        normals,
        uvs,
        uvs1,
        colors,
        tangents,
        material: tri.material,
    }
}

/// The two triangles of a quad given counter-clockwise: (0, 1, 2) and (0, 2, 3).
pub fn quad_triangles(corners: [Vec3; 4], material: u32) -> [Triangle; 2] {
    let [a, b, c, d] = corners;
    [
        Triangle {
            positions: [a, b, c],
            normals: None,
            uvs: None,
            uvs1: None,
            colors: None,
            tangents: None,
            material,
        },
        Triangle {
            positions: [a, c, d],
            normals: None,
            uvs: None,
            uvs1: None,
            colors: None,
            tangents: None,
            material,
        },
    ]
}

/// The 6 faces of the cube [-1,1]³ as quads, counter-clockwise seen from outside.
pub fn cube_quads() -> [[Vec3; 4]; 6] {
    // (normal, u, v) with u × v = normal.
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    faces.map(|(n, u, v)| [n - u - v, n + u - v, n + u + v, n - u + v])
}

/// The square [-1,1]² in z=0, counter-clockwise seen from +z.
pub fn rectangle_quad() -> [Vec3; 4] {
    [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ]
}
