//! The BVH traversal over the flat GPU layout agrees with brute force.

mod common;

use std::time::Instant;

use glam::{Mat4, Vec3};
use lumagraph_scene::import::import_mesh;
use lumagraph_scene::traverse::{intersect_brute_force, ray_aabb, safe_inverse};
use lumagraph_scene::{
    Environment, GpuScene, Hit, Material, Ray, RenderSettings, Scene, Shape, intersect,
    intersect_within, occluded,
};

fn sphere_grid_scene() -> Scene {
    let path = common::assets().join("SphereGrids/SphereGrid_MetalRough.gltf");
    let mesh = import_mesh(&path, Mat4::IDENTITY).unwrap();
    let mut materials = mesh.materials;
    materials.push(Material {
        emission: Vec3::ONE,
        ..Material::named("glow")
    });
    let glow = materials.len() as u32 - 1;
    // Spheres between and in front of the grid's spheres, one overlapping a mesh sphere,
    // and disks turned every way among them.
    let mut shapes = Vec::new();
    for i in 0..8 {
        let f = i as f32;
        shapes.push(Shape::sphere(
            Vec3::new(-2.4 + 0.6 * f, 0.6 * (f - 3.5), 0.3 * (f - 4.0)),
            0.15 + 0.05 * f,
            if i % 3 == 0 { glow } else { 0 },
        ));
    }
    shapes.push(Shape::sphere(Vec3::new(0.0, 0.0, 0.4), 0.3, 1));
    for i in 0..6 {
        let f = i as f32;
        shapes.push(Shape {
            kind: lumagraph_scene::shapes::DISK,
            center: Vec3::new(2.0 - 0.8 * f, 1.5 - 0.5 * f, 0.5),
            radius: 0.2 + 0.1 * f,
            axis: Vec3::new(f.sin(), 0.5, f.cos()).normalize(),
            material: if i % 2 == 0 { glow } else { 1 },
        });
    }
    Scene {
        camera: lumagraph_scene::Camera {
            position: Vec3::new(0.0, 0.0, 8.0),
            forward: Vec3::NEG_Z,
            up: Vec3::Y,
            fov_y_deg: 40.0,
            aperture_radius: 0.0,
            focus_distance: 8.0,
            autofocus: false,
        },
        materials,
        triangles: mesh.triangles,
        instanced: Vec::new(),
        lights: Vec::new(),
        textures: Vec::new(),
        shapes,
        environment: Environment::None,
        settings: RenderSettings {
            width: 64,
            height: 64,
            max_bounces: 20,
            spp: 1,
            seed: 0,
            texture_mips: true,
        },
        report: mesh.report,
        stats: lumagraph_scene::LoadStats::default(),
    }
}

