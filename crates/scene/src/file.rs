//! The scene file format (RON, `version: 2`), as written by hand.
//!
//! ```ron
//! (
//!     version: 2,
//!     camera: Perspective(position: (0, 0, 3.9), target: (0, 0, 0), up: (0, 1, 0), fov_y: 39.3077),
//!     materials: { "white": (base_color: (0.8, 0.8, 0.8)) },
//!     shapes: [
//!         Sphere(center: (0, 0, 0), radius: 1, material: "white"),
//!         Quad(corners: [(-1, 1, 0), (1, 1, 0), (1, 1, 1), (-1, 1, 1)], material: "white",
//!              emission: (10, 10, 10)),
//!         Mesh(name: "box", path: "CornellBox/CornellBox.gltf", transform: (scale: (2, 2, 2))),
//!     ],
//!     lights: [Point(position: (0, 0.9, 0), intensity: (2, 2, 2))],
//!     environment: Constant((1, 1, 1)),
//!     render: (width: 256, height: 256, spp: 16),
//! )
//! ```
//!
//! Version 2 changed the orientation of environment maps to Mitsuba's (the map's centre
//! column is seen looking along +z; `azimuth` and `elevation` rotate as Mitsuba's
//! `rotate`). Version 1 files are still read: their maps are turned so they light the
//! scene as before (see [`Environment::Map`]).
//!
//! Optional fields are written without `Some(…)` (ron's `implicit_some` is on). Every
//! struct refuses unknown fields. Vectors are tuples `(x, y, z)`. Angles are in
//! degrees. Paths are relative to the scene file. Shapes follow Mitsuba's conventions:
//! a `Rectangle` is the square [-1,1]² in the plane z=0 with its front normal +z, a `Box`
//! is the cube [-1,1]³ with outward normals, both placed by their `transform`; a `Quad`
//! is given by 4 world corners, counter-clockwise seen from its front. Emitters are
//! one-sided (radiance from the front only) unless `two_sided: true`.

use std::collections::BTreeMap;

use serde::Deserialize;

/// The scene file version this build writes; it also reads version 1 (see the module docs).
pub const VERSION: u32 = 2;

/// A 3-vector written `(x, y, z)`.
pub type V3 = [f32; 3];

/// The whole file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// [`VERSION`], or 1.
    pub version: u32,
    /// The camera.
    pub camera: CameraDesc,
    /// Named materials.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialDesc>,
    /// The shapes, each triangulated or kept as an analytic sphere.
    pub shapes: Vec<ShapeDesc>,
    /// Point, spot and directional lights.
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// What rays that leave the scene see.
    #[serde(default)]
    pub environment: Environment,
    /// Image size and sampling.
    pub render: RenderSettings,
    /// Whether meshes placed several times (a `Mesh` with `instances`, a glTF mesh used by
    /// several nodes or with `EXT_mesh_gpu_instancing`) are stored once or copied.
    #[serde(default)]
    pub instancing: crate::scene::Instancing,
}

/// Where the camera comes from.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
#[non_exhaustive]
pub enum CameraDesc {
    /// A pinhole or thin-lens camera given by position, target and up.
    Perspective {
        /// Eye position.
        position: V3,
        /// A point the camera looks at.
        target: V3,
        /// Up direction (need not be orthogonal to the view direction).
        #[serde(default = "default_up")]
        up: V3,
        /// Full vertical field of view, degrees.
        fov_y: f32,
        /// Lens radius; 0 is a pinhole.
        #[serde(default)]
        aperture_radius: f32,
        /// Distance to the plane in focus; the distance to `target` when absent.
        #[serde(default)]
        focus_distance: Option<f32>,
        /// Focus on whatever the image center sees (overrides `focus_distance`).
        #[serde(default)]
        autofocus: bool,
    },
    /// A camera of a glTF file loaded by a `Mesh` shape, placed by its node (and the
    /// shape's transform).
    Gltf {
        /// The `name` of the `Mesh` shape whose file holds the camera.
        shape: String,
        /// Which camera of the file, in node order.
        #[serde(default)]
        index: usize,
        /// Lens radius; 0 is a pinhole.
        #[serde(default)]
        aperture_radius: f32,
        /// Distance to the plane in focus; 1 when absent.
        #[serde(default)]
        focus_distance: Option<f32>,
        /// Focus on whatever the image center sees (overrides `focus_distance`).
        #[serde(default)]
        autofocus: bool,
    },
}

fn default_up() -> V3 {
    [0.0, 1.0, 0.0]
}

