//! The two tables of [`super`]: the GPU record of a material, field by field in layout
//! order (`material_record!`), and the lobe parameters of the scene format
//! (`lobe_params!`). A lobe parameter has a field of the same name in the record.

use super::{Field, Kind, Param, ParamMut, Value, desc_ty};
use crate::file::MaterialDesc;

/// A record field's Rust type from its WGSL type.
macro_rules! record_ty {
    (f32) => {
        f32
    };
    (u32) => {
        u32
    };
    (vec3f) => {
        [f32; 3]
    };
}

/// `GpuMaterial` and its field list from its rows (`name: wgsl_type`, in layout order).
macro_rules! material_record {
    ($( $(#[doc = $doc:literal])* $field:ident : $ty:ident, )*) => {
        /// A material as the path tracer reads it (`Material` in WGSL, written from the same
        /// rows: [`super::wgsl`]). Laid out as WGSL lays out storage buffers: every `vec3f`
        /// starts at a multiple of 16 bytes and is followed by a 4-byte scalar. Texture ids
        /// index the scene's textures (see [`crate::texture::pack_atlas`]), 16 bits each,
        /// 0xFFFF = none; each texture multiplies its factor.
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        pub struct GpuMaterial {
            $( $(#[doc = $doc])* pub $field: record_ty!($ty), )*
        }

        impl GpuMaterial {
            /// Every field, in layout order.
            pub const FIELDS: &'static [Field] = &[$(
                Field {
                    name: stringify!($field),
                    wgsl: stringify!($ty),
                    offset: std::mem::offset_of!(GpuMaterial, $field),
                    doc: concat!($($doc, "\n",)*),
                },
            )*];

            /// Every field's value, in layout order.
            pub fn values(&self) -> Vec<Value> {
                vec![$( Value::from(self.$field), )*]
            }
        }
    };
}

material_record! {
    /// Diffuse albedo or metal reflectance, linear RGB.
    base_color: vec3f,
    /// Perceptual roughness in [0, 1].
    roughness: f32,
    /// Emitted radiance, linear RGB.
    emission: vec3f,
    /// 0 dielectric, 1 metal.
    metallic: f32,
    /// Dielectric specular strength, 0.5 ⇒ F0 = 0.04.
    specular: f32,
    /// Specular tint towards the base color.
    specular_tint: f32,
    /// Transmitted fraction of the dielectric lobe.
    transmission: f32,
    /// Index of refraction.
    ior: f32,
    /// Base color texture (low 16 bits) and metallic-roughness texture (high 16 bits).
    tex_base_mr: u32,
    /// Emissive texture (low 16 bits) and normal texture (high 16 bits).
    tex_emissive_normal: u32,
    /// `MATERIAL_*` flags.
    flags: u32,
    /// glTF `normalTexture.scale`.
    normal_scale: f32,
    /// Transmission texture (low 16 bits, R) and specular texture (high 16 bits, A).
    tex_transmission_specular: u32,
    /// Specular color texture (low 16 bits, RGB sRGB) and the clear coat's normal texture
    /// (high 16 bits).
    tex_specular_color: u32,
    /// Roughness of the diffuse base: 0 Lambertian, else energy-preserving Oren–Nayar (EON).
    diffuse_roughness: f32,
    /// Opacity, times the base colour texture's alpha (`MATERIAL_ALPHA_MASK`, `_BLEND`).
    opacity: f32,
    /// A conductor's index of refraction, real part (`MATERIAL_CONDUCTOR`).
    eta: vec3f,
    /// `MATERIAL_ALPHA_MASK`'s cutoff.
    alpha_cutoff: f32,
    /// A conductor's extinction coefficient.
    k: vec3f,
    /// Clear coat texture (low 16 bits, R) and clear coat roughness texture (high 16 bits, G).
    tex_coat: u32,
    /// A conductor's cosine-weighted average Fresnel reflectance, for the metal lobe's
    /// multiple-scattering term.
    f_avg: vec3f,
    /// Sheen colour texture (low 16 bits, RGB sRGB) and sheen roughness texture (high 16
    /// bits, A).
    tex_sheen: u32,
    /// Absorption coefficient of the medium inside (`MATERIAL_MEDIUM`).
    sigma_a: vec3f,
    /// Henyey–Greenstein asymmetry of the medium's phase function.
    phase_g: f32,
    /// Scattering coefficient of the medium inside.
    sigma_s: vec3f,
    /// Padding.
    pad5: u32,
    /// Sheen colour, linear RGB; black: none (sheen.wgsl).
    sheen_color: vec3f,
    /// Sheen perceptual roughness.
    sheen_roughness: f32,
    /// Clear coat weight; 0: none (coat.wgsl).
    clearcoat: f32,
    /// Clear coat perceptual roughness.
    clearcoat_roughness: f32,
    /// Padding.
    pad6: u32,
    /// Padding.
    pad7: u32,
    /// Colour of the dielectric specular at normal incidence: multiplies F0 (clamped to 1),
    /// not the grazing reflectance (bsdf.wgsl's `dielectric_fresnel`).
    specular_color: vec3f,
    /// glTF `clearcoatNormalTexture.scale`.
    clearcoat_normal_scale: f32,
    /// Clear coat tint, linear RGB; white: none (coat.wgsl).
    clearcoat_tint: vec3f,
    /// Padding.
    pad8: u32,
}

/// Calls `$then!` with the arguments given and then every lobe parameter, one row each:
/// `lobe.name: f32|rgb = default, check, "editor label", "editor tooltip", editor maximum;`
/// with its doc. `check` is the loader's (`unit_range`: in [0, 1]; `non_negative3`: finite
/// and ≥ 0). The rows are in the scene format's order.
macro_rules! lobe_params {
    ($then:ident ! $($pass:tt)*) => {
        $then! { $($pass)*
            /// Perceptual roughness in [0, 1] (α = roughness²) of the specular, metal and
            /// glass lobes. Default 0.5.
            specular.roughness: f32 = 0.5, unit_range,
                "roughness", "perceptual; α = roughness²", 1.0;
            /// Roughness of the diffuse base in [0, 1] (`OpenPBR`'s `base_diffuse_roughness`):
            /// 0 is Lambertian, above 0 the energy-preserving Oren–Nayar model (EON). Default 0.
            diffuse.diffuse_roughness: f32 = 0.0, unit_range,
                "diffuse roughness", "0 Lambertian; above 0 energy-preserving Oren–Nayar (EON)", 1.0;
            /// Dielectric specular strength; 0.5 means F0 = 0.04. Default 0.5. Use 0 for a pure
            /// Lambertian surface.
            specular.specular: f32 = 0.5, unit_range,
                "specular", "dielectric specular strength; 0.5: F0 = 0.04", 1.0;
            /// Tints the dielectric specular towards the base color, in [0, 1]. Default 0.
            specular.specular_tint: f32 = 0.0, unit_range,
                "specular tint", "towards the base colour", 1.0;
            /// Colour of the dielectric specular at normal incidence (glTF's
            /// `specularColorFactor`), linear RGB, ≥ 0: it multiplies F0 (clamped to 1) and leaves
            /// the grazing reflection white. Default white.
            specular.specular_color: rgb = [1.0, 1.0, 1.0], non_negative3,
                "specular colour",
                "multiplies F0 (to at most 1), not the grazing reflection; white: none",
                // Up to 25: F0 = 0.04 × 25 = 1 at the default strength.
                25.0;
            /// Fraction of the dielectric lobe that is transmitted (glass), in [0, 1]. Default 0.
            transmission.transmission: f32 = 0.0, unit_range,
                "transmission", "transmitted fraction of the dielectric lobe", 1.0;
            /// Weight in [0, 1] of a clear coat on top (glTF `KHR_materials_clearcoat`): a
            /// dielectric layer of ior 1.5 that reflects like a varnish and lets the rest through.
            /// Default 0 (none).
            coat.clearcoat: f32 = 0.0, unit_range,
                "clear coat", "weight of a varnish on top (ior 1.5)", 1.0;
            /// Perceptual roughness of the clear coat in [0, 1]. Default 0 (a mirror).
            coat.clearcoat_roughness: f32 = 0.0, unit_range,
                "coat roughness", "0: a mirror", 1.0;
            /// Colour of the clear coat, linear RGB (Autodesk Standard Surface's `coat_color`): it
            /// tints what lies below the coat, seen through it on the light's way in and out.
            /// The rule is Standard Surface's as its `MaterialX` graph applies it
            /// (`coat_attenuation`): the layers below a coat of weight `clearcoat` are multiplied
            /// by 1 + `clearcoat` · (`clearcoat_tint` − 1), once, for the round trip, at every angle
            /// (`OpenPBR`'s `coat_color` instead lengthens the path with the angle). The coat's own
            /// reflection stays white. Each channel in [0, 1]. Default white (none).
            coat.clearcoat_tint: rgb = [1.0, 1.0, 1.0], non_negative3,
                "coat tint", "colour of what is seen through the coat; white: none", 1.0;
            /// Colour of a sheen under the clear coat (glTF `KHR_materials_sheen`: the velvet of
            /// cloth at grazing angles), linear RGB. Default black (none).
            sheen.sheen_color: rgb = [0.0, 0.0, 0.0], non_negative3,
                "sheen", "colour of a cloth sheen under the coat; black: none", 1.0;
            /// Perceptual roughness of the sheen in [0, 1] (below 0.07 taken as 0.07). Default 0.
            sheen.sheen_roughness: f32 = 0.0, unit_range,
                "sheen roughness", "below 0.07 taken as 0.07", 1.0;
        }
    };
}

pub(crate) use lobe_params;

/// [`PARAMS`] from the rows of `lobe_params!`.
macro_rules! params_table {
    ($(
        $(#[doc = $doc:literal])*
        $lobe:ident . $name:ident : $kind:ident = $default:expr, $check:ident,
        $label:literal, $tip:literal, $max:literal;
    )*) => {
        /// Every lobe parameter, in the scene format's order.
        pub static PARAMS: &[Param] = &[$(
            Param {
                lobe: stringify!($lobe),
                name: stringify!($name),
                doc: concat!($($doc, "\n",)*),
                label: $label,
                tip: $tip,
                max: $max,
                load: |d, m| {
                    m.$name = crate::load::$check(stringify!($name), d.$name)?;
                    Ok(())
                },
                flatten: |m, g| g.$name = <desc_ty!($kind) as Kind>::gpu(m.$name),
                save: |d| Kind::text(d.$name),
                export: |m| serde_json::json!(<desc_ty!($kind) as Kind>::gpu(m.$name)),
                edit: {
                    fn edit(d: &mut MaterialDesc) -> ParamMut<'_> {
                        Kind::edit(&mut d.$name)
                    }
                    edit
                },
            },
        )*];
    };
}

lobe_params!(params_table!);
