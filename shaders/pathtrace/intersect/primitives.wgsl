#import "pathtrace/scene_types.wgsl"

// Ray/primitive tests shared by the BVH traversal (bvh.wgsl) and the scene-specialized
// intersection code the renderer generates for small scenes. Mirrors
// crates/scene/src/traverse.rs. Hits count for 0 < t < t_max (and, for triangles, only
// beyond `origin_err`, which the CPU mirror does not have: it is always 0 there).
const F32_MAX: f32 = 3.40282347e38;

// The primitive a ray leaves from (a triangle's index, or a shape's | PRIM_SHAPE). A flat
// triangle cannot be hit again by a ray leaving it, nor a sphere by a ray leaving it outwards
// (each shape's test keeps its own rule, pathtrace/shapes/), so skipping it removes
// self-intersection whatever the coordinates' magnitude, with no offset of the origin; for
// triangles the origin's error only has to clear coplanar neighbours (below). A ray entering
// a sphere (`skip_inward`) meets it at its far side.
var<private> skip_prim: u32 = NO_HIT;
// The instance of the triangle left (a hit's `inst`): a triangle of an instanced mesh is one
// surface per instance.
var<private> skip_inst: u32 = NO_INSTANCE;
var<private> skip_inward: bool = false;
// For rays leaving a triangle (camera rays and rays leaving a shape have 0 for both): the
// unit normal of the triangle left, and a componentwise bound on the rounding error of the
// origin. Such rays start exactly at the computed hit, not offset: an offset of even one
// float step is 1/128 at 1e5, which visibly moves shadow boundaries. Instead a triangle
// parallel to the one left (within 2.6 degrees) whose plane passes within the origin's error
// is not hit: the coplanar neighbours of the triangle left, whatever the coordinates'
// magnitude. Other triangles (a wall meeting the floor at a corner) are hit as usual.
var<private> origin_n: vec3<f32> = vec3<f32>(0.0);
var<private> origin_err: vec3<f32> = vec3<f32>(0.0);
// The origin's error off the plane it leaves, and that over the ray's cosine to it: the
// distance along the ray within which it may still be behind that plane.
var<private> origin_off: f32 = 0.0;
var<private> origin_slab: f32 = 0.0;
// cos^2 of 2.6 degrees: "parallel" above it.
const PARALLEL_COS2: f32 = 0.998;

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

// Moller-Trumbore. Returns vec4(hit ? 1 : 0, t, u, v); t, u, v only mean something on a hit.
fn intersect_triangle(origin: vec3<f32>, dir: vec3<f32>, v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, t_max: f32) -> vec4<f32> {
    return intersect_planar(origin, dir, v0, e1, e2, t_max, false);
}

// The parallelogram of the triangles (v0, v0 + e1, v0 + e2) and (v0, v0 + e2, v0 + e2 - e1)
// (a quad split along v0 -> v0 + e2), in one test: the first triangle's, u, v and t bit for
// bit, with the second's hits at u < 0 (u in [-1, 0], u + v in [0, 1]). The scene-specialized
// intersection of small scenes tests a quad's two triangles so.
fn intersect_parallelogram(origin: vec3<f32>, dir: vec3<f32>, v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, t_max: f32) -> vec4<f32> {
    return intersect_planar(origin, dir, v0, e1, e2, t_max, true);
}

fn intersect_planar(origin: vec3<f32>, dir: vec3<f32>, v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, t_max: f32, parallelogram: bool) -> vec4<f32> {
    let p = cross(dir, e2);
    let det = dot(e1, p);
    // A ray parallel to the plane (det 0) gets infinite or NaN u, v, t, which fail `inside`
    // below: no early return, which llvmpipe would not take anyway (it runs an if's body
    // whether or not a lane needs it) and whose masking cost 1.47x on the Cornell box.
    let inv_det = 1.0 / det;
    let s = origin - v0;
    let u = dot(s, p) * inv_det;
    let q = cross(s, e1);
    let v = dot(dir, q) * inv_det;
    let t = dot(e2, q) * inv_det;
    let inside = select(u >= 0.0, u + v >= 0.0 && v <= 1.0, parallelogram) && v >= 0.0 && u + v <= 1.0 && t < t_max;
    var hit = inside && t > 0.0;
    // Rays leaving a triangle: near their origin, within its error, a hit may be an artefact
    // of that error. Where the origin is within its error of this triangle's plane (|t det| is
    // the distance to it times |n|), a parallel plane is the one left (a coplanar neighbour:
    // never hit), and another one meets it at an edge: hit, at t ~ 0 whatever the sign of the
    // computed t, only at a concave corner (a corner of this triangle, or parallelogram, is in
    // front of the plane left, as a wall over a floor) by a ray crossing it towards its back
    // (det > 0).
    // Elsewhere, at a convex edge (as the top of a box seen from its side), a hit closer than
    // `origin_slab` is one the origin, rounded to behind the plane it leaves, sees from inside.
    let n = cross(e1, e2);
    let on_plane = abs(t * det) <= dot(abs(n), origin_err);
    // Computed for every triangle and chosen with select, not behind an if: llvmpipe runs an
    // if's body whether or not a lane needs it, and masking it cost more than these few
    // operations (1.28x on the Cornell box, docs/benchmarks.md).
    let a0 = -dot(s, origin_n);
    let d1 = dot(e1, origin_n);
    let d2 = dot(e2, origin_n);
    let corner = select(max(d1, d2), max(max(d1, d2), d2 - d1), parallelogram);
    let concave = max(a0, a0 + corner) > origin_off;
    let along = dot(n, origin_n);
    let parallel = along * along > PARALLEL_COS2 * dot(n, n);
    let near_origin = inside && (on_plane || (t > 0.0 && t <= origin_slab));
    hit = select(hit, select(concave, det > 0.0 && concave && !parallel, on_plane), near_origin);
    return vec4<f32>(select(0.0, 1.0, hit), t, u, v);
}
