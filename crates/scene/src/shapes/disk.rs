//! The disk: `center`, `radius` and its front normal `axis`, one-sided as a triangle is
//! (WGSL: `shaders/pathtrace/shapes/disk.wgsl`). Mitsuba 3's `disk`, placed by a rotation
//! taking +z to `axis` and a uniform scale.

use glam::Vec3;

use super::ShapeKind;
use crate::gpu::GpuShape;

/// The disk.
pub struct Disk;

impl ShapeKind for Disk {
    fn name(&self) -> &'static str {
        "disk"
    }

    fn closed(&self) -> bool {
        false
    }

    /// The disk's exact box, grown by 2^-20 of its size for the rounding of its test.
    fn bounds(&self, s: &GpuShape) -> [Vec3; 2] {
        let (c, n) = (Vec3::from(s.center), Vec3::from(s.axis));
        let half = s.radius * (Vec3::ONE - n * n).max(Vec3::ZERO).powf(0.5);
        let pad = (c.abs().max_element() + s.radius) * 2f32.powi(-20);
        [c - half - pad, c + half + pad]
    }

    fn area(&self, s: &GpuShape) -> f32 {
        std::f32::consts::PI * s.radius * s.radius
    }

    fn intersect(&self, s: &GpuShape, origin: Vec3, dir: Vec3, t_max: f32) -> Option<f32> {
        let (c, n) = (Vec3::from(s.center), Vec3::from(s.axis));
        let t = n.dot(c - origin) / n.dot(dir);
        let d = origin + t * dir - c;
        (t > 0.0 && t < t_max && d.dot(d) <= s.radius * s.radius).then_some(t)
    }

    fn normal(&self, s: &GpuShape, _p: Vec3) -> Vec3 {
        Vec3::from(s.axis)
    }

    /// A polygon of `segments` sides around the disk, in its plane.
    fn hull(&self, s: &GpuShape, segments: u32) -> Vec<[Vec3; 3]> {
        let sides = segments.max(8);
        let step = std::f32::consts::TAU / sides as f32;
        let [t, b, _] = basis(Vec3::from(s.axis));
        let c = Vec3::from(s.center);
        let r = s.radius / (0.5 * step).cos();
        let at = |i: u32| {
            let phi = i as f32 * step;
            c + r * (phi.cos() * t + phi.sin() * b)
        };
        (0..sides).map(|i| [c, at(i), at(i + 1)]).collect()
    }

    fn mitsuba(&self, s: &GpuShape) -> serde_json::Value {
        let [t, b, n] = basis(Vec3::from(s.axis));
        let (r, c) = (s.radius, s.center);
        let row = |k: usize| [r * t[k], r * b[k], r * n[k], c[k]];
        serde_json::json!({
            "type": "disk",
            "to_world": [row(0), row(1), row(2), [0.0, 0.0, 0.0, 1.0]],
        })
    }
}

/// An orthonormal basis whose third vector is the unit `n` (Duff et al. 2017), as
/// `onb` in `shaders/common/sampling.wgsl` builds it.
fn basis(n: Vec3) -> [Vec3; 3] {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    [
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
        n,
    ]
}
