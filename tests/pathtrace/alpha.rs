//! Alpha (glTF `alphaMode`): `Mask` cuts a surface out where its opacity is below the
//! cutoff and `Blend` lets rays through with probability 1 − opacity, in every intersector
//! (the WGSL BVH, inline intersection, the CPU mirror) and in the G-buffer raster, for
//! camera rays, bounces and shadow rays alike.

use crate::common;
use lumagraph::pathtrace::specialize::Tracing;

use std::sync::Arc;

use glam::{Vec2, Vec3};
use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::pathtrace::specialize::{Feature, Intersector};
use lumagraph::render::Resources;
use lumagraph::render::cpu::Image;
use lumagraph::scene::traverse::{Ray, intersect};
use lumagraph::scene::{AlphaMode, GpuScene, Scene, Texture, Wrap};

/// A red quad (material 0 of the file, `a_front`) 1 unit in front of a blue wall (`b_wall`),
/// seen head-on, under a white sky; `size`² pixels.
fn front_and_wall(size: u32) -> Scene {
    front_and_tiled_wall(size, 1)
}

/// [`front_and_wall`] with the wall made of `tiles`² quads (over 64 primitives: past what a
/// CPU adapter intersects inline, so the host does it where Embree is found).
pub(super) fn front_and_tiled_wall(size: u32, tiles: u32) -> Scene {
    let mut wall = String::new();
    let step = 6.0 / tiles as f32;
    for j in 0..tiles {
        for i in 0..tiles {
            let (x0, y0) = (-3.0 + step * i as f32, -3.0 + step * j as f32);
            let (x1, y1) = (x0 + step, y0 + step);
            wall.push_str(&format!(
                "Quad(material: \"b_wall\", corners: [({x0:?}, {y0:?}, -0.5), ({x1:?}, {y0:?}, -0.5), ({x1:?}, {y1:?}, -0.5), ({x0:?}, {y1:?}, -0.5)]),\n"
            ));
        }
    }
    let text = format!(
        "(version: 2,
          camera: Perspective(position: (0.0, 0.0, 4.0), target: (0.0, 0.0, 0.0), fov_y: 30.0),
          materials: {{
            \"a_front\": (base_color: (0.9, 0.1, 0.1), roughness: 1.0, specular: 0.0, two_sided: true),
            \"b_wall\": (base_color: (0.1, 0.1, 0.9), roughness: 1.0, specular: 0.0),
          }},
          shapes: [
            Quad(material: \"a_front\", corners: [(-0.8, -0.8, 0.5), (0.8, -0.8, 0.5), (0.8, 0.8, 0.5), (-0.8, 0.8, 0.5)]),
            {wall}
          ],
          environment: Constant((1.0, 1.0, 1.0)),
          render: (width: {size}, height: {size}, max_bounces: 4, spp: 1, seed: 0))"
    );
    Scene::from_ron(&text, &common::repo("assets")).unwrap()
}

/// `scene` with the front quad's material alpha-masked by an 8×8 checkerboard (alpha 0 and
/// 255, nearest texels) at cutoff 0.5, its UVs over the quad.
pub(super) fn checker_masked(mut scene: Scene) -> Scene {
    scene.textures = vec![Texture {
        name: "checker".into(),
        width: 8,
        height: 8,
        texels: (0..64)
            .map(|k| {
                let a = if (k % 8 + k / 8) % 2 == 0 { 255 } else { 0 };
                [230, 25, 25, a]
            })
            .collect(),
        wrap: [Wrap::Repeat; 2],
        nearest: true,
        uv_set: 0,
        transform: lumagraph::scene::UvTransform::IDENTITY,
    }];
    let m = &mut scene.materials[0];
    m.textures.base_color = 0;
    m.alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    for t in &mut scene.triangles {
        t.uvs = Some(
            t.positions
                .map(|p| Vec2::new((p.x + 0.8) / 1.6, (0.8 - p.y) / 1.6)),
        );
    }
    scene
}

