//! Ray queries on the CPU over exactly the flat layout of [`GpuScene`], written to be
//! mirrored line for line by `shaders/pathtrace/intersect/bvh.wgsl` (same names, same order of
//! operations). Used by tests against brute force, and as the reference for the shader.
//!
//! Rays start at `origin` and hits count for `0 < t < t_max`: callers offset origins off
//! surfaces themselves. Directions need not be normalized; `t` is in units of `dir`.

use glam::Vec3;

use crate::bvh::{BVH_END, NODE_COUNT_SHIFT, NODE_INSTANCES, NODE_SHAPES};
use crate::flatten::GpuScene;
use crate::gpu::{
    GpuInstance, INSTANCE_MIRROR, MATERIAL_ALPHA_BLEND, MATERIAL_ALPHA_MASK, NO_HIT, NO_INSTANCE,
    PRIM_SHAPE,
};

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
    /// Triangle index, or sphere index | [`PRIM_SHAPE`].
    pub prim: u32,
    /// Distance along the ray, in units of `dir`.
    pub t: f32,
    /// Barycentric weight of corner 1 (triangles; 0 for spheres).
    pub u: f32,
    /// Barycentric weight of corner 2 (triangles; 0 for spheres).
    pub v: f32,
    /// The instance whose mesh the triangle is of (its first node slot, see
    /// [`GpuScene::instance_at`]), or [`NO_INSTANCE`] for the scene's own primitives.
    pub inst: u32,
}

impl Hit {
    /// Whether the hit is on a sphere.
    pub fn is_shape(&self) -> bool {
        self.prim & PRIM_SHAPE != 0
    }

