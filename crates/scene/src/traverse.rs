//! Ray queries on the CPU over exactly the flat layout of [`GpuScene`], written to be
//! mirrored line for line by `shaders/pathtrace/bvh.wgsl` (same names, same order of
//! operations). Used by tests against brute force, and as the reference for the shader.
//!
//! Rays start at `origin` and hits count for `0 < t < t_max`: callers offset origins off
//! surfaces themselves. Directions need not be normalized; `t` is in units of `dir`.

use glam::Vec3;

use crate::bvh::{BVH_END, NODE_COUNT_SHIFT, NODE_SPHERES};
use crate::flatten::GpuScene;
use crate::gpu::{MATERIAL_ALPHA_BLEND, MATERIAL_ALPHA_MASK, NO_HIT, PRIM_SPHERE};

/// A ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction, not necessarily unit length.
    pub dir: Vec3,
}

/// The closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Triangle index, or sphere index | [`PRIM_SPHERE`].
    pub prim: u32,
    /// Distance along the ray, in units of `dir`.
    pub t: f32,
    /// Barycentric weight of corner 1 (triangles; 0 for spheres).
    pub u: f32,
    /// Barycentric weight of corner 2 (triangles; 0 for spheres).
    pub v: f32,
}

impl Hit {
    /// Whether the hit is on a sphere.
    pub fn is_sphere(&self) -> bool {
        self.prim & PRIM_SPHERE != 0
    }

    /// The index in `tri_positions` or `spheres`.
    pub fn index(&self) -> usize {
        (self.prim & !PRIM_SPHERE) as usize
    }
}

/// Box tests keep a hit at the far side when rounding moves it: the far distance is
/// scaled by 1 + 2γ₃ (Ize, "Robust BVH ray traversal").
const ROBUST_FAR: f32 = 1.000_000_4;
/// Direction components smaller than this are replaced by it (with their sign) before
/// inverting, so the slab test never computes 0 × ∞.
const MIN_DIR: f32 = 1e-20;

/// `1 / dir`, finite.
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let f = |x: f32| {
        1.0 / if x.abs() < MIN_DIR {
            MIN_DIR.copysign(x)
        } else {
            x
        }
    };
    Vec3::new(f(d.x), f(d.y), f(d.z))
}

/// Slab test: whether the ray meets the box at some `0 <= t <= t_max`.
pub fn ray_aabb(origin: Vec3, inv_dir: Vec3, bmin: Vec3, bmax: Vec3, t_max: f32) -> bool {
    let t0 = (bmin - origin) * inv_dir;
    let t1 = (bmax - origin) * inv_dir;
    let near = t0.min(t1).max_element().max(0.0);
    let far = (t0.max(t1).min_element() * ROBUST_FAR).min(t_max);
    near <= far
}

/// Möller–Trumbore against corner `v0` and edges `e1`, `e2`: `Some((t, u, v))` for a hit
/// with `0 < t < t_max`. Both sides count.
pub fn intersect_triangle(
    origin: Vec3,
    dir: Vec3,
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = origin - v0;
    let u = s.dot(p) * inv_det;
    let q = s.cross(e1);
    let v = dir.dot(q) * inv_det;
    let t = e2.dot(q) * inv_det;
    // Written so that NaN fails every test.
    let hit = u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < t_max;
    hit.then_some((t, u, v))
}

