// requires: fn trace_scene (the intersector's walk: intersect/bvh.wgsl, intersect/wide_bvh.wgsl
//   or intersect/ray_query.wgsl, each of which imports this file)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/intersect/primitives.wgsl"

// The intersector contract, for intersectors that trace a ray with one function: the
// including file defines
//   fn trace_scene(ray: Ray, t_max: f32, any_hit: bool) -> Hit
// (the closest hit with 0 < t < t_max, or with any_hit the first hit found; the primitive a
// ray leaves skipped and each candidate tested as candidates.wgsl tests it), and this file
// gives the path tracer the three calls it makes. The binary BVH (bvh.wgsl), the 8-wide BVH
// (wide_bvh.wgsl) and ray queries (ray_query.wgsl) keep it so; the intersection generated
// inline for small scenes (crates/pathtrace/src/specialize/codegen.rs) writes the three calls
// itself, each with its own loop over the primitives.

// The closest hit with 0 < t < t_max; hit.prim == NO_HIT on a miss.
fn intersect_scene_within(ray: Ray, t_max: f32) -> Hit {
    return trace_scene(ray, t_max, false);
}

// The closest hit; hit.prim == NO_HIT on a miss.
fn intersect_scene(ray: Ray) -> Hit {
    return trace_scene(ray, F32_MAX, false);
}

// Whether anything is hit with 0 < t < t_max (shadow rays).
fn occluded(ray: Ray, t_max: f32) -> bool {
    return trace_scene(ray, t_max, true).prim != NO_HIT;
}
