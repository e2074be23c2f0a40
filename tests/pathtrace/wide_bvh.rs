//! The 8-wide compressed BVH (`plan`: "8-wide BVH"; `crates/render/src/wide_bvh.rs`,
//! `shaders/pathtrace/intersect/wide_bvh.wgsl`): CPU adapters traverse it where they traverse a BVH
//! in WGSL, GPU adapters the binary BVH, each as measured faster there
//! (`docs/benchmarks.md`); `--intersector wide` or `binary` (or a test's resources) asks for
//! one. Its hits are the binary BVH's: the same exact tests on the same primitives.

use crate::common;
use lumagraph::pathtrace::specialize::Tracing;

use lumagraph::pathtrace::intersect::wide_bvh::{WIDE_BVH_STACK, WideBvh};
use lumagraph::pathtrace::specialize::{Features, Intersector, PathTraceOptions, Specialization};
use lumagraph::render::Resources;
use lumagraph::scene::{GpuScene, PRIM_SHAPE, Scene};

fn scene(rel: &str) -> GpuScene {
    GpuScene::build(&Scene::load(&common::repo(rel)).unwrap()).unwrap()
}

/// The choice, without a device: a CPU adapter walks the wide BVH where it traverses one in
/// WGSL (not where it intersects a small scene inline or on the host), a GPU adapter the
/// binary one, and neither where ray queries trace the scene; `Intersector::WIDE_BVH` /
/// `BinaryBvh` (`--intersector wide` / `binary`) ask for either, over inline, host and ray
/// queries alike; the general shader never uses it. The shader traverses the wide BVH (`wide_bvh.wgsl`)
/// exactly where it is chosen, and the plan's reasons name the measurements.
#[test]
fn the_wide_bvh_is_chosen_on_cpu_adapters_and_where_asked() {
    let small = scene("assets/cornell_spheres.ron");
    let large = scene("tests/scenes/mesh_env.ron");
    let opts = |cpu: bool, ray_query_limit: Option<u32>, intersector| PathTraceOptions {
        specialize: true,
        cpu_adapter: cpu,
        ray_query_limit,
        intersector,
        ..PathTraceOptions::default()
    };
    let cases = [
        ("GPU", &large, opts(false, None, Intersector::AUTO), false),
        (
            "GPU, asked",
            &large,
            opts(false, None, Intersector::WIDE_BVH),
            true,
        ),
        (
            "GPU, small scene, asked",
            &small,
            opts(false, None, Intersector::WIDE_BVH),
            true,
        ),
        (
            "GPU with ray queries",
            &large,
            opts(false, Some(1 << 24), Intersector::AUTO),
            false,
        ),
        (
            "GPU with ray queries, asked",
            &large,
            opts(false, Some(1 << 24), Intersector::WIDE_BVH),
            true,
        ),
        ("CPU", &large, opts(true, None, Intersector::AUTO), true),
        (
            "CPU, binary asked for",
            &large,
            opts(true, None, Intersector::BINARY_BVH),
            false,
        ),
        (
            "CPU, small scene",
            &small,
            opts(true, None, Intersector::AUTO),
            false,
        ),
        (
            "CPU, small scene, asked",
            &small,
            opts(true, None, Intersector::WIDE_BVH),
            true,
        ),
        (
            "CPU with a host intersector",
            &large,
            PathTraceOptions {
                host_rays: true,
                ..opts(true, None, Intersector::AUTO)
            },
            false,
        ),
        (
            // The host cannot trace spheres: the adapter's choice, inline, as unasked.
            "CPU, small scene of spheres, the host asked for",
            &small,
            PathTraceOptions {
                host_rays: true,
                ..opts(true, None, Intersector::HOST)
            },
            false,
        ),
        (
            "CPU with a host intersector, asked",
            &large,
            PathTraceOptions {
                host_rays: true,
                ..opts(true, None, Intersector::WIDE_BVH)
            },
            true,
        ),
        (
            "general shader, asked",
            &large,
            PathTraceOptions {
                specialize: false,
                ..opts(false, None, Intersector::WIDE_BVH)
            },
            false,
        ),
    ];
    for (what, scene, options, expected) in cases {
        let f = Features::decide(scene, options);
        let wide = f.intersector() == Intersector::WIDE_BVH;
        println!("{what}: {wide} ({})", f.why(Intersector::WIDE_BVH));
        assert_eq!(wide, expected, "{what}: {}", f.summary());
        let source = Specialization::new(scene, options).source().unwrap();
        assert_eq!(source.contains("WIDE_ROBUST_FAR"), expected, "{what}");
    }
    for (cpu, measured_on) in [(false, "H200"), (true, "lavapipe")] {
        let f = Features::decide(&large, opts(cpu, None, Intersector::AUTO));
        let why = f.why(Intersector::WIDE_BVH);
        assert!(why.contains(measured_on), "{why}");
    }
}

