//! Instanced meshes through the GPU: the two-level walk of `pathtrace/intersect/bvh.wgsl` against the
//! CPU mirror's, ray by ray; the path tracer's image of an instanced scene against the same
//! scene with its instances copied; and a scene of 1000 instances of a 100 352-triangle
//! mesh, whose copies (100 M triangles) no intersector could hold.

use crate::common;
use lumagraph::pathtrace::specialize::Tracing;

use std::sync::Arc;

use glam::Vec3;
use lumagraph::graph::ParamValue;
use lumagraph::pathtrace::raycast::{RayQuery, Raycaster};
use lumagraph::pathtrace::specialize::{Feature, Intersector};
use lumagraph::pathtrace::{SceneBuffers, library::compile};
use lumagraph::render::Resources;
use lumagraph::scene::{GpuScene, NO_HIT, Ray, Scene, intersect_within};

/// The sphere grid (55 200 triangles, 25 metal-rough materials) placed 6 times (moved,
/// turned, scaled unevenly, mirrored), a sphere, and a floor and an area light of the
/// scene's own.
fn scene_text(instancing: &str) -> String {
    format!(
        r#"(
    version: 2,
    camera: Perspective(position: (0, 2, 26), target: (0, 0, 0), up: (0, 1, 0), fov_y: 45),
    materials: {{ "grey": (base_color: (0.5, 0.5, 0.5)), "light": (base_color: (0, 0, 0)) }},
    shapes: [
        Mesh(name: "grid", path: "SphereGrids/SphereGrid_MetalRough.gltf", instances: [
            (),
            (translate: (7, 0, 0)),
            (translate: (-7, 1, 0), rotate: [(axis: (0, 1, 0), degrees: 30)]),
            (translate: (0, 7, -3), scale: (1, 2, 0.5)),
            (translate: (0, -7, 2), scale: (-1, 1, 1)),
            (matrix: [[0, -1, 0, 3], [1, 0, 0, -3], [0, 0, 1, 4], [0, 0, 0, 1]]),
        ]),
        Sphere(center: (6, 6, 3), radius: 1.5, material: "grey"),
        Quad(corners: [(-20, -12, -8), (20, -12, -8), (20, -12, 12), (-20, -12, 12)], material: "grey"),
        Quad(corners: [(-4, 14, -2), (-4, 14, 2), (4, 14, 2), (4, 14, -2)], material: "light",
             emission: (20, 20, 20)),
    ],
    environment: Constant((0.2, 0.2, 0.25)),
    render: (width: 8, height: 8, max_bounces: 6),
    instancing: {instancing},
)"#
    )
}

fn gpu_scene(instancing: &str) -> GpuScene {
    GpuScene::build(&Scene::from_ron(&scene_text(instancing), &common::repo("assets")).unwrap())
        .unwrap()
}

