//! The directional light (Mitsuba 3's `directional`, glTF's `directional`): parallel light
//! from infinitely far away, as the sun. Its record: `e1` the unit direction it travels in,
//! `emission` the irradiance (W/m²) on a surface facing it.

use glam::Vec3;

use super::point::rgb;
use super::{Fields, LightKind};
use crate::error::SceneError;
use crate::gpu::GpuLight;
use crate::luminance;

/// A directional light travelling along the unit `direction`, of irradiance `irradiance`
/// (W/m², linear RGB).
pub fn directional(direction: Vec3, irradiance: Vec3) -> GpuLight {
    super::record(2, Vec3::ZERO, direction, irradiance)
}

pub(super) struct Directional;

impl LightKind for Directional {
    fn name(&self) -> &'static str {
        "Directional"
    }

    fn fields(&self) -> &'static [&'static str] {
        &["direction", "irradiance"]
    }

    fn load(&self, f: &Fields) -> Result<GpuLight, SceneError> {
        Ok(directional(
            f.direction("direction")?,
            f.non_negative3("irradiance")?,
        ))
    }

    /// The irradiance over the disk of the scene's bounding sphere.
    fn power(&self, l: &GpuLight, radius: f32) -> f32 {
        std::f32::consts::PI * radius * radius * luminance(Vec3::from(l.emission))
    }

    fn mitsuba(&self, l: &GpuLight) -> serde_json::Value {
        serde_json::json!({"type": "directional", "direction": l.e1, "irradiance": rgb(l.emission)})
    }
}
