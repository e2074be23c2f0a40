//! Rays per second of the host intersector (`lumagraph_pathtrace::embree`) on a scene file,
//! for each build and trace setting, with the path tracer's own CPU traversal beside it.
//!
//! ```sh
//! cargo run --release -p lumagraph-pathtrace --example embree_rays -- assets/bench/mesh_env.ron [FILTER]
//! ```
//!
//! `FILTER` keeps the settings whose names contain it; `RAYON_NUM_THREADS` sets the
//! threads.
//!
//! Ray sets: camera rays (one per pixel through the pixel centre, pinhole); "bounce" rays,
//! one cosine-distributed bounce off each camera hit (a path tracer's second segment);
//! "random" rays from uniformly random points of random triangles, on a random side,
//! cosine-distributed about the normal. Closest hit (`intersect`) and any hit to infinity
//! (`occluded`) on each, on rayon's threads (all cores); best of several runs.
// A benchmark binary: it panics on bad input rather than reporting it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use lumagraph_pathtrace::embree::{Embree, HostHit, HostRay, HostScene, Tuning};
use lumagraph_scene::traverse::{self, Ray};
use lumagraph_scene::{GpuScene, Scene};

fn next_f32(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let w = ((*state >> ((*state >> 28) + 4)) ^ *state).wrapping_mul(277_803_737);
    ((w >> 22) ^ w) as f32 / 4_294_967_296.0
}

fn host_ray(origin: Vec3, dir: Vec3) -> HostRay {
    HostRay {
        origin: origin.to_array(),
        tnear: 0.0,
        dir: dir.to_array(),
        tfar: f32::INFINITY,
    }
}

/// A cosine-distributed direction about `n`.
fn cosine(n: Vec3, s: &mut u32) -> Vec3 {
    let (u1, u2) = (next_f32(s), next_f32(s));
    let (radius, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
    let a = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X }
        .cross(n)
        .normalize();
    let b = n.cross(a);
    (a * (radius * phi.cos()) + b * (radius * phi.sin()) + n * (1.0 - u1).sqrt()).normalize()
}

fn normal(c: &[[f32; 3]; 3]) -> Vec3 {
    let [c0, c1, c2] = c.map(Vec3::from);
    (c1 - c0).cross(c2 - c0).normalize()
}

fn camera_rays(g: &GpuScene) -> Vec<HostRay> {
    let c = g.camera;
    let (w, h) = (g.settings.width, g.settings.height);
    let (right, up, forward) = (Vec3::from(c.right), Vec3::from(c.up), Vec3::from(c.forward));
    (0..w * h)
        .map(|i| {
            let x = (2.0 * ((i % w) as f32 + 0.5) / w as f32 - 1.0) * c.tan_half_fov * c.aspect;
            let y = (1.0 - 2.0 * ((i / w) as f32 + 0.5) / h as f32) * c.tan_half_fov;
            host_ray(
                Vec3::from(c.position),
                (forward + right * x + up * y).normalize(),
            )
        })
        .collect()
}

fn bounce_rays(g: &GpuScene, rays: &[HostRay], hits: &[HostHit]) -> Vec<HostRay> {
    let mut s = 12_345_u32;
    rays.iter()
        .zip(hits)
        .filter(|(_, h)| h.is_hit())
        .map(|(r, h)| {
            let dir = Vec3::from(r.dir);
            let mut n = normal(&g.tri_corners[h.prim as usize]);
            if n.dot(dir) > 0.0 {
                n = -n;
            }
            host_ray(
                Vec3::from(r.origin) + dir * h.t + n * 1e-4,
                cosine(n, &mut s),
            )
        })
        .collect()
}

fn random_rays(g: &GpuScene, count: usize) -> Vec<HostRay> {
    let mut s = 777_u32;
    (0..count)
        .map(|_| {
            let i = ((next_f32(&mut s) * g.tri_corners.len() as f32) as usize)
                .min(g.tri_corners.len() - 1);
            let [c0, c1, c2] = g.tri_corners[i].map(Vec3::from);
            let (mut a, mut b) = (next_f32(&mut s), next_f32(&mut s));
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let mut n = normal(&g.tri_corners[i]);
            if next_f32(&mut s) < 0.5 {
                n = -n;
            }
            let p = c0 + a * (c1 - c0) + b * (c2 - c0) + n * 1e-4;
            host_ray(p, cosine(n, &mut s))
        })
        .collect()
}

/// Best rate of `f` over runs totalling at least a fifth of a second, in M rays/s.
fn rate(rays: usize, mut f: impl FnMut()) -> f64 {
    f();
    let (mut best, start) = (f64::MAX, Instant::now());
    let mut runs = 0;
    while runs < 3 || start.elapsed().as_secs_f64() < 0.2 {
        let t = Instant::now();
        f();
        best = best.min(t.elapsed().as_secs_f64());
        runs += 1;
    }
    rays as f64 / best / 1e6
}

/// Closest-hit and occluded rates on each set, in M rays/s.
fn measure(host: &HostScene, sets: &[(&str, Vec<HostRay>)]) -> Vec<f64> {
    let mut out = Vec::new();
    for (_, rays) in sets {
        let mut hits = vec![HostHit::default(); rays.len()];
        let mut occluded = vec![0; rays.len()];
        out.push(rate(rays.len(), || host.intersect(rays, &mut hits)));
        out.push(rate(rays.len(), || host.occluded(rays, &mut occluded)));
    }
    out
}