/// The pinhole ray through the centre of pixel (x, y), as the shader makes it.
fn pixel_ray(g: &GpuScene, x: u32, y: u32) -> Ray {
    common::image_ray(g, Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
}

/// `PathTrace` (with its first-hit albedo) and `GBuffer` albedo of `scene`, `resources`'
/// intersector, one frame of 4 spp, and the path tracer's shader features.
pub(super) fn albedos(
    scene: &Arc<GpuScene>,
    resources: Resources,
) -> Option<(
    Image,
    Image,
    Image,
    lumagraph::pathtrace::specialize::Features,
)> {
    let ctx = common::gpu()?;
    let graph = Graph {
        nodes: vec![
            Node::new("pt", "PathTrace").with("samples_per_frame", ParamValue::Int(4)),
            Node::new("gb", "GBuffer"),
            Node::new("acc", "Accumulate"),
        ],
        edges: vec![Edge::new("pt.color", "acc.color")],
        ..Graph::default()
    };
    let keep = ["pt.albedo", "gb.albedo", "acc.color"].map(str::to_owned);
    let plan = compile(&graph, &keep, Some(scene)).unwrap();
    let resources = Resources {
        scene: Some(Arc::clone(scene)),
        ..resources
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    let features = lumagraph::pathtrace::nodes::pathtrace::features(&exec, "pt")
        .unwrap()
        .clone();
    exec.run_frame().unwrap();
    Some((
        exec.read_port("pt.albedo").unwrap(),
        exec.read_port("gb.albedo").unwrap(),
        exec.read_port("acc.color").unwrap(),
        features,
    ))
}

/// Through the checkerboard's cut-out squares the camera sees the wall: per pixel, the
/// first-hit albedo of the path tracer (inline intersection, as lavapipe runs the small
/// scene, BVH traversal, as GPUs do, and with the wall in 64 quads host intersection, as
/// lavapipe runs larger scenes with Embree) and of the G-buffer raster against the material
/// the CPU mirror's traversal finds through the pixel centre, and through the 8-wide BVH
/// (`--intersector wide`). Measured: every pixel agrees
/// (0 of 4096); asserted: at most 0.5 % differ (texel edges that rounding puts on either
/// side), and the cut-out squares are half the quad's pixels within 10 %.
#[test]
fn masked_checkerboard_shows_the_wall_through_its_holes() {
    let inline_or_bvh = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        ..Tracing::default()
    });
    let wgsl = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        intersector: Intersector::BINARY_BVH,
        ..Tracing::default()
    });
    let wide = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        intersector: Intersector::WIDE_BVH,
        ..Tracing::default()
    });
    check_checkerboard(
        1,
        &[
            ("inline", Resources::default()),
            ("BVH", inline_or_bvh),
            ("8-wide BVH", wide.clone()),
        ],
    );
    check_checkerboard(
        8,
        &[
            ("host", Resources::default()),
            ("WGSL BVH", wgsl),
            ("8-wide BVH", wide),
        ],
    );
}

/// [`masked_checkerboard_shows_the_wall_through_its_holes`] through ray queries: each
/// candidate the device finds takes the same any-hit test (on a driver with ray queries,
/// `common::ray_queries_here`).
#[test]
fn masked_checkerboard_shows_the_wall_through_ray_queries() {
    if !common::ray_queries_here("masked_checkerboard_shows_the_wall_through_ray_queries") {
        return;
    }
    let ray_queries = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        intersector: Intersector::RAY_QUERIES,
        ..Tracing::default()
    });
    check_checkerboard(1, &[("ray queries", ray_queries.clone())]);
    check_checkerboard(8, &[("ray queries", ray_queries)]);
}

