//! Ray queries (`plan`: "ray queries"): where the device has them
//! (`wgpu::Features::EXPERIMENTAL_RAY_QUERY`; lavapipe from Mesa 25, which the set-up
//! installs), the device's acceleration structure finds the candidates and
//! `pathtrace/intersect/ray_query.wgsl` tests them with the WGSL BVH's own tests. GPU adapters trace
//! through them; CPU adapters when asked (`--intersector rays`, or a test's resources).
//! The GPU tests run on a driver with ray queries: the test device's, or else Mesa 25's
//! lavapipe in a child process (`common::ray_queries_here`); without one they fail unless
//! `LUMAGRAPH_ALLOW_NO_RAY_QUERY=1`.

use crate::common;
use lumagraph::pathtrace::specialize::Tracing;

use lumagraph::pathtrace::specialize::{
    AdapterTraits, Features, Intersector, PathTraceOptions, Specialization,
};
use lumagraph::render::Resources;
use lumagraph::scene::{GpuScene, Scene};

fn scene(rel: &str) -> GpuScene {
    GpuScene::build(&Scene::load(&common::repo(rel)).unwrap()).unwrap()
}

fn options(traits: AdapterTraits, forced: bool) -> PathTraceOptions {
    PathTraceOptions {
        specialize: true,
        cpu_adapter: traits.cpu,
        ray_query_limit: traits.ray_query_limit,
        intersector: if forced {
            Intersector::RAY_QUERIES
        } else {
            Intersector::AUTO
        },
        ..PathTraceOptions::default()
    }
}

/// Which intersector the features choose (by its handle, never by label).
fn intersector(f: &Features) -> &'static str {
    match f.intersector() {
        Intersector::INLINE => "inline",
        Intersector::HOST => "host",
        Intersector::RAY_QUERIES => "ray queries",
        Intersector::BINARY_BVH | Intersector::WIDE_BVH => "WGSL BVH",
        other => panic!("{other:?}: {}", f.summary()),
    }
}

/// The choice, without a device: a GPU adapter with ray queries traces through them (one
/// intersector only, the BVH's code left out); a GPU without them traverses the BVH in
/// WGSL; a CPU adapter keeps inline intersection for small scenes and the WGSL BVH for
/// large ones unless ray queries are asked for, and then takes them even for small
/// scenes; the general shader never does; a scene over the device's primitive limit does
/// not, and says why. The shader source enables `wgpu_ray_query` exactly when they are
/// chosen.
#[test]
fn ray_queries_are_chosen_where_the_device_has_them() {
    let small = scene("assets/cornell_spheres.ron");
    let large = scene("tests/scenes/mesh_env.ron");
    let rq = Some(1 << 24);
    let gpu = |ray_query_limit| AdapterTraits {
        cpu: false,
        ray_query_limit,
    };
    let cpu = |ray_query_limit| AdapterTraits {
        cpu: true,
        ray_query_limit,
    };
    let cases = [
        (
            "GPU with ray queries",
            &small,
            gpu(rq),
            false,
            "ray queries",
        ),
        (
            "GPU with ray queries",
            &large,
            gpu(rq),
            false,
            "ray queries",
        ),
        ("GPU without", &small, gpu(None), false, "WGSL BVH"),
        ("CPU with ray queries", &small, cpu(rq), false, "inline"),
        (
            "CPU with ray queries, asked",
            &small,
            cpu(rq),
            true,
            "ray queries",
        ),
        (
            "CPU with ray queries, asked",
            &large,
            cpu(rq),
            true,
            "ray queries",
        ),
        ("CPU without, asked", &small, cpu(None), true, "inline"),
        (
            "GPU, limit of 8 primitives",
            &small,
            gpu(Some(8)),
            false,
            "WGSL BVH",
        ),
    ];
    for (what, scene, traits, forced, expected) in cases {
        let f = Features::decide(scene, options(traits, forced));
        println!(
            "{what}: {} ({})",
            intersector(&f),
            f.why(Intersector::RAY_QUERIES)
        );
        assert_eq!(intersector(&f), expected, "{what}: {}", f.summary());
        let source = Specialization::new(scene, options(traits, forced))
            .source()
            .unwrap();
        assert_eq!(
            source.starts_with("enable wgpu_ray_query;"),
            expected == "ray queries",
            "{what}"
        );
        assert_eq!(
            source.contains("rayQueryInitialize"),
            expected == "ray queries",
            "{what}"
        );
    }
    let f = Features::decide(&small, options(gpu(Some(8)), false));
    assert!(
        f.why(Intersector::RAY_QUERIES)
            .contains("at most 8 primitives"),
        "{}",
        f.why(Intersector::RAY_QUERIES)
    );
    let general = PathTraceOptions {
        specialize: false,
        ..options(gpu(rq), true)
    };
    assert_ne!(
        Features::decide(&large, general).intersector(),
        Intersector::RAY_QUERIES
    );
}

/// `name` through ray queries and through the WGSL BVH (as a GPU without ray queries runs
/// it), at 64×64 and 16 spp (`common::same_hits`).
fn against_wgsl_bvh(name: &str) -> Option<(usize, f64)> {
    // Both as a GPU adapter runs (the same dispatches, materials read from buffers).
    let rq = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        intersector: Intersector::RAY_QUERIES,
        as_gpu_adapter: true,
        ..Tracing::default()
    });
    let bvh = Resources {
        ..Resources::default()
    }
    .with(Tracing {
        as_gpu_adapter: true,
        intersector: Intersector::BINARY_BVH,
        ..Tracing::default()
    });
    common::same_hits(name, rq, bvh, |a, b| {
        assert_eq!(intersector(a), "ray queries", "{}", a.summary());
        assert_eq!(intersector(b), "WGSL BVH", "{}", b.summary());
    })
}

/// Ray queries against the WGSL BVH on scenes that exercise every part of the intersector
/// contract: triangles and an area light (Cornell box: shadow rays, MIS), spheres and every
/// lobe under an environment (the material furnace: the spheres' boxes, rays entering and
/// leaving spheres), 5 120 triangles under an environment map (the suite's mesh), a
/// scattering medium (rays cut at media boundaries, `intersect_scene_within`). The hits are
/// the same tests on the same primitives, so the images agree to the last bit but where a
/// ray meets two primitives at the same distance (measured: the colors of all four
/// bit-identical; 22 first-hit albedos and normals of the Cornell box differ, all of them on
/// its corner lines, which pass through pixel centres, at bit-identical depths).
#[test]
fn ray_queries_render_what_the_wgsl_bvh_renders() {
    if !common::ray_queries_here("ray_queries_render_what_the_wgsl_bvh_renders") {
        return;
    }
    for name in [
        "cornell.ron",
        "furnace_materials.ron",
        "../tests/scenes/mesh_env.ron",
        "../tests/scenes/media_scattering.ron",
        "../tests/scenes/disk.ron",
    ] {
        let Some((far, mean)) = against_wgsl_bvh(name) else {
            return;
        };
        // Measured: 0 pixels differ in any bit, on all four. A color sample can only differ
        // through a tie (jittered rays: next to never), so 4 pixels are allowed.
        assert!(far <= 4, "{name}: {far} pixels differ beyond 1e-4");
        assert!(mean.abs() <= 1e-4, "{name}: means differ by {mean:.2e}");
    }
}
