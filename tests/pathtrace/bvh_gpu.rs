//! The GPU BVH traversal agrees with the CPU traversal of the same flat layout: 100 000
//! random rays against a glTF mesh (55 200 triangles) plus spheres, same primitive and the
//! same distance within 1e-5 relative.
//!
//! Two primitives can be hit at the same distance (a shared edge, or a sphere touching a
//! triangle); there the GPU's and CPU's float rounding may pick either. Such ties are
//! accepted when both distances agree, and counted: they must stay rare.

use crate::common;

use lumagraph::pathtrace::SceneBuffers;
use lumagraph::pathtrace::raycast::{RayQuery, Raycaster};
use lumagraph::scene::{GpuScene, NO_HIT, Ray, Scene, intersect_within};

const SCENE: &str = r#"(
    version: 1,
    camera: Perspective(position: (0, 0, 8), target: (0, 0, 0), up: (0, 1, 0), fov_y: 40),
    materials: { "grey": (base_color: (0.5, 0.5, 0.5)) },
    shapes: [
        Mesh(name: "grid", path: "SphereGrids/SphereGrid_MetalRough.gltf"),
        Sphere(center: (-2.4, -2.1, -1.2), radius: 0.15, material: "grey"),
        Sphere(center: (0.6, 0.3, 0.3), radius: 0.4, material: "grey"),
        Sphere(center: (0.0, 0.0, 0.4), radius: 0.3, material: "grey"),
        Sphere(center: (1.8, 1.5, 0.0), radius: 0.5, material: "grey"),
    ],
    render: (width: 8, height: 8),
)"#;

fn random_rays(n: usize) -> Vec<RayQuery> {
    let mut rng = common::Pcg(0x853c_49e6_748f_ea9b);
    (0..n)
        .map(|_| {
            let origin = [
                rng.range(-4.0, 4.0),
                rng.range(-4.0, 4.0),
                rng.range(-4.0, 4.0),
            ];
            // Half the rays aim at the grid, half go anywhere.
            let dir = if rng.next() < 0.5 {
                let target = [
                    rng.range(-3.0, 3.0),
                    rng.range(-3.0, 3.0),
                    rng.range(-0.6, 0.6),
                ];
                [
                    target[0] - origin[0],
                    target[1] - origin[1],
                    target[2] - origin[2],
                ]
            } else {
                let z = rng.range(-1.0, 1.0);
                let phi = rng.range(0.0, std::f32::consts::TAU);
                let r = (1.0 - z * z).sqrt();
                [r * phi.cos(), r * phi.sin(), z]
            };
            RayQuery {
                origin,
                t_max: f32::MAX,
                dir,
                pad: 0,
            }
        })
        .collect()
}

/// Enough of the rays hit for the comparison to mean something, and ties (the same distance,
/// another primitive) stay rare.
fn enough_hits_few_ties(hits: usize, ties: usize) {
    eprintln!("{hits} hits agree, {ties} ties at equal distance");
    assert!(hits > 30_000, "too few hits to mean anything: {hits}");
    assert!(ties * 1000 < hits, "{ties} ties in {hits} hits");
}

#[test]
fn gpu_and_cpu_traversals_agree_on_100k_rays() {
    let Some(ctx) = common::gpu() else { return };
    let scene = Scene::from_ron(SCENE, &common::repo("assets")).unwrap();
    let gpu_scene = GpuScene::build(&scene).unwrap();
    assert!(
        gpu_scene.tri_positions.len() > 50_000,
        "{} triangles",
        gpu_scene.tri_positions.len()
    );
    let buffers = SceneBuffers::upload(ctx, &gpu_scene).unwrap();
    let rays = random_rays(100_000);
    let start = std::time::Instant::now();
    let gpu = Raycaster::new(ctx)
        .unwrap()
        .cast(ctx, &buffers, &rays)
        .unwrap();
    eprintln!(
        "GPU: 100k closest-hit queries in {:.0} ms",
        start.elapsed().as_secs_f64() * 1e3
    );

    let (mut hits, mut ties) = (0, 0);
    for (q, g) in rays.iter().zip(&gpu) {
        let ray = Ray {
            origin: q.origin.into(),
            dir: q.dir.into(),
        };
        let cpu = intersect_within(&gpu_scene, &ray, q.t_max);
        match cpu {
            None => assert_eq!(g.prim, NO_HIT, "CPU misses, GPU hits {g:?} for {q:?}"),
            Some(c) => {
                assert_ne!(g.prim, NO_HIT, "CPU hits {c:?}, GPU misses for {q:?}");
                let rel = (g.t - c.t).abs() / c.t;
                assert!(rel <= 1e-5, "t differs: GPU {g:?} CPU {c:?} for {q:?}");
                if g.prim == c.prim {
                    hits += 1;
                } else {
                    ties += 1;
                }
            }
        }
    }
    enough_hits_few_ties(hits, ties);
}

/// The 8-wide BVH (`Raycaster::wide`, its buffer bound in the binary one's place) finds the
/// same hits on the same 100 000 rays: every ray hits or misses alike, at the same distance
/// to the bit (the same exact tests); only at ties may the primitive differ, as rarely as
/// against the CPU above.
#[test]
fn the_wide_bvh_finds_the_binary_bvhs_hits() {
    let Some(ctx) = common::gpu() else { return };
    let scene = Scene::from_ron(SCENE, &common::repo("assets")).unwrap();
    let gpu_scene = GpuScene::build(&scene).unwrap();
    let buffers = SceneBuffers::upload(ctx, &gpu_scene).unwrap();
    let wide = lumagraph::pathtrace::intersect::wide_bvh::WideBvh::build(&gpu_scene).unwrap();
    let wide_nodes = lumagraph::pathtrace::intersect::wide_bvh::upload(ctx, &wide).unwrap();
    let rays = random_rays(100_000);
    let binary = Raycaster::new(ctx)
        .unwrap()
        .cast(ctx, &buffers, &rays)
        .unwrap();
    let through_wide = Raycaster::wide(ctx)
        .unwrap()
        .cast_through(ctx, &buffers, &wide_nodes, &rays)
        .unwrap();
    let (mut hits, mut ties) = (0, 0);
    for ((q, b), w) in rays.iter().zip(&binary).zip(&through_wide) {
        assert_eq!(
            b.prim == NO_HIT,
            w.prim == NO_HIT,
            "{b:?} against {w:?} for {q:?}"
        );
        if b.prim == NO_HIT {
            continue;
        }
        assert_eq!(
            b.t.to_bits(),
            w.t.to_bits(),
            "{b:?} against {w:?} for {q:?}"
        );
        if b.prim == w.prim {
            hits += 1;
        } else {
            ties += 1;
        }
    }
    enough_hits_few_ties(hits, ties);
}
