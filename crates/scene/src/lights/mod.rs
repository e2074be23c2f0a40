//! Lights without area, each kind one part, as shapes are ([`crate::shapes`]): its Rust
//! side in `lights/<kind>.rs` (its fields in the scene format and their checks, its GPU
//! record, its power for light selection, its Mitsuba 3 emitter) and its WGSL side in
//! `shaders/pathtrace/lights/<kind>.wgsl` (`<kind>_light_sample`: the direction, distance
//! and radiance it sends to a shading point). [`KINDS`] lists them, once: a light's kind is
//! its index there, and the WGSL that calls a kind by its index, `pathtrace/light_kinds.wgsl`,
//! is written from the list ([`wgsl`]), not kept on disk.
//!
//! Every such light is a delta light: never hit by a ray, reached by light sampling alone,
//! with no MIS. Area lights are emissive triangles and shapes, sampled by `lights.wgsl`
//! through the triangle's corners and the shape's kind. Adding a kind: its two files and a
//! line in [`KINDS`]; the scene format reads it by its name (`Point(…)`) through
//! [`Fields`], export writes its [`LightKind::mitsuba`] and `scripts/references/make.py`
//! passes that through unchanged.

mod directional;
mod fields;
mod point;
mod projector;
mod spot;

use std::fmt::Write as _;

use glam::Vec3;

pub use directional::directional;
pub use fields::Fields;
pub use point::point;
pub use spot::spot;

use crate::error::SceneError;
use crate::gpu::GpuLight;

/// What the Rust side knows of a kind of light. Its parameters are a [`GpuLight`]'s, which
/// a light without area reads as a frame and a few numbers: `p0` its position, `e1` the
/// unit direction it shines along (its frame's z), `e2` its frame's unit x, `emission` its
/// intensity or irradiance, `params` the kind's own numbers. Each kind says which it uses.
pub trait LightKind: Sync {
    /// Its name in the scene format (`Spot`); in lowercase, its WGSL file's name and its
    /// WGSL function's prefix.
    fn name(&self) -> &'static str;
    /// The fields it reads in the scene format (besides `name`), for unknown-field errors.
    fn fields(&self) -> &'static [&'static str];
    /// Reads and checks its fields: its record, `kind` and `power` left for the caller.
    ///
    /// # Errors
    /// [`crate::ErrorKind::BadValue`] naming the field.
    fn load(&self, f: &Fields) -> Result<GpuLight, SceneError>;
    /// The power it emits (luminance, W) for light selection; `radius` bounds the scene
    /// (a light at infinity lights the disk of that radius).
    fn power(&self, l: &GpuLight, radius: f32) -> f32;
    /// Its Mitsuba 3 emitter dictionary, as JSON (`type`, and `to_world` as a row-major
    /// 4×4 matrix where it has one).
    fn mitsuba(&self, l: &GpuLight) -> serde_json::Value;
}

/// Every kind of light without area, by its index. A [`GpuLight::kind`] is that index + 1
/// (0: an area light).
pub static KINDS: [&dyn LightKind; 4] = [
    &point::Point,
    &spot::Spot,
    &directional::Directional,
    &projector::Projector,
];

/// The kind named `name` (the scene format's word, exact case).
pub fn kind_named(name: &str) -> Option<u32> {
    KINDS
        .iter()
        .position(|k| k.name() == name)
        .map(|i| i as u32)
}

/// The kind of a record, if it is a light without area (its `kind` is an index into [`KINDS`] + 1).
pub fn kind_of(l: &GpuLight) -> Option<&'static dyn LightKind> {
    (l.kind as usize)
        .checked_sub(1)
        .and_then(|i| KINDS.get(i).copied())
}

/// A record of kind `kind` (an index into [`KINDS`]) with the frame and colour given;
/// `params` and `power` are the caller's.
pub(crate) fn record(kind: u32, position: Vec3, axis: Vec3, emission: Vec3) -> GpuLight {
    GpuLight {
        p0: position.to_array(),
        e1: axis.to_array(),
        e2: frame_x(axis).to_array(),
        emission: emission.to_array(),
        prim: crate::gpu::NO_LIGHT,
        kind: kind + 1,
        ..GpuLight::default()
    }
}

