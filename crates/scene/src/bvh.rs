//! The BVH: built by [`obvhs`] (PLOC + reinsertion + leaf collapse) over the boxes of
//! triangles and spheres together, then flattened into [`GpuBvhNode`]s for the GPU.
//!
//! # Layout (32 bytes a node, two 16-byte loads)
//! Nodes are in depth-first order: the root is node 0 and an inner node's **first child is
//! the next node** (`i + 1`); only the second child's index is stored. Inner node
//! children are ordered so the first one has the lower centroid along the node's `axis`;
//! a ray with a negative direction component on that axis visits the second child first.
//!
//! | field | inner node | leaf |
//! |---|---|---|
//! | `aabb_min`, `aabb_max` | bounds of the subtree | bounds of its primitives |
//! | `index` | second child's node index | first primitive, in its kind's array (instances: the node slot of the first, see below) |
//! | `bits` bits 0–1 | split axis (0 x, 1 y, 2 z) | bit 0: kind instances ([`NODE_INSTANCES`]) |
//! | `bits` bit 2 | 0 | kind: 0 triangles (`tri_positions`), 1 spheres (`spheres`) |
//! | `bits` bits 3–31 | 0 (this is what makes it inner) | primitive count ≥ 1 |
//!
//! A leaf holds one kind only: when obvhs puts several kinds in one leaf, it is split into
//! inner nodes over one leaf per kind.
//!
//! # Instances (two levels)
//! A scene with instanced meshes has one BVH per mesh (the bottom level: over its triangles
//! in its own space, stored once) after the top-level one, whose leaves may hold instances.
//! Each instance ([`crate::gpu::GpuInstance`]: its transforms and its mesh's root) takes two
//! node slots after the last node, and an instance leaf's `index` is the slot of its first
//! instance (the next at `index + 2`). A ray meeting an instance leaf walks each instance's
//! bottom-level BVH with the ray in the mesh's space, then goes on past the leaf; a
//! bottom-level BVH's skip links end with [`BVH_END`] as the top level's do, which is where
//! the walk leaves the instance. Triangles and spheres are **reordered** so
//! that every leaf's primitives are contiguous in their array: no index indirection, one
//! load fewer per primitive. [`crate::GpuScene::tri_source`] maps back to the scene order.
//!
//! # Skip links (stackless traversal)
//! The traversal keeps no stack. A ray visits an inner node's children in the order its
//! direction's sign on the node's `axis` gives (the second child first when negative), so
//! the depth-first order in which a ray visits the nodes depends only on its direction's
//! octant (the signs of its three components). For each node and each of the 8 octants,
//! `FlatBvh::skips` holds the node that comes after the node's subtree in that order,
//! or [`BVH_END`]: where a ray goes after a leaf, or after an inner node whose box it
//! misses. After an inner node whose box it meets, it goes to the near child. This visits
//! the nodes in the order a stack traversal would (push the far child, pop after a leaf or
//! a miss), so hits are the same, without a per-ray stack array (which llvmpipe keeps in
//! scratch memory, one access per SIMD lane).
//!
//! Octant `o` has bit `a` set when the direction's component on axis `a` is `< 0`. On the
//! GPU each node is a 64-byte record: the 32-byte [`GpuBvhNode`], then its 8 skip links
//! (octants 0 to 7), so the link a ray needs is in the cache line of the node it has just
//! read. The recursive flattening refuses trees deeper than [`BVH_MAX_DEPTH`].

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;

use crate::error::{ErrorKind, SceneError};
use crate::gpu::GpuBvhNode;

/// Most inner nodes above a leaf; deeper trees are refused (the flattening recurses).
pub const BVH_MAX_DEPTH: usize = 64;

/// A skip link's value after the last node of an octant's order: the traversal ends.
pub const BVH_END: u32 = u32::MAX;

/// Ray octants, each with its own visit order.
pub const BVH_OCTANTS: usize = 8;

/// `bits` bit: the leaf holds spheres.
pub const NODE_SHAPES: u32 = 4;
/// `bits` bit: the leaf holds instances.
pub const NODE_INSTANCES: u32 = 1;
/// `bits` shift of the primitive count.
pub const NODE_COUNT_SHIFT: u32 = 3;

