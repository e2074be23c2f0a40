//! The projector (Mitsuba 3's `projector` with a constant `irradiance`): a point light
//! that lights a square pyramid, the reciprocal of a pinhole camera with a square film. Its
//! light is scaled by the inverse of the camera's importance, so that a plane at distance 1
//! facing it receives a constant irradiance: from a point at local depth z and distance d
//! it sends π E d / z³ (Mitsuba's `eval_direction`: π E / (z² cos θ)), i.e. an intensity
//! of π E / cos³ θ. Its record: `p0` the position, `e1` the unit axis (local z), `e2` the
//! local x (Mitsuba's `look_at` with `up`), `emission` the irradiance E, `params` = (tan of
//! the half field of view in x, in y).

use glam::Vec3;

use super::fields::bad;
use super::point::rgb;
use super::{Fields, LightKind};
use crate::error::SceneError;
use crate::gpu::GpuLight;
use crate::luminance;

pub(super) struct Projector;

impl LightKind for Projector {
    fn name(&self) -> &'static str {
        "Projector"
    }

    fn fields(&self) -> &'static [&'static str] {
        &["position", "target", "up", "irradiance", "fov"]
    }

    /// `fov`: the full field of view in degrees, in (0, 180), the same in x and y (a
    /// constant irradiance has a square film); `up` default +y.
    fn load(&self, f: &Fields) -> Result<GpuLight, SceneError> {
        let position = f.v3("position")?;
        let axis = f.towards(position, "target")?;
        let up = f.opt_v3("up")?.unwrap_or(Vec3::Y);
        if up.cross(axis).length_squared() < 1e-12 {
            return Err(bad("up", "must not be parallel to the axis"));
        }
        let fov = f.opt_f32("fov")?.ok_or_else(|| bad("fov", "is missing"))?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(bad("fov", format!("{fov} must be in (0, 180) degrees")));
        }
        let t = (0.5 * fov).to_radians().tan();
        Ok(GpuLight {
            e2: super::look_at_x(axis, up).to_array(),
            params: [t, t, 0.0],
            ..super::record(3, position, axis, f.non_negative3("irradiance")?)
        })
    }

    /// ∫ π E / cos³ θ dω over the pyramid = π E × the film's area at depth 1 (dω = cos³ θ dA
    /// there).
    fn power(&self, l: &GpuLight, _radius: f32) -> f32 {
        let [tx, ty, _] = l.params;
        std::f32::consts::PI * 4.0 * tx * ty * luminance(Vec3::from(l.emission))
    }

    fn mitsuba(&self, l: &GpuLight) -> serde_json::Value {
        let (p, x, z) = (Vec3::from(l.p0), Vec3::from(l.e2), Vec3::from(l.e1));
        serde_json::json!({
            "type": "projector",
            "irradiance": rgb(l.emission),
            "fov": 2.0 * l.params[0].atan().to_degrees(),
            "to_world": super::to_world(p, x, z),
        })
    }
}