/// A unit vector perpendicular to the unit `z`, as Mitsuba's `look_at` picks its x axis
/// with `up` = +y (or +x when `z` is nearly vertical): `normalize(up × z)`.
pub(crate) fn frame_x(z: Vec3) -> Vec3 {
    look_at_x(z, Vec3::Y)
}

/// Mitsuba's `look_at` x axis for the unit direction `z` and `up`: `normalize(up × z)`,
/// with +x (else +z) for an `up` parallel to `z`.
pub(crate) fn look_at_x(z: Vec3, up: Vec3) -> Vec3 {
    [up, Vec3::X, Vec3::Z]
        .into_iter()
        .map(|u| u.cross(z))
        .find(|x| x.length_squared() > 1e-6)
        .unwrap_or(Vec3::X)
        .normalize()
}

/// The row-major `to_world` of a frame at `p` with unit axes x, `y = z × x` and z: Mitsuba's
/// `look_at(origin = p, target = p + z, up = y)`.
pub(crate) fn to_world(p: Vec3, x: Vec3, z: Vec3) -> serde_json::Value {
    let y = z.cross(x);
    let row = |k: usize| [x[k], y[k], z[k], p[k]];
    serde_json::json!([row(0), row(1), row(2), [0.0, 0.0, 0.0, 1.0]])
}

/// The name shaders import the dispatch by.
pub const FILE: &str = "pathtrace/light_kinds.wgsl";

/// The dispatch, `pathtrace/light_kinds.wgsl`: an import of every kind's file, its
/// [`GpuLight::kind`] as a constant `LIGHT_<NAME>`, and `punctual_sample` calling the
/// kind of the light it is given.
pub fn wgsl() -> String {
    wgsl_for(|_| true)
}

/// [`wgsl`] for the kinds `present` says a scene has (an index into [`KINDS`]), the others
/// left out (every kind if it has none): leaving a kind out never changes an image, as the
/// scene has no light of it.
pub fn wgsl_for(present: impl Fn(u32) -> bool) -> String {
    let kinds = crate::shapes::kinds_present(&KINDS, present);
    let mut out = String::from(
        "// Generated from crates/scene/src/lights/mod.rs (`KINDS`): calls each light \
         without area\n// by its kind. Not a file on disk.\n",
    );
    for (_, k) in &kinds {
        let _ = writeln!(
            out,
            "#import \"pathtrace/lights/{}.wgsl\"",
            k.name().to_lowercase()
        );
    }
    for (i, k) in KINDS.iter().enumerate() {
        let _ = writeln!(
            out,
            "const LIGHT_{}: u32 = {}u;",
            k.name().to_uppercase(),
            i + 1
        );
    }
    out.push_str(
        "\n// What light `l` (a light without area) sends to `x`: `wi`, `dist`, `radiance` \
         and `margin`,\n// with `pdf` 1, or 0 where it sends nothing towards `x`.\n\
         fn punctual_sample(l: Light, x: vec3f) -> LightSample {\n",
    );
    for (i, k) in kinds.iter().skip(1) {
        let _ = writeln!(
            out,
            "    if l.kind == {}u {{\n        return {}_light_sample(l, x);\n    }}",
            i + 1,
            k.name().to_lowercase()
        );
    }
    let _ = writeln!(
        out,
        "    return {}_light_sample(l, x);\n}}",
        kinds[0].1.name().to_lowercase()
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dispatch_calls_every_kind_and_leaves_out_absent_ones() {
        let all = wgsl();
        for k in KINDS {
            let name = k.name().to_lowercase();
            assert!(all.contains(&format!("{name}_light_sample(l, x)")), "{all}");
        }
        let spots = wgsl_for(|k| k == 1);
        assert!(spots.contains("return spot_light_sample(l, x);"), "{spots}");
        assert!(!spots.contains("point.wgsl"), "{spots}");
        assert!(!spots.contains("if l.kind"), "{spots}");
    }

    #[test]
    fn frames_are_orthonormal_and_follow_mitsubas_look_at() {
        for z in [
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::new(1.0, 2.0, -3.0).normalize(),
        ] {
            let x = frame_x(z);
            assert!(
                (x.length() - 1.0).abs() < 1e-6 && x.dot(z).abs() < 1e-6,
                "{z}"
            );
        }
        // look_at(up = +y) along −z: x = up × z = (−1, 0, 0)... here +y × −z = −x.
        assert!((frame_x(Vec3::NEG_Z) - Vec3::NEG_X).length() < 1e-6);
    }
}