/// BVH build settings.
#[derive(Clone, Copy, Debug)]
pub struct BvhOptions {
    /// Most primitives in one leaf (1..=255); obvhs's collapse picks fewer where cheaper.
    pub max_leaf_size: u32,
    /// Relative cost of a node visit against a primitive test, for the leaf collapse.
    /// Higher gives bigger leaves.
    pub traversal_cost: f32,
}

impl Default for BvhOptions {
    fn default() -> Self {
        Self {
            max_leaf_size: 4,
            traversal_cost: 1.0,
        }
    }
}

/// The flattened tree and the primitive orders it implies.
#[derive(Clone, Debug, Default)]
pub(crate) struct FlatBvh {
    pub nodes: Vec<GpuBvhNode>,
    /// New triangle order: `tri_order[i]` is the input triangle stored at `i`.
    pub tri_order: Vec<u32>,
    /// New sphere order, likewise.
    pub shape_order: Vec<u32>,
    /// New instance order, likewise; an instance leaf's `index` is its first instance in
    /// this order until [`crate::GpuScene`] makes it a node slot.
    pub instance_order: Vec<u32>,
    /// For each node and ray octant, the node after its subtree in that octant's visit
    /// order, or [`BVH_END`] (see the module docs).
    pub skips: Vec<[u32; BVH_OCTANTS]>,
    /// Most inner nodes above a leaf.
    pub depth: usize,
}

/// The skip links of `nodes` (depth-first, first child adjacent, see the module docs).
pub fn skip_links(nodes: &[GpuBvhNode]) -> Vec<[u32; BVH_OCTANTS]> {
    let mut skips = vec![[BVH_END; BVH_OCTANTS]; nodes.len()];
    if nodes.is_empty() {
        return skips;
    }
    // (node, the node after its subtree); the explicit stack keeps deep trees off the
    // call stack.
    let mut todo = Vec::new();
    for octant in 0..BVH_OCTANTS {
        todo.push((0u32, BVH_END));
        while let Some((i, next)) = todo.pop() {
            skips[i as usize][octant] = next;
            let node = &nodes[i as usize];
            if node.bits >> NODE_COUNT_SHIFT == 0 {
                let (first, second) = (i + 1, node.index);
                let (near, far) = if (octant >> (node.bits & 3)) & 1 == 1 {
                    (second, first)
                } else {
                    (first, second)
                };
                todo.push((far, next));
                todo.push((near, far));
            }
        }
    }
    skips
}

/// Builds and flattens the BVH over `tri_boxes` (primitives `0..n`), `shape_boxes`
/// (primitives `n..`) and `instance_boxes` (after the spheres).
pub(crate) fn build(
    tri_boxes: &[Aabb],
    shape_boxes: &[Aabb],
    instance_boxes: &[Aabb],
    options: &BvhOptions,
) -> Result<FlatBvh, SceneError> {
    let n_tris = tri_boxes.len() as u32;
    let n_shapes = shape_boxes.len() as u32;
    let boxes: Vec<Aabb> = tri_boxes
        .iter()
        .chain(shape_boxes)
        .chain(instance_boxes)
        .copied()
        .collect();
    let mut flat = FlatBvh::default();
    if boxes.is_empty() {
        return Ok(flat);
    }
    let params = BvhBuildParams {
        max_prims_per_leaf: options.max_leaf_size.clamp(1, 255),
        collapse_traversal_cost: options.traversal_cost,
        ..BvhBuildParams::medium_build()
    };
    let bvh = obvhs::bvh2::builder::build_bvh2(&boxes, params, &mut Duration::default());
    let mut f = Flattener {
        bvh: &bvh,
        boxes: &boxes,
        n_tris,
        n_shapes,
        out: &mut flat,
    };
    f.node(0, 0)?;
    flat.skips = skip_links(&flat.nodes);
    Ok(flat)
}

struct Flattener<'a> {
    bvh: &'a Bvh2,
    boxes: &'a [Aabb],
    n_tris: u32,
    n_shapes: u32,
    out: &'a mut FlatBvh,
}

fn to3(v: Vec3A) -> [f32; 3] {
    Vec3::from(v).to_array()
}