    /// The index in `tri_positions` or `spheres`.
    pub fn index(&self) -> usize {
        (self.prim & !PRIM_SHAPE) as usize
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
/// `pathtrace/intersect/alpha.wgsl`, line for line).
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
/// `pathtrace/intersect/alpha.wgsl`, line for line).
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

/// [`triangle_hit_counts`] for shape `i` (no texture: the opacity alone).
pub fn shape_hit_counts(scene: &GpuScene, i: u32, ray: &Ray) -> bool {
    let m = &scene.materials[scene.shapes[i as usize].material as usize];
    if m.flags & (MATERIAL_ALPHA_MASK | MATERIAL_ALPHA_BLEND) == 0 {
        return true;
    }
    alpha_stops(m, m.opacity, i | PRIM_SHAPE, ray)
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

/// Boxes of a mesh's BVH are tested with the ray moved into the mesh's space: they grow by
/// this much of the coordinates involved (`INSTANCE_PAD` in `pathtrace/intersect/instances.wgsl`).
const INSTANCE_PAD: f32 = 9.536_743e-7;

/// The rows `first..first + 3` of `inst` (0: object to world, 3: world to object) applied
/// to point `p` (`w` 1) or vector (`w` 0).
fn instance_apply(inst: &GpuInstance, first: usize, p: Vec3, w: f32) -> Vec3 {
    let row = |r: usize| {
        let x = if r < 3 {
            inst.to_world[r]
        } else {
            inst.to_object[r - 3]
        };
        Vec3::new(x[0], x[1], x[2]).dot(p) + w * x[3]
    };
    Vec3::new(row(first), row(first + 1), row(first + 2))
}

/// A triangle of `inst`'s mesh in world space: corner 0 and the edges to corners 1 and 2
/// (`place_triangle`).
pub fn place_triangle(inst: &GpuInstance, tri: &crate::gpu::GpuTriangle) -> (Vec3, Vec3, Vec3) {
    (
        instance_apply(inst, 0, v3(tri.v0), 1.0),
        instance_apply(inst, 0, v3(tri.e1), 0.0),
        instance_apply(inst, 0, v3(tri.e2), 0.0),
    )
}

/// A normal of `inst`'s mesh in world space, not normalized (`instance_normal`).
pub fn instance_normal(inst: &GpuInstance, n: Vec3) -> Vec3 {
    let row = |r: usize| {
        Vec3::new(
            inst.to_object[r][0],
            inst.to_object[r][1],
            inst.to_object[r][2],
        )
    };
    n.x * row(0) + n.y * row(1) + n.z * row(2)
}

/// The ray the boxes of a level are tested with (`InstanceRay`).
#[derive(Clone, Copy)]
struct BoxRay {
    origin: Vec3,
    inv_dir: Vec3,
    octant: u32,
    pad: f32,
    root: u32,
}

fn max3(v: Vec3) -> f32 {
    v.x.max(v.y).max(v.z)
}

fn octant_of(d: Vec3) -> u32 {
    u32::from(d.x < 0.0) | (u32::from(d.y < 0.0) << 1) | (u32::from(d.z < 0.0) << 2)
}

/// `ray` in the space of `inst`'s mesh (`instance_ray`).
fn instance_ray(inst: &GpuInstance, ray: &Ray) -> BoxRay {
    let origin = instance_apply(inst, 3, ray.origin, 1.0);
    let dir = instance_apply(inst, 3, ray.dir, 0.0);
    // The moved origin's terms (bounded by the largest row sum times the origin's largest
    // coordinate, plus the translation), the moved origin and the mesh's extent.
    let pad = INSTANCE_PAD
        * (inst.pad_scale * max3(ray.origin.abs()) + inst.pad_base + max3(origin.abs()));
    BoxRay {
        origin,
        inv_dir: safe_inverse(dir),
        octant: octant_of(dir),
        pad,
        root: inst.root,
    }
}

/// Triangle `i` of `inst`'s mesh, tested in world space as a copy of it would be (corners 1
/// and 2 swapped where the instance mirrors, u and v swapped back):
/// `candidate_instance_triangle`.
fn instance_triangle_hit(
    scene: &GpuScene,
    inst: &GpuInstance,
    i: u32,
    ray: &Ray,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let tri = &scene.tri_positions[i as usize];
    let (v0, e1, e2) = place_triangle(inst, tri);
    let mirror = inst.flags & INSTANCE_MIRROR != 0;
    let (a, b) = if mirror { (e2, e1) } else { (e1, e2) };
    intersect_triangle(ray.origin, ray.dir, v0, a, b, t_max)
        .map(|(t, u, v)| if mirror { (t, v, u) } else { (t, u, v) })
}

/// The tests of a leaf's triangles (of the instance `inst`, or the scene's own where it is
/// [`NO_INSTANCE`]) or spheres, narrowing `hit`; `true` where `ANY` and one counts.
fn leaf_hits<const ANY: bool>(
    scene: &GpuScene,
    node: crate::gpu::GpuBvhNode,
    inst: u32,
    ray: &Ray,
    alpha: bool,
    hit: &mut Hit,
) -> bool {
    let (first, count) = (node.index, node.bits >> NODE_COUNT_SHIFT);
    let slot = |s: u32| scene.instance_at(s, 0);
    if node.bits & NODE_SHAPES == 0 {
        for i in first..first + count {
            let tri = scene.tri_positions[i as usize];
            let r = if inst == NO_INSTANCE {
                intersect_triangle(
                    ray.origin,
                    ray.dir,
                    v3(tri.v0),
                    v3(tri.e1),
                    v3(tri.e2),
                    hit.t,
                )
            } else {
                instance_triangle_hit(scene, slot(inst), i, ray, hit.t)
            };
            if let Some((t, u, v)) = r
                && (!alpha
                    || tri.flags & crate::gpu::TRI_ALPHA == 0
                    || triangle_hit_counts(scene, i, u, v, ray))
            {
                *hit = Hit {
                    prim: i,
                    t,
                    u,
                    v,
                    inst,
                };
                if ANY {
                    return true;
                }
            }
        }
    } else {
        for i in first..first + count {
            let s = &scene.shapes[i as usize];
            if let Some(t) =
                crate::shapes::KINDS[s.kind as usize].intersect(s, ray.origin, ray.dir, hit.t)
                && (!alpha || shape_hit_counts(scene, i, ray))
            {
                *hit = Hit {
                    prim: i | PRIM_SHAPE,
                    t,
                    u: 0.0,
                    v: 0.0,
                    inst: NO_INSTANCE,
                };
                if ANY {
                    return true;
                }
            }
        }
    }
    false
}

fn traverse<const ANY: bool>(scene: &GpuScene, ray: &Ray, t_max: f32) -> Option<Hit> {
    let mut hit = Hit {
        prim: NO_HIT,
        t: t_max,
        u: 0.0,
        v: 0.0,
        inst: NO_INSTANCE,
    };
    if scene.bvh_nodes.is_empty() {
        return None;
    }
    let alpha = scene.header.features & crate::gpu::FEATURE_ALPHA != 0;
    // Bit `a` set where the direction's component on axis `a` is negative: such rays visit
    // the second child of a node split on `a` first.
    let octant = octant_of(ray.dir);
    let world = BoxRay {
        origin: ray.origin,
        inv_dir: safe_inverse(ray.dir),
        octant,
        pad: 0.0,
        root: 0,
    };
    // The ray the boxes are tested with: the world's, or the walked instance's.
    let mut at = world;
    // The instance walked (its slot) or NO_INSTANCE, the slot after its leaf's last one,
    // and the top-level node after that leaf.
    let mut inst = NO_INSTANCE;
    let mut inst_end = 0u32;
    let mut resume = 0u32;
    let mut node_index = 0u32;
    let slot = |s: u32| scene.instance_at(s, 0);
    loop {
        if node_index == BVH_END {
            if inst == NO_INSTANCE {
                break;
            }
            // The instance's mesh is done: the leaf's next instance, or back to the top.
            inst += 2;
            if inst == inst_end {
                inst = NO_INSTANCE;
                at = world;
                node_index = resume;
            } else {
                at = instance_ray(slot(inst), ray);
                node_index = at.root;
            }
            continue;
        }
        let node = scene.bvh_nodes[node_index as usize];
        let pad = Vec3::splat(at.pad);
        if ray_aabb(
            at.origin,
            at.inv_dir,
            v3(node.aabb_min) - pad,
            v3(node.aabb_max) + pad,
            hit.t,
        ) {
            let count = node.bits >> NODE_COUNT_SHIFT;
            if count == 0 {
                // Inner node: on to the near child (the first one is adjacent, the second at
                // `index`).
                let axis = node.bits & 3;
                node_index = if (at.octant >> axis) & 1 == 1 {
                    node.index
                } else {
                    node_index + 1
                };
                continue;
            }
            let first = node.index;
            if node.bits & NODE_INSTANCES != 0 {
                inst = first;
                inst_end = first + 2 * count;
                resume = scene.bvh_skips[node_index as usize][octant as usize];
                at = instance_ray(slot(inst), ray);
                node_index = at.root;
                continue;
            }
            if leaf_hits::<ANY>(scene, node, inst, ray, alpha, &mut hit) {
                return Some(hit);
            }
        }
        // A leaf, or a box missed: past this subtree.
        node_index = scene.bvh_skips[node_index as usize][at.octant as usize];
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
                inst: NO_INSTANCE,
            });
        }
    }
    for (i, s) in scene.shapes.iter().enumerate() {
        if let Some(t) =
            crate::shapes::KINDS[s.kind as usize].intersect(s, ray.origin, ray.dir, best)
        {
            best = t;
            hit = Some(Hit {
                prim: i as u32 | PRIM_SHAPE,
                t,
                u: 0.0,
                v: 0.0,
                inst: NO_INSTANCE,
            });
        }
    }
    hit
}
