#import "pathtrace/intersect/primitives.wgsl"
#import "pathtrace/intersect/instances.wgsl"
#import "pathtrace/shapes.wgsl"

// A candidate primitive tested as every intersector tests the primitives it finds (the BVH's
// leaves, the wide BVH's, the device's ray-query candidates): the exact ray/primitive test,
// the rules for rays leaving a surface (`skip_prim`, the origin's error, primitives.wgsl) and
// the any-hit test of alpha-masked and blended materials (alpha.wgsl).
// requires: const HAS_ALPHA (options.wgsl, or intersect/raycast.wgsl)
// requires: var tri_positions, var shapes (integrator/pathtrace.wgsl or intersect/raycast.wgsl)
// requires: fn triangle_hit_counts, fn shape_hit_counts (the any-hit tests:
//   intersect/alpha.wgsl, or intersect/raycast.wgsl)

// Triangle `i`: vec4(1, t, u, v) where it counts as a hit with 0 < t < t_max, else x = 0.
fn candidate_triangle(i: u32, ray: Ray, t_max: f32) -> vec4<f32> {
    let tri = tri_positions[i];
    return candidate_triangle_at(i, tri.v0, tri.e1, tri.e2, tri.flags, ray, t_max);
}

// Triangle `i` whose record (`tri_positions[i]`, or a copy of it) is `v0`, `e1`, `e2`,
// `flags`.
fn candidate_triangle_at(i: u32, v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, flags: u32, ray: Ray, t_max: f32) -> vec4<f32> {
    let r = intersect_triangle(ray.origin, ray.dir, v0, e1, e2, t_max);
    // The any-hit test only for triangles whose material needs it (the flag rides in the
    // record just read).
    if (r.x != 0.0 && i != skip_prim && (!HAS_ALPHA || (flags & TRI_ALPHA) == 0u || triangle_hit_counts(i, r.z, r.w, ray))) {
        return r;
    }
    return vec4<f32>(0.0);
}

// Triangle `i` of the mesh of the instance at `slot` (instances.wgsl), placed by `placed`
// (`instance_placement(slot)`, read once per instance), tested in world space
// as a copy of it would be: the same front side (corners 1 and 2 swapped where the instance
// mirrors, u and v swapped back), the same rules for rays leaving it (the instance counts:
// the triangle left is `skip_prim` in instance `skip_inst`).
fn candidate_instance_triangle(i: u32, slot: u32, placed: Placement, ray: Ray, t_max: f32) -> vec4<f32> {
    let tri = tri_positions[i];
    let w = place_with(placed, tri);
    let mirror = placed.mirror;
    var r = intersect_triangle(ray.origin, ray.dir, w.v0, select(w.e1, w.e2, mirror), select(w.e2, w.e1, mirror), t_max);
    r = select(r, r.xywz, mirror);
    if (r.x != 0.0 && (i != skip_prim || slot != skip_inst) && (!HAS_ALPHA || (tri.flags & TRI_ALPHA) == 0u || triangle_hit_counts(i, r.z, r.w, ray))) {
        return r;
    }
    return vec4<f32>(0.0);
}

// Shape `i` (its index in `shapes`, without PRIM_SHAPE): t where it counts as a hit with
// 0 < t < t_max, else 0.
fn candidate_shape(i: u32, ray: Ray, t_max: f32) -> f32 {
    return candidate_shape_at(i, shapes[i], ray, t_max);
}

// Shape `i` whose record (`shapes[i]`, or a copy of it) is `s`.
fn candidate_shape_at(i: u32, s: Shape, ray: Ray, t_max: f32) -> f32 {
    let t = shape_intersect(i | PRIM_SHAPE, s, ray, t_max);
    if (t > 0.0 && (!HAS_ALPHA || shape_hit_counts(i, ray))) {
        return t;
    }
    return 0.0;
}
