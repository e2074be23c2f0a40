//! Adaptive sampling (`PathTrace.adaptive_error`): pixels stop taking samples once their
//! estimated relative error is below the threshold, Accumulate averages each pixel over its
//! own frames, and `samples` says where the samples went.

use crate::common;

use lumagraph::graph::{Edge, ParamValue};
use lumagraph::render::cpu::Image;
use lumagraph::render::metrics;

const CORNELL: &str = "assets/cornell.ron";

/// A progressive render with adaptive sampling at `error` (0: off), keeping the mean and
/// `samples`.
fn adaptive(
    scene: &std::sync::Arc<lumagraph::scene::GpuScene>,
    error: f64,
) -> Option<lumagraph::render::Executor> {
    let mut graph = common::progressive_graph(&[
        ("samples_per_frame", ParamValue::Int(4)),
        ("adaptive_error", ParamValue::Float(error)),
        ("adaptive_min_spp", ParamValue::Int(16)),
    ]);
    // Something must read `samples` for the executor to keep it.
    graph
        .nodes
        .push(lumagraph::graph::Node::new("shown", "Exposure"));
    graph.edges.push(Edge::new("pt.samples", "shown.color"));
    common::executor(&graph, &["acc.color", "pt.samples"], scene)
}

/// Sum of a channel over the image.
fn channel_sum(image: &Image, c: usize) -> f64 {
    image.pixels.iter().map(|p| f64::from(p[c])).sum()
}

/// Without a threshold every pixel samples every frame; with one, some pixels stop, but
/// none before `adaptive_min_spp`, and `samples` (alpha: samples per pixel) adds up to the
/// samples the path tracer counted.
#[test]
fn samples_output_counts_what_was_taken() {
    let scene = common::gpu_scene(CORNELL, Some(64));
    let Some(mut off) = adaptive(&scene, 0.0) else {
        return;
    };
    off.run_frames(12, true).unwrap();
    let samples = off.read_port("pt.samples").unwrap();
    assert!(
        samples.pixels.iter().all(|p| p[0] == 1.0 && p[3] == 48.0),
        "without adaptive sampling every pixel takes every frame's samples"
    );

    let mut on = adaptive(&scene, 0.1).unwrap();
    on.run_frames(12, true).unwrap();
    let samples = on.read_port("pt.samples").unwrap();
    let taken = channel_sum(&samples, 3);
    let counted = common::counter(&mut on, "adaptive_samples");
    println!(
        "64² Cornell, adaptive_error 0.1, 48 spp: {taken} samples taken, {:.1} % of uniform",
        100.0 * taken / (48.0 * 4096.0)
    );
    #[expect(clippy::cast_precision_loss, reason = "a sample count")]
    let counted_f = counted as f64;
    assert!(
        (taken - counted_f).abs() < 0.5,
        "samples output {taken} vs counter {counted}"
    );
    let fewest = samples.pixels.iter().map(|p| p[3]).fold(f32::MAX, f32::min);
    assert!(fewest >= 16.0, "a pixel stopped at {fewest} spp, before 16");
    assert!(
        taken < 0.9 * 48.0 * 4096.0,
        "adaptive sampling at 0.1 stopped almost nothing ({taken} samples)"
    );
    for p in &samples.pixels {
        assert!(
            (f64::from(p[0]) - f64::from(p[3]) / 48.0).abs() < 1e-6,
            "share {} for {} samples of 48",
            p[0],
            p[3]
        );
    }
}

/// The mean of each 32×32 block of an adaptive render of the Cornell box agrees with
/// Mitsuba's reference: stopped pixels keep the mean of their own samples (were they
/// averaged with the zeros of the frames they skip, the blocks would darken by the share
/// skipped, about 25 % here). Measured at 64 spp (blocks brighter than 0.02): a uniform
/// render's worst block is 1.66 % off and the blocks are off by −0.03 % on average; this
/// adaptive one's (77 % of the samples) 3.2 % and −0.20 % (stopping on a low error estimate
/// favors pixels whose noise happened to be small: a bias that grows with the threshold).
/// Bounds: 5 % for the worst block, 1 % for the average.
#[test]
fn adaptive_render_keeps_block_means() {
    let scene = common::gpu_scene(CORNELL, None);
    let Some(mut exec) = adaptive(&scene, 0.05) else {
        return;
    };
    exec.run_frames(16, true).unwrap();
    let image = exec.read_port("acc.color").unwrap();
    let samples = exec.read_port("pt.samples").unwrap();
    let share = channel_sum(&samples, 3) / (64.0 * 65536.0);
    let reference =
        lumagraph::render::image_io::load(&common::repo("tests/reference/cornell_ref.exr"))
            .unwrap();
    let ours = metrics::block_means(&image, 32);
    let theirs = metrics::block_means(&reference, 32);
    let mut worst: f64 = 0.0;
    let (mut signed, mut count) = (0.0, 0.0);
    for (a, b) in ours.iter().zip(&theirs) {
        for c in 0..3 {
            if b[c] > 0.02 {
                let d = a[c] / b[c] - 1.0;
                worst = worst.max(d.abs());
                signed += d;
                count += 1.0;
            }
        }
    }
    let signed = signed / count;
    println!(
        "Cornell 256², adaptive_error 0.05, 64 spp: {:.1} % of the samples, worst block {:.2} %, \
         blocks on average {:+.2} %, relMSE {:.3e}",
        100.0 * share,
        100.0 * worst,
        100.0 * signed,
        metrics::relmse(&image, &reference)
    );
    assert!(share < 0.85, "too little stopped to test anything: {share}");
    assert!(worst < 0.05, "a block mean is {:.2} % off", 100.0 * worst);
    assert!(
        signed.abs() < 0.01,
        "the blocks are {:+.2} % off on average",
        100.0 * signed
    );
}

/// A render interrupted and resumed from its checkpoint (adaptive sampling's halves and
/// stopped pixels included) is the uninterrupted one, bit for bit.
#[test]
fn adaptive_render_resumes_identically() {
    let scene = common::gpu_scene(CORNELL, Some(48));
    let Some(mut whole) = adaptive(&scene, 0.1) else {
        return;
    };
    whole.run_frames(12, true).unwrap();
    let mut first = adaptive(&scene, 0.1).unwrap();
    first.run_frames(6, true).unwrap();
    let checkpoint = first.checkpoint(7).unwrap();
    let mut resumed = adaptive(&scene, 0.1).unwrap();
    resumed.restore(&checkpoint).unwrap();
    resumed.run_frames(6, true).unwrap();
    for port in ["acc.color", "pt.samples"] {
        let (a, b) = (
            whole.read_port(port).unwrap(),
            resumed.read_port(port).unwrap(),
        );
        assert!(a.pixels == b.pixels, "{port} differs after resuming");
    }
    let samples = whole.read_port("pt.samples").unwrap();
    assert!(
        samples.pixels.iter().any(|p| p[3] < 48.0),
        "nothing stopped: the resume did not test the stopped pixels"
    );
    // A state of another size is refused with a message, not a panic.
    let other = common::gpu_scene(CORNELL, Some(40));
    let mut wrong = adaptive(&other, 0.1).unwrap();
    let err = wrong.restore(&checkpoint).unwrap_err().to_string();
    assert!(err.contains("pt"), "{err}");
}