/// The scene format's material, its lobe parameters' fields from `lobe_params!`
/// ([`crate::lobes`]).
macro_rules! material_desc {
    ({ $($field:tt)* } { $($default:tt)* } $(
        $(#[doc = $doc:literal])*
        $lobe:ident . $name:ident : $kind:ident = $value:expr, $check:ident,
        $label:literal, $tip:literal, $max:literal;
    )*) => {
        /// A material; every field has a default, so a diffuse material is just `base_color`.
        #[derive(Clone, Debug, PartialEq, Deserialize)]
        #[serde(deny_unknown_fields, default)]
        pub struct MaterialDesc {
            $($field)*
            $( $(#[doc = $doc])* pub $name: crate::lobes::desc_ty!($kind), )*
        }

        impl Default for MaterialDesc {
            fn default() -> Self {
                Self {
                    $($default)*
                    $( $name: $value, )*
                }
            }
        }
    };
}

crate::lobes::lobe_params!(material_desc! {
    /// Diffuse albedo, or metal reflectance (linear RGB). Default 0.8 grey.
    pub base_color: V3,
    /// Emitted radiance (linear RGB). Default black.
    pub emission: V3,
    /// 0 dielectric, 1 metal. Default 0, or 1 with `conductor`, `eta` or `k`.
    pub metallic: Option<f32>,
    /// A measured conductor by name (`"Au"`, `"Ag"`, `"Al"`, `"Cu"`, …; see
    /// [`crate::conductor::PRESETS`]): the metal lobe uses the exact conductor Fresnel
    /// with its complex index of refraction instead of Schlick's on `base_color`.
    pub conductor: Option<String>,
    /// Real part of a conductor's index of refraction (RGB); with `k`, instead of a named
    /// `conductor`.
    pub eta: Option<V3>,
    /// Imaginary part (extinction coefficient) of a conductor's index of refraction (RGB).
    pub k: Option<V3>,
    /// Compensate the energy that single-scattering microfacet lobes lose (metal:
    /// Kulla–Conty; rough glass: reflections into the surface sent back out). Default
    /// true; false matches renderers without it (Mitsuba's `roughconductor`,
    /// `roughdielectric`).
    pub multiscatter: bool,
    /// Index of refraction. Default 1.5.
    pub ior: f32,
    /// Emission leaves both sides. Default false (front only).
    pub two_sided: bool,
    /// glTF `KHR_materials_volume`: the color white light turns into after
    /// `attenuation_distance` inside the shape (Beer–Lambert absorption,
    /// `σ_a = −ln(color) / distance`). Default white (none).
    pub attenuation_color: Option<V3>,
    /// The distance, in scene units, at which light inside has `attenuation_color`.
    /// Default infinite (no absorption).
    pub attenuation_distance: Option<f32>,
    /// A homogeneous medium inside the shapes of this material (excludes the
    /// `attenuation_*` fields). Default none.
    pub medium: Option<MediumDesc>,
    /// No surface: rays cross the shape's boundary unchanged, into or out of its `medium`
    /// (an index-matched boundary, Mitsuba's `null` BSDF). Default false.
    pub index_matched: bool,
    /// How the surface's opacity (`opacity` × the base colour texture's alpha) is used:
    /// `Opaque` ignores it (default), `Mask` cuts the surface out where it is below
    /// `alpha_cutoff`, `Blend` lets rays through with probability 1 − opacity (stochastic
    /// transparency). glTF's `alphaMode`.
    pub alpha_mode: AlphaModeDesc,
    /// `Mask`'s cutoff in [0, 1]. Default 0.5 (glTF's `alphaCutoff`).
    pub alpha_cutoff: f32,
    /// The surface's opacity in [0, 1] (glTF's base colour factor alpha, OBJ's `d`).
    /// Default 1.
    pub opacity: f32,
} {
    base_color: [0.8, 0.8, 0.8],
    emission: [0.0; 3],
    metallic: None,
    conductor: None,
    eta: None,
    k: None,
    multiscatter: true,
    ior: 1.5,
    two_sided: false,
    attenuation_color: None,
    attenuation_distance: None,
    medium: None,
    index_matched: false,
    alpha_mode: AlphaModeDesc::Opaque,
    alpha_cutoff: 0.5,
    opacity: 1.0,
});

/// How a material's opacity is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum AlphaModeDesc {
    /// Opacity is ignored.
    #[default]
    Opaque,
    /// The surface is cut out where its opacity is below the cutoff.
    Mask,
    /// Rays pass through with probability 1 − opacity.
    Blend,
}

/// A homogeneous participating medium: coefficients per unit length of the scene
/// (extinction `σ_t = σ_a + σ_s`, single-scattering albedo `σ_s / σ_t`), linear RGB.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MediumDesc {
    /// Absorption coefficient `σ_a`. Default 0.
    pub sigma_a: V3,
    /// Scattering coefficient `σ_s`. Default 0.
    pub sigma_s: V3,
    /// Henyey–Greenstein asymmetry of the phase function, in (−1, 1); 0 is isotropic,
    /// > 0 forward. Default 0.
    pub g: f32,
}

impl Default for MediumDesc {
    fn default() -> Self {
        Self {
            sigma_a: [0.0; 3],
            sigma_s: [0.0; 3],
            g: 0.0,
        }
    }
}

/// A placement: either scale, then rotations in the order listed, then translation; or a
/// full row-major 4×4 `matrix` acting on column vectors (Mitsuba's `to_world`).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransformDesc {
    /// Translation, applied last.
    pub translate: Option<V3>,
    /// Rotations, applied in the order listed, after the scale.
    pub rotate: Vec<Rotation>,
    /// Per-axis scale, applied first.
    pub scale: Option<V3>,
    /// A full matrix, 4 rows of 4 written as lists `[[..], [..], [..], [..]]`; excludes
    /// the other fields.
    pub matrix: Option<Vec<Vec<f32>>>,
}