fn random_ray(rng: &mut common::Pcg) -> Ray {
    let origin = Vec3::new(
        rng.range(-4.0, 4.0),
        rng.range(-4.0, 4.0),
        rng.range(-4.0, 4.0),
    );
    // Half the rays aim at a point of the grid, half go anywhere.
    let dir = if rng.f32() < 0.5 {
        let target = Vec3::new(
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
            rng.range(-0.6, 0.6),
        );
        target - origin
    } else {
        let z = rng.range(-1.0, 1.0);
        let phi = rng.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    // Some axis-aligned rays, which exercise the zero-direction path of the slab test.
    match rng.next_u32() % 16 {
        0 => Ray {
            origin,
            dir: Vec3::new(0.0, 0.0, -dir.z.signum()),
        },
        1 => Ray {
            origin,
            dir: Vec3::new(dir.x, 0.0, 0.0),
        },
        _ => Ray { origin, dir },
    }
}

/// An exact reference that shares no code with the BVH: the triangles in scene order, cut
/// into chunks of 64 consecutive ones (strips of one UV sphere); a chunk is scanned
/// triangle by triangle whenever the ray meets its box, padded and tested in f64 so the
/// culling is conservative. Spheres are always tested.
struct Reference {
    chunks: Vec<([f64; 3], [f64; 3], Vec<u32>)>,
}

impl Reference {
    fn new(g: &GpuScene) -> Self {
        let mut by_source = vec![0u32; g.tri_source.len()];
        for (gpu, &src) in g.tri_source.iter().enumerate() {
            by_source[src as usize] = gpu as u32;
        }
        let chunks = by_source
            .chunks(64)
            .map(|ids| {
                let mut lo = [f64::INFINITY; 3];
                let mut hi = [f64::NEG_INFINITY; 3];
                for &i in ids {
                    let t = g.tri_positions[i as usize];
                    let v0 = Vec3::from(t.v0);
                    for p in [v0, v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2)] {
                        for k in 0..3 {
                            lo[k] = lo[k].min(f64::from(p[k]));
                            hi[k] = hi[k].max(f64::from(p[k]));
                        }
                    }
                }
                for k in 0..3 {
                    let pad = 1e-4 * (hi[k] - lo[k]) + 1e-5;
                    lo[k] -= pad;
                    hi[k] += pad;
                }
                (lo, hi, ids.to_vec())
            })
            .collect();
        Self { chunks }
    }

    fn meets(lo: &[f64; 3], hi: &[f64; 3], ray: &Ray) -> bool {
        let (mut near, mut far) = (0.0f64, f64::INFINITY);
        for k in 0..3 {
            let o = f64::from(ray.origin[k]);
            let d = f64::from(ray.dir[k]);
            if d == 0.0 {
                if o < lo[k] || o > hi[k] {
                    return false;
                }
                continue;
            }
            let (a, b) = ((lo[k] - o) / d, (hi[k] - o) / d);
            near = near.max(a.min(b));
            far = far.min(a.max(b));
        }
        near <= far
    }

    fn intersect(&self, g: &GpuScene, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut t_max = f32::MAX;
        for (lo, hi, ids) in &self.chunks {
            if !Self::meets(lo, hi, ray) {
                continue;
            }
            for &i in ids {
                let t = g.tri_positions[i as usize];
                let r = lumagraph_scene::traverse::intersect_triangle(
                    ray.origin,
                    ray.dir,
                    Vec3::from(t.v0),
                    Vec3::from(t.e1),
                    Vec3::from(t.e2),
                    t_max,
                );
                if let Some((t, u, v)) = r {
                    t_max = t;
                    best = Some(Hit {
                        prim: i,
                        t,
                        u,
                        v,
                        inst: lumagraph_scene::NO_INSTANCE,
                    });
                }
            }
        }
        for (i, s) in g.shapes.iter().enumerate() {
            let r = lumagraph_scene::shapes::KINDS[s.kind as usize]
                .intersect(s, ray.origin, ray.dir, t_max);
            if let Some(t) = r {
                t_max = t;
                best = Some(Hit {
                    prim: i as u32 | lumagraph_scene::PRIM_SHAPE,
                    t,
                    u: 0.0,
                    v: 0.0,
                    inst: lumagraph_scene::NO_INSTANCE,
                });
            }
        }
        best
    }
}

fn check(g: &GpuScene, rays: &[Ray], reference: Option<&Reference>) -> (usize, usize) {
    let mut hits = 0;
    let mut ties = 0;
    for ray in rays {
        let fast = intersect(g, ray);
        let slow = match reference {
            Some(r) => r.intersect(g, ray),
            None => intersect_brute_force(g, ray, f32::MAX),
        };
        match (fast, slow) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                hits += 1;
                assert!(
                    (a.t - b.t).abs() <= 1e-5 * b.t.abs(),
                    "t differs for {ray:?}: bvh {a:?}, brute {b:?}"
                );
                if a.prim != b.prim {
                    // Two primitives at the same distance (a shared edge): either is right.
                    ties += 1;
                }
                if a.prim == b.prim {
                    assert_eq!((a.u, a.v), (b.u, b.v));
                }
            }
            (a, b) => panic!("{ray:?}: bvh {a:?}, brute {b:?}"),
        }
        // Shadow rays agree with the closest hit.
        if let Some(Hit { t, .. }) = slow {
            assert!(occluded(g, ray, t * 1.0001), "{ray:?}");
            assert!(!occluded(g, ray, t * 0.9999), "{ray:?}");
            assert_eq!(intersect_within(g, ray, t * 0.9999), None);
        } else {
            assert!(!occluded(g, ray, f32::MAX));
        }
    }
    (hits, ties)
}

fn check_parallel(g: &GpuScene, rays: &[Ray], reference: Option<&Reference>) -> (usize, usize) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get().min(4));
    let chunk = rays.len().div_ceil(threads);
    std::thread::scope(|s| {
        let handles: Vec<_> = rays
            .chunks(chunk)
            .map(|c| s.spawn(move || check(g, c, reference)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap())
            .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    })
}

