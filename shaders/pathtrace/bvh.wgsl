#import "pathtrace/primitives.wgsl"

// BVH traversal, a line-for-line mirror of crates/scene/src/traverse.rs. The including
// shader declares the storage buffers:
//   var<storage, read> bvh_nodes: array<BvhNode>;
//   var<storage, read> tri_positions: array<TriPositions>;
//   var<storage, read> spheres: array<Sphere>;
// Hits count for 0 < t < t_max; callers offset ray origins off surfaces.

const BVH_STACK_SIZE: u32 = 64u;

// Closest hit (any_hit false) or first hit found (any_hit true) with 0 < t < t_max.
fn traverse_bvh(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(NO_HIT, t_max, 0.0, 0.0);
    let inv_dir = safe_inverse(ray.dir);
    var stack: array<u32, BVH_STACK_SIZE>;
    var sp = 0u;
    var node_index = 0u;
    loop {
        let node = bvh_nodes[node_index];
        if (ray_aabb(ray.origin, inv_dir, node.aabb_min, node.aabb_max, hit.t)) {
            let count = node.bits >> NODE_COUNT_SHIFT;
            if (count == 0u) {
                // Inner node: the first child is adjacent, the second at `index`.
                let axis = node.bits & 3u;
                if (ray.dir[axis] < 0.0) {
                    stack[sp] = node_index + 1u;
                    node_index = node.index;
                } else {
                    stack[sp] = node.index;
                    node_index = node_index + 1u;
                }
                sp = sp + 1u;
                continue;
            }
            let first = node.index;
            if ((node.bits & NODE_SPHERES) == 0u) {
                for (var i = first; i < first + count; i = i + 1u) {
                    let tri = tri_positions[i];
                    let r = intersect_triangle(ray.origin, ray.dir, tri.v0, tri.e1, tri.e2, hit.t);
                    if (r.x != 0.0 && i != skip_prim) {
                        hit = Hit(i, r.y, r.z, r.w);
                        if (any_hit) {
                            return hit;
                        }
                    }
                }
            } else {
                for (var i = first; i < first + count; i = i + 1u) {
                    let s = spheres[i];
                    let t = intersect_sphere_from(i | PRIM_SPHERE, ray.origin, ray.dir, s.center, s.radius, hit.t);
                    if (t > 0.0) {
                        hit = Hit(i | PRIM_SPHERE, t, 0.0, 0.0);
                        if (any_hit) {
                            return hit;
                        }
                    }
                }
            }
        }
        if (sp == 0u) {
            break;
        }
        sp = sp - 1u;
        node_index = stack[sp];
    }
    return hit;
}

// The closest hit with 0 < t < t_max; hit.prim == NO_HIT on a miss.
fn intersect_scene_within(ray: Ray, t_max: f32) -> Hit {
    return traverse_bvh(ray, t_max, false);
}

// The closest hit; hit.prim == NO_HIT on a miss.
fn intersect_scene(ray: Ray) -> Hit {
    return traverse_bvh(ray, F32_MAX, false);
}

// Whether anything is hit with 0 < t < t_max (shadow rays).
fn occluded(ray: Ray, t_max: f32) -> bool {
    return traverse_bvh(ray, t_max, true).prim != NO_HIT;
}
