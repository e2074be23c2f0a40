//! The à-trous Denoise node on the Cornell box against Mitsuba's 24 576-spp reference.
//!
//! At 16 spp (16 frames of 1 sample, so Accumulate's variance has 16 frames to go on), the
//! filtered image's relMSE must be at least 4× lower than the raw accumulation's, for the
//! scene's seed and for another one (the defaults were tuned looking at both; see
//! `docs/denoise.md`). `cargo run --example denoise_sweep` prints the grid the defaults were
//! chosen from.

use crate::common;

use std::sync::Arc;

use lumagraph::graph::{Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::cpu::Image;
use lumagraph::render::{Resources, image_io, metrics};
use lumagraph::scene::{GpuScene, Scene};

fn cornell(seed: Option<u32>) -> Arc<GpuScene> {
    let scene = Scene::load(&common::repo("assets/cornell.ron")).unwrap();
    let mut gpu = GpuScene::build(&scene).unwrap();
    if let Some(seed) = seed {
        gpu.settings.seed = seed;
    }
    Arc::new(gpu)
}

/// `PathTrace` (1 spp a frame) → `Accumulate` → `Denoise`, guided by `GBuffer`.
fn graph(params: &[(&str, ParamValue)]) -> Graph {
    let source = Node::new("pt", "PathTrace").with("samples_per_frame", ParamValue::Int(1));
    common::denoise_graph(source, params)
}

/// `(raw, filtered)` after `spp` frames.
fn render(
    scene: &Arc<GpuScene>,
    spp: u32,
    params: &[(&str, ParamValue)],
) -> Option<(Image, Image)> {
    let ctx = common::gpu()?;
    let plan = compile(
        &graph(params),
        &["acc.color".into(), "dn.color".into()],
        Some(scene),
    )
    .unwrap();
    let resources = Resources {
        scene: Some(Arc::clone(scene)),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frames(spp, true).unwrap();
    Some((
        exec.read_port("acc.color").unwrap(),
        exec.read_port("dn.color").unwrap(),
    ))
}

fn reference() -> Image {
    image_io::load(&common::repo("tests/reference/cornell_ref.exr")).unwrap()
}

#[test]
fn atrous_at_16_spp_is_4x_better_than_raw() {
    let reference = reference();
    for seed in [None, Some(0x5eed_1234)] {
        let Some((raw, filtered)) = render(&cornell(seed), 16, &[]) else {
            return;
        };
        assert!(filtered.pixels.iter().flatten().all(|v| v.is_finite()));
        let (r, f) = (
            metrics::relmse(&raw, &reference),
            metrics::relmse(&filtered, &reference),
        );
        eprintln!(
            "seed {seed:?}: 16 spp relMSE raw {r:.4e}, à-trous {f:.4e} ({:.2}× lower)",
            r / f
        );
        assert!(
            f * 4.0 <= r,
            "à-trous relMSE {f:.4e} is not 4× below raw {r:.4e}"
        );
    }
}

/// The GPU filter against its plain-Rust mirror (`cpu::denoise`) on the same inputs (Cornell
/// at 4 spp): the float arithmetic is the same up to the order of sums and `exp`, so the two
/// agree to 1e-3 relative in almost every pixel (measured: all of them, guided or not).
#[test]
fn gpu_filter_matches_cpu_mirror() {
    use lumagraph::render::cpu::{DenoiseParams, denoise};
    let Some(ctx) = common::gpu() else { return };
    let scene = cornell(None);
    let keep: Vec<String> = [
        "acc.color",
        "acc.variance",
        "gb.albedo",
        "gb.normal",
        "gb.depth",
        "dn.color",
    ]
    .map(str::to_owned)
    .to_vec();
    for guided in [true, false] {
        let params = [("variance_guided", ParamValue::Bool(guided))];
        let plan = compile(&graph(&params), &keep, Some(&scene)).unwrap();
        let resources = Resources {
            scene: Some(Arc::clone(&scene)),
            ..Resources::default()
        };
        let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
        exec.run_frames(4, true).unwrap();
        let read = |p: &str| exec.read_port(p).unwrap();
        let cpu = denoise(
            &read("acc.color"),
            &read("acc.variance"),
            &read("gb.albedo"),
            &read("gb.normal"),
            &read("gb.depth"),
            &DenoiseParams {
                iterations: 5,
                sigma_color: 4.0,
                sigma_normal: 0.02,
                sigma_depth: 0.5,
                variance_guided: guided,
            },
        );
        let gpu = read("dn.color");
        let n = gpu.pixels.len();
        let off = gpu
            .pixels
            .iter()
            .zip(&cpu.pixels)
            .filter(|(g, c)| (0..3).any(|k| (g[k] - c[k]).abs() > 1e-3 * c[k].abs().max(1e-2)))
            .count();
        eprintln!("guided {guided}: {off} of {n} pixels differ by more than 1e-3 relative");
        assert!(off * 1000 <= n, "{off} of {n} pixels differ");
    }
}