/// Ray/sphere in the numerically robust form of Haines et al., "Precision improvements for
/// ray/sphere intersection" (Ray Tracing Gems, ch. 7): the discriminant from the distance
/// of the center to the line, and the smaller root by the stable quotient. Returns the
/// nearest `t` with `0 < t < t_max` (the far side when the origin is inside).
#[expect(
    clippy::neg_cmp_op_on_partial_ord,
    reason = "a NaN discriminant must miss, written as in the WGSL mirror"
)]
pub fn intersect_sphere(
    origin: Vec3,
    dir: Vec3,
    center: Vec3,
    radius: f32,
    t_max: f32,
) -> Option<f32> {
    let f = origin - center;
    let a = dir.dot(dir);
    let b = -f.dot(dir);
    let l = f + (b / a) * dir;
    let disc = a * (radius * radius - l.dot(l));
    if !(disc >= 0.0) {
        return None;
    }
    let c = f.dot(f) - radius * radius;
    let root = disc.sqrt();
    let q = b + if b < 0.0 { -root } else { root };
    let t0 = c / q;
    let t1 = q / a;
    let near = t0.min(t1);
    let far = t0.max(t1);
    if near > 0.0 && near < t_max {
        Some(near)
    } else if far > 0.0 && far < t_max {
        Some(far)
    } else {
        None
    }
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// The PCG hash of `common/rng.wgsl`.
fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// A number in [0, 1) that is a function of the ray and the triangle only: stochastic
/// transparency's choice, the same for the ray wherever it is traced (`alpha_hash` in
/// `pathtrace/alpha.wgsl`, line for line).
pub fn alpha_hash(prim: u32, ray: &Ray) -> f32 {
    let bits = |x: f32| x.to_bits();
    let mut h = pcg_hash(bits(ray.dir.z));
    for w in [
        bits(ray.dir.y),
        bits(ray.dir.x),
        bits(ray.origin.z),
        bits(ray.origin.y),
        bits(ray.origin.x),
        prim,
    ] {
        h = pcg_hash(w ^ h);
    }
    (h >> 8) as f32 * 5.960_464_5e-8
}

/// The any-hit test every intersector applies to a candidate hit on triangle `prim` at
/// barycentrics (`u`, `v`): whether it counts, by its material's alpha mode — `Mask`
/// where its opacity (× the vertex colour's alpha and the base colour texture's alpha at the
/// hit) reaches the cutoff,
/// `Blend` where [`alpha_hash`] falls below it, always otherwise (`triangle_hit_counts` in
/// `pathtrace/alpha.wgsl`, line for line).
pub fn triangle_hit_counts(scene: &GpuScene, prim: u32, u: f32, v: f32, ray: &Ray) -> bool {
    let m = &scene.materials[scene.tri_shading[prim as usize].material as usize];
    if m.flags & (MATERIAL_ALPHA_MASK | MATERIAL_ALPHA_BLEND) == 0 {
        return true;
    }
    let mut alpha = m.opacity;
    if let Some(tc) = scene.tri_texcoords.get(prim as usize) {
        alpha *= tc.color(u, v).w;
        let tex = m.tex_base_mr & 0xFFFF;
        if tex != 0xFFFF {
            alpha *= scene.atlas.sample(tex, tc.uv(u, v), false).w;
        }
    }
    alpha_stops(m, alpha, prim, ray)
}

/// Whether `alpha` lets the surface of `m` stop `ray` (`prim` draws the blend).
fn alpha_stops(m: &crate::gpu::GpuMaterial, alpha: f32, prim: u32, ray: &Ray) -> bool {
    if m.flags & MATERIAL_ALPHA_MASK != 0 {
        return alpha >= m.alpha_cutoff;
    }
    alpha_hash(prim, ray) < alpha
}

/// [`triangle_hit_counts`] for sphere `i` (no texture: the opacity alone).
pub fn sphere_hit_counts(scene: &GpuScene, i: u32, ray: &Ray) -> bool {
    let m = &scene.materials[scene.spheres[i as usize].material as usize];
    if m.flags & (MATERIAL_ALPHA_MASK | MATERIAL_ALPHA_BLEND) == 0 {
        return true;
    }
    alpha_stops(m, m.opacity, i | PRIM_SPHERE, ray)
}

/// The closest hit with `0 < t < t_max`, walking the BVH.
pub fn intersect_within(scene: &GpuScene, ray: &Ray, t_max: f32) -> Option<Hit> {
    traverse::<false>(scene, ray, t_max)
}

/// The closest hit, walking the BVH.
pub fn intersect(scene: &GpuScene, ray: &Ray) -> Option<Hit> {
    traverse::<false>(scene, ray, f32::MAX)
}

/// Whether anything is hit with `0 < t < t_max` (shadow rays; stops at the first hit).
pub fn occluded(scene: &GpuScene, ray: &Ray, t_max: f32) -> bool {
    traverse::<true>(scene, ray, t_max).is_some()
}

fn traverse<const ANY: bool>(scene: &GpuScene, ray: &Ray, t_max: f32) -> Option<Hit> {
    let mut hit = Hit {
        prim: NO_HIT,
        t: t_max,
        u: 0.0,
        v: 0.0,
    };
    if scene.bvh_nodes.is_empty() {
        return None;
    }
    let alpha = scene.header.features & crate::gpu::FEATURE_ALPHA != 0;
    let inv_dir = safe_inverse(ray.dir);
    // Bit `a` set where the direction's component on axis `a` is negative: such rays visit
    // the second child of a node split on `a` first.
    let octant = u32::from(ray.dir.x < 0.0)
        | (u32::from(ray.dir.y < 0.0) << 1)
        | (u32::from(ray.dir.z < 0.0) << 2);
    let mut node_index = 0u32;
    while node_index != BVH_END {
        let node = scene.bvh_nodes[node_index as usize];
        if ray_aabb(
            ray.origin,
            inv_dir,
            v3(node.aabb_min),
            v3(node.aabb_max),
            hit.t,
        ) {
            let count = node.bits >> NODE_COUNT_SHIFT;
            if count == 0 {
                // Inner node: on to the near child (the first one is adjacent, the second at
                // `index`).
                let axis = node.bits & 3;
                node_index = if (octant >> axis) & 1 == 1 {
                    node.index
                } else {
                    node_index + 1
                };
                continue;
            }
            let first = node.index;
            if node.bits & NODE_SPHERES == 0 {
                for i in first..first + count {
                    let tri = scene.tri_positions[i as usize];
                    if let Some((t, u, v)) = intersect_triangle(
                        ray.origin,
                        ray.dir,
                        v3(tri.v0),
                        v3(tri.e1),
                        v3(tri.e2),
                        hit.t,
                    ) && (!alpha
                        || tri.flags & crate::gpu::TRI_ALPHA == 0
                        || triangle_hit_counts(scene, i, u, v, ray))
                    {
                        hit = Hit { prim: i, t, u, v };
                        if ANY {
                            return Some(hit);
                        }
                    }
                }
            } else {
                for i in first..first + count {
                    let s = scene.spheres[i as usize];
                    if let Some(t) =
                        intersect_sphere(ray.origin, ray.dir, v3(s.center), s.radius, hit.t)
                        && (!alpha || sphere_hit_counts(scene, i, ray))
                    {
                        hit = Hit {
                            prim: i | PRIM_SPHERE,
                            t,
                            u: 0.0,
                            v: 0.0,
                        };
                        if ANY {
                            return Some(hit);
                        }
                    }
                }
            }
        }
        // A leaf, or a box missed: past this subtree.
        node_index = scene.bvh_skips[node_index as usize][octant as usize];
    }
    (hit.prim != NO_HIT).then_some(hit)
}

/// The closest hit by testing every primitive, in array order: the reference the BVH
/// traversal is tested against.
pub fn intersect_brute_force(scene: &GpuScene, ray: &Ray, t_max: f32) -> Option<Hit> {
    let mut hit: Option<Hit> = None;
    let mut best = t_max;
    for (i, tri) in scene.tri_positions.iter().enumerate() {
        let r = intersect_triangle(
            ray.origin,
            ray.dir,
            v3(tri.v0),
            v3(tri.e1),
            v3(tri.e2),
            best,
        );
        if let Some((t, u, v)) = r {
            best = t;
            hit = Some(Hit {
                prim: i as u32,
                t,
                u,
                v,
            });
        }
    }
    for (i, s) in scene.spheres.iter().enumerate() {
        if let Some(t) = intersect_sphere(ray.origin, ray.dir, v3(s.center), s.radius, best) {
            best = t;
            hit = Some(Hit {
                prim: i as u32 | PRIM_SPHERE,
                t,
                u: 0.0,
                v: 0.0,
            });
        }
    }
    hit
}
