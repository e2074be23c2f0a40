//! Closest-hit rays per second on the CPU, for a scene file: the path tracer's own BVH
//! traversal (`lumagraph_scene::traverse`, the line-for-line mirror of
//! `shaders/pathtrace/intersect/bvh.wgsl`) beside obvhs's compressed wide BVH (CWBVH), on the same
//! rays. It measures how much of the BVH shader's cost on a CPU adapter is the traversal
//! itself and how much is the way the driver compiles it (see docs/benchmarks.md).
//!
//! ```sh
//! cargo run --release -p lumagraph-scene --example cpu_rays -- assets/bench/mesh_env.ron
//! ```
//!
//! Rays: one per pixel through the pixel centre from the scene's camera (pinhole), then
//! three generations of cosine-distributed bounces from each hit (fixed seed), as a path
//! tracer's first bounces are. Each generation is timed on one thread, mirror then CWBVH.
//! The hit counts may differ by a fraction of a percent (rays at edges and corners: obvhs's
//! triangle test is not the path tracer's).
// A benchmark binary: it panics on bad input rather than reporting it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;
use std::time::{Duration, Instant};

use glam::{Vec3, Vec3A};
use lumagraph_scene::traverse::{self, Ray};
use lumagraph_scene::{GpuScene, Scene};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::RayHit;
use obvhs::triangle::Triangle;

fn next_f32(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let w = ((*state >> ((*state >> 28) + 4)) ^ *state).wrapping_mul(277_803_737);
    ((w >> 22) ^ w) as f32 / 4_294_967_296.0
}

/// Mean rays per second of `f` over `rays`, with the number of hits.
fn time(
    rays: &[Ray],
    mut f: impl FnMut(&Ray) -> Option<(u32, f32)>,
) -> (f64, Vec<Option<(u32, f32)>>) {
    let start = Instant::now();
    let hits: Vec<_> = rays.iter().map(&mut f).collect();
    (rays.len() as f64 / start.elapsed().as_secs_f64(), hits)
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "assets/bench/mesh_env.ron".to_owned());
    let start = Instant::now();
    let scene = GpuScene::build(&Scene::load(Path::new(&path)).expect("scene")).expect("flatten");
    println!(
        "{path}: {} triangles, {} spheres (ignored), load + BVH {:.0} ms",
        scene.tri_positions.len(),
        scene.shapes.len(),
        start.elapsed().as_secs_f64() * 1e3
    );
    let tris: Vec<Triangle> = scene
        .tri_positions
        .iter()
        .map(|t| {
            let v0 = Vec3A::from(t.v0);
            Triangle {
                v0,
                v1: v0 + Vec3A::from(t.e1),
                v2: v0 + Vec3A::from(t.e2),
            }
        })
        .collect();
    let start = Instant::now();
    let cwbvh = build_cwbvh_from_tris(
        &tris,
        BvhBuildParams::medium_build(),
        &mut Duration::default(),
    );
    let cw_tris: Vec<Triangle> = cwbvh
        .primitive_indices
        .iter()
        .map(|&i| tris[i as usize])
        .collect();
    println!(
        "CWBVH build (obvhs medium_build): {:.0} ms",
        start.elapsed().as_secs_f64() * 1e3
    );

    let c = scene.camera;
    let (w, h) = (scene.settings.width, scene.settings.height);
    let (right, up, forward) = (Vec3::from(c.right), Vec3::from(c.up), Vec3::from(c.forward));
    let mut rays: Vec<Ray> = (0..w * h)
        .map(|i| {
            let x = (2.0 * ((i % w) as f32 + 0.5) / w as f32 - 1.0) * c.tan_half_fov * c.aspect;
            let y = (1.0 - 2.0 * ((i / w) as f32 + 0.5) / h as f32) * c.tan_half_fov;
            Ray {
                origin: Vec3::from(c.position),
                dir: (forward + right * x + up * y).normalize(),
            }
        })
        .collect();
    let mut seed = 12_345_u32;
    println!(
        "generation  rays     hits     (CWBVH)  mirror M rays/s  CWBVH M rays/s  CWBVH / mirror"
    );
    for generation in 0..4 {
        let (mirror, hits) = time(&rays, |r| {
            traverse::intersect(&scene, r).map(|h| (h.prim, h.t))
        });
        let (wide, wide_hits) = time(&rays, |r| {
            let mut hit = RayHit::none();
            let ray = obvhs::ray::Ray::new_inf(Vec3A::from(r.origin), Vec3A::from(r.dir));
            cwbvh
                .ray_traverse(ray, &mut hit, |ray, id| cw_tris[id].intersect(ray))
                .then(|| (cwbvh.primitive_indices[hit.primitive_id as usize], hit.t))
        });
        let count = |h: &[Option<(u32, f32)>]| h.iter().filter(|h| h.is_some()).count();
        println!(
            "{generation:<11} {:<8} {:<8} {:<8} {:<16.2} {:<15.2} {:.2}x",
            rays.len(),
            count(&hits),
            count(&wide_hits),
            mirror / 1e6,
            wide / 1e6,
            wide / mirror
        );
        // Cosine-distributed bounces off each hit, leaving along the side the ray came from.
        let mut next = Vec::new();
        for (r, hit) in rays.iter().zip(&hits) {
            let Some((prim, t)) = hit else { continue };
            let tri = &scene.tri_positions[*prim as usize];
            let mut n = Vec3::from(tri.e1).cross(Vec3::from(tri.e2)).normalize();
            if n.dot(r.dir) > 0.0 {
                n = -n;
            }
            let (u1, u2) = (next_f32(&mut seed), next_f32(&mut seed));
            let (radius, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
            let a = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X }
                .cross(n)
                .normalize();
            let b = n.cross(a);
            next.push(Ray {
                origin: r.origin + r.dir * *t + n * 1e-4,
                dir: (a * (radius * phi.cos()) + b * (radius * phi.sin()) + n * (1.0 - u1).sqrt())
                    .normalize(),
            });
        }
        rays = next;
    }
}
