// requires: const HAS_TRIANGLES, const HAS_SHAPES (options.wgsl; intersect/raycast.wgsl declares
//   its own)
// requires: var bvh_nodes (integrator/pathtrace.wgsl or intersect/raycast.wgsl)
#import "pathtrace/intersect/primitives.wgsl"
#import "pathtrace/intersect/candidates.wgsl"
#import "pathtrace/intersect/contract.wgsl"

// Scene intersection through the 8-wide compressed BVH (CWBVH, Ylitie, Karras and Laine,
// HPG 2017) that crates/pathtrace/src/intersect/wide_bvh.rs builds and packs: what the plan calls
// "8-wide BVH". One node holds the boxes of up to eight children on a 256-step grid (a byte
// a bound); one node read tests them all, and the children hit are visited nearest first by
// the ray's octant, the rest kept on a short stack as (first child node, hit bits) pairs.
// Leaves are up to three primitives, copied into the records in leaf order and tested with
// the same tests as every other intersector's (candidates.wgsl), so hits are those of
// bvh.wgsl.
//
// The including shader declares `bvh_nodes: array<vec4<u32>>` (here: the wide BVH's records,
// see wide_bvh.rs for the layout), `tri_positions` and `shapes`, and the constants
// HAS_TRIANGLES, HAS_SHAPES and HAS_ALPHA.

// Entries of the traversal stack: one per level of the tree at most (wide_bvh.rs refuses
// deeper trees). It is private to the invocation: in workgroup memory (entry d of invocation
// l at d * 64 + l) the traversal measured 0.58-0.66x as fast on an NVIDIA H200
// (docs/benchmarks.md).
const WIDE_STACK: u32 = 32u;
// Far distance scale of the child box test: its t values go through more roundings than
// ray_aabb's (grid step times inverse direction, corner minus origin, a multiply-add).
const WIDE_ROBUST_FAR: f32 = 1.000001;

// The hit bits of four children (`first` to `first` + 3) whose info bytes are in `info`
// and grid bounds in the words `lx` (low x) to `hz` (high z), a byte each: an inner child
// hit sets bit 24 + slot ^ oct_inv (the highest bits are visited first: nearest first by
// the octant), a leaf hit its primitives' bits (count in unary) at its first one's offset.
// Empty slots have info 0 and set nothing.
fn wide_children(first: u32, info: u32, lx: u32, hx: u32, ly: u32, hy: u32, lz: u32, hz: u32, imask: u32, scale: vec3<f32>, offset: vec3<f32>, t_max: f32, oct_inv: u32) -> u32 {
    var hits = 0u;
    for (var j = 0u; j < 4u; j = j + 1u) {
        let s = j * 8u;
        let lo = vec3<f32>(f32((lx >> s) & 0xffu), f32((ly >> s) & 0xffu), f32((lz >> s) & 0xffu));
        let hi = vec3<f32>(f32((hx >> s) & 0xffu), f32((hy >> s) & 0xffu), f32((hz >> s) & 0xffu));
        // t of grid coordinate q along each axis: q * scale + offset.
        let t0 = lo * scale + offset;
        let t1 = hi * scale + offset;
        let tn = min(t0, t1);
        let tf = max(t0, t1);
        let near = max(max(max(tn.x, tn.y), tn.z), 0.0);
        let far = min(min(min(tf.x, tf.y), tf.z) * WIDE_ROBUST_FAR, t_max);
        let k = first + j;
        let child_info = (info >> s) & 0xffu;
        let at_bit = select(child_info & 31u, 24u + (k ^ oct_inv), ((imask >> k) & 1u) != 0u);
        hits = hits | select(0u, (child_info >> 5u) << at_bit, near <= far);
    }
    return hits;
}

