// Instances of instanced meshes, as the traversal and the surface read them: each takes two
// node slots of `bvh_nodes` after the last node (crates/scene/src/bvh.rs, `GpuInstance`):
// vec4s 0-2 the object-to-world matrix's rows, 3-5 the world-to-object one's, 6 its mesh's
// BVH root node, its flags (INSTANCE_MIRROR) and the two terms of its boxes' padding
// (`instance_ray`), 7 its index. An instance is named by its
// first slot. Mirrored line for line by crates/scene/src/traverse.rs.
// requires: var bvh_nodes (integrator/pathtrace.wgsl or intersect/raycast.wgsl)
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/intersect/primitives.wgsl"

// Boxes of a mesh's BVH are tested with the ray moved into the mesh's space, which rounding
// moves off the true one: they grow by this much of the coordinates involved (8 float steps),
// so no box a hit is in is missed. The triangles themselves are tested in world space.
const INSTANCE_PAD: f32 = 9.536743e-7;

fn instance_row(slot: u32, row: u32) -> vec4f {
    return bitcast<vec4f>(bvh_nodes[slot * 4u + row]);
}

// Its mesh's BVH root, its flags, and its padding's scale and base (f32 bits).
fn instance_info(slot: u32) -> vec4u {
    return bvh_nodes[slot * 4u + 6u];
}

fn instance_mirrors(slot: u32) -> bool {
    return (instance_info(slot).y & INSTANCE_MIRROR) != 0u;
}

// The rows `first`..`first + 2` of the instance at `slot` applied to point `p` (w = 1) or
// vector (w = 0).
fn instance_apply(slot: u32, first: u32, p: vec3f, w: f32) -> vec3f {
    let x = instance_row(slot, first);
    let y = instance_row(slot, first + 1u);
    let z = instance_row(slot, first + 2u);
    return vec3f(dot(x.xyz, p) + w * x.w, dot(y.xyz, p) + w * y.w, dot(z.xyz, p) + w * z.w);
}

// A normal of the mesh in world space (the inverse transpose: the world-to-object rows
// transposed), not normalized.
fn instance_normal(slot: u32, n: vec3f) -> vec3f {
    return n.x * instance_row(slot, 3u).xyz + n.y * instance_row(slot, 4u).xyz + n.z * instance_row(slot, 5u).xyz;
}

// An instance's object-to-world rows and whether it mirrors: what placing its triangles
// takes, read once when a walk enters the instance (llvmpipe pays for every load in the
// candidate loop).
struct Placement {
    x: vec4f,
    y: vec4f,
    z: vec4f,
    mirror: bool,
}

fn instance_placement(slot: u32) -> Placement {
    return Placement(instance_row(slot, 0u), instance_row(slot, 1u), instance_row(slot, 2u), instance_mirrors(slot));
}

fn placed_point(m: Placement, p: vec3f, w: f32) -> vec3f {
    return vec3f(dot(m.x.xyz, p) + w * m.x.w, dot(m.y.xyz, p) + w * m.y.w, dot(m.z.xyz, p) + w * m.z.w);
}

// A triangle of the instance's mesh in world space: corner 0 and the edges to corners 1 and
// 2 (as stored: a mirroring instance's candidate test swaps them, candidates.wgsl).
struct PlacedTriangle {
    v0: vec3f,
    e1: vec3f,
    e2: vec3f,
}

fn place_with(m: Placement, tri: TriPositions) -> PlacedTriangle {
    return PlacedTriangle(placed_point(m, tri.v0, 1.0), placed_point(m, tri.e1, 0.0), placed_point(m, tri.e2, 0.0));
}

fn place_triangle(slot: u32, tri: TriPositions) -> PlacedTriangle {
    return place_with(instance_placement(slot), tri);
}

// The ray in the instance's mesh's space, for its boxes: origin, 1 / direction, octant, the
// boxes' padding, and the mesh's BVH root; and the instance's placement, for its triangles.
struct InstanceRay {
    origin: vec3f,
    inv_dir: vec3f,
    octant: u32,
    pad: f32,
    root: u32,
    placed: Placement,
}

// The world's own level: the ray as it is, its triangles placed by the identity (which
// leaves every coordinate as it is, bit for bit), so one candidate test serves both levels:
// llvmpipe would run both sides of a branch between two tests for every candidate.
fn world_ray(ray: Ray, octant: u32) -> InstanceRay {
    let identity = Placement(vec4f(1.0, 0.0, 0.0, 0.0), vec4f(0.0, 1.0, 0.0, 0.0), vec4f(0.0, 0.0, 1.0, 0.0), false);
    return InstanceRay(ray.origin, safe_inverse(ray.dir), octant, 0.0, 0u, identity);
}

fn max3(v: vec3f) -> f32 {
    return max(max(v.x, v.y), v.z);
}

fn instance_ray(slot: u32, ray: Ray) -> InstanceRay {
    let x = instance_row(slot, 3u);
    let y = instance_row(slot, 4u);
    let z = instance_row(slot, 5u);
    let info = instance_info(slot);
    let origin = vec3f(dot(x.xyz, ray.origin) + x.w, dot(y.xyz, ray.origin) + y.w, dot(z.xyz, ray.origin) + z.w);
    let dir = vec3f(dot(x.xyz, ray.dir), dot(y.xyz, ray.dir), dot(z.xyz, ray.dir));
    // The moved origin's terms (bounded by the largest row sum times the origin's largest
    // coordinate, plus the translation), the moved origin and the mesh's extent.
    let pad = INSTANCE_PAD * (bitcast<f32>(info.z) * max3(abs(ray.origin)) + bitcast<f32>(info.w) + max3(abs(origin)));
    let octant = select(0u, 1u, dir.x < 0.0) | select(0u, 2u, dir.y < 0.0) | select(0u, 4u, dir.z < 0.0);
    let placed = Placement(instance_row(slot, 0u), instance_row(slot, 1u), instance_row(slot, 2u), (info.y & INSTANCE_MIRROR) != 0u);
    return InstanceRay(origin, safe_inverse(dir), octant, pad, info.x, placed);
}