/// 100 000 random rays against the exact chunked reference, and the first 2 000 of them
/// against plain brute force over every primitive (which also checks the reference).
#[test]
fn bvh_agrees_with_brute_force_on_100k_rays() {
    let scene = sphere_grid_scene();
    let start = Instant::now();
    let g = GpuScene::build(&scene).unwrap();
    let build = start.elapsed();
    assert_eq!(g.tri_positions.len(), scene.triangles.len());
    assert_eq!(g.shapes.len(), 15);
    assert_eq!(g.lights.len(), 6);
    assert!(g.header.bvh_depth as usize <= lumagraph_scene::BVH_MAX_DEPTH);

    let mut rng = common::Pcg::new(7);
    let rays: Vec<Ray> = (0..100_000).map(|_| random_ray(&mut rng)).collect();
    let start = Instant::now();
    let found = rays.iter().filter(|r| intersect(&g, r).is_some()).count();
    eprintln!(
        "BVH alone: 100k closest-hit queries in {:?} on one thread ({found} hits)",
        start.elapsed()
    );
    let start = Instant::now();
    let (brute_hits, _) = check_parallel(&g, &rays[..2000], None);
    let brute_time = start.elapsed();
    let start = Instant::now();
    let reference = Reference::new(&g);
    let (hits, ties) = check_parallel(&g, &rays, Some(&reference));
    eprintln!("2000 rays against brute force in {brute_time:?} ({brute_hits} hits)");
    eprintln!(
        "{} triangles, {} nodes, depth {}, build {build:?}; 100k rays checked in {:?} \
         ({hits} hits, {ties} ties)",
        g.tri_positions.len(),
        g.bvh_nodes.len(),
        g.header.bvh_depth,
        start.elapsed()
    );
    assert!(hits > 30_000, "{hits}");
    assert!(ties < 100, "{ties}");
}

#[test]
fn bvh_structure_is_consistent() {
    let scene = sphere_grid_scene();
    let g = GpuScene::build(&scene).unwrap();
    // Every primitive is in exactly one leaf; children lie inside their parent's box.
    let mut tri_seen = vec![0u32; g.tri_positions.len()];
    let mut sphere_seen = vec![0u32; g.shapes.len()];
    let mut stack = vec![(0usize, 0usize)];
    let mut max_depth = 0;
    while let Some((i, depth)) = stack.pop() {
        max_depth = max_depth.max(depth);
        let n = g.bvh_nodes[i];
        let count = n.bits >> 3;
        if count == 0 {
            for c in [i + 1, n.index as usize] {
                let child = g.bvh_nodes[c];
                for k in 0..3 {
                    assert!(
                        child.aabb_min[k] >= n.aabb_min[k] && child.aabb_max[k] <= n.aabb_max[k]
                    );
                }
                stack.push((c, depth + 1));
            }
        } else {
            let seen = if n.bits & 4 == 0 {
                &mut tri_seen
            } else {
                &mut sphere_seen
            };
            for p in n.index..n.index + count {
                seen[p as usize] += 1;
            }
        }
    }
    assert!(tri_seen.iter().all(|&c| c == 1));
    assert!(sphere_seen.iter().all(|&c| c == 1));
    assert_eq!(max_depth, g.header.bvh_depth as usize);
    // The source maps are permutations.
    let mut src = g.tri_source.clone();
    src.sort_unstable();
    assert!(src.iter().enumerate().all(|(i, &s)| s == i as u32));
    // Leaves are small.
    let leaves = g.bvh_nodes.iter().filter(|n| n.bits >> 3 != 0).count();
    let mean = (g.tri_positions.len() + g.shapes.len()) as f32 / leaves as f32;
    eprintln!(
        "{} nodes, {leaves} leaves, {mean:.2} primitives a leaf",
        g.bvh_nodes.len()
    );
    assert!(mean <= 4.0);
}

