//! The 8-wide compressed BVH (CWBVH, Ylitie, Karras and Laine, "Efficient Incoherent Ray
//! Traversal on GPUs Through Compressed Wide BVHs", HPG 2017) that `pathtrace/intersect/wide_bvh.wgsl`
//! traverses where the plan's intersector is `wide` ([`WideBvhKind`], [`Intersector::WIDE_BVH`]).
//! [`obvhs`] builds it (PLOC, reinsertion, then the conversion to eight children per node,
//! up to three primitives per leaf) over the same padded boxes the device's acceleration
//! structure gets ([`super::primitive_boxes`]); this module packs it into one storage buffer that
//! takes the binary BVH's binding.
//!
//! # Layout (`vec4<u32>` records)
//! | records | what |
//! |---|---|
//! | 0 | header: x = the record where the primitive list starts, y = node count, z = depth |
//! | 1 + 5 i .. 1 + 5 i + 5 | node i: obvhs's 80-byte `CwBvhNode`, byte for byte |
//! | `x` + 3 j .. `x` + 3 j + 3 | leaf slot j's primitive, copied from the scene in leaf order: a triangle's `GpuTriangle` (v0 and flags, e1, e2) with its index in `tri_positions` in the second record's w; a shape's center and radius, its axis and its index `| PRIM_SHAPE` (second record), its kind (third record's x) |
//!
//! A node (80 bytes): its box's corner `p` (3 f32) and per axis the exponent of the child
//! grid's step (a byte each) and `imask` (which children are inner nodes); the first child
//! node and first primitive; one meta byte per child (inner: `0b001` then 24 + slot; leaf:
//! its primitive count in unary in the top 3 bits, its first primitive's offset below); then
//! the children's boxes on the node's 256-step grid, a byte a bound, per axis and side.
//! Children are visited nearest first by the ray's octant (the paper's "octant order").
//! The leaves' primitives are copies, in leaf order, so a leaf's are read from the records
//! next to each other, with no index to follow; their index in the scene's arrays rides
//! along for the hit, the shading data and the any-hit test.
//! The primitives' boxes are the ones [`super::primitive_boxes`] pads, and the conversion rounds
//! child bounds outwards, so a child's box holds whatever the exact tests can hit in it.

use glam::Vec3;
use lumagraph_scene::GpuScene;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use wgpu::util::DeviceExt as _;

use super::{Intersector, IntersectorKind, Traversal};
use lumagraph_render::context::GpuContext;
use lumagraph_render::error::{RenderError, Result};
use crate::specialize::PathTraceOptions;
use crate::specialize::support::Content;

/// Most nodes on a path from the root: the traversal's stack holds one entry a level.
pub const WIDE_BVH_STACK: usize = 32;

/// `pathtrace/intersect/wide_bvh.wgsl`'s shape bit in the primitive list (the shader's `PRIM_SHAPE`).
const PRIM_SHAPE: u32 = lumagraph_scene::PRIM_SHAPE;

/// A scene's wide BVH, packed for the GPU.
#[derive(Clone, Debug)]
pub struct WideBvh {
    /// The buffer's records (see the module docs).
    pub records: Vec<[u32; 4]>,
    /// Nodes.
    pub nodes: usize,
    /// Most nodes on a path from the root.
    pub depth: usize,
    /// The buffer's size in bytes.
    pub bytes: u64,
}

impl WideBvh {
    /// Builds the wide BVH over `scene`'s triangles and spheres.
    ///
    /// # Errors
    /// A message when the tree is deeper than the traversal's stack ([`WIDE_BVH_STACK`]).
    pub fn build(scene: &GpuScene) -> Result<Self, String> {
        if !scene.instances.is_empty() {
            return Err(crate::embree::flat_only("the 8-wide BVH", scene));
        }
        let (tri_boxes, shape_boxes) = super::primitive_boxes(scene);
        let n_tris = u32::try_from(tri_boxes.len()).map_err(|_| "too many triangles")?;
        let boxes: Vec<Aabb> = tri_boxes
            .iter()
            .chain(&shape_boxes)
            .map(|b| {
                Aabb::new(
                    Vec3::from_slice(&b[..3]).into(),
                    Vec3::from_slice(&b[3..]).into(),
                )
            })
            .collect();
        let params = obvhs::BvhBuildParams {
            max_prims_per_leaf: 3,
            ..obvhs::BvhBuildParams::medium_build()
        };
        let bvh = if boxes.is_empty() {
            CwBvh::default()
        } else {
            obvhs::cwbvh::builder::build_cwbvh(&boxes, params, &mut std::time::Duration::default())
        };
        let depth = depth(&bvh);
        if depth > WIDE_BVH_STACK {
            return Err(format!(
                "the 8-wide BVH is {depth} nodes deep, over the traversal's stack of {WIDE_BVH_STACK}"
            ));
        }
        let prims_at = 1 + 5 * bvh.nodes.len();
        let mut records = Vec::with_capacity(prims_at + 3 * bvh.primitive_indices.len());
        records.push([
            u32::try_from(prims_at).map_err(|_| "too many nodes")?,
            u32::try_from(bvh.nodes.len()).map_err(|_| "too many nodes")?,
            u32::try_from(depth).unwrap_or(u32::MAX),
            0,
        ]);
        records.extend(
            bvh.nodes
                .iter()
                .flat_map(|n| bytemuck::cast::<_, [[u32; 4]; 5]>(*n)),
        );
        for &p in &bvh.primitive_indices {
            if p < n_tris {
                let t = &scene.tri_positions[p as usize];
                let v = |a: [f32; 3], w: u32| [a[0].to_bits(), a[1].to_bits(), a[2].to_bits(), w];
                records.extend([v(t.v0, t.flags), v(t.e1, p), v(t.e2, 0)]);
            } else {
                let i = p - n_tris;
                let sp = &scene.shapes[i as usize];
                let (c, a) = (sp.center.map(f32::to_bits), sp.axis.map(f32::to_bits));
                records.extend([
                    [c[0], c[1], c[2], sp.radius.to_bits()],
                    [a[0], a[1], a[2], i | PRIM_SHAPE],
                    [sp.kind, 0, 0, 0],
                ]);
            }
        }
        if records.len() == 1 {
            // An empty scene: one node record with no children, which rays miss.
            records.extend([[0u32; 4]; 5]);
        }
        let bytes = std::mem::size_of_val(&records[..]) as u64;
        Ok(Self {
            records,
            nodes: bvh.nodes.len(),
            depth,
            bytes,
        })
    }
}