/// A rotation about an axis through the origin.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// The axis (normalized on load).
    pub axis: V3,
    /// Angle in degrees, counter-clockwise looking down the axis.
    pub degrees: f32,
}

/// One shape of the scene.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
#[non_exhaustive]
pub enum ShapeDesc {
    /// Triangles from a glTF (`.gltf`, `.glb`) or OBJ (`.obj`) file.
    Mesh {
        /// Name for messages and for `CameraDesc::Gltf`.
        #[serde(default)]
        name: Option<String>,
        /// The file, relative to the scene file.
        path: String,
        /// Placement of the whole file.
        #[serde(default)]
        transform: TransformDesc,
        /// A scene material that replaces every material of the file.
        #[serde(default)]
        material: Option<String>,
        /// Every material of the file reduced to a Lambertian diffuse of its base colour
        /// (factor, texture and vertex colours), its opacity, alpha mode and emission kept and
        /// every other lobe and texture left out: the scene as renderers that read only
        /// those see it (`lumagraph export` and Mitsuba's `diffuse`, `bitmap` and `mask`).
        #[serde(default)]
        diffuse: bool,
        /// Emitted radiance, replacing the materials' own.
        #[serde(default)]
        emission: Option<V3>,
        /// Emission leaves both sides.
        #[serde(default)]
        two_sided: bool,
        /// Places of the whole file (each after `transform`): the file is read once and
        /// its meshes are instances, one per entry (see `instancing`). Empty: placed once.
        #[serde(default)]
        instances: Vec<TransformDesc>,
    },
    /// An analytic sphere.
    Sphere {
        /// Name for messages.
        #[serde(default)]
        name: Option<String>,
        /// Center, world space.
        center: V3,
        /// Radius, > 0.
        radius: f32,
        /// Material name.
        material: String,
        /// Emitted radiance, replacing the material's own.
        #[serde(default)]
        emission: Option<V3>,
        /// Emission leaves both sides.
        #[serde(default)]
        two_sided: bool,
    },
    /// An analytic disk (Mitsuba's `disk`), one-sided as a triangle is: its front faces
    /// `normal`.
    Disk {
        /// Name for messages.
        #[serde(default)]
        name: Option<String>,
        /// Center, world space.
        center: V3,
        /// Front normal, world space (any length but 0).
        normal: V3,
        /// Radius, > 0.
        radius: f32,
        /// Material name.
        material: String,
        /// Emitted radiance, replacing the material's own.
        #[serde(default)]
        emission: Option<V3>,
        /// Emission leaves both sides.
        #[serde(default)]
        two_sided: bool,
    },
    /// The square [-1,1]² in z=0, front normal +z, then `transform`: 2 triangles.
    Rectangle {
        /// Name for messages.
        #[serde(default)]
        name: Option<String>,
        /// Placement.
        #[serde(default)]
        transform: TransformDesc,
        /// Material name.
        material: String,
        /// Emitted radiance, replacing the material's own.
        #[serde(default)]
        emission: Option<V3>,
        /// Emission leaves both sides.
        #[serde(default)]
        two_sided: bool,
    },
    /// The cube [-1,1]³ with outward normals, then `transform`: 12 triangles.
    Box {
        /// Name for messages.
        #[serde(default)]
        name: Option<String>,
        /// Placement.
        #[serde(default)]
        transform: TransformDesc,
        /// Material name.
        material: String,
        /// Emitted radiance, replacing the material's own.
        #[serde(default)]
        emission: Option<V3>,
        /// Emission leaves both sides.
        #[serde(default)]
        two_sided: bool,
    },
    /// A planar quad by 4 world corners, counter-clockwise seen from the front:
    /// triangles (0, 1, 2) and (0, 2, 3).
    Quad {
        /// Name for messages.
        #[serde(default)]
        name: Option<String>,
        /// The 4 corners, world space, as a list `[(x, y, z), …]`.
        corners: Vec<V3>,
        /// Material name.
        material: String,
        /// Emitted radiance, replacing the material's own.
        #[serde(default)]
        emission: Option<V3>,
        /// Emission leaves both sides.
        #[serde(default)]
        two_sided: bool,
    },
}

