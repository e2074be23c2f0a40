//! The host intersector (`lumagraph_pathtrace::embree`) against the path tracer's own BVH
//! traversal (`lumagraph_scene::traverse`, the mirror of the WGSL) on the mesh benchmark
//! scene, and on small hand-made cases.
//!
//! Embree must load: without it these tests fail, unless `LUMAGRAPH_ALLOW_NO_EMBREE=1`,
//! when they print why and pass.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;
use lumagraph_pathtrace::embree::{Embree, HostHit, HostRay, HostScene, Tuning};
use lumagraph_scene::traverse::{self, Ray};
use lumagraph_scene::{GpuScene, Scene};
use rayon::prelude::*;

/// Embree, or `None` (after saying why) when it may be missing.
fn embree() -> Option<Arc<Embree>> {
    // As the command line does (`lumagraph::overrides`): the library reads no variable.
    if let Ok(path) = std::env::var("LUMAGRAPH_EMBREE") {
        let _ = lumagraph_pathtrace::embree::configure(lumagraph_pathtrace::embree::Library::Path(
            path,
        ));
    }
    match Embree::load() {
        Ok(e) => Some(e),
        Err(why) if std::env::var("LUMAGRAPH_ALLOW_NO_EMBREE").is_ok_and(|v| v == "1") => {
            eprintln!("skipped (LUMAGRAPH_ALLOW_NO_EMBREE=1): {why}");
            None
        }
        Err(why) => panic!(
            "{why}\n\
             install it (apt-get install libembree3-3, or scripts/setup.sh), point \
             LUMAGRAPH_EMBREE at the library, or set LUMAGRAPH_ALLOW_NO_EMBREE=1 to skip"
        ),
    }
}

#[path = "../../../tests/common/bench_mesh.rs"]
mod bench_mesh;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

/// `assets/bench/mesh_env.ron` flattened, its mesh made first when missing.
fn mesh_env() -> GpuScene {
    bench_mesh::bench_blob(&repo(""));
    let scene = Scene::load(&repo("assets/bench/mesh_env.ron")).expect("scene");
    GpuScene::build(&scene).expect("flatten")
}

fn next_f32(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let w = ((*state >> ((*state >> 28) + 4)) ^ *state).wrapping_mul(277_803_737);
    ((w >> 22) ^ w) as f32 / 4_294_967_296.0
}

fn ray(origin: Vec3, dir: Vec3, tfar: f32) -> HostRay {
    HostRay {
        origin: origin.to_array(),
        tnear: 0.0,
        dir: dir.to_array(),
        tfar,
    }
}

/// One ray per pixel through the pixel centre, as `cpu_rays` makes them.
fn camera_rays(g: &GpuScene) -> Vec<HostRay> {
    let c = g.camera;
    let (w, h) = (g.settings.width, g.settings.height);
    let (right, up, forward) = (Vec3::from(c.right), Vec3::from(c.up), Vec3::from(c.forward));
    (0..w * h)
        .map(|i| {
            let x = (2.0 * ((i % w) as f32 + 0.5) / w as f32 - 1.0) * c.tan_half_fov * c.aspect;
            let y = (1.0 - 2.0 * ((i / w) as f32 + 0.5) / h as f32) * c.tan_half_fov;
            let dir = (forward + right * x + up * y).normalize();
            ray(Vec3::from(c.position), dir, f32::INFINITY)
        })
        .collect()
}

