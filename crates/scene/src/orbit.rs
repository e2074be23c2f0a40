//! Camera moves as the editor's preview makes them: orbit about the target, pan, and
//! dolly towards the target. They change a perspective camera's `position` and `target`
//! (as written in the scene file); `up` stays.

use glam::Vec3;

use crate::file::V3;

/// `position` turned about `target`: by `yaw` degrees about `up` (positive turns the
/// camera to its right around the target) and `pitch` degrees about the camera's right
/// axis (positive raises it), the elevation kept within 1° of `up` and its opposite.
pub fn orbit(position: V3, target: V3, up: V3, yaw: f32, pitch: f32) -> V3 {
    let (p, t, up) = (
        Vec3::from(position),
        Vec3::from(target),
        Vec3::from(up).normalize(),
    );
    let offset = p - t;
    let r = offset.length();
    if r == 0.0 || !up.is_finite() {
        return position;
    }
    let turned = glam::Quat::from_axis_angle(up, yaw.to_radians()) * offset;
    // Elevation above the plane normal to `up`, clamped short of the poles.
    let dir = turned / r;
    let elevation = dir.dot(up).clamp(-1.0, 1.0).asin();
    let limit = 89f32.to_radians();
    let new = (elevation + pitch.to_radians()).clamp(-limit, limit);
    let flat = (dir - up * dir.dot(up)).normalize_or_zero();
    if flat == Vec3::ZERO {
        return (t + turned).to_array();
    }
    (t + r * (flat * new.cos() + up * new.sin())).to_array()
}

/// `position` and `target` moved together in the image plane: `right` and `up_amount`
/// times the distance between them, along the camera's right and up axes.
pub fn pan(position: V3, target: V3, up: V3, right: f32, up_amount: f32) -> (V3, V3) {
    let (p, t) = (Vec3::from(position), Vec3::from(target));
    let forward = (t - p).normalize_or_zero();
    let r = forward.cross(Vec3::from(up)).normalize_or_zero();
    let u = r.cross(forward);
    let shift = (p - t).length() * (right * r + up_amount * u);
    ((p + shift).to_array(), (t + shift).to_array())
}

/// `position` moved along the line to `target` so its distance is multiplied by `factor`
/// (below 1 comes closer), never onto the target.
pub fn dolly(position: V3, target: V3, factor: f32) -> V3 {
    let (p, t) = (Vec3::from(position), Vec3::from(target));
    let factor = if factor.is_finite() {
        factor.max(1e-3)
    } else {
        1.0
    };
    (t + (p - t) * factor).to_array()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: V3, b: V3) -> bool {
        (Vec3::from(a) - Vec3::from(b)).length() < 1e-5
    }

    #[test]
    fn orbit_keeps_the_distance_and_turns_by_the_angle() {
        let (p, t, up) = ([0.0, 0.0, 3.9], [0.0; 3], [0.0, 1.0, 0.0]);
        let q = orbit(p, t, up, 90.0, 0.0);
        assert!(close(q, [3.9, 0.0, 0.0]), "{q:?}");
        let q = orbit(p, t, up, 0.0, 30.0);
        assert!((Vec3::from(q).length() - 3.9).abs() < 1e-5);
        assert!((q[1] - 3.9 * 0.5).abs() < 1e-5, "{q:?}");
        // Clamped short of the pole.
        let q = orbit(p, t, up, 0.0, 120.0);
        assert!(q[1] < 3.9 && q[1] > 3.89, "{q:?}");
    }

    #[test]
    fn pan_moves_both_and_dolly_scales_the_distance() {
        let (p, t) = pan([0.0, 0.0, 2.0], [0.0; 3], [0.0, 1.0, 0.0], 0.5, 0.0);
        assert!(
            close(p, [1.0, 0.0, 2.0]) && close(t, [1.0, 0.0, 0.0]),
            "{p:?} {t:?}"
        );
        assert!(close(
            dolly([0.0, 0.0, 2.0], [0.0; 3], 0.5),
            [0.0, 0.0, 1.0]
        ));
    }
}
