// From its includer: the bindings `bvh_nodes`, `tri_positions` and `spheres`, the constants
// `HAS_TRIANGLES`, `HAS_SPHERES` and `HAS_ALPHA`, and the any-hit tests `triangle_hit_counts`
// and `sphere_hit_counts` (in the path tracer options.wgsl and alpha.wgsl; raycast.wgsl
// declares its own).
#import "pathtrace/primitives.wgsl"
#import "pathtrace/candidates.wgsl"
#import "pathtrace/contract.wgsl"

// BVH traversal, a line-for-line mirror of crates/scene/src/traverse.rs. The including
// shader declares the storage buffers:
//   var<storage, read> bvh_nodes: array<vec4<u32>>;
//   var<storage, read> tri_positions: array<TriPositions>;
//   var<storage, read> spheres: array<Sphere>;
// and the constants HAS_TRIANGLES and HAS_SPHERES (false where the scene has none of them:
// that leaf test is left out), and HAS_ALPHA with the any-hit tests `triangle_hit_counts` and
// `sphere_hit_counts` (alpha.wgsl; always true where HAS_ALPHA is false). A leaf's
// primitives are tested as every intersector tests its candidates (candidates.wgsl).
// Hits count for 0 < t < t_max; callers offset ray origins off surfaces.
//
// `bvh_nodes` holds one 64-byte record per node (4 vec4s): the BvhNode (aabb_min, index;
// aabb_max, bits), then its skip links for ray octants 0-3 and 4-7: the node after its
// subtree in the order rays of that octant visit the tree (see crates/scene/src/bvh.rs).
// With them the traversal keeps no stack, which llvmpipe would keep in scratch memory.

// Skip link past the last node: the traversal ends.
const BVH_END: u32 = 0xffffffffu;

// Closest hit (any_hit false) or first hit found (any_hit true) with 0 < t < t_max.
fn trace_scene(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(NO_HIT, t_max, 0.0, 0.0);
    let inv_dir = safe_inverse(ray.dir);
    // Bit a set where the direction's component on axis a is negative: such rays visit the
    // second child of a node split on a first.
    let octant = select(0u, 1u, ray.dir.x < 0.0) | select(0u, 2u, ray.dir.y < 0.0) | select(0u, 4u, ray.dir.z < 0.0);
    var node_index = 0u;
    loop {
        if (node_index == BVH_END) {
            break;
        }
        let lo = bvh_nodes[node_index * 4u];
        let hi = bvh_nodes[node_index * 4u + 1u];
        if (ray_aabb(ray.origin, inv_dir, bitcast<vec3<f32>>(lo.xyz), bitcast<vec3<f32>>(hi.xyz), hit.t)) {
            let count = hi.w >> NODE_COUNT_SHIFT;
            if (count == 0u) {
                // Inner node: on to the near child (the first one is adjacent, the second at
                // `index`).
                let axis = hi.w & 3u;
                node_index = select(node_index + 1u, lo.w, ((octant >> axis) & 1u) == 1u);
                continue;
            }
            let first = lo.w;
            if (HAS_TRIANGLES && (!HAS_SPHERES || (hi.w & NODE_SPHERES) == 0u)) {
                for (var i = first; i < first + count; i = i + 1u) {
                    let r = candidate_triangle(i, ray, hit.t);
                    if (r.x != 0.0) {
                        hit = Hit(i, r.y, r.z, r.w);
                        if (any_hit) {
                            return hit;
                        }
                    }
                }
            } else if (HAS_SPHERES) {
                for (var i = first; i < first + count; i = i + 1u) {
                    let t = candidate_sphere(i, ray, hit.t);
                    if (t > 0.0) {
                        hit = Hit(i | PRIM_SPHERE, t, 0.0, 0.0);
                        if (any_hit) {
                            return hit;
                        }
                    }
                }
            }
        }
        // A leaf, or a box missed: past this subtree.
        node_index = bvh_nodes[node_index * 4u + 2u + (octant >> 2u)][octant & 3u];
    }
    return hit;
}