impl Flattener<'_> {
    fn too_deep(depth: usize) -> Result<(), SceneError> {
        if depth > BVH_MAX_DEPTH {
            return Err(SceneError::new(ErrorKind::BvhTooDeep {
                depth,
                max: BVH_MAX_DEPTH,
            }));
        }
        Ok(())
    }

    /// Emits source node `src` and its subtree at `depth`; returns its output index.
    fn node(&mut self, src: usize, depth: usize) -> Result<u32, SceneError> {
        Self::too_deep(depth)?;
        self.out.depth = self.out.depth.max(depth);
        let n = &self.bvh.nodes[src];
        let at = self.out.nodes.len();
        self.out.nodes.push(GpuBvhNode::default());
        if n.is_leaf() {
            let first = n.first_index as usize;
            let prims = &self.bvh.primitive_indices[first..first + n.prim_count as usize];
            let mut kinds: [Vec<u32>; 3] = Default::default();
            for &p in prims {
                let kind = if p < self.n_tris {
                    0
                } else if p < self.n_tris + self.n_shapes {
                    1
                } else {
                    2
                };
                kinds[kind].push(p);
            }
            let groups: Vec<(usize, Vec<u32>)> = kinds
                .into_iter()
                .enumerate()
                .filter(|(_, g)| !g.is_empty())
                .collect();
            self.out.nodes.pop();
            self.kinds(&groups, depth)?;
            return Ok(at as u32);
        }
        let (mut a, mut b) = (n.first_index as usize, n.first_index as usize + 1);
        let ca = self.bvh.nodes[a].aabb().center();
        let cb = self.bvh.nodes[b].aabb().center();
        let d = (cb - ca).abs();
        let axis = if d.x >= d.y && d.x >= d.z {
            0
        } else if d.y >= d.z {
            1
        } else {
            2
        };
        if ca[axis] > cb[axis] {
            std::mem::swap(&mut a, &mut b);
        }
        self.node(a, depth + 1)?;
        let right = self.node(b, depth + 1)?;
        self.out.nodes[at] = GpuBvhNode {
            aabb_min: to3(n.aabb().min),
            index: right,
            aabb_max: to3(n.aabb().max),
            bits: axis as u32,
        };
        Ok(at as u32)
    }

    /// One leaf per kind of `groups` (kind 0 triangles, 1 spheres, 2 instances), under a
    /// chain of inner nodes where there are several; returns the first node's index.
    fn kinds(&mut self, groups: &[(usize, Vec<u32>)], depth: usize) -> Result<u32, SceneError> {
        Self::too_deep(depth)?;
        self.out.depth = self.out.depth.max(depth);
        let at = self.out.nodes.len();
        let [(kind, prims), rest @ ..] = groups else {
            unreachable!("a leaf has primitives");
        };
        if rest.is_empty() {
            let leaf = self.leaf(*kind, prims);
            self.out.nodes.push(leaf);
            return Ok(at as u32);
        }
        self.out.nodes.push(GpuBvhNode::default());
        let first = self.leaf(*kind, prims);
        self.out.nodes.push(first);
        let right = self.kinds(rest, depth + 1)?;
        let mut aabb = Aabb::empty();
        for (_, g) in groups {
            for &p in g {
                aabb = aabb.union(&self.boxes[p as usize]);
            }
        }
        self.out.nodes[at] = GpuBvhNode {
            aabb_min: to3(aabb.min),
            index: right,
            aabb_max: to3(aabb.max),
            bits: 0,
        };
        Ok(at as u32)
    }

    /// A leaf over `prims`, all of `kind`, appending them to that kind's order.
    fn leaf(&mut self, kind: usize, prims: &[u32]) -> GpuBvhNode {
        let mut aabb = Aabb::empty();
        for &p in prims {
            aabb = aabb.union(&self.boxes[p as usize]);
        }
        let (order, offset, bits) = match kind {
            0 => (&mut self.out.tri_order, 0, 0),
            1 => (&mut self.out.shape_order, self.n_tris, NODE_SHAPES),
            _ => (
                &mut self.out.instance_order,
                self.n_tris + self.n_shapes,
                NODE_INSTANCES,
            ),
        };
        let index = order.len() as u32;
        order.extend(prims.iter().map(|&p| p - offset));
        GpuBvhNode {
            aabb_min: to3(aabb.min),
            index,
            aabb_max: to3(aabb.max),
            bits: ((prims.len() as u32) << NODE_COUNT_SHIFT) | bits,
        }
    }
}