/// One node of the packed records, as the shader reads it.
struct Node {
    p: [f32; 3],
    step: [f32; 3],
    imask: u32,
    child_base: u32,
    prim_base: u32,
    info: [u8; 8],
    /// Per axis, per child: the low and high grid bounds.
    lo: [[u8; 8]; 3],
    hi: [[u8; 8]; 3],
}

fn node(records: &[[u32; 4]], i: usize) -> Node {
    let w: Vec<u32> = records[1 + 5 * i..6 + 5 * i]
        .iter()
        .flatten()
        .copied()
        .collect();
    let bytes = |k: usize| -> [u8; 8] {
        let mut b = [0u8; 8];
        b[..4].copy_from_slice(&w[k].to_le_bytes());
        b[4..].copy_from_slice(&w[k + 1].to_le_bytes());
        b
    };
    Node {
        p: [
            f32::from_bits(w[0]),
            f32::from_bits(w[1]),
            f32::from_bits(w[2]),
        ],
        step: [0, 8, 16].map(|s| f32::from_bits(((w[3] >> s) & 0xff) << 23)),
        imask: w[3] >> 24,
        child_base: w[4],
        prim_base: w[5],
        info: bytes(6),
        lo: [bytes(8), bytes(12), bytes(16)],
        hi: [bytes(10), bytes(14), bytes(18)],
    }
}

/// Walks node `i`: every primitive below child slot `k` must lie inside that child's box
/// as the shader decodes it (corner plus grid bound times step). Appends the primitives
/// found and returns their exact box and the subtree's depth.
fn check_node(
    scene: &GpuScene,
    records: &[[u32; 4]],
    i: usize,
    found: &mut Vec<u32>,
) -> ([f32; 3], [f32; 3], usize) {
    let n = node(records, i);
    let prims_at = records[0][0] as usize;
    let (mut lo_all, mut hi_all) = ([f32::MAX; 3], [f32::MIN; 3]);
    let mut depth = 1;
    let mut inner_seen = 0;
    for k in 0..8 {
        let info = n.info[k];
        if info == 0 {
            continue;
        }
        let (lo, hi, d) = if n.imask >> k & 1 == 1 {
            let child = n.child_base as usize + inner_seen;
            inner_seen += 1;
            check_node(scene, records, child, found)
        } else {
            let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
            let count = (info >> 5).count_ones();
            for j in 0..count {
                let slot = n.prim_base as usize + usize::from(info & 31) + j as usize;
                let record = &records[prims_at + 3 * slot..prims_at + 3 * slot + 3];
                let p = record[1][3];
                found.push(p);
                // The copy is the scene's primitive, bit for bit.
                if p & PRIM_SHAPE == 0 {
                    let t = &scene.tri_positions[p as usize];
                    let bits = |a: [f32; 3]| a.map(f32::to_bits);
                    assert_eq!(record[0][..3], bits(t.v0));
                    assert_eq!(record[0][3], t.flags);
                    assert_eq!(record[1][..3], bits(t.e1));
                    assert_eq!(record[2][..3], bits(t.e2));
                } else {
                    let sp = &scene.shapes[(p & !PRIM_SHAPE) as usize];
                    assert_eq!(record[0][..3], sp.center.map(f32::to_bits));
                    assert_eq!(record[0][3], sp.radius.to_bits());
                }
                let (a, b) = exact_box(scene, p);
                for c in 0..3 {
                    lo[c] = lo[c].min(a[c]);
                    hi[c] = hi[c].max(b[c]);
                }
            }
            (lo, hi, 0)
        };
        depth = depth.max(d + 1);
        for c in 0..3 {
            let box_lo = f32::from(n.lo[c][k]).mul_add(n.step[c], n.p[c]);
            let box_hi = f32::from(n.hi[c][k]).mul_add(n.step[c], n.p[c]);
            assert!(
                box_lo <= lo[c] && hi[c] <= box_hi,
                "node {i} child {k} axis {c}: box {box_lo}..{box_hi} does not hold {}..{}",
                lo[c],
                hi[c]
            );
            lo_all[c] = lo_all[c].min(lo[c]);
            hi_all[c] = hi_all[c].max(hi[c]);
        }
    }
    assert_eq!(inner_seen as u32, n.imask.count_ones(), "node {i}");
    (lo_all, hi_all, depth)
}