/// [`gpu_scene`] without its sphere (host intersection traces triangles only), and with
/// `veil` the grid's every material replaced by a grey of opacity 0.5, blended (stochastic
/// transparency: each ray's choice is a hash of the ray and the triangle).
fn triangles_scene(instancing: &str, veil: bool) -> GpuScene {
    let mut text = scene_text(instancing).replace(
        r#"Sphere(center: (6, 6, 3), radius: 1.5, material: "grey"),"#,
        "",
    );
    if veil {
        text = text
            .replace(
                r#""light": (base_color: (0, 0, 0)) }"#,
                r#""light": (base_color: (0, 0, 0)),
                   "veil": (base_color: (0.7, 0.7, 0.7), alpha_mode: Blend, opacity: 0.5) }"#,
            )
            .replace(
                r#"Mesh(name: "grid", "#,
                r#"Mesh(name: "grid", material: "veil", "#,
            );
        assert!(text.contains(r#"material: "veil""#) && text.contains("alpha_mode: Blend"));
    }
    assert!(!text.contains("Sphere("));
    GpuScene::build(&Scene::from_ron(&text, &common::repo("assets")).unwrap()).unwrap()
}

/// 50 000 random rays, half aimed at the instances.
fn rays(n: usize) -> Vec<RayQuery> {
    let mut rng = common::Pcg(0x9e37_79b9_7f4a_7c15);
    (0..n)
        .map(|k| {
            let origin = Vec3::new(
                rng.range(-15.0, 15.0),
                rng.range(-15.0, 15.0),
                rng.range(-10.0, 20.0),
            );
            let spread = if k % 2 == 0 { 9.0 } else { 30.0 };
            let target = Vec3::new(
                rng.range(-spread, spread),
                rng.range(-spread, spread),
                rng.range(-3.0, 3.0),
            );
            RayQuery {
                origin: origin.to_array(),
                t_max: if k % 3 == 0 { 20.0 } else { f32::MAX },
                dir: (target - origin).normalize().to_array(),
                pad: 0,
            }
        })
        .collect()
}

/// The GPU's two-level walk against the mirror's on 50 000 rays: every ray hits or misses
/// alike, at the same distance (1e-5 relative), on the same triangle of the same instance
/// except at ties (another primitive at the same distance), which stay rare.
#[test]
fn the_gpu_walks_instances_as_the_mirror_does() {
    let Some(ctx) = common::gpu() else { return };
    let scene = gpu_scene("On");
    assert_eq!(scene.instances.len(), 6);
    let buffers = SceneBuffers::upload(ctx, &scene).unwrap();
    let queries = rays(50_000);
    let gpu = Raycaster::new(ctx)
        .unwrap()
        .cast(ctx, &buffers, &queries)
        .unwrap();
    let (mut hits, mut in_instances, mut ties) = (0, 0, 0);
    for (q, g) in queries.iter().zip(&gpu) {
        let ray = Ray {
            origin: q.origin.into(),
            dir: q.dir.into(),
        };
        match intersect_within(&scene, &ray, q.t_max) {
            None => assert_eq!(
                g.prim, NO_HIT,
                "the mirror misses, the GPU hits {g:?}: {q:?}"
            ),
            Some(c) => {
                assert_ne!(
                    g.prim, NO_HIT,
                    "the mirror hits {c:?}, the GPU misses: {q:?}"
                );
                let rel = (g.t - c.t).abs() / c.t;
                assert!(rel <= 1e-5, "GPU {g:?} mirror {c:?}: {q:?}");
                if (g.prim, g.inst) == (c.prim, c.inst) {
                    hits += 1;
                    in_instances += usize::from(c.inst != lumagraph::scene::NO_INSTANCE);
                } else {
                    ties += 1;
                }
            }
        }
    }
    println!("{hits} hits agree ({in_instances} in instances), {ties} ties");
    assert!(
        in_instances > 10_000,
        "too few instance hits: {in_instances}"
    );
    assert!(ties * 1000 < hits, "{ties} ties in {hits} hits");
}

/// `scene` rendered at 64×64, `spp` samples, through the binary BVH as a GPU adapter runs
/// it: color, albedo, normal and depth, and whether the two-level walk was compiled in.
fn render(
    scene: GpuScene,
    spp: u32,
    seed: u32,
) -> Option<(Vec<lumagraph::render::cpu::Image>, bool)> {
    let ctx = common::gpu()?;
    let mut scene = scene;
    (scene.settings.width, scene.settings.height) = (64, 64);
    scene.settings.seed = seed;
    let scene = Arc::new(scene);
    let ports = ["acc.color", "pt.albedo", "pt.normal", "pt.depth"];
    let outputs: Vec<String> = ports.iter().map(|p| (*p).to_owned()).collect();
    let graph = common::progressive_graph(&[("samples_per_frame", ParamValue::Int(4))]);
    let plan = compile(&graph, &outputs, Some(&scene)).unwrap();
    let resources = Resources {
        scene: Some(scene),
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        intersector: Intersector::BINARY_BVH,
        ..Tracing::default()
    });
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    let features = lumagraph::pathtrace::nodes::pathtrace::features(&exec, "pt")
        .unwrap()
        .clone();
    println!("{}", features.summary());
    exec.run_frames(spp.div_ceil(4), true).unwrap();
    let images = ports.iter().map(|p| exec.read_port(p).unwrap()).collect();
    Some((images, features.on(Feature::Instances)))
}

