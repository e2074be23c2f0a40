#import "pathtrace/intersect/primitives.wgsl"
#import "pathtrace/intersect/candidates.wgsl"
#import "pathtrace/intersect/contract.wgsl"
#import "pathtrace/shared.wgsl"

// Scene intersection through the device's ray queries (`enable wgpu_ray_query`, which the
// renderer puts at the top of the shader): the device's acceleration structure
// (crates/pathtrace/src/accel.rs) finds the candidates, and each is tested here exactly as the
// BVH traversal of bvh.wgsl tests a leaf's primitives: the same ray/primitive tests, the
// same rules for rays leaving a surface (`skip_prim`, the origin's error) and the same
// any-hit test (alpha.wgsl). So the device only replaces the BVH: on GPUs with ray-tracing
// hardware that is its traversal units, elsewhere (lavapipe) the driver's own BVH.
//
// The acceleration structure has one instance per kind of primitive, its custom data saying
// which: triangles (ACCEL_TRIANGLES) and analytic shapes (ACCEL_SHAPES), each primitive a box, in
// the order of `tri_positions` and `shapes` (a candidate's primitive index is the
// primitive's). Every candidate box comes back to this loop, which generates a hit only
// where the exact test hits, so the device culls the boxes beyond it. (Triangles are boxes,
// not the device's triangles: its watertight test and Moller-Trumbore disagree at shared
// edges, and a ray the device sends to one triangle and the exact test to none would go
// through.)
//
// requires: const HAS_TRIANGLES, const HAS_SHAPES (options.wgsl)

@group(0) @binding(24) var scene_accel: acceleration_structure;

// Closest hit (any_hit false) or first hit found (any_hit true) with 0 < t < t_max.
fn trace_scene(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(NO_HIT, t_max, 0.0, 0.0, NO_INSTANCE);
    var rq: ray_query;
    // The device's range must be finite and not below its t_min (a shadow ray's may be
    // neither); the exact tests keep `t_max` itself.
    let far = clamp(t_max, 0.0, F32_MAX);
    rayQueryInitialize(&rq, scene_accel, RayDesc(RAY_FLAG_NONE, 0xFFu, 0.0, far, ray.origin, ray.dir));
    while (rayQueryProceed(&rq)) {
        let c = rayQueryGetCandidateIntersection(&rq);
        let i = c.primitive_index;
        if (HAS_TRIANGLES && c.instance_custom_data == ACCEL_TRIANGLES) {
            let r = candidate_triangle(i, ray, hit.t);
            if (r.x != 0.0) {
                hit = Hit(i, r.y, r.z, r.w, NO_INSTANCE);
                // A hit at a concave corner may come at t <= 0 (primitives.wgsl); the device
                // takes none below its t_min of 0.
                // (Bound by a `let`: naga 30 rejects an expression in the call itself.)
                let at = max(r.y, 0.0);
                rayQueryGenerateIntersection(&rq, at);
                if (any_hit) {
                    rayQueryTerminate(&rq);
                }
            }
        } else if (HAS_SHAPES && c.instance_custom_data == ACCEL_SHAPES) {
            let t = candidate_shape(i, ray, hit.t);
            if (t > 0.0) {
                hit = Hit(i | PRIM_SHAPE, t, 0.0, 0.0, NO_INSTANCE);
                rayQueryGenerateIntersection(&rq, t);
                if (any_hit) {
                    rayQueryTerminate(&rq);
                }
            }
        }
    }
    return hit;
}
