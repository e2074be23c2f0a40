//! The path tracer's support matrix (`lumagraph_pathtrace::specialize::support`): printed, each
//! cell checked against what the decisions do when that intersector (or the wavefront) is
//! asked for on a small scene with that row's content, and the table in
//! `docs/pathtracer.md` checked against it. No GPU needed.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;

use lumagraph_pathtrace::intersect::KINDS;
use lumagraph_pathtrace::specialize::support::{self, Content, HOST_RAYS_MAX_BOUNCES, Tracer};
use lumagraph_pathtrace::specialize::{Feature, Features, Intersector, PathTraceOptions, Schedule};
use lumagraph_scene::{FEATURE_ALPHA, GpuScene, MATERIAL_MEDIUM, Scene};

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

fn scene(rel: &str) -> GpuScene {
    GpuScene::build(&Scene::load(&root().join(rel)).unwrap()).unwrap()
}

/// A CPU adapter with Embree and ray queries: every intersector available.
fn base_options() -> PathTraceOptions {
    PathTraceOptions {
        specialize: true,
        cpu_adapter: true,
        host_rays: true,
        ray_query_limit: Some(1 << 24),
        ..PathTraceOptions::default()
    }
}

/// A small scene with `content` (and nothing else of the matrix's rows), and the options
/// that render it.
fn with(content: Content) -> (GpuScene, PathTraceOptions) {
    let mut options = base_options();
    let mut s = scene("assets/cornell.ron");
    match content {
        Content::GeneralShader => options.specialize = false,
        Content::GpuAdapter => options.cpu_adapter = false,
        Content::ManyPrimitives => s = scene("tests/scenes/mesh_env.ron"),
        Content::Shapes => s = scene("assets/cornell_spheres.ron"),
        Content::Instances => s = scene("tests/scenes/instances.ron"),
        Content::Media => s.materials[0].flags |= MATERIAL_MEDIUM,
        Content::Adaptive => options.adaptive = true,
        Content::ManyBounces => s.settings.max_bounces = HOST_RAYS_MAX_BOUNCES,
        Content::Alpha => s.header.features |= FEATURE_ALPHA,
        Content::Aovs => options.aovs = true,
    }
    (s, options)
}

/// Whether `tracer` traces `scene` when asked for: the decisions give it, and a render
/// asking for it is not refused.
fn traced(tracer: Tracer, scene: &GpuScene, options: PathTraceOptions) -> (bool, String) {
    let options = match tracer {
        Tracer::Wavefront => PathTraceOptions {
            intersector: Intersector::BINARY_BVH,
            schedule: Schedule::Wavefront,
            ..options
        },
        Tracer::Intersector(intersector) => PathTraceOptions {
            intersector,
            ..options
        },
    };
    let f = Features::decide(scene, options);
    let refusal = support::refusal(scene, options, &f);
    let given = match tracer {
        Tracer::Wavefront => f.on(Feature::Wavefront),
        _ => f.intersector() == options.intersector,
    };
    assert_eq!(
        given,
        refusal.is_none(),
        "{tracer:?}: the decision and the refusal disagree ({refusal:?}; {})",
        f.summary()
    );
    (given, refusal.unwrap_or_default())
}

#[test]
fn every_cell_of_the_support_matrix_is_what_the_decisions_do() {
    println!("{}", support::markdown());
    let matrix = support::matrix();
    // A column per intersector (and the wavefront's); each names its kind.
    assert_eq!(matrix.len(), KINDS.len() + 1);
    for (tracer, _) in &matrix {
        if let Tracer::Intersector(i) = *tracer {
            assert_eq!(Tracer::of(i), Some(*tracer));
            assert_eq!(Intersector::from_name(i.name()), Ok(i));
        }
    }
    // The scene every row starts from has none of them, and everything traces it.
    let (plain, options) = (scene("assets/cornell.ron"), base_options());
    for c in Content::ALL {
        assert!(!c.in_scene(&plain, options), "cornell.ron has {c:?}");
    }
    for &(tracer, _) in &matrix {
        let (given, why) = traced(tracer, &plain, options);
        assert!(given, "{tracer:?} on cornell.ron: {why}");
    }
    let mut checked = 0;
    for c in Content::ALL {
        let (s, options) = with(c);
        assert!(c.in_scene(&s, options), "{c:?}");
        // Anything else the scene has (the instanced scene has more than 64 primitives)
        // is traced by every column that traces `c`, so the cell alone decides.
        for other in Content::ALL
            .into_iter()
            .filter(|&o| o != c && o.in_scene(&s, options))
        {
            for &(tracer, _) in &matrix {
                assert!(
                    !tracer.traces(c) || tracer.traces(other),
                    "the {c:?} scene has {other:?} too, which {tracer:?} does not trace"
                );
            }
        }
        for &(tracer, _) in &matrix {
            let (given, why) = traced(tracer, &s, options);
            assert_eq!(
                given,
                tracer.traces(c),
                "{tracer:?} with {c:?}: the table says {}, the decisions {}: {why}",
                tracer.traces(c),
                given
            );
            checked += 1;
        }
    }
    assert_eq!(checked, Content::ALL.len() * matrix.len());
}

/// The last intersector the adapter's choice tries traces every row of the matrix and is
/// always taken: whatever the scene, something traces it.
#[test]
fn the_last_intersector_traces_everything() {
    let last = KINDS[KINDS.len() - 1];
    assert!(last.traces().iter().all(|&t| t), "{}", last.describe());
    for c in Content::ALL {
        let (s, options) = with(c);
        assert!(last.auto(&s, options).is_ok(), "{c:?}");
        assert!(last.unavailable(&s, options).is_none(), "{c:?}");
    }
}

/// Asked for where the adapter lacks it: the host without Embree, ray queries without
/// them; each refused with why.
#[test]
fn an_intersector_the_adapter_lacks_is_refused_with_why() {
    let plain = scene("assets/cornell.ron");
    let options = PathTraceOptions {
        host_rays: false,
        ray_query_limit: None,
        ..base_options()
    };
    for (tracer, what) in [
        (
            Tracer::Intersector(Intersector::HOST),
            "no host intersector",
        ),
        (
            Tracer::Intersector(Intersector::RAY_QUERIES),
            "no ray queries",
        ),
    ] {
        let (given, why) = traced(tracer, &plain, options);
        assert!(!given && why.contains(what), "{tracer:?}: {why}");
    }
}

/// `docs/pathtracer.md` shows the matrix as [`support::markdown`] writes it.
#[test]
fn the_docs_show_the_support_matrix() {
    let doc = std::fs::read_to_string(root().join("docs/pathtracer.md")).unwrap();
    let table = support::markdown();
    assert!(
        doc.contains(&table),
        "docs/pathtracer.md does not hold the support matrix; put this table in it:\n{table}"
    );
}