/// Rays from random points of random triangles, 1e-4 off the surface on a random side,
/// cosine-distributed about the normal on that side; then rays from random points of the
/// scene's bounds in uniform directions.
fn random_rays(g: &GpuScene, count: usize, seed: u32) -> Vec<HostRay> {
    let mut s = seed;
    let mut rays = Vec::with_capacity(2 * count);
    for _ in 0..count {
        let i =
            ((next_f32(&mut s) * g.tri_corners.len() as f32) as usize).min(g.tri_corners.len() - 1);
        let [c0, c1, c2] = g.tri_corners[i].map(Vec3::from);
        let (mut a, mut b) = (next_f32(&mut s), next_f32(&mut s));
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let p = c0 + a * (c1 - c0) + b * (c2 - c0);
        let mut n = (c1 - c0).cross(c2 - c0).normalize();
        if next_f32(&mut s) < 0.5 {
            n = -n;
        }
        let (u1, u2) = (next_f32(&mut s), next_f32(&mut s));
        let (radius, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
        let t = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X }
            .cross(n)
            .normalize();
        let bt = n.cross(t);
        let dir = t * (radius * phi.cos()) + bt * (radius * phi.sin()) + n * (1.0 - u1).sqrt();
        rays.push(ray(p + n * 1e-4, dir.normalize(), f32::INFINITY));
    }
    let (lo, hi) = g.tri_corners.iter().flatten().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &c| (lo.min(c.into()), hi.max(c.into())),
    );
    for _ in 0..count {
        let f = Vec3::new(next_f32(&mut s), next_f32(&mut s), next_f32(&mut s));
        let origin = lo + f * (hi - lo);
        let z = 1.0 - 2.0 * next_f32(&mut s);
        let phi = std::f32::consts::TAU * next_f32(&mut s);
        let r = (1.0 - z * z).max(0.0).sqrt();
        rays.push(ray(
            origin,
            Vec3::new(r * phi.cos(), r * phi.sin(), z),
            f32::INFINITY,
        ));
    }
    rays
}

fn mirror(g: &GpuScene, rays: &[HostRay]) -> Vec<Option<traverse::Hit>> {
    rays.par_iter()
        .map(|r| {
            let ray = Ray {
                origin: Vec3::from(r.origin),
                dir: Vec3::from(r.dir),
            };
            traverse::intersect_within(g, &ray, r.tfar.min(f32::MAX))
        })
        .collect()
}

/// Compares Embree's closest hits with the mirror's; returns the number of rays whose
/// primitive differs (hit against miss included).
fn compare(name: &str, g: &GpuScene, rays: &[HostRay], hits: &[HostHit]) -> usize {
    let reference = mirror(g, rays);
    let (mut differ, mut agree, mut worst_t, mut worst_uv) = (0, 0, 0.0f32, 0.0f32);
    for (i, (hit, want)) in hits.iter().zip(&reference).enumerate() {
        match want {
            Some(want) if hit.prim == want.prim => {
                agree += 1;
                let dt = (hit.t - want.t).abs() / want.t.abs().max(1e-6);
                let duv = (hit.u - want.u).abs().max((hit.v - want.v).abs());
                worst_t = worst_t.max(dt);
                worst_uv = worst_uv.max(duv);
                assert!(
                    dt <= 1e-4,
                    "{name} ray {i}: t {} against {} (prim {})",
                    hit.t,
                    want.t,
                    want.prim
                );
                assert!(
                    duv <= 1e-3,
                    "{name} ray {i}: u, v ({}, {}) against ({}, {})",
                    hit.u,
                    hit.v,
                    want.u,
                    want.v
                );
            }
            None if !hit.is_hit() => {}
            _ => differ += 1,
        }
    }
    println!(
        "{name}: {} rays, {agree} hits agree, {differ} differ in primitive \
         (worst relative t {worst_t:.1e}, worst u/v {worst_uv:.1e})",
        rays.len()
    );
    differ
}

