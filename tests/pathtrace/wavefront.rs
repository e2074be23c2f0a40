//! The wavefront (`Schedule::Wavefront`, `--schedule wavefront`): the paths of a frame
//! taken one bounce at a time by the steps of `pathtrace/integrator/wave.wgsl`, each step's rays traced
//! on the device by `wave_trace` through the intersector the megakernel uses, with the same
//! rules for rays leaving a surface. Same random numbers, same arithmetic, same hits: the
//! images are the megakernel's, bit for bit.

use crate::common;

use std::sync::Arc;

use lumagraph::pathtrace::specialize::{Feature, Intersector, Schedule, Tracing};
use lumagraph::render::Resources;
use lumagraph::scene::GpuScene;

fn as_gpu(intersector: Intersector, schedule: Schedule) -> Resources {
    Resources {
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        intersector,
        schedule,
        ..Tracing::default()
    })
}

/// The wavefront against the megakernel, both as a GPU adapter runs them, at 64×64 and
/// 16 spp (4 frames of 4): glass and an area light through the binary BVH
/// (`tests/scenes/host/cornell_glass.ron`: refraction, MIS at emitter hits, shadow rays
/// leaving either side of a surface). Asserted: color, albedo, normal and depth
/// bit-identical (measured so, and on `cornell_metals.ron`'s metals and on `mesh_env.ron`
/// through the binary and the 8-wide BVH; left out here: each wavefront shader costs
/// lavapipe five pipelines to compile, about a minute with a cold shader cache).
#[test]
fn the_wavefront_renders_what_the_megakernel_renders() {
    let name = "../tests/scenes/host/cornell_glass.ron";
    let intersector = Intersector::BINARY_BVH;
    let Some((front, how_front)) =
        common::render_with(name, (64, 64), 16, as_gpu(intersector, Schedule::Wavefront))
    else {
        return;
    };
    let (mega, how_mega) = common::render_with(
        name,
        (64, 64),
        16,
        as_gpu(intersector, Schedule::Megakernel),
    )
    .unwrap();
    assert!(how_front.on(Feature::Wavefront), "{}", how_front.summary());
    assert!(!how_mega.on(Feature::Wavefront), "{}", how_mega.summary());
    assert!(front[0].pixels.iter().any(|p| p[0] > 0.0), "{name}: black");
    for (i, port) in ["color", "albedo", "normal", "depth"].iter().enumerate() {
        let differ = common::differing(&front[i], &mega[i], None);
        println!("{name} ({intersector:?}) {port}: {differ} pixels differ");
        assert_eq!(differ, 0, "{name} ({intersector:?}) {port}");
    }
}

/// Alpha masks in the wavefront's tracing: the checkerboard-masked quad before a wall of
/// 8×8 quads (`alpha.rs`), under a white sky, 4 spp: camera rays and bounces pass its holes
/// as in the megakernel. Asserted: the color bit-identical.
#[test]
fn the_wavefront_sees_through_alpha_masks_as_the_megakernel_does() {
    use super::alpha::{albedos, checker_masked, front_and_tiled_wall};
    let scene = Arc::new(GpuScene::build(&checker_masked(front_and_tiled_wall(64, 8))).unwrap());
    let Some((_, _, front, how)) =
        albedos(&scene, as_gpu(Intersector::BINARY_BVH, Schedule::Wavefront))
    else {
        return;
    };
    let (_, _, mega, _) = albedos(
        &scene,
        as_gpu(Intersector::BINARY_BVH, Schedule::Megakernel),
    )
    .unwrap();
    assert!(
        how.on(Feature::Wavefront) && how.on(Feature::Alpha),
        "{}",
        how.summary()
    );
    let differ = common::differing(&front, &mega, None);
    println!("masked checkerboard: {differ} pixels differ");
    assert_eq!(differ, 0);
}