/// The mean of each 8×8 block's color, summed over the channels.
fn block_means(image: &lumagraph::render::cpu::Image) -> Vec<f64> {
    let (w, h) = (image.width as usize, image.height as usize);
    let mut out = vec![0.0; (w / 8) * (h / 8)];
    for y in 0..h {
        for x in 0..w {
            let p = image.pixels[y * w + x];
            out[(y / 8) * (w / 8) + x / 8] += f64::from(p[0] + p[1] + p[2]) / 64.0;
        }
    }
    out
}

/// The instanced scene and its copies, 64×64 at 64 spp through the binary BVH: the
/// first-hit depth agrees to 1e-4 relative where the same surface is hit (all but edge
/// pixels, where a ray may meet the neighbour of the triangle the other met), and the 8×8
/// block means of the color differ by no more than the same scene rendered with another seed
/// differs from itself (the same random numbers follow the same paths, so the difference is
/// far below that noise).
#[test]
fn instanced_and_copied_scenes_render_alike() {
    let Some((inst, on)) = render(gpu_scene("On"), 64, 1) else {
        return;
    };
    assert!(on, "the two-level walk is compiled in for instances");
    let (flat, on) = render(gpu_scene("Off"), 64, 1).unwrap();
    assert!(!on, "and left out without them");
    let (noise, _) = render(gpu_scene("Off"), 64, 2).unwrap();
    let depth_far = common::differing(&inst[3], &flat[3], Some(1e-4));
    println!("depth: {depth_far} of 4096 pixels beyond 1e-4 relative");
    assert!(depth_far <= 16, "{depth_far} depth pixels differ");
    let (a, b, n) = (
        block_means(&inst[0]),
        block_means(&flat[0]),
        block_means(&noise[0]),
    );
    let worst = |x: &[f64], y: &[f64]| {
        x.iter()
            .zip(y)
            .map(|(p, q)| (p - q).abs() / q.abs().max(1e-3))
            .fold(0.0, f64::max)
    };
    let (between, seeds) = (worst(&a, &b), worst(&n, &b));
    println!(
        "8x8 block means: instanced against copied {between:.2e} relative at worst; another \
         seed {seeds:.2e}"
    );
    assert!(b.iter().sum::<f64>() > 1.0, "black");
    assert!(
        between < 0.25 * seeds,
        "{between} against the noise {seeds}"
    );
}