/// The mesh scene: same primitive for all but 1 ray in 2 000 (rays through shared edges
/// and corners, where two triangle tests may pick either side or none), `t` within 1e-4
/// relative and u, v within 1e-3 where they agree; occlusion as the closest hit says.
#[test]
fn embree_matches_the_mirror_traversal() {
    let Some(embree) = embree() else { return };
    let g = mesh_env();
    assert_eq!(g.tri_corners.len(), g.tri_positions.len());
    for (c, t) in g.tri_corners.iter().zip(&g.tri_positions) {
        assert_eq!(c[0], t.v0);
        assert_eq!((Vec3::from(c[1]) - Vec3::from(c[0])).to_array(), t.e1);
        assert_eq!((Vec3::from(c[2]) - Vec3::from(c[0])).to_array(), t.e2);
    }
    let host = HostScene::new(embree, &g.tri_corners).expect("Embree scene");
    assert_eq!(host.len(), g.tri_corners.len());

    for (name, rays) in [
        ("camera", camera_rays(&g)),
        ("random", random_rays(&g, 30_000, 7)),
    ] {
        let mut hits = vec![HostHit::default(); rays.len()];
        host.intersect(&rays, &mut hits);
        let differ = compare(name, &g, &rays, &hits);
        assert!(
            differ * 2000 <= rays.len(),
            "{name}: {differ} of {} rays hit another primitive",
            rays.len()
        );

        // Shadow rays: each ray cut at a random fraction (0.5 to 1.5) of its closest hit's
        // distance, or at 10 when it misses. Rays whose cut is within 1e-3 of the hit
        // decide on rounding and are left out.
        let mut s = 99_u32;
        let mut cut = rays.clone();
        let mut expected = Vec::with_capacity(rays.len());
        for (r, h) in cut.iter_mut().zip(&hits) {
            r.tfar = if h.is_hit() {
                h.t * (0.5 + next_f32(&mut s))
            } else {
                10.0
            };
            expected.push(h.is_hit() && (h.t - r.tfar).abs() > 1e-3 * h.t && h.t < r.tfar);
        }
        let mut occluded = vec![7; cut.len()];
        host.occluded(&cut, &mut occluded);
        let mut wrong = 0;
        for ((h, r), (&o, &e)) in hits.iter().zip(&cut).zip(occluded.iter().zip(&expected)) {
            assert!(o <= 1, "occluded writes 0 or 1");
            let ambiguous = h.is_hit() && (h.t - r.tfar).abs() <= 1e-3 * h.t;
            if !ambiguous && (o == 1) != e {
                wrong += 1;
            }
        }
        println!("{name}: occluded disagrees with the closest hit on {wrong} rays");
        assert!(
            wrong * 2000 <= rays.len(),
            "{name}: occluded disagrees with the closest hit on {wrong} rays"
        );
    }
}

/// Single rays, packets and the coherent flag give the default's (stream) results.
#[test]
fn packets_and_streams_agree_with_single_rays() {
    let Some(embree) = embree() else { return };
    let g = mesh_env();
    let mut rays = camera_rays(&g);
    rays.truncate(20_003);
    rays.extend(random_rays(&g, 5_001, 3));
    // Some "no ray"s among them.
    for r in rays.iter_mut().step_by(37) {
        r.tfar = -1.0;
    }
    let single = HostScene::new(Arc::clone(&embree), &g.tri_corners).unwrap();
    let mut want = vec![HostHit::default(); rays.len()];
    single.intersect(&rays, &mut want);
    let mut want_occluded = vec![0; rays.len()];
    single.occluded(&rays, &mut want_occluded);
    for r in rays.iter().step_by(37) {
        assert!(r.tfar < 0.0);
    }
    for (i, w) in want.iter().enumerate().step_by(37) {
        assert_eq!(*w, HostHit::MISS, "no ray {i} hits nothing");
        assert_eq!(want_occluded[i], 0);
    }
    for (packet, coherent) in [(1, false), (8, false), (16, false), (0, true), (1, true)] {
        let tuning = Tuning {
            packet,
            coherent,
            chunk: 1000,
            ..Tuning::default()
        };
        let host = HostScene::with_tuning(Arc::clone(&embree), &g.tri_corners, tuning).unwrap();
        let mut hits = vec![HostHit::default(); rays.len()];
        host.intersect(&rays, &mut hits);
        let mut occluded = vec![7; rays.len()];
        host.occluded(&rays, &mut occluded);
        for i in 0..rays.len() {
            assert_eq!(hits[i], want[i], "{tuning:?}: ray {i}");
            assert_eq!(occluded[i], want_occluded[i], "{tuning:?}: ray {i}");
        }
    }
}