/// Texture levels of detail in the wavefront's steps: the grazing checker floor under a
/// checkered ceiling (`textures.rs`), 3 bounces, 4 spp, where rays that bounce off the floor
/// read the ceiling's texture at a level their cone (kept in the path's state between
/// steps) gives. Asserted: the color bit-identical to the megakernel's, and different from
/// the image without mips (the levels are read).
#[test]
fn the_wavefront_carries_the_ray_cone_as_the_megakernel_does() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Arc::new(super::textures::grazing_checker(dir.path(), true, true));
    let flat = Arc::new(super::textures::grazing_checker(dir.path(), false, true));
    let render = |scene: &Arc<GpuScene>, schedule| {
        common::render_scene_with(scene, 4, as_gpu(Intersector::BINARY_BVH, schedule))
    };
    let Some((front, how)) = render(&scene, Schedule::Wavefront) else {
        return;
    };
    let (mega, _) = render(&scene, Schedule::Megakernel).unwrap();
    let (without, _) = render(&flat, Schedule::Megakernel).unwrap();
    assert!(how.on(Feature::Wavefront), "{}", how.summary());
    let differ = common::differing(&front[0], &mega[0], None);
    let changed = common::differing(&without[0], &mega[0], None);
    println!("grazing checker: {differ} pixels differ; {changed} without mips");
    assert_eq!(differ, 0);
    assert!(changed > 1000, "{changed}");
}

/// Where the wavefront is compiled in: asked for, or (the default) on a GPU adapter for a
/// scene of textured materials and at least `WAVEFRONT_MIN_TRIANGLES` triangles, the kind of
/// scene it measured faster on (Sponza on an NVIDIA H200, `docs/benchmarks.md`); never where
/// its steps cannot trace the scene (spheres, media: the steps shade triangle hits only); and
/// the plan says why.
#[test]
fn the_wavefront_is_used_where_asked_for_or_measured_faster() {
    use lumagraph::pathtrace::specialize::{Features, PathTraceOptions, WAVEFRONT_MIN_TRIANGLES};
    use lumagraph::scene::Scene;
    let decide = |scene: &GpuScene, schedule, cpu_adapter| {
        Features::decide(
            scene,
            PathTraceOptions {
                specialize: true,
                cpu_adapter,
                schedule,
                ..PathTraceOptions::default()
            },
        )
    };
    let mesh = common::gpu_scene("tests/scenes/mesh_env.ron", Some(32));
    let small_textured = common::gpu_scene("assets/boxtextured.ron", Some(32));
    // The textured box, its 12 triangles copied side by side past the threshold.
    let mut scene = Scene::load(&common::repo("assets/boxtextured.ron")).unwrap();
    let box_triangles = scene.triangles.clone();
    for i in 1..=WAVEFRONT_MIN_TRIANGLES / box_triangles.len() {
        let offset = glam::Vec3::new(3.0 * i as f32, 0.0, 0.0);
        scene.triangles.extend(box_triangles.iter().map(|t| {
            let mut t = *t;
            t.positions = t.positions.map(|p| p + offset);
            t
        }));
    }
    let large_textured = GpuScene::build(&scene).unwrap();
    assert!(large_textured.tri_positions.len() >= WAVEFRONT_MIN_TRIANGLES);
    // Asked for.
    assert!(decide(&mesh, Schedule::Wavefront, false).on(Feature::Wavefront));
    assert!(decide(&small_textured, Schedule::Wavefront, false).on(Feature::Wavefront));
    let off = decide(&large_textured, Schedule::Megakernel, false);
    assert!(!off.on(Feature::Wavefront), "{}", off.summary());
    // The default: large textured scenes on GPU adapters.
    let chosen = decide(&large_textured, Schedule::Auto, false);
    let why = chosen.reason(Feature::Wavefront);
    assert!(chosen.on(Feature::Wavefront), "{why}");
    assert!(why.contains("textured"), "{why}");
    for (scene, what) in [
        (&mesh, "no textured material"),
        (&small_textured, "triangles <"),
    ] {
        let f = decide(scene, Schedule::Auto, false);
        let why = f.reason(Feature::Wavefront);
        assert!(!f.on(Feature::Wavefront), "{why}");
        assert!(
            why.contains(what) && why.contains("--schedule wavefront"),
            "{why}"
        );
    }
    let cpu = decide(&large_textured, Schedule::Auto, true);
    assert!(!cpu.on(Feature::Wavefront));
    assert!(cpu.reason(Feature::Wavefront).contains("CPU adapter"));
    // Never where the steps cannot trace the scene.
    let spheres = common::gpu_scene("assets/cornell_spheres.ron", Some(32));
    let f = decide(&spheres, Schedule::Wavefront, false);
    assert!(!f.on(Feature::Wavefront));
    let why = f.reason(Feature::Wavefront);
    assert!(why.contains("analytic shapes"), "{why}");
    let media = common::gpu_scene("tests/scenes/media_scattering.ron", Some(32));
    assert!(!decide(&media, Schedule::Wavefront, false).on(Feature::Wavefront));
}
