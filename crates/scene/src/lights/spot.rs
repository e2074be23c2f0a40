//! The spot light (Mitsuba 3's `spot`): a point light emitting into a cone, full within
//! `beam_width` of its axis and falling linearly in angle to 0 at `cutoff_angle`. glTF's
//! `spot` maps onto it (its smooth falloff becomes the linear one). Its record: `p0` the
//! position, `e1` the unit axis, `emission` the radiant intensity on the axis (W/sr),
//! `params` = (cutoff, beam width) half-angles in radians.

use glam::Vec3;

use super::fields::bad;
use super::point::rgb;
use super::{Fields, LightKind};
use crate::error::SceneError;
use crate::gpu::GpuLight;
use crate::luminance;

/// A spot light at `position` shining along the unit `axis`, of radiant intensity
/// `intensity` on the axis (W/sr), black beyond `cutoff` and full within `beam` (radians).
pub fn spot(position: Vec3, axis: Vec3, intensity: Vec3, cutoff: f32, beam: f32) -> GpuLight {
    GpuLight {
        params: [cutoff, beam, 0.0],
        ..super::record(1, position, axis, intensity)
    }
}

pub(super) struct Spot;

impl LightKind for Spot {
    fn name(&self) -> &'static str {
        "Spot"
    }

    fn fields(&self) -> &'static [&'static str] {
        &[
            "position",
            "target",
            "intensity",
            "cutoff_angle",
            "beam_width",
        ]
    }

    /// `cutoff_angle` in (0, 90] degrees, default 20; `beam_width` in [0, `cutoff_angle`],
    /// default ¾ of it (Mitsuba's defaults).
    fn load(&self, f: &Fields) -> Result<GpuLight, SceneError> {
        let position = f.v3("position")?;
        let axis = f.towards(position, "target")?;
        let cutoff_degrees = f.f32_or("cutoff_angle", 20.0)?;
        let cutoff = f.angle_or("cutoff_angle", 20.0, 90.0)?;
        if cutoff == 0.0 {
            return Err(bad("cutoff_angle", "0 degrees lights nothing"));
        }
        let beam = match f.opt_f32("beam_width")? {
            Some(_) => f.angle_or("beam_width", 0.0, cutoff_degrees)?,
            None => 0.75 * cutoff,
        };
        Ok(spot(
            position,
            axis,
            f.non_negative3("intensity")?,
            cutoff,
            beam,
        ))
    }

    /// ∫ falloff over the sphere × I: 2π (1 − cos beam) over the full cone, plus the linear
    /// ramp's share (midpoint rule in θ over [beam, cutoff]).
    fn power(&self, l: &GpuLight, _radius: f32) -> f32 {
        use std::f32::consts::PI;
        let [cutoff, beam, _] = l.params;
        let full = 2.0 * PI * (1.0 - beam.cos());
        let steps = 64;
        let dt = (cutoff - beam) / steps as f32;
        let ramp: f32 = (0..steps)
            .map(|i| {
                let t = beam + (i as f32 + 0.5) * dt;
                2.0 * PI * t.sin() * (cutoff - t) / (cutoff - beam).max(1e-12) * dt
            })
            .sum();
        (full + ramp) * luminance(Vec3::from(l.emission))
    }

    fn mitsuba(&self, l: &GpuLight) -> serde_json::Value {
        let (p, z) = (Vec3::from(l.p0), Vec3::from(l.e1));
        serde_json::json!({
            "type": "spot",
            "intensity": rgb(l.emission),
            "cutoff_angle": l.params[0].to_degrees(),
            "beam_width": l.params[1].to_degrees(),
            "to_world": super::to_world(p, Vec3::from(l.e2), z),
        })
    }
}