#[test]
fn skip_links_follow_each_octants_stack_order() {
    let scene = sphere_grid_scene();
    let g = GpuScene::build(&scene).unwrap();
    assert_eq!(g.bvh_skips.len(), g.bvh_nodes.len());
    for octant in 0..8u32 {
        // The order a stack traversal that enters every box visits the nodes in: near child
        // first, where near is the second child when the octant's bit for the axis is set.
        let mut order = Vec::new();
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            order.push(i);
            let n = g.bvh_nodes[i as usize];
            if n.bits >> 3 == 0 {
                let (near, far) = if (octant >> (n.bits & 3)) & 1 == 1 {
                    (n.index, i + 1)
                } else {
                    (i + 1, n.index)
                };
                stack.push(far);
                stack.push(near);
            }
        }
        assert_eq!(order.len(), g.bvh_nodes.len());
        // Skip links entering every box: a leaf goes to its skip link, an inner node to its
        // near child. The same walk.
        let mut walk = Vec::new();
        let mut i = 0u32;
        while i != lumagraph_scene::BVH_END {
            walk.push(i);
            let n = g.bvh_nodes[i as usize];
            i = if n.bits >> 3 == 0 {
                if (octant >> (n.bits & 3)) & 1 == 1 {
                    n.index
                } else {
                    i + 1
                }
            } else {
                g.bvh_skips[i as usize][octant as usize]
            };
        }
        assert_eq!(walk, order, "octant {octant}");
        // An inner node's skip link is where the walk goes after its subtree.
        let position: Vec<usize> = {
            let mut p = vec![0; order.len()];
            for (k, &i) in order.iter().enumerate() {
                p[i as usize] = k;
            }
            p
        };
        for (i, n) in g.bvh_nodes.iter().enumerate() {
            let size = subtree_size(&g, i as u32);
            let after = order.get(position[i] + size).copied();
            assert_eq!(
                g.bvh_skips[i][octant as usize],
                after.unwrap_or(lumagraph_scene::BVH_END),
                "node {i} ({}), octant {octant}",
                n.bits
            );
        }
    }
}

fn subtree_size(g: &GpuScene, i: u32) -> usize {
    let n = g.bvh_nodes[i as usize];
    if n.bits >> 3 == 0 {
        1 + subtree_size(g, i + 1) + subtree_size(g, n.index)
    } else {
        1
    }
}

#[test]
fn cornell_rays_from_camera() {
    let scene = Scene::load(&common::assets().join("cornell.ron")).unwrap();
    let g = GpuScene::build(&scene).unwrap();
    let c = g.camera;
    let (right, up, fwd) = (Vec3::from(c.right), Vec3::from(c.up), Vec3::from(c.forward));
    let mut hits = 0;
    for y in 0..32 {
        for x in 0..32 {
            let sx = (2.0 * (x as f32 + 0.5) / 32.0 - 1.0) * c.tan_half_fov * c.aspect;
            let sy = (2.0 * (y as f32 + 0.5) / 32.0 - 1.0) * c.tan_half_fov;
            let ray = Ray {
                origin: Vec3::from(c.position),
                dir: fwd + sx * right - sy * up,
            };
            let a = intersect(&g, &ray);
            let b = intersect_brute_force(&g, &ray, f32::MAX);
            assert_eq!(a.map(|h| h.t), b.map(|h| h.t));
            hits += usize::from(a.is_some());
        }
    }
    // The box fills the view except for a thin border at the open front.
    assert!(hits > 32 * 32 * 8 / 10, "{hits}");
    // The center pixel sees the front face of the large box, near z = -0.07.
    let h = intersect(
        &g,
        &Ray {
            origin: Vec3::from(c.position),
            dir: fwd,
        },
    )
    .unwrap();
    assert!(h.t > 3.9 && h.t < 4.0, "{h:?}");
    let m = &scene.materials[g.tri_shading[h.index()].material as usize];
    assert_eq!(m.name, "white");
}

#[test]
fn slab_test_on_flat_boxes() {
    // A box of zero thickness (an axis-aligned wall) is still hit.
    let inv = safe_inverse(Vec3::new(0.1, -0.2, -1.0));
    assert!(ray_aabb(
        Vec3::new(0.0, 0.0, 3.0),
        inv,
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        f32::MAX
    ));
    // Axis-parallel rays inside and outside a slab.
    let inv = safe_inverse(Vec3::new(0.0, -0.0, -1.0));
    let (lo, hi) = (Vec3::new(0.0, -1.0, -1.0), Vec3::new(1.0, 1.0, 1.0));
    assert!(ray_aabb(Vec3::new(0.5, 0.0, 3.0), inv, lo, hi, f32::MAX));
    assert!(!ray_aabb(Vec3::new(1.5, 0.0, 3.0), inv, lo, hi, f32::MAX));
    assert!(!ray_aabb(Vec3::new(0.5, 0.0, 3.0), inv, lo, hi, 1.5));
    // Behind the origin.
    assert!(!ray_aabb(Vec3::new(0.5, 0.0, -3.0), inv, lo, hi, f32::MAX));
}