/// The settings compared: the default, then one change at a time.
fn variants() -> Vec<(&'static str, Tuning)> {
    let base = Tuning::default();
    let with = |f: &dyn Fn(&mut Tuning)| {
        let mut t = base;
        f(&mut t);
        t
    };
    vec![
        ("default (stream, medium, chunk 2048)", base),
        ("quality high", with(&|t| t.quality = 2)),
        ("quality low (two-level)", with(&|t| t.quality = 0)),
        ("robust", with(&|t| t.robust = true)),
        ("compact", with(&|t| t.compact = true)),
        ("coherent context", with(&|t| t.coherent = true)),
        ("rtcIntersect1", with(&|t| t.packet = 1)),
        (
            "rtcIntersect1, quality high",
            with(&|t| (t.packet, t.quality) = (1, 2)),
        ),
        ("packets of 8", with(&|t| t.packet = 8)),
        ("packets of 16", with(&|t| t.packet = 16)),
        ("chunk 1024", with(&|t| t.chunk = 1024)),
        ("chunk 4096", with(&|t| t.chunk = 4096)),
        ("chunk 16384", with(&|t| t.chunk = 16384)),
    ]
}

/// Hit counts, and how many hits `RTC_SCENE_FLAG_ROBUST` (watertight triangle tests) adds.
fn robust_check(embree: &Arc<Embree>, g: &GpuScene, sets: &[(&str, Vec<HostRay>)]) {
    let scene = |robust| {
        let tuning = Tuning {
            robust,
            ..Tuning::default()
        };
        HostScene::with_tuning(Arc::clone(embree), &g.tri_corners, tuning).unwrap()
    };
    let (host, robust) = (scene(false), scene(true));
    for (name, rays) in sets {
        let mut hits = vec![HostHit::default(); rays.len()];
        host.intersect(rays, &mut hits);
        let mut robust_hits = vec![HostHit::default(); rays.len()];
        robust.intersect(rays, &mut robust_hits);
        let n = hits.iter().filter(|h| h.is_hit()).count();
        let count = |f: &dyn Fn(&HostHit, &HostHit) -> bool| {
            hits.iter()
                .zip(&robust_hits)
                .filter(|(a, b)| f(a, b))
                .count()
        };
        println!(
            "{name}: {} rays, {n} hit; robust: {} more hits, {} fewer, {} on another triangle",
            rays.len(),
            count(&|a, b| !a.is_hit() && b.is_hit()),
            count(&|a, b| a.is_hit() && !b.is_hit()),
            count(&|a, b| a.is_hit() && b.is_hit() && a.prim != b.prim),
        );
    }
}

/// The table: build time and rates of each setting whose name contains `only`. Every
/// setting is measured in turn, `ROUNDS` times over, and the best of each kept, so that
/// other work on the machine during one round does not count.
fn table(embree: &Arc<Embree>, g: &GpuScene, sets: &[(&str, Vec<HostRay>)], only: &str) {
    const ROUNDS: usize = 3;
    println!(
        "\nM rays/s, closest hit then occluded:   build ms  camera         bounce         random"
    );
    let variants: Vec<_> = variants()
        .into_iter()
        .filter(|(name, _)| name.contains(only))
        .collect();
    let mut best = vec![(f64::MAX, vec![0.0; 2 * sets.len()]); variants.len()];
    for _ in 0..ROUNDS {
        for ((_, tuning), best) in variants.iter().zip(&mut best) {
            let start = Instant::now();
            let host = HostScene::with_tuning(Arc::clone(embree), &g.tri_corners, *tuning).unwrap();
            best.0 = best.0.min(start.elapsed().as_secs_f64() * 1e3);
            for (b, r) in best.1.iter_mut().zip(measure(&host, sets)) {
                *b = r.max(*b);
            }
        }
    }
    for ((name, _), (build, rates)) in variants.iter().zip(&best) {
        let rates: String = rates.iter().map(|r| format!(" {r:>6.2}")).collect();
        println!("{name:<38} {build:>8.0} {rates}");
    }
}

/// The path tracer's own traversal, one thread, closest hit only.
fn mirror(g: &GpuScene, sets: &[(&str, Vec<HostRay>)]) {
    let mut line = String::new();
    for (_, rays) in sets {
        let rays: Vec<Ray> = rays
            .iter()
            .take(1 << 15)
            .map(|r| Ray {
                origin: Vec3::from(r.origin),
                dir: Vec3::from(r.dir),
            })
            .collect();
        let r = rate(rays.len(), || {
            for r in &rays {
                std::hint::black_box(traverse::intersect(g, r));
            }
        });
        line.push_str(&format!(" {r:>6.2}      -"));
    }
    println!("{:<38} {:>8} {line}", "mirror traversal, 1 thread", "-");
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "assets/bench/mesh_env.ron".to_owned());
    let only = std::env::args().nth(2).unwrap_or_default();
    let g = GpuScene::build(&Scene::load(Path::new(&path)).expect("scene")).expect("flatten");
    let embree = Embree::load().unwrap_or_else(|e| panic!("{e}"));
    println!(
        "{path}: {} triangles ({} spheres ignored); {} from {}; {} rayon threads",
        g.tri_corners.len(),
        g.shapes.len(),
        embree.version(),
        embree.library(),
        rayon::current_num_threads()
    );
    let camera = camera_rays(&g);
    let host = HostScene::new(Arc::clone(&embree), &g.tri_corners).unwrap();
    let mut hits = vec![HostHit::default(); camera.len()];
    host.intersect(&camera, &mut hits);
    let sets = [
        ("camera", camera.clone()),
        ("bounce", bounce_rays(&g, &camera, &hits)),
        ("random", random_rays(&g, 1 << 18)),
    ];
    robust_check(&embree, &g, &sets);
    table(&embree, &g, &sets, &only);
    if "mirror".contains(&only) {
        mirror(&g, &sets);
    }
}
