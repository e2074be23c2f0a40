//! `lumagraph bench`: path tracing throughput on the current adapter, with the
//! scene-specialized shader (with its scene data inlined, then read from buffers; with the
//! host intersecting the rays, then the WGSL BVH) and the general (BVH) one side by side.

use std::sync::Arc;
use std::time::Instant;

use super::progressive::counter;
use crate::graph::{Edge, Graph, Node, ParamValue};
use crate::render::specialize::Feature;
use crate::render::{Executor, GpuContext, Resources, compile};
use crate::scene::GpuScene;
use anyhow::Result;

/// CPU time used so far by all of this process's threads (on a CPU adapter, the driver's
/// worker threads do the path tracing), from `/proc/self/task/*/schedstat`; `None` where
/// that is not available.
fn cpu_time() -> Option<f64> {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    #[expect(clippy::cast_precision_loss, reason = "a duration in seconds")]
    Some(ns as f64 * 1e-9)
}

/// Throughput of one shader.
struct Figures {
    /// Best paths per second of wall time.
    wall: f64,
    /// Best paths per CPU second of the whole process, where known: on a shared machine
    /// this moves less with the other jobs' load than the wall figure.
    cpu: Option<f64>,
    /// The shader's notes.
    how: String,
    /// Host intersection's figures over all runs, where it was used.
    host: Option<HostFigures>,
    /// The shader's features (what the variants to compare with are chosen by).
    features: Option<crate::render::specialize::Features>,
}

/// Where host intersection's time went, summed over the timed runs.
#[derive(Default)]
struct HostFigures {
    frames: u64,
    steps: u64,
    wall_ns: u64,
    wait_ns: u64,
    embree_ns: u64,
    other_ns: u64,
}

/// Best paths/s of `runs` renders of `spp` samples per pixel, with the shader choices of
/// `variant` (its scene is replaced by `scene`).
fn measure(
    ctx: &GpuContext,
    scene: &Arc<GpuScene>,
    variant: Resources,
    spp: u32,
    runs: u32,
) -> Result<Figures> {
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
        ..variant
    };
    let mut exec = Executor::new(ctx, plan, &resources)?;
    let features = exec.shader_features("pathtrace").cloned();
    let how = exec
        .notes()
        .into_iter()
        .map(|(_, n)| n)
        .collect::<Vec<_>>()
        .join("; ");
    exec.warm_up()?; // the driver compiles the pipeline at the first dispatch
    let frames = spp.div_ceil(spf);
    let pixels = f64::from(scene.settings.width) * f64::from(scene.settings.height);
    let paths = pixels * f64::from(frames * spf);
    let mut best = 0.0_f64;
    let mut best_cpu: Option<f64> = None;
    let mut host: Option<HostFigures> = None;
    for _ in 0..runs.max(1) {
        let before = exec.counters()?;
        let cpu_start = cpu_time();
        let start = Instant::now();
        exec.run_frames(frames, false)?;
        let secs = start.elapsed().as_secs_f64();
        let after = exec.counters()?;
        let diff = |name: &str| counter(&after, name).saturating_sub(counter(&before, name));
        if after.iter().any(|(_, c)| c.name == "host_steps") {
            let h = host.get_or_insert_with(HostFigures::default);
            h.frames += u64::from(frames);
            h.steps += diff("host_steps");
            h.wall_ns += u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
            h.wait_ns += diff("host_wait_ns");
            h.embree_ns += diff("host_embree_ns");
            h.other_ns += diff("host_other_ns");
        }
        best = best.max(paths / secs);
        if let (Some(a), Some(b)) = (cpu_start, cpu_time()) {
            best_cpu = Some(best_cpu.unwrap_or(0.0).max(paths / (b - a)));
        }
    }
    Ok(Figures {
        wall: best,
        cpu: best_cpu,
        how,
        host,
        features,
    })
}

impl Figures {
    /// Whether the shader compiled `f` in.
    fn on(&self, f: Feature) -> bool {
        self.features.as_ref().is_some_and(|x| x.on(f))
    }
}

/// One line of the report.
fn print(label: &str, f: &Figures) {
    let cpu = f
        .cpu
        .map(|c| format!(", {:.3} M per CPU second", c / 1e6))
        .unwrap_or_default();
    println!(
        "  {label:<12} {:>8.3} M paths/s{cpu}   ({})",
        f.wall / 1e6,
        f.how
    );
    if let Some(h) = &f.host {
        #[expect(clippy::cast_precision_loss, reason = "milliseconds")]
        let ms = |ns: u64| ns as f64 * 1e-6 / h.frames.max(1) as f64;
        println!(
            "  {:<12} host thread, per frame of {} steps: {:.0} ms waiting for the kernel, {:.0} ms in Embree, {:.0} ms reading back, listing and recording (of {:.0} ms)",
            "",
            h.steps / h.frames.max(1),
            ms(h.wait_ns),
            ms(h.embree_ns),
            ms(h.other_ns),
            ms(h.wall_ns)
        );
    }
}

/// Runs the benchmark and prints the figures.
pub fn run(scene: &Arc<GpuScene>, spp: u32, runs: u32, specialized_only: bool) -> Result<()> {
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    println!(
        "{}x{}, {} bounces, {spp} spp per run, best of {runs}:",
        scene.settings.width, scene.settings.height, scene.settings.max_bounces
    );
    let special = measure(&ctx, scene, Resources::default(), spp, runs)?;
    print("specialized", &special);
    // Where the specialized shader walks the 8-wide BVH, the binary one beside it (the
    // specialized shader as LUMAGRAPH_BVH=binary runs it).
    let binary = if special.on(Feature::WideBvh) {
        let binary = Resources {
            wide_bvh: Some(false),
            ..Resources::default()
        };
        let binary = measure(&ctx, scene, binary, spp, runs)?;
        print("binary BVH", &binary);
        println!(
            "  specialized (8-wide BVH) / binary BVH: {:.2}x",
            special.wall / binary.wall
        );
        Some(binary)
    } else {
        None
    };
    if specialized_only {
        return Ok(());
    }
    let wgsl = if special.on(Feature::HostRays) {
        let wgsl = Resources {
            wgsl_intersection: true,
            ..Resources::default()
        };
        let wgsl = measure(&ctx, scene, wgsl, spp, runs)?;
        print("WGSL BVH", &wgsl);
        Some(wgsl)
    } else {
        None
    };
    let buffers = if special.on(Feature::InlineData) {
        let buffers = Resources {
            scene_data_in_buffers: true,
            ..Resources::default()
        };
        let buffers = measure(&ctx, scene, buffers, spp, runs)?;
        print("buffers", &buffers);
        Some(buffers)
    } else {
        None
    };
    let general = Resources {
        general_shaders: true,
        ..Resources::default()
    };
    let general = measure(&ctx, scene, general, spp, runs)?;
    print("general", &general);
    if binary.is_some() {
        // The general shader walks the binary BVH.
        println!(
            "  (the general shader traverses the binary BVH; specialized / general below is \
             both changes together)"
        );
    }
    if let Some(wgsl) = wgsl {
        println!(
            "  specialized (host intersection) / WGSL BVH: {:.2}x",
            special.wall / wgsl.wall
        );
    }
    if let Some(buffers) = buffers {
        println!(
            "  specialized / buffers: {:.2}x",
            special.wall / buffers.wall
        );
    }
    println!(
        "  specialized / general: {:.2}x",
        special.wall / general.wall
    );
    Ok(())
}