/// A mesh of `2 n²` triangles: a wavy square of side 1 in the xy plane, written as a binary
/// PLY.
fn wavy_ply(n: usize) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        (n + 1) * (n + 1),
        2 * n * n
    )
    .into_bytes();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5);
            let z = 0.05 * (12.0 * x).sin() * (9.0 * y).cos();
            for c in [x, y, z] {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as i32;
    for j in 0..n {
        for i in 0..n {
            for tri in [
                [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
            ] {
                out.push(3);
                for v in tri {
                    out.extend_from_slice(&v.to_le_bytes());
                }
            }
        }
    }
    out
}

/// 1000 instances (a 10×10×10 lattice) of a 100 352-triangle mesh: loaded as instances
/// (`instancing: Auto`: the copies would be 100 M triangles), its GPU geometry stated
/// against what the copies would take, traced by the default choice of intersector (the
/// binary BVH: the only one that walks instances), and its first hits where the mirror
/// finds them.
#[test]
fn a_thousand_instances_of_a_100k_triangle_mesh() {
    let Some(ctx) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("wavy.ply"), wavy_ply(224)).unwrap();
    let places: Vec<String> = (0..1000)
        .map(|k| {
            let (x, y, z) = (k % 10, (k / 10) % 10, k / 100);
            format!(
                "(translate: ({}, {}, {}), rotate: [(axis: (0, 1, 0), degrees: {})])",
                2 * x,
                2 * y,
                -2 * z,
                7 * k
            )
        })
        .collect();
    let text = format!(
        "(version: 2,
  camera: Perspective(position: (9, 9, 14), target: (9, 9, -9), up: (0, 1, 0), fov_y: 60),
  materials: {{ \"grey\": (base_color: (0.6, 0.6, 0.6)) }},
  shapes: [Mesh(path: \"wavy.ply\", material: \"grey\", instances: [{}])],
  environment: Constant((1, 1, 1)),
  render: (width: 48, height: 48, max_bounces: 3),
)",
        places.join(", ")
    );
    let path = dir.path().join("lattice.ron");
    std::fs::write(&path, text).unwrap();
    let started = std::time::Instant::now();
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.instanced.len(), 1);
    assert_eq!(scene.instanced[0].triangles.len(), 100_352);
    let gpu = GpuScene::build(&scene).unwrap();
    let load = started.elapsed();
    assert_eq!(gpu.instances.len(), 1000);
    assert_eq!(gpu.instanced_triangles, 100_352_000);
    // The copies' geometry, from the bytes a flat triangle takes (its records and its share
    // of the BVH's, here as in the mesh's own BVH).
    let per_triangle = (gpu.geometry_bytes() as f64) / gpu.tri_positions.len() as f64;
    let copies = per_triangle * gpu.instanced_triangles as f64;
    println!(
        "1000 instances of 100 352 triangles: loaded and laid out in {:.2} s, {:.1} MiB of GPU \
         geometry; copied, about {:.1} GiB ({per_triangle:.0} bytes a triangle)",
        load.as_secs_f64(),
        gpu.geometry_bytes() as f64 / f64::from(1 << 20),
        copies / f64::from(1 << 30)
    );
    assert!(gpu.geometry_bytes() < 64 << 20);

    let scene = Arc::new(gpu);
    let outputs = vec!["acc.color".to_owned(), "pt.depth".to_owned()];
    let graph = common::progressive_graph(&[("samples_per_frame", ParamValue::Int(4))]);
    let plan = compile(&graph, &outputs, Some(&scene)).unwrap();
    let resources = Resources {
        scene: Some(scene.clone()),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    let features = lumagraph::pathtrace::nodes::pathtrace::features(&exec, "pt")
        .unwrap()
        .clone();
    println!("{}", features.summary());
    assert!(features.on(Feature::Instances));
    // The instances walked as such: by the host where it intersects, else the binary BVH.
    assert!(
        matches!(
            features.intersector(),
            Intersector::HOST | Intersector::BINARY_BVH
        ),
        "{}",
        features.summary()
    );
    let started = std::time::Instant::now();
    exec.run_frames(1, true).unwrap();
    println!(
        "48x48, 4 spp, 3 bounces: {:.2} s",
        started.elapsed().as_secs_f64()
    );
    let depth = exec.read_port("pt.depth").unwrap();
    let color = exec.read_port("acc.color").unwrap();
    assert!(color.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
    // The depth AOV is the distance along each pixel-centre ray, the mirror's to 1e-4.
    let (mut hit, mut checked) = (0, 0);
    for y in (0..48).step_by(3) {
        for x in (0..48).step_by(3) {
            let ray = common::image_ray(&scene, glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let want = lumagraph::scene::intersect(&scene, &ray).map_or(0.0, |h| h.t);
            let got = depth.pixels[y * 48 + x][0];
            checked += 1;
            if want > 0.0 {
                hit += 1;
            }
            assert!(
                (got - want).abs() <= 1e-4 * want.max(1.0),
                "pixel ({x}, {y}): depth {got}, the mirror {want}"
            );
        }
    }
    println!("{hit} of {checked} pixel-centre rays hit, at the mirror's depth");
    assert!(hit > checked / 2, "{hit} of {checked}");
}

/// The intersectors that take flat scenes only refuse an instanced one by name, and the path
/// tracer's choice sends it to the binary BVH whatever is asked, saying why: it is never
/// traced as its object-space meshes laid flat. Host intersection takes instances where it
/// takes the rest of the scene: not this one, which has a sphere; without it, a CPU
/// adapter with Embree gives it to the host, asked or not.
#[test]
fn flat_only_intersectors_refuse_instances_and_the_choice_says_why() {
    use lumagraph::pathtrace::specialize::{Features, PathTraceOptions, Schedule};
    let scene = gpu_scene("On");
    let e = lumagraph::pathtrace::intersect::wide_bvh::WideBvh::build(&scene).unwrap_err();
    assert!(
        e.contains("the 8-wide BVH takes flat scenes only, and this one has 6 instances"),
        "{e}"
    );
    let e = lumagraph::pathtrace::accel::unsupported(&scene, u32::MAX).unwrap();
    assert!(e.contains("ray queries takes flat scenes only"), "{e}");
    for (cpu_adapter, intersector) in [
        (true, Intersector::AUTO),
        (true, Intersector::WIDE_BVH),
        (true, Intersector::HOST),
        (true, Intersector::INLINE),
        (false, Intersector::RAY_QUERIES),
    ] {
        let options = PathTraceOptions {
            specialize: true,
            cpu_adapter,
            host_rays: true,
            ray_query_limit: Some(u32::MAX),
            intersector,
            schedule: Schedule::Wavefront,
            ..PathTraceOptions::default()
        };
        let f = Features::decide(&scene, options);
        assert!(f.on(Feature::Instances), "{intersector:?}");
        assert_eq!(f.intersector(), Intersector::BINARY_BVH, "{intersector:?}");
        assert!(
            !f.on(Feature::Wavefront),
            "{intersector:?}: the wavefront is on"
        );
        assert!(
            f.why(Intersector::WIDE_BVH).contains("instanced meshes")
                || f.why(Intersector::RAY_QUERIES).contains("instanced meshes"),
            "{intersector:?}: {}",
            f.summary()
        );
    }
    let triangles = triangles_scene("On", false);
    for intersector in [Intersector::AUTO, Intersector::HOST] {
        let options = PathTraceOptions {
            specialize: true,
            cpu_adapter: true,
            host_rays: true,
            intersector,
            ..PathTraceOptions::default()
        };
        let f = Features::decide(&triangles, options);
        assert!(
            f.intersector() == Intersector::HOST && f.on(Feature::Instances),
            "{intersector:?}: {}",
            f.summary()
        );
        assert!(
            lumagraph::pathtrace::specialize::support::refusal(&triangles, options, &f).is_none(),
            "{intersector:?}"
        );
    }
}

/// Embree's two levels (a scene per mesh, an instance geometry per instance) against the
/// CPU mirror's two-level walk on the same 50 000 rays as the GPU's test, opaque and with
/// every instanced triangle blended at opacity 0.5 (the any-hit filter must draw each
/// choice from the world-space ray and the triangle's index, as the mirror does): the
/// closest hit on the same triangle of the same instance (its node slot, as the WGSL names
/// it) at the same distance (1e-5 relative, of 1 below 1) and barycentrics (1e-3), and the
/// same occlusion up to `t_max`. Embree's test is watertight where the mirror's
/// Möller-Trumbore is not, and a ray through an edge may meet one neighbour or the other:
/// at most 0.2 % of rays may differ (measured: none opaque, 1 blended of 50 000, and
/// 1 occlusion). Fails without Embree unless `LUMAGRAPH_ALLOW_NO_EMBREE=1`.
#[test]
fn embree_hits_instances_as_the_mirror_does() {
    use lumagraph::pathtrace::embree::{Embree, HostHit, HostRay, HostScene};
    use lumagraph::scene::NO_INSTANCE;
    let embree = match Embree::load() {
        Ok(e) => e,
        Err(e) => {
            assert!(
                std::env::var("LUMAGRAPH_ALLOW_NO_EMBREE").is_ok_and(|v| v == "1"),
                "Embree 3 is not installed ({e}): scripts/setup.sh installs it, or set \
                 LUMAGRAPH_ALLOW_NO_EMBREE=1"
            );
            return;
        }
    };
    let queries = rays(50_000);
    let host_rays: Vec<HostRay> = queries
        .iter()
        .map(|q| HostRay {
            origin: q.origin,
            tnear: 0.0,
            dir: q.dir,
            tfar: q.t_max,
        })
        .collect();
    for (name, scene) in [
        ("opaque", triangles_scene("On", false)),
        ("blended", triangles_scene("On", true)),
    ] {
        assert_eq!(scene.instances.len(), 6);
        let scene = Arc::new(scene);
        let host = HostScene::of_scene(Arc::clone(&embree), &scene).unwrap();
        assert!(host.has_instances());
        let mut hits = vec![HostHit::default(); queries.len()];
        let mut insts = vec![0; queries.len()];
        host.intersect_instances(&host_rays, &mut hits, &mut insts);
        let mut occluded = vec![0; queries.len()];
        host.occluded(&host_rays, &mut occluded);
        let (mut agree, mut in_instances, mut differ, mut blocked_differ) = (0, 0, 0, 0);
        for (i, q) in queries.iter().enumerate() {
            let ray = Ray {
                origin: q.origin.into(),
                dir: q.dir.into(),
            };
            let (h, inst) = (hits[i], insts[i]);
            let same = match intersect_within(&scene, &ray, q.t_max) {
                None => !h.is_hit(),
                Some(c) => {
                    h.is_hit()
                        && (h.prim, inst) == (c.prim, c.inst)
                        && (h.t - c.t).abs() <= 1e-5 * c.t.max(1.0)
                        && (h.u - c.u).abs() <= 1e-3
                        && (h.v - c.v).abs() <= 1e-3
                }
            };
            if same {
                agree += 1;
                in_instances += usize::from(h.is_hit() && inst != NO_INSTANCE);
            } else {
                differ += 1;
            }
            if !h.is_hit() {
                assert_eq!(inst, NO_INSTANCE, "a miss names no instance");
            }
            let blocked = lumagraph::scene::occluded(&scene, &ray, q.t_max);
            blocked_differ += usize::from(blocked != (occluded[i] != 0));
        }
        println!(
            "{name}: {agree} rays agree ({in_instances} hits in instances), {differ} differ; \
             {blocked_differ} occlusions differ"
        );
        assert!(
            in_instances > 5_000,
            "{name}: too few instance hits: {in_instances}"
        );
        assert!(
            differ * 500 <= queries.len(),
            "{name}: {differ} rays differ"
        );
        assert!(
            blocked_differ * 500 <= queries.len(),
            "{name}: {blocked_differ} occlusions differ"
        );
    }
}

/// The scene (without its sphere) rendered at 64×64 and 16 spp by host intersection
/// (Embree, on a CPU adapter) with its grid kept as 6 instances (`instancing: On`), against
/// the same instances through the binary WGSL BVH's two-level walk, and against the copies
/// (`Off`) through host intersection; opaque, and with the grid blended at opacity 0.5 (the
/// any-hit filter on instanced triangles). The kernel's random numbers and shading are the
/// same throughout; only the hits differ in rounding, and a path that meets an edge may take
/// another turn.
///
/// Opaque: against the binary BVH's instances (the shading reads the host's instance hits
/// as it reads the walk's), at most 1.5 % of pixels beyond 1e-4 relative (measured 29 of
/// 4096, as many as host intersection against the WGSL over copies: 21); against the
/// copies, at most 8 % (measured 210: the binary BVH's instances against its own copies
/// differ as much, 200, as copies are placed once in f64 and instances at every hit in
/// f32). The image means within 1e-3 relative of both (measured -2.0e-4 and -1.5e-4).
///
/// Blended: a blended surface's choice hashes the ray's bits, so once a path's hit rounds
/// another way its later choices are new draws, and pixels are not compared but for a
/// bound against the binary BVH's instances, 25 % (measured 751 of 4096; host against the
/// WGSL over copies: 727). The image means: within 1e-3 of the binary BVH's instances
/// (measured -2.3e-5) and within 6e-3 of the copies, whose choices also draw on their own
/// triangle numbers (measured 2.0e-3; with seeds 1 to 3: -1.5e-3, -1.1e-3, -1.6e-3, and the
/// binary BVH's instances against its copies 2.2e-3: noise, with no sign of a bias).
///
/// Nothing runs on a GPU adapter; fails on a CPU adapter without Embree unless
/// `LUMAGRAPH_ALLOW_NO_EMBREE=1`.
#[test]
fn host_intersection_renders_instances_as_the_binary_bvh_and_the_copies_do() {
    let Some(ctx) = common::gpu() else { return };
    if !ctx.is_cpu() {
        println!("a GPU adapter: no host intersection");
        return;
    }
    // (blended, the most pixels beyond 1e-4 against the binary BVH and against the copies,
    // the largest difference of the means against the copies).
    for (veil, walk_pixels, copy_pixels, copy_mean) in
        [(false, 0.015, 0.08, 1e-3), (true, 0.25, 1.0, 6e-3)]
    {
        let render = |instancing: &str, intersector: Intersector| {
            let tracer = Tracing {
                intersector,
                ..Tracing::default()
            };
            common::render_scene(
                triangles_scene(instancing, veil),
                (64, 64),
                16,
                Resources::default().with(tracer),
            )
            .unwrap()
        };
        let (inst, how) = render("On", Intersector::AUTO);
        if how.intersector() != Intersector::HOST {
            assert!(
                std::env::var("LUMAGRAPH_ALLOW_NO_EMBREE").is_ok_and(|v| v == "1"),
                "no host intersection on this CPU adapter ({}): install Embree 3 \
                 (scripts/setup.sh), or set LUMAGRAPH_ALLOW_NO_EMBREE=1",
                how.why(Intersector::HOST)
            );
            return;
        }
        assert!(how.on(Feature::Instances), "{}", how.summary());
        let (walk, how) = render("On", Intersector::BINARY_BVH);
        assert!(
            how.intersector() == Intersector::BINARY_BVH && how.on(Feature::Instances),
            "{}",
            how.summary()
        );
        let (flat, how) = render("Off", Intersector::HOST);
        assert!(
            how.intersector() == Intersector::HOST && !how.on(Feature::Instances),
            "{}",
            how.summary()
        );
        let sum = |i: &lumagraph::render::cpu::Image| {
            i.pixels
                .iter()
                .map(|p| f64::from(p[0] + p[1] + p[2]))
                .sum::<f64>()
        };
        assert!(sum(&flat[0]) > 1.0, "black");
        let n = inst[0].pixels.len();
        for (what, other, pixels, means) in [
            ("the binary BVH", &walk, walk_pixels, 1e-3),
            ("the copies", &flat, copy_pixels, copy_mean),
        ] {
            let (a, b) = (&inst[0], &other[0]);
            let far = common::differing(a, b, Some(1e-4));
            let rel = (sum(a) - sum(b)) / sum(b);
            println!(
                "blended {veil}, against {what}: {} of {n} pixels differ in any bit, {far} \
                 beyond 1e-4 relative, the worst by {:.2e}; the means by {rel:.2e}",
                common::differing(a, b, None),
                common::worst_relative(a, b)
            );
            assert!(
                far as f64 <= pixels * n as f64,
                "blended {veil}, against {what}: {far} pixels differ"
            );
            assert!(
                rel.abs() <= means,
                "blended {veil}, against {what}: the means differ by {rel}"
            );
        }
    }
}
