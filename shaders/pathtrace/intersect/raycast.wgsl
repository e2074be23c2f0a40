// Ray queries: the closest hit of each ray in a buffer, through the same BVH traversal the
// path tracer uses. Used to check the GPU traversal against the CPU one, and for picking.
#import "pathtrace/scene_types.wgsl"

struct Query {
    origin: vec3<f32>,
    t_max: f32,
    dir: vec3<f32>,
    pad: u32,
}

struct Params {
    count: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> queries: array<Query>;
@group(0) @binding(2) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(3) var<storage, read> bvh_nodes: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> tri_positions: array<TriPositions>;
@group(0) @binding(5) var<storage, read> shapes: array<Shape>;

#import "pathtrace/intersect/bvh.wgsl"

// Ray queries are not specialized to the scene: both primitive kinds' tests are compiled;
// they see every surface solid (no material is bound: alpha's any-hit test is not run).
const HAS_TRIANGLES: bool = true;
const HAS_SHAPES: bool = true;
const HAS_ALPHA: bool = false;
const HAS_INSTANCES: bool = true;

fn triangle_hit_counts(prim: u32, u: f32, v: f32, ray: Ray) -> bool {
    return true;
}

fn shape_hit_counts(i: u32, ray: Ray) -> bool {
    return true;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.y * 65535u * 64u + id.x;
    if i >= params.count {
        return;
    }
    let q = queries[i];
    hits[i] = intersect_scene_within(Ray(q.origin, q.dir), q.t_max);
}
