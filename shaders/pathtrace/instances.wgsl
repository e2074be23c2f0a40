// Instances of instanced meshes, as the traversal and the surface read them: each takes two
// node slots of `bvh_nodes` after the last node (crates/scene/src/bvh.rs, `GpuInstance`):
// vec4s 0-2 the object-to-world matrix's rows, 3-5 the world-to-object one's, 6 its mesh's
// BVH root node, its index and its flags (INSTANCE_MIRROR). An instance is named by its
// first slot. Mirrored line for line by crates/scene/src/traverse.rs.
// From its includer: the binding `bvh_nodes`.
#import "pathtrace/scene_types.wgsl"
#import "pathtrace/primitives.wgsl"

// Boxes of a mesh's BVH are tested with the ray moved into the mesh's space, which rounding
// moves off the true one: they grow by this much of the coordinates involved (8 float steps),
// so no box a hit is in is missed. The triangles themselves are tested in world space.
const INSTANCE_PAD: f32 = 9.536743e-7;

fn instance_row(slot: u32, row: u32) -> vec4f {
    return bitcast<vec4f>(bvh_nodes[slot * 4u + row]);
}

// Its mesh's BVH root, its index and its flags.
fn instance_info(slot: u32) -> vec4u {
    return bvh_nodes[slot * 4u + 6u];
}

fn instance_mirrors(slot: u32) -> bool {
    return (instance_info(slot).z & INSTANCE_MIRROR) != 0u;
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

// A triangle of the instance's mesh in world space: corner 0 and the edges to corners 1 and
// 2 (as stored: a mirroring instance's candidate test swaps them, candidates.wgsl).
struct PlacedTriangle {
    v0: vec3f,
    e1: vec3f,
    e2: vec3f,
}

fn place_triangle(slot: u32, tri: TriPositions) -> PlacedTriangle {
    return PlacedTriangle(instance_apply(slot, 0u, tri.v0, 1.0), instance_apply(slot, 0u, tri.e1, 0.0), instance_apply(slot, 0u, tri.e2, 0.0));
}

// The ray in the instance's mesh's space, for its boxes: origin, 1 / direction, octant, the
// boxes' padding, and the mesh's BVH root.
struct InstanceRay {
    origin: vec3f,
    inv_dir: vec3f,
    octant: u32,
    pad: f32,
    root: u32,
}

fn max3(v: vec3f) -> f32 {
    return max(max(v.x, v.y), v.z);
}

fn instance_ray(slot: u32, ray: Ray) -> InstanceRay {
    let origin = instance_apply(slot, 3u, ray.origin, 1.0);
    let dir = instance_apply(slot, 3u, ray.dir, 0.0);
    let root = instance_info(slot).x;
    // The moved origin's terms, the origin itself and the mesh's extent (its root box).
    let o = abs(ray.origin);
    let x = instance_row(slot, 3u);
    let y = instance_row(slot, 4u);
    let z = instance_row(slot, 5u);
    let terms = vec3f(dot(abs(x.xyz), o) + abs(x.w), dot(abs(y.xyz), o) + abs(y.w), dot(abs(z.xyz), o) + abs(z.w));
    let lo = bitcast<vec3f>(bvh_nodes[root * 4u].xyz);
    let hi = bitcast<vec3f>(bvh_nodes[root * 4u + 1u].xyz);
    let extent = max3(max(abs(lo), abs(hi)));
    let pad = INSTANCE_PAD * (max3(terms) + max3(abs(origin)) + extent);
    let octant = select(0u, 1u, dir.x < 0.0) | select(0u, 2u, dir.y < 0.0) | select(0u, 4u, dir.z < 0.0);
    return InstanceRay(origin, safe_inverse(dir), octant, pad, root);
}