// Closest hit (any_hit false) or first hit found (any_hit true) with 0 < t < t_max.
fn trace_scene(ray: Ray, t_max: f32, any_hit: bool) -> Hit {
    var hit = Hit(NO_HIT, t_max, 0.0, 0.0, NO_INSTANCE);
    let inv_dir = safe_inverse(ray.dir);
    // The octant, inverted as the builder orders children (x 4, y 2, z 1; set where the
    // component is >= 0).
    let oct_inv = select(4u, 0u, ray.dir.x < 0.0) | select(2u, 0u, ray.dir.y < 0.0) | select(1u, 0u, ray.dir.z < 0.0);
    let prims_at = bvh_nodes[0].x;
    var stack: array<vec2<u32>, WIDE_STACK>;
    var depth = 0u;
    // A group of nodes: x the first child node, y the children still to visit (bits 24-31,
    // at 24 + slot ^ oct_inv) over the parent's imask (bits 0-7). The root's group holds it
    // alone.
    var nodes = vec2<u32>(0u, 0x80000000u);
    // A group of primitives: x the first, y one bit for each still to test.
    var prims = vec2<u32>(0u, 0u);
    loop {
        // The primitives of the last leaf children hit: copies in leaf order, 3 records
        // each, the scene's index in the second's w.
        while (prims.y != 0u) {
            let k = firstTrailingBit(prims.y);
            prims.y = prims.y & (prims.y - 1u);
            let at = prims_at + 3u * (prims.x + k);
            let r0 = bvh_nodes[at];
            let r1 = bvh_nodes[at + 1u];
            let p = r1.w;
            if (HAS_TRIANGLES && (!HAS_SHAPES || (p & PRIM_SHAPE) == 0u)) {
                let r2 = bvh_nodes[at + 2u];
                let r = candidate_triangle_at(p, bitcast<vec3<f32>>(r0.xyz), bitcast<vec3<f32>>(r1.xyz), bitcast<vec3<f32>>(r2.xyz), r0.w, ray, hit.t);
                if (r.x != 0.0) {
                    hit = Hit(p, r.y, r.z, r.w, NO_INSTANCE);
                    if (any_hit) {
                        return hit;
                    }
                }
            } else if (HAS_SHAPES) {
                let r2 = bvh_nodes[at + 2u];
                let s = Shape(bitcast<vec3<f32>>(r0.xyz), bitcast<f32>(r0.w), bitcast<vec3<f32>>(r1.xyz), r2.x, 0u, 0u, 0u, 0u);
                let t = candidate_shape_at(p & ~PRIM_SHAPE, s, ray, hit.t);
                if (t > 0.0) {
                    hit = Hit(p, t, 0.0, 0.0, NO_INSTANCE);
                    if (any_hit) {
                        return hit;
                    }
                }
            }
        }
        if ((nodes.y & 0xff000000u) == 0u) {
            if (depth == 0u) {
                break;
            }
            depth = depth - 1u;
            nodes = stack[depth];
        }
        // The next child: the highest bit, then the rest of the group on the stack.
        let group = nodes.y;
        let bit = firstLeadingBit(group);
        nodes.y = group & ~(1u << bit);
        if ((nodes.y & 0xff000000u) != 0u) {
            stack[depth] = nodes;
            depth = depth + 1u;
        }
        let child_slot = (bit - 24u) ^ oct_inv;
        // Inner children are stored in slot order: count the inner slots below this one.
        let at = 1u + 5u * (nodes.x + countOneBits(group & ((1u << child_slot) - 1u) & 0xffu));
        let w0 = bvh_nodes[at];
        let w1 = bvh_nodes[at + 1u];
        let wx = bvh_nodes[at + 2u];
        let wy = bvh_nodes[at + 3u];
        let wz = bvh_nodes[at + 4u];
        let p = bitcast<vec3<f32>>(w0.xyz);
        let imask = w0.w >> 24u;
        // Grid step per axis: 2^(e - 127), the exponent a byte each.
        let step = vec3<f32>(
            bitcast<f32>((w0.w & 0xffu) << 23u),
            bitcast<f32>(((w0.w >> 8u) & 0xffu) << 23u),
            bitcast<f32>(((w0.w >> 16u) & 0xffu) << 23u),
        );
        // t of grid coordinate q along each axis: q * scale + offset.
        let scale = step * inv_dir;
        let offset = (p - ray.origin) * inv_dir;
        // Children 0-3 in the words' low halves' bytes (x, and z for the high bounds),
        // 4-7 in y and w.
        let hits = wide_children(0u, w1.z, wx.x, wx.z, wy.x, wy.z, wz.x, wz.z, imask, scale, offset, hit.t, oct_inv)
            | wide_children(4u, w1.w, wx.y, wx.w, wy.y, wy.w, wz.y, wz.w, imask, scale, offset, hit.t, oct_inv);
        nodes = vec2<u32>(w1.x, (hits & 0xff000000u) | imask);
        prims = vec2<u32>(w1.y, hits & 0x00ffffffu);
    }
    return hit;
}