/// The unpadded box of primitive `p` (a triangle's index, or a shape's `| PRIM_SHAPE`).
fn exact_box(scene: &GpuScene, p: u32) -> ([f32; 3], [f32; 3]) {
    use glam::Vec3;
    if p & PRIM_SHAPE != 0 {
        let s = &scene.shapes[(p & !PRIM_SHAPE) as usize];
        let [lo, hi] = lumagraph::scene::shapes::KINDS[s.kind as usize].bounds(s);
        (lo.to_array(), hi.to_array())
    } else {
        let t = &scene.tri_positions[p as usize];
        let v0 = Vec3::from(t.v0);
        let (v1, v2) = (v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2));
        (v0.min(v1).min(v2).to_array(), v0.max(v1).max(v2).to_array())
    }
}

/// The packed tree, decoded as the shader decodes it: every triangle and sphere is in
/// exactly one leaf, and every child's box on its parent's grid holds all the primitives
/// below it (the builder rounds bounds outwards, the primitives' boxes are padded); the
/// depth it reports is the tree's and within the traversal's stack.
#[test]
fn every_primitive_sits_inside_its_ancestors_boxes() {
    for rel in [
        "assets/cornell.ron",
        "assets/cornell_spheres.ron",
        "assets/furnace_materials.ron",
        "tests/scenes/mesh_env.ron",
        "tests/scenes/disk.ron",
    ] {
        let s = scene(rel);
        let bvh = WideBvh::build(&s).unwrap();
        let mut found = Vec::new();
        let (_, _, depth) = check_node(&s, &bvh.records, 0, &mut found);
        found.sort_unstable();
        let mut expected: Vec<u32> = (0..s.tri_positions.len() as u32)
            .chain((0..s.shapes.len() as u32).map(|i| i | PRIM_SHAPE))
            .collect();
        expected.sort_unstable();
        println!(
            "{rel}: {} primitives, {} nodes, {} deep, {} bytes",
            found.len(),
            bvh.nodes,
            bvh.depth,
            bvh.bytes
        );
        assert_eq!(found, expected, "{rel}: primitives missing or repeated");
        assert_eq!(depth, bvh.depth, "{rel}");
        assert!(bvh.depth <= WIDE_BVH_STACK, "{rel}");
        assert_eq!(records_nodes(&bvh), bvh.nodes, "{rel}");
    }
}

fn records_nodes(bvh: &WideBvh) -> usize {
    bvh.records[0][1] as usize
}

/// The wide BVH against the binary one, both as a GPU adapter runs them, on scenes that
/// exercise the intersector contract: triangles and an area light (Cornell box: shadow
/// rays), triangles and spheres in one tree (leaves of both kinds), disk lights and a disk
/// among triangles and a sphere, spheres under an
/// environment with every lobe (rays entering and leaving spheres), 5 120 triangles under an
/// environment map, a scattering medium (`intersect_scene_within`). The same exact tests on
/// the same primitives: the first-hit depth is bit-identical, albedo and normal differ only
/// at ties (`common::same_hits`), and the colors agree but where a jittered ray meets a tie.
#[test]
fn the_wide_bvh_renders_what_the_binary_bvh_renders() {
    let wide = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        intersector: Intersector::WIDE_BVH,
        ..Tracing::default()
    });
    let binary = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        intersector: Intersector::BINARY_BVH,
        ..Tracing::default()
    });
    for name in [
        "cornell.ron",
        "cornell_spheres.ron",
        "furnace_materials.ron",
        "../tests/scenes/mesh_env.ron",
        "../tests/scenes/media_scattering.ron",
        "../tests/scenes/disk.ron",
    ] {
        let Some((far, mean)) = common::same_hits(name, wide.clone(), binary.clone(), |a, b| {
            assert_eq!(a.intersector(), Intersector::WIDE_BVH, "{}", a.summary());
            assert_eq!(b.intersector(), Intersector::BINARY_BVH, "{}", b.summary());
        }) else {
            return;
        };
        assert!(far <= 4, "{name}: {far} pixels differ beyond 1e-4");
        assert!(mean.abs() <= 1e-4, "{name}: means differ by {mean:.2e}");
    }
}