/// Uploads `bvh`'s records into a storage buffer.
///
/// # Errors
/// [`RenderError::TooLarge`] when they exceed the device's largest storage binding.
pub fn upload(ctx: &GpuContext, bvh: &WideBvh) -> Result<wgpu::Buffer> {
    let limits = ctx.device.limits();
    let binding = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if bvh.bytes > binding {
        return Err(RenderError::TooLarge {
            what: format!("scene part \"8-wide BVH\": {} nodes", bvh.nodes),
            adapter: ctx.info.name.clone(),
            message: format!(
                "{} in one storage buffer, over the adapter's largest storage binding of {}; \
                 `--intersector binary` traverses the binary BVH",
                lumagraph_render::human_bytes(bvh.bytes),
                lumagraph_render::human_bytes(binding)
            ),
        });
    }
    Ok(ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("8-wide BVH"),
            contents: bytemuck::cast_slice(&bvh.records),
            usage: wgpu::BufferUsages::STORAGE,
        }))
}

/// Most nodes on a path from the root (0 for an empty tree).
fn depth(bvh: &CwBvh) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut todo = vec![(0usize, 1usize)];
    while let Some((i, d)) = todo.pop() {
        deepest = deepest.max(d);
        let n = &bvh.nodes[i];
        let inner = u32::from(n.imask).count_ones() as usize;
        for k in 0..inner {
            todo.push((n.child_base_idx as usize + k, d + 1));
        }
    }
    deepest
}

impl Intersector {
    /// The 8-wide compressed BVH traversed in WGSL (`pathtrace/intersect/wide_bvh.wgsl`).
    pub const WIDE_BVH: Self = Self::named("wide");
}

/// Why a CPU adapter traverses the 8-wide BVH unless asked otherwise: measured in
/// `docs/benchmarks.md` ("The 8-wide BVH on lavapipe").
const CPU_REASON: &str = "a CPU adapter: the 8-wide BVH measured 2.3x the binary \
     one's paths/s on Sponza and 1.4x on an 82 k-triangle mesh on lavapipe \
     (--intersector binary asks for the binary one)";

/// Why a GPU adapter traverses the binary BVH unless asked otherwise: measured in
/// `docs/benchmarks.md` ("The 8-wide BVH against the binary one").
const GPU_REASON: &str = "the binary BVH: the 8-wide one measured 0.82x on Sponza \
     and 1.01x on a 1.3 M-triangle mesh on an NVIDIA H200 (--intersector wide asks for it)";

/// The 8-wide BVH as an intersector: the adapter's choice on CPU adapters wherever the
/// host does not trace; its records are bound in the binary BVH's place.
pub struct WideBvhKind;

impl IntersectorKind for WideBvhKind {
    fn intersector(&self) -> Intersector {
        Intersector::WIDE_BVH
    }

    fn describe(&self) -> &'static str {
        "the 8-wide BVH"
    }

    fn how(&self) -> &'static str {
        "8-wide BVH traversal"
    }

    fn traces(&self) -> [bool; Content::ALL.len()] {
        use Content as C;
        Content::ALL.map(|c| !matches!(c, C::GeneralShader | C::Instances))
    }

    fn auto(&self, _scene: &GpuScene, options: PathTraceOptions) -> Result<String, String> {
        if options.cpu_adapter {
            Ok(CPU_REASON.to_owned())
        } else {
            Err(GPU_REASON.to_owned())
        }
    }

    fn wgsl(&self, _scene: &GpuScene, _alpha: bool) -> Option<String> {
        Some("#import \"pathtrace/intersect/wide_bvh.wgsl\"\n".to_owned())
    }

    fn build(
        &self,
        ctx: &GpuContext,
        scene: &std::sync::Arc<GpuScene>,
    ) -> Result<Box<dyn Traversal>> {
        let start = std::time::Instant::now();
        let mut bvh = WideBvh::build(scene).map_err(|e| {
            RenderError::Gpu(format!("{e} (--intersector binary traverses the binary BVH)"))
        })?;
        let took = start.elapsed();
        let buffer = upload(ctx, &bvh)?;
        bvh.records = Vec::new();
        Ok(Box::new(Built { buffer, bvh, took }))
    }
}

/// The 8-wide BVH's buffer (bound in the binary BVH's place), with its node count, depth,
/// size and build time.
struct Built {
    buffer: wgpu::Buffer,
    bvh: WideBvh,
    took: std::time::Duration,
}

impl Traversal for Built {
    fn bvh_nodes(&self) -> Option<&wgpu::Buffer> {
        Some(&self.buffer)
    }

    fn note(&self, _scene: &GpuScene) -> Option<String> {
        Some(format!(
            "8-wide BVH: {} nodes, {} deep, {} built in {:.1} ms",
            self.bvh.nodes,
            self.bvh.depth,
            lumagraph_render::human_bytes(self.bvh.bytes),
            self.took.as_secs_f64() * 1e3
        ))
    }
}