/// [`masked_checkerboard_shows_the_wall_through_its_holes`] with the wall in `tiles`²
/// quads, through each of `intersectors`.
fn check_checkerboard(tiles: u32, intersectors: &[(&str, Resources)]) {
    let scene = checker_masked(front_and_tiled_wall(64, tiles));
    let gpu = Arc::new(GpuScene::build(&scene).unwrap());
    let expected: Vec<Option<u32>> = (0..64 * 64)
        .map(|i| {
            intersect(&gpu, &pixel_ray(&gpu, i % 64, i / 64))
                .map(|h| gpu.tri_shading[h.index()].material)
        })
        .collect();
    let front = expected.iter().filter(|m| **m == Some(0)).count();
    let wall_inside = (0..64 * 64)
        .filter(|&i| {
            let (x, y) = (i % 64, i / 64);
            // Inside the quad's silhouette (±0.8 at distance 3.5 under a 30° view: ±27.3
            // pixels about the centre).
            (6..58).contains(&x) && (6..58).contains(&y) && expected[i as usize] == Some(1)
        })
        .count();
    println!("CPU mirror: {front} pixels on the front quad, {wall_inside} through its holes");
    assert!(
        (0.4..0.6).contains(&(wall_inside as f64 / (wall_inside + front) as f64)),
        "{wall_inside} holes against {front} quad pixels"
    );
    let colour = |p: [f32; 4]| {
        if p[3] == 0.0 {
            None
        } else if p[0] > p[2] {
            Some(0)
        } else {
            Some(1)
        }
    };
    for (name, resources) in intersectors {
        let Some((pt, gb, _, features)) = albedos(&gpu, resources.clone()) else {
            return;
        };
        assert!(
            features.on(Feature::Alpha),
            "{name}: the alpha test was left out"
        );
        let host = features.intersector() == Intersector::HOST;
        if *name == "host" && !host {
            assert!(
                !common::gpu().is_some_and(lumagraph::render::GpuContext::is_cpu)
                    || std::env::var("LUMAGRAPH_ALLOW_NO_EMBREE").is_ok_and(|v| v == "1"),
                "no host intersection on this CPU adapter: {}",
                features.why(Intersector::HOST)
            );
            continue;
        }
        assert_eq!(host, *name == "host", "{name}: {}", features.summary());
        assert_eq!(
            features.intersector() == Intersector::RAY_QUERIES,
            *name == "ray queries",
            "{name}: {}",
            features.summary()
        );
        assert_eq!(
            features.intersector() == Intersector::WIDE_BVH,
            *name == "8-wide BVH",
            "{name}: {}",
            features.summary()
        );
        for (what, image) in [("path tracer", &pt), ("G-buffer", &gb)] {
            let differ = image
                .pixels
                .iter()
                .zip(&expected)
                .filter(|(p, e)| colour(**p) != **e)
                .count();
            println!("{name}, {what}: {differ} of 4096 pixels differ from the CPU mirror");
            assert!(differ <= 20, "{name}, {what}: {differ} pixels differ");
        }
    }
}

/// Stochastic transparency has the expected value of the blend: a black quad of opacity 0.3
/// in front of a white sky (no wall) lets 70 % of the light through, 0.7 in every pixel it
/// covers. Over 36×36 pixels inside it at 256 spp (331 776 samples of a Bernoulli(0.7)
/// times 1): the mean within 5 standard errors (σ/√n = 0.46/576 = 8.0e-4), through inline
/// intersection and the BVH.
#[test]
fn blended_quad_passes_one_minus_its_opacity() {
    let mut scene = front_and_wall(64);
    scene.triangles.truncate(2);
    let m = &mut scene.materials[0];
    m.base_color = Vec3::ZERO;
    m.opacity = 0.3;
    m.alpha_mode = AlphaMode::Blend;
    let gpu = Arc::new(GpuScene::build(&scene).unwrap());
    for (name, bvh) in [("inline", false), ("BVH", true)] {
        let Some(ctx) = common::gpu() else { return };
        let plan = compile(
            &common::progressive_graph(&[("samples_per_frame", ParamValue::Int(64))]),
            &["acc.color".to_owned()],
            Some(&gpu),
        )
        .unwrap();
        let resources = Resources {
            scene: Some(Arc::clone(&gpu)),
            ..Resources::default()
        }
        .with(Tracing {
            as_gpu_adapter: bvh,
            ..Tracing::default()
        });
        let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
        exec.run_frames(4, true).unwrap();
        let image = exec.read_port("acc.color").unwrap();
        let mut sum = 0.0;
        let mut n = 0.0;
        for y in 14..50 {
            for x in 14..50 {
                let p = image.pixels[y * 64 + x];
                sum += f64::from(p[0] + p[1] + p[2]) / 3.0;
                n += 1.0;
            }
        }
        let mean = sum / n;
        let se = (0.7f64 * 0.3).sqrt() / (n * 256.0).sqrt();
        println!("{name}: mean {mean:.5} (expected 0.7, standard error {se:.2e})");
        assert!((mean - 0.7).abs() < 5.0 * se, "{name}: mean {mean}");
    }
}

