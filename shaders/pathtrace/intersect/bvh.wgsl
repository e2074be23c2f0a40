// requires: const HAS_TRIANGLES, const HAS_SHAPES, const HAS_INSTANCES (options.wgsl;
//   intersect/raycast.wgsl declares its own)
// requires: var bvh_nodes (integrator/pathtrace.wgsl or intersect/raycast.wgsl)
#import "pathtrace/intersect/primitives.wgsl"
#import "pathtrace/intersect/candidates.wgsl"
#import "pathtrace/intersect/contract.wgsl"

// BVH traversal, a line-for-line mirror of crates/scene/src/traverse.rs. The including
// shader declares the storage buffers:
//   var<storage, read> bvh_nodes: array<vec4<u32>>;
//   var<storage, read> tri_positions: array<TriPositions>;
//   var<storage, read> shapes: array<Shape>;
// and the constants HAS_TRIANGLES and HAS_SHAPES (false where the scene has none of them:
// that leaf test is left out), and HAS_ALPHA with the any-hit tests `triangle_hit_counts` and
// `shape_hit_counts` (alpha.wgsl; always true where HAS_ALPHA is false). A leaf's
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
// With instanced meshes (HAS_INSTANCES) the walk has two levels: a leaf of instances walks
// each instance's mesh BVH in turn, its boxes tested with the ray in the mesh's space (`at`),
// then goes on past the leaf (`resume`); a mesh BVH ends with BVH_END as the top level does.
fn trace_scene(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(NO_HIT, t_max, 0.0, 0.0, NO_INSTANCE);
    // The ray the boxes are tested with: the world's, or the walked instance's.
    // Bit a set where the direction's component on axis a is negative: such rays visit the
    // second child of a node split on a first.
    let octant = select(0u, 1u, ray.dir.x < 0.0) | select(0u, 2u, ray.dir.y < 0.0) | select(0u, 4u, ray.dir.z < 0.0);
    let world = world_ray(ray, octant);
    var at = world;
    // The instance walked (its slot) or NO_INSTANCE, the slot after its leaf's last one, and
    // the top-level node after that leaf.
    var inst = NO_INSTANCE;
    var inst_end = 0u;
    var resume = 0u;
    var node_index = 0u;
    loop {
        // Whether this step enters instance `inst`: decided on both paths below and done
        // once, at the end (llvmpipe runs an if's body whether or not a lane needs it, so
        // the entry, with its loads, is written once).
        var enter = false;
        if (node_index == BVH_END) {
            if (!HAS_INSTANCES || inst == NO_INSTANCE) {
                break;
            }
            // The instance's mesh is done: the leaf's next instance, or back to the top.
            inst = inst + 2u;
            enter = inst != inst_end;
            if (!enter) {
                inst = NO_INSTANCE;
                at = world;
                node_index = resume;
                continue;
            }
        } else {
            let lo = bvh_nodes[node_index * 4u];
            let hi = bvh_nodes[node_index * 4u + 1u];
            var box_lo = bitcast<vec3<f32>>(lo.xyz);
            var box_hi = bitcast<vec3<f32>>(hi.xyz);
            if (HAS_INSTANCES) {
                box_lo = box_lo - at.pad;
                box_hi = box_hi + at.pad;
            }
            if (ray_aabb(at.origin, at.inv_dir, box_lo, box_hi, hit.t)) {
                let count = hi.w >> NODE_COUNT_SHIFT;
                if (count == 0u) {
                    // Inner node: on to the near child (the first one is adjacent, the second
                    // at `index`).
                    let axis = hi.w & 3u;
                    node_index = select(node_index + 1u, lo.w, ((at.octant >> axis) & 1u) == 1u);
                    continue;
                }
                let first = lo.w;
                if (HAS_INSTANCES && (hi.w & NODE_INSTANCES) != 0u) {
                    inst = first;
                    inst_end = first + 2u * count;
                    resume = bvh_nodes[node_index * 4u + 2u + (octant >> 2u)][octant & 3u];
                    enter = true;
                } else if (HAS_TRIANGLES && (!HAS_SHAPES || (hi.w & NODE_SHAPES) == 0u)) {
                    for (var i = first; i < first + count; i = i + 1u) {
                        // The scene's own triangles through the same test, placed by the
                        // identity.
                        var r: vec4<f32>;
                        if (HAS_INSTANCES) {
                            r = candidate_instance_triangle(i, inst, at.placed, ray, hit.t);
                        } else {
                            r = candidate_triangle(i, ray, hit.t);
                        }
                        if (r.x != 0.0) {
                            hit = Hit(i, r.y, r.z, r.w, inst);
                            if (any_hit) {
                                return hit;
                            }
                        }
                    }
                } else if (HAS_SHAPES) {
                    for (var i = first; i < first + count; i = i + 1u) {
                        let t = candidate_shape(i, ray, hit.t);
                        if (t > 0.0) {
                            hit = Hit(i | PRIM_SHAPE, t, 0.0, 0.0, NO_INSTANCE);
                            if (any_hit) {
                                return hit;
                            }
                        }
                    }
                }
            }
            if (!enter) {
                // A leaf, or a box missed: past this subtree.
                node_index = bvh_nodes[node_index * 4u + 2u + (at.octant >> 2u)][at.octant & 3u];
                continue;
            }
        }
        // Into instance `inst`: its mesh's BVH, the ray in its space.
        at = instance_ray(inst, ray);
        node_index = at.root;
    }
    return hit;
}
