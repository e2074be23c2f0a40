#import "pathtrace/scene_types.wgsl"

// Ray/primitive tests shared by the BVH traversal (bvh.wgsl) and the scene-specialized
// intersection code the renderer generates for small scenes. Mirrors
// crates/scene/src/traverse.rs. Hits count for 0 < t < t_max.
const F32_MAX: f32 = 3.40282347e38;

// A triangle rays must not hit: the one they leave from. A flat triangle cannot be hit again
// by a ray leaving it, so skipping it removes self-intersection whatever the coordinates'
// magnitude, and the origin offset only has to clear coplanar neighbours.
var<private> skip_prim: u32 = NO_HIT;
// Far box distance scale, 1 + 2 gamma_3 (Ize, "Robust BVH ray traversal").
const ROBUST_FAR: f32 = 1.0000004;
// Direction components below this are replaced by it (with their sign) before inverting.
const MIN_DIR: f32 = 1e-20;

fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let small = select(vec3<f32>(MIN_DIR), vec3<f32>(-MIN_DIR), d < vec3<f32>(0.0));
    return 1.0 / select(d, small, abs(d) < vec3<f32>(MIN_DIR));
}

fn ray_aabb(origin: vec3<f32>, inv_dir: vec3<f32>, bmin: vec3<f32>, bmax: vec3<f32>, t_max: f32) -> bool {
    let t0 = (bmin - origin) * inv_dir;
    let t1 = (bmax - origin) * inv_dir;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let near = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let far = min(min(min(hi.x, hi.y), hi.z) * ROBUST_FAR, t_max);
    return near <= far;
}

// Moller-Trumbore. Returns vec4(hit ? 1 : 0, t, u, v).
fn intersect_triangle(origin: vec3<f32>, dir: vec3<f32>, v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, t_max: f32) -> vec4<f32> {
    let p = cross(dir, e2);
    let det = dot(e1, p);
    if (det == 0.0) {
        return vec4<f32>(0.0);
    }
    let inv_det = 1.0 / det;
    let s = origin - v0;
    let u = dot(s, p) * inv_det;
    let q = cross(s, e1);
    let v = dot(dir, q) * inv_det;
    let t = dot(e2, q) * inv_det;
    let hit = u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < t_max;
    return vec4<f32>(select(0.0, 1.0, hit), t, u, v);
}

// Robust ray/sphere (Ray Tracing Gems, ch. 7). Returns the nearest t in (0, t_max), or -1.
fn intersect_sphere(origin: vec3<f32>, dir: vec3<f32>, center: vec3<f32>, radius: f32, t_max: f32) -> f32 {
    let f = origin - center;
    let a = dot(dir, dir);
    let b = -dot(f, dir);
    let l = f + (b / a) * dir;
    let disc = a * (radius * radius - dot(l, l));
    if (!(disc >= 0.0)) {
        return -1.0;
    }
    let c = dot(f, f) - radius * radius;
    let root = sqrt(disc);
    let q = b + select(root, -root, b < 0.0);
    let t0 = c / q;
    let t1 = q / a;
    let near = min(t0, t1);
    let far = max(t0, t1);
    if (near > 0.0 && near < t_max) {
        return near;
    } else if (far > 0.0 && far < t_max) {
        return far;
    }
    return -1.0;
}