impl ShapeDesc {
    /// Every kind, as written in the file.
    pub const KINDS: [&'static str; 6] = ["Mesh", "Sphere", "Disk", "Rectangle", "Box", "Quad"];

    /// An analytic shape's kind ([`crate::shapes::KINDS`]), center, radius, axis (zero
    /// where its kind has none) and material; `None` for the shapes made of triangles.
    pub fn analytic(&self) -> Option<(u32, V3, f32, V3, &str)> {
        match self {
            Self::Sphere {
                center,
                radius,
                material,
                ..
            } => Some((crate::shapes::SPHERE, *center, *radius, [0.0; 3], material)),
            Self::Disk {
                center,
                normal,
                radius,
                material,
                ..
            } => Some((crate::shapes::DISK, *center, *radius, *normal, material)),
            _ => None,
        }
    }

    /// The shape's name, if it has one.
    pub fn name(&self) -> Option<&str> {
        match self {
            Self::Mesh { name, .. }
            | Self::Sphere { name, .. }
            | Self::Disk { name, .. }
            | Self::Rectangle { name, .. }
            | Self::Box { name, .. }
            | Self::Quad { name, .. } => name.as_deref(),
        }
    }

    /// The kind, as written in the file.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Mesh { .. } => "Mesh",
            Self::Sphere { .. } => "Sphere",
            Self::Disk { .. } => "Disk",
            Self::Rectangle { .. } => "Rectangle",
            Self::Box { .. } => "Box",
            Self::Quad { .. } => "Quad",
        }
    }

    /// Emission override and two-sided flag.
    pub fn emitter(&self) -> (Option<V3>, bool) {
        match self {
            Self::Mesh {
                emission,
                two_sided,
                ..
            }
            | Self::Sphere {
                emission,
                two_sided,
                ..
            }
            | Self::Disk {
                emission,
                two_sided,
                ..
            }
            | Self::Rectangle {
                emission,
                two_sided,
                ..
            }
            | Self::Box {
                emission,
                two_sided,
                ..
            }
            | Self::Quad {
                emission,
                two_sided,
                ..
            } => (*emission, *two_sided),
        }
    }
}

/// A light that is not a surface (point, spot, directional, projector: one of
/// [`crate::lights::KINDS`]), written as its kind's name and its fields,
/// `Spot(position: (0, 2, 0), target: (0, 0, 0), intensity: (5, 5, 5))`. None of them is
/// seen by rays (they have no area); they light the scene through light sampling only. The
/// fields are checked by the kind when the scene loads ([`crate::lights::LightKind::load`]);
/// an unknown kind or field is refused as the file is read.
#[derive(Clone, Debug, PartialEq)]
pub struct LightDesc {
    /// Its kind: an index into [`crate::lights::KINDS`].
    pub kind: u32,
    /// Name for messages.
    pub name: Option<String>,
    /// Its other fields, as written.
    pub fields: crate::lights::Fields,
}

impl LightDesc {
    /// The light's name, if it has one.
    pub fn name(&self) -> Option<&str> {
        self.name.as_deref()
    }

    /// The kind, as written in the file.
    pub fn kind(&self) -> &'static str {
        crate::lights::KINDS[self.kind as usize].name()
    }
}

impl<'de> Deserialize<'de> for LightDesc {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("LightDesc", &[], LightVisitor)
    }
}

