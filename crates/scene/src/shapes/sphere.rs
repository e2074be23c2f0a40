//! The sphere: `center` and `radius` (WGSL: `shaders/pathtrace/shapes/sphere.wgsl`).

use glam::Vec3;

use super::ShapeKind;
use crate::gpu::GpuShape;

/// The sphere.
pub struct Sphere;

impl ShapeKind for Sphere {
    fn name(&self) -> &'static str {
        "sphere"
    }

    fn closed(&self) -> bool {
        true
    }

    fn bounds(&self, s: &GpuShape) -> [Vec3; 2] {
        let c = Vec3::from(s.center);
        [c - s.radius, c + s.radius]
    }

    fn area(&self, s: &GpuShape) -> f32 {
        4.0 * std::f32::consts::PI * s.radius * s.radius
    }

    fn intersect(&self, s: &GpuShape, origin: Vec3, dir: Vec3, t_max: f32) -> Option<f32> {
        crate::traverse::intersect_sphere(origin, dir, Vec3::from(s.center), s.radius, t_max)
    }

    fn normal(&self, s: &GpuShape, p: Vec3) -> Vec3 {
        (p - Vec3::from(s.center)).normalize_or_zero()
    }

    /// A UV sphere, `segments` around and half as many from pole to pole, its corners
    /// pushed out by 1/cos(step) so that its faces enclose the sphere.
    fn hull(&self, s: &GpuShape, segments: u32) -> Vec<[Vec3; 3]> {
        let around = segments.max(8);
        let rings = (around / 2).max(4);
        let step = std::f32::consts::PI / rings as f32;
        let r = s.radius / step.cos();
        let c = Vec3::from(s.center);
        let point = |i: u32, j: u32| {
            let theta = j as f32 * step;
            let phi = i as f32 * std::f32::consts::TAU / around as f32;
            c + r * Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )
        };
        let mut out = Vec::new();
        for j in 0..rings {
            for i in 0..around {
                let q = [
                    point(i, j),
                    point(i + 1, j),
                    point(i + 1, j + 1),
                    point(i, j + 1),
                ];
                out.push([q[0], q[1], q[2]]);
                out.push([q[0], q[2], q[3]]);
            }
        }
        out
    }

    fn mitsuba(&self, s: &GpuShape) -> serde_json::Value {
        serde_json::json!({"type": "sphere", "center": s.center, "radius": s.radius})
    }
}