/// A masked quad whose opacity is below its cutoff everywhere is not there for any ray:
/// the wall behind it, lit by the sky through where the quad was, renders as without the
/// quad (same 8×8-block means, Welch's t-test over 16 independent frames, α = 1e-3); and
/// a masked quad whose opacity reaches the cutoff everywhere renders bit for bit as the
/// opaque quad.
#[test]
fn a_fully_cut_out_quad_is_invisible_and_a_full_one_solid() {
    let base = front_and_wall(32);
    let mut gone = base.clone();
    gone.materials[0].opacity = 0.2;
    gone.materials[0].alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    let mut without = base.clone();
    without.triangles.drain(0..2);
    let frames = |s: &Scene, seed: u32| {
        common::independent_frames(&GpuScene::build(s).unwrap(), seed, &[], 16, 8)
    };
    let Some(a) = frames(&gone, 1) else { return };
    let b = frames(&without, 2).unwrap();
    let (tests, worst) = common::same_means(&a, &b, 8, 1e-3, 1e-3).unwrap();
    println!("cut out vs absent: {tests} tests, largest |t| {worst:.2} of the critical value");
    let mut full = base.clone();
    full.materials[0].opacity = 0.7;
    full.materials[0].alpha_mode = AlphaMode::Mask { cutoff: 0.5 };
    let solid = frames(&base, 3).unwrap();
    let masked = frames(&full, 3).unwrap();
    assert!(
        solid == masked,
        "a mask that keeps everything changed the image"
    );
    let mean = |f: &[Image]| {
        f[0].pixels.iter().map(|p| f64::from(p[0])).sum::<f64>() / f[0].pixels.len() as f64
    };
    assert!(
        (mean(&solid) - mean(&a)).abs() > 0.01,
        "the quad should change the image: {} vs {}",
        mean(&solid),
        mean(&a)
    );
}

/// Host intersection's any-hit test (Embree's filter) against the CPU mirror's, ray by ray:
/// the checkerboard scene's pixel-centre rays (closest hit and occlusion) and the same rays
/// through a blended copy of the quad (the hash's choices must be the mirror's). Measured:
/// every ray agrees; asserted: at most 0.5 % differ.
#[test]
fn embree_applies_the_same_any_hit_test_as_the_mirror() {
    use lumagraph::pathtrace::embree::{Embree, HostHit, HostRay, HostScene};
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
    let masked = checker_masked(front_and_tiled_wall(64, 8));
    let mut blended = masked.clone();
    blended.materials[0].alpha_mode = AlphaMode::Blend;
    blended.materials[0].opacity = 0.6;
    for (name, scene) in [("mask", masked), ("blend", blended)] {
        let gpu = Arc::new(GpuScene::build(&scene).unwrap());
        let host = HostScene::of_scene(Arc::clone(&embree), &gpu).unwrap();
        let rays: Vec<Ray> = (0..64 * 64)
            .map(|i| pixel_ray(&gpu, i % 64, i / 64))
            .collect();
        let host_rays: Vec<HostRay> = rays
            .iter()
            .map(|r| HostRay {
                origin: r.origin.to_array(),
                tnear: 0.0,
                dir: r.dir.to_array(),
                tfar: f32::MAX,
            })
            .collect();
        let mut hits = vec![HostHit::default(); rays.len()];
        host.intersect(&host_rays, &mut hits);
        // Occlusion up to the wall: only the front quad can occlude.
        let shadow: Vec<HostRay> = host_rays
            .iter()
            .map(|r| HostRay { tfar: 3.9, ..*r })
            .collect();
        let mut occluded = vec![0u32; rays.len()];
        host.occluded(&shadow, &mut occluded);
        let mut differ = 0;
        let mut front = 0;
        for (i, r) in rays.iter().enumerate() {
            let mirror = intersect(&gpu, r).map(|h| gpu.tri_shading[h.index()].material);
            let embree = hits[i]
                .is_hit()
                .then(|| gpu.tri_shading[hits[i].prim as usize].material);
            let blocked = lumagraph::scene::occluded(&gpu, r, 3.9);
            if mirror != embree || blocked != (occluded[i] != 0) {
                differ += 1;
            }
            front += usize::from(mirror == Some(0));
        }
        println!("{name}: {differ} of 4096 rays differ; {front} hit the front quad");
        assert!(differ <= 20, "{name}: {differ} rays differ");
        assert!(front > 500 && front < 2000, "{name}: {front} front hits");
    }
}
