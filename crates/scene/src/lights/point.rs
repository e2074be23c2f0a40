//! The point light (Mitsuba 3's `point`, glTF's `point`): light from one point, the same in
//! every direction. Its record: `p0` the position, `emission` the radiant intensity (W/sr).

use glam::Vec3;

use super::{Fields, LightKind};
use crate::error::SceneError;
use crate::gpu::GpuLight;
use crate::luminance;

/// A point light at `position` of radiant intensity `intensity` (W/sr, linear RGB).
pub fn point(position: Vec3, intensity: Vec3) -> GpuLight {
    super::record(0, position, Vec3::Z, intensity)
}

pub(super) struct Point;

impl LightKind for Point {
    fn name(&self) -> &'static str {
        "Point"
    }

    fn fields(&self) -> &'static [&'static str] {
        &["position", "intensity"]
    }

    fn load(&self, f: &Fields) -> Result<GpuLight, SceneError> {
        Ok(point(f.v3("position")?, f.non_negative3("intensity")?))
    }

    /// 4π I.
    fn power(&self, l: &GpuLight, _radius: f32) -> f32 {
        4.0 * std::f32::consts::PI * luminance(Vec3::from(l.emission))
    }

    fn mitsuba(&self, l: &GpuLight) -> serde_json::Value {
        serde_json::json!({"type": "point", "position": l.p0, "intensity": rgb(l.emission)})
    }
}

/// Mitsuba's `rgb` value.
pub(super) fn rgb(c: [f32; 3]) -> serde_json::Value {
    serde_json::json!({"type": "rgb", "value": c})
}