struct LightVisitor;

impl<'de> serde::de::Visitor<'de> for LightVisitor {
    type Value = LightDesc;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a light, its kind's name and its fields: Point(position: …, …)")
    }

    fn visit_enum<A: serde::de::EnumAccess<'de>>(self, data: A) -> Result<LightDesc, A::Error> {
        use serde::de::{Error, VariantAccess};
        let (Key(name), variant): (Key, _) = data.variant()?;
        let kind = crate::lights::kind_named(&name).ok_or_else(|| {
            let names: Vec<String> = crate::lights::KINDS
                .iter()
                .map(|k| format!("`{}`", k.name()))
                .collect();
            A::Error::custom(format!(
                "unknown light `{name}`, expected one of {}",
                names.join(", ")
            ))
        })?;
        variant.struct_variant(&[], FieldsVisitor(kind))
    }
}

struct FieldsVisitor(u32);

/// A field's name: an identifier, as RON writes struct fields.
struct Key(String);

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Key;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a field name")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Key, E> {
                Ok(Key(v.to_owned()))
            }
        }
        d.deserialize_identifier(V)
    }
}

impl<'de> serde::de::Visitor<'de> for FieldsVisitor {
    type Value = LightDesc;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("the light's fields, (name: value, …)")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<LightDesc, A::Error> {
        use serde::de::Error;
        let kind = crate::lights::KINDS[self.0 as usize];
        let mut out = LightDesc {
            kind: self.0,
            name: None,
            fields: crate::lights::Fields::default(),
        };
        while let Some(Key(key)) = map.next_key::<Key>()? {
            if key == "name" {
                out.name = map.next_value::<Option<String>>()?;
                continue;
            }
            if !kind.fields().contains(&key.as_str()) {
                return Err(A::Error::unknown_field(&key, kind.fields()));
            }
            if out.fields.0.contains_key(&key) {
                return Err(A::Error::custom(format!("duplicate field `{key}`")));
            }
            let value = map.next_value::<ron::Value>()?;
            out.fields.0.insert(key, value);
        }
        Ok(out)
    }
}

/// What rays that leave the scene see.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[non_exhaustive]
pub enum Environment {
    /// Black.
    #[default]
    None,
    /// The same radiance (linear RGB) from every direction.
    Constant(V3),
    /// An equirectangular image (Radiance `.hdr` or `.exr`, linear), importance sampled,
    /// in Mitsuba's orientation: looking along +z one sees the image's centre column, along
    /// +x the column a quarter from its left edge, along +y its top row. The map is turned
    /// by `elevation` about +x, then by `azimuth` about +y (counter-clockwise seen from
    /// above: Mitsuba's `to_world = rotate(y, azimuth) · rotate(x, elevation)`).
    ///
    /// Version 1 files saw the centre column along −z and turned the other way; they are
    /// read as `azimuth' = −(azimuth + 180)`, `elevation' = −elevation`, which lights the
    /// scene exactly as before.
    Map {
        /// The image, relative to the scene file (made absolute on load).
        path: String,
        /// Radiance scale.
        #[serde(default = "one")]
        intensity: f32,
        /// Rotation about the up (+y) axis, degrees, counter-clockwise seen from above.
        #[serde(default)]
        azimuth: f32,
        /// Tilt of the map's horizon, degrees (rotation about +x, before the azimuth).
        #[serde(default)]
        elevation: f32,
        /// Whether camera rays that miss see the map (else black); lighting is unchanged.
        #[serde(default = "yes")]
        show_background: bool,
    },
}

fn one() -> f32 {
    1.0
}

fn yes() -> bool {
    true
}

/// Image size and sampling.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Most scattering events per path (Mitsuba `max_depth` = this + 1). Default 20.
    #[serde(default = "default_max_bounces")]
    pub max_bounces: u32,
    /// Samples per pixel. Default 1.
    #[serde(default = "default_spp")]
    pub spp: u32,
    /// Random seed. Default 0.
    #[serde(default)]
    pub seed: u32,
    /// Mip chains for the textures, each lookup's level chosen from a ray cone and the two
    /// levels around it blended (trilinear; see `docs/pathtracer.md`, "Texture level of
    /// detail"). Default true; false samples every texture at full resolution (bilinear),
    /// as renderers without mip maps (Mitsuba's `bitmap`) do.
    #[serde(default = "yes")]
    pub texture_mips: bool,
}

fn default_max_bounces() -> u32 {
    20
}

fn default_spp() -> u32 {
    1
}
