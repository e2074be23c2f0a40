//! `lumagraph bench`: path tracing throughput on the current adapter, with the
//! scene-specialized shader (with its scene data inlined, then read from buffers) and the
//! general (BVH) one side by side.

use std::sync::Arc;
use std::time::Instant;

use crate::graph::{Edge, Graph, Node, ParamValue};
use crate::render::{Executor, GpuContext, Resources, compile};
use crate::scene::GpuScene;
use anyhow::Result;

/// Best paths/s of `runs` renders of `spp` samples per pixel.
fn measure(
    ctx: &GpuContext,
    scene: &Arc<GpuScene>,
    general: bool,
    data_in_buffers: bool,
    spp: u32,
    runs: u32,
) -> Result<(f64, String)> {
    let spf = spp.min(16);
    let graph = Graph {
        nodes: vec![
            Node::new("pathtrace", "PathTrace")
                .with("samples_per_frame", ParamValue::Int(i64::from(spf))),
            Node::new("accumulate", "Accumulate"),
        ],
        edges: vec![Edge::new("pathtrace.color", "accumulate.color")],
        ..Graph::default()
    };
    let plan = compile(&graph, &["accumulate.color".into()], Some(scene))?;
    let resources = Resources {
        scene: Some(Arc::clone(scene)),
        general_shaders: general,
        scene_data_in_buffers: data_in_buffers,
        ..Resources::default()
    };
    let mut exec = Executor::new(ctx, plan, &resources)?;
    let how = exec
        .notes()
        .into_iter()
        .map(|(_, n)| n)
        .collect::<Vec<_>>()
        .join("; ");
    exec.warm_up()?; // the driver compiles the pipeline at the first dispatch
    let frames = spp.div_ceil(spf);
    let pixels = f64::from(scene.settings.width) * f64::from(scene.settings.height);
    let mut best = 0.0_f64;
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        exec.run_frames(frames, false)?;
        let secs = start.elapsed().as_secs_f64();
        best = best.max(pixels * f64::from(frames * spf) / secs);
    }
    Ok((best, how))
}

/// Runs the benchmark and prints the figures.
pub fn run(scene: &Arc<GpuScene>, spp: u32, runs: u32) -> Result<()> {
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    println!(
        "{}x{}, {} bounces, {spp} spp per run, best of {runs}:",
        scene.settings.width, scene.settings.height, scene.settings.max_bounces
    );
    let (special, how_s) = measure(&ctx, scene, false, false, spp, runs)?;
    println!(
        "  specialized  {:>8.3} M paths/s   ({how_s})",
        special / 1e6
    );
    let inlined = how_s.contains("materials and lights inlined");
    let buffers = if inlined {
        let (buffers, how_b) = measure(&ctx, scene, false, true, spp, runs)?;
        println!(
            "  buffers      {:>8.3} M paths/s   ({how_b})",
            buffers / 1e6
        );
        Some(buffers)
    } else {
        None
    };
    let (general, how_g) = measure(&ctx, scene, true, false, spp, runs)?;
    println!(
        "  general      {:>8.3} M paths/s   ({how_g})",
        general / 1e6
    );
    if let Some(buffers) = buffers {
        println!("  specialized / buffers: {:.2}x", special / buffers);
    }
    println!("  specialized / general: {:.2}x", special / general);
    Ok(())
}