/// Embree's barycentrics and primitive IDs are the path tracer's: hit point
/// (1 - u - v)·c0 + u·c1 + v·c2, prim the index given; both sides hit.
#[test]
fn conventions_on_small_scenes() {
    let Some(embree) = embree() else { return };
    let corners = [
        [[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0]],
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[0.0, 0.0, -5.0], [1.0, 0.0, -5.0], [0.0, 1.0, -5.0]],
        // Never hit: a corner not finite, and no area.
        [[f32::NAN, 0.0, 0.5], [1.0, 0.0, 0.5], [0.0, 1.0, 0.5]],
        [[0.0, 0.0, 0.6], [1.0, 1.0, 0.6], [0.5, 0.5, 0.6]],
    ];
    let host = HostScene::new(Arc::clone(&embree), &corners).unwrap();
    let rays = [
        // Down onto triangle 1 from above (z = 1), through triangle 3's plane: t = 1.
        ray(Vec3::new(0.2, 0.3, 1.0), Vec3::NEG_Z, f32::INFINITY),
        // Down through triangle 4's line onto triangle 1.
        ray(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z, f32::INFINITY),
        // Up from below, unnormalized: the back side, t in units of dir.
        ray(Vec3::new(0.5, 0.25, -1.0), Vec3::Z * 2.0, f32::INFINITY),
        // Beside every triangle.
        ray(Vec3::new(0.8, 0.8, 1.0), Vec3::NEG_Z, f32::INFINITY),
        // Stops short of triangle 1.
        ray(Vec3::new(0.2, 0.3, 1.0), Vec3::NEG_Z, 0.9),
        // Starts past triangle 1: tnear skips it, triangle 2 is hit.
        HostRay {
            tnear: 1.5,
            ..ray(Vec3::new(0.2, 0.3, 1.0), Vec3::NEG_Z, f32::INFINITY)
        },
        // No rays.
        ray(Vec3::new(0.2, 0.3, 1.0), Vec3::NEG_Z, -1.0),
        ray(Vec3::new(f32::NAN, 0.3, 1.0), Vec3::NEG_Z, 10.0),
        ray(Vec3::new(0.2, 0.3, 1.0), Vec3::NEG_Z, 0.0),
    ];
    let mut hits = [HostHit::default(); 9];
    host.intersect(&rays, &mut hits);
    let close = |h: HostHit, prim: u32, t: f32, u: f32, v: f32| {
        h.prim == prim && (h.t - t).abs() < 1e-6 && (h.u - u).abs() < 1e-6 && (h.v - v).abs() < 1e-6
    };
    assert!(close(hits[0], 1, 1.0, 0.2, 0.3), "{:?}", hits[0]);
    assert!(close(hits[1], 1, 1.0, 0.25, 0.25), "{:?}", hits[1]);
    assert!(close(hits[2], 1, 0.5, 0.5, 0.25), "{:?}", hits[2]);
    assert_eq!(hits[3], HostHit::MISS);
    assert_eq!(hits[4], HostHit::MISS);
    assert!(close(hits[5], 2, 6.0, 0.2, 0.3), "{:?}", hits[5]);
    assert_eq!(&hits[6..], &[HostHit::MISS; 3]);
    let mut occluded = [7; 9];
    host.occluded(&rays, &mut occluded);
    assert_eq!(occluded, [1, 1, 1, 0, 0, 1, 0, 0, 0]);

    // No triangles: everything misses.
    let empty = HostScene::new(embree, &[]).unwrap();
    assert!(empty.is_empty());
    let mut hits = [HostHit::default(); 9];
    empty.intersect(&rays, &mut hits);
    assert_eq!(hits, [HostHit::MISS; 9]);
    empty.occluded(&rays, &mut occluded);
    assert_eq!(occluded, [0; 9]);
}

#[test]
fn version_names_embree_3() {
    let Some(embree) = embree() else { return };
    let version = embree.version();
    println!("{version} from {}", embree.library());
    assert!(version.starts_with("Embree 3."), "{version}");
}
