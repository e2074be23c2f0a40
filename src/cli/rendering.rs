//! `lumagraph render`: a graph and its scene rendered to files, progressively, in tiles,
//! over sample ranges or frames.

use std::path::Path;
use std::sync::Arc;

use anyhow::Result;

use super::loading::{TextureArgs, fit_textures, load_scene, uses_scene};
use super::{choice, frames, load, progressive, split, tiled};
use crate::render::{Executor, GpuContext, NodeLibrary, Resources};
use crate::session::Session;

pub(super) fn render(args: &RenderArgs<'_>) -> Result<()> {
    if let Some((frames, skip_missing)) = &args.frames {
        return frames::render(args, frames, *skip_missing);
    }
    let graph = load(args.graph, args.overrides)?;
    // The adapter and device are made on a thread of their own while the scene loads.
    let device = std::thread::spawn(GpuContext::headless);
    let mut scene = load_scene(args.scene)?;
    let plan = args
        .library
        .compile(&graph, &[], scene.as_ref().map(|s| &*s.gpu))?;
    crate::graph::outputs::output_files(&plan, &graph, args.out, args.outputs_anywhere)?;
    let progressive = uses_scene(&plan);
    if scene.is_some() && !progressive {
        println!("scene not used: no node of this graph renders a scene");
    }
    let ctx = device
        .join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))?;
    println!("adapter: {}", ctx.describe());
    if let (Some(s), true) = (scene.as_mut(), progressive) {
        fit_textures(s, &ctx, args.textures)?;
    }
    let resources = Resources {
        base_dir: graph.base_dir(),
        out_dir: args.out.to_owned(),
        outputs_anywhere: args.outputs_anywhere,
        scene: scene.as_ref().map(|s| Arc::clone(&s.gpu)),
        ..args.choice.apply(Resources::default())
    };
    if let Some(done) =
        tiled::render_if_needed(args, &graph, scene.as_ref(), &plan, &ctx, &resources)?
    {
        return Ok(done);
    }
    let left_out = plan.left_out.clone();
    let built = std::time::Instant::now();
    let stage = progressive::Stage::start("pipelines and uploads");
    let mut exec = Executor::with_library(&ctx, plan, &resources, args.library)?;
    drop(stage);
    progressive::print_built(built);
    for (node, note) in exec.notes() {
        println!("{node}: {note}");
    }
    if let Some(range) = args.samples {
        anyhow::ensure!(progressive, "--samples needs a graph that renders a scene");
        let origin = split::Origin {
            graph: args.graph,
            scene: args.scene,
            overrides: args.overrides,
            key: crate::session::render_key(&graph, scene.as_ref().map(|s| &*s.gpu)),
            out: args.out,
        };
        return split::render_partial(&mut exec, range, &origin);
    }
    let report = if progressive {
        let spp = args
            .spp
            .or(scene.as_ref().map(|s| s.scene.settings.spp))
            .unwrap_or(1);
        let mut checkpoints = args.checkpoints.clone();
        let (g, s) = (graph.clone(), scene.as_ref().map(|s| Arc::clone(&s.gpu)));
        checkpoints.key =
            progressive::Key::new(move || crate::session::render_key(&g, s.as_deref()));
        let mut session = Session::from_executor(
            exec,
            graph,
            scene.as_ref().map(|s| Arc::clone(&s.gpu)),
            resources,
            Arc::clone(args.library),
        );
        let report = progressive::render(&mut session, spp, &checkpoints)?;
        finish(session.executor(), &report, &left_out)?;
        return Ok(());
    } else {
        // The first frame includes pipeline compilation inside the driver; time a second one.
        let first = exec.run_frame()?;
        let report = exec.run_frame()?;
        println!(
            "frame: {:.1} ms wall (first frame, with shader compilation: {:.1} ms)",
            report.wall.as_secs_f64() * 1e3,
            first.wall.as_secs_f64() * 1e3
        );
        report
    };
    finish(&mut exec, &report, &left_out)
}

/// What `render` prints at the end: GPU time per pass, measurements, files written and
/// what the plan left out.
pub(super) fn finish(
    exec: &mut Executor,
    report: &crate::render::FrameReport,
    left_out: &[crate::graph::LeftOut],
) -> Result<()> {
    match &report.pass_ms {
        Some(times) => {
            println!(
                "time per pass (last frame; {}):",
                report.pass_clock.describe()
            );
            for (name, ms) in times {
                println!("  {name:<16} {ms:>9.3} ms");
            }
        }
        None => println!("GPU time per pass: not available (adapter has no timestamp queries)"),
    }
    for (node, m) in exec.measurements()? {
        println!("measured {node}.{}: {:.6e}", m.name, m.value);
    }
    for path in &report.written {
        println!("wrote {}", path.display());
    }
    for l in left_out {
        println!("left out {}: {}", l.what, l.reason);
    }
    Ok(())
}

pub(super) struct RenderArgs<'a> {
    pub(super) library: &'a Arc<NodeLibrary>,
    pub(super) graph: &'a Path,
    pub(super) scene: Option<&'a Path>,
    pub(super) out: &'a Path,
    pub(super) spp: Option<u32>,
    pub(super) overrides: &'a [String],
    pub(super) checkpoints: progressive::Checkpoints,
    /// `--tile`.
    pub(super) tile: Option<u32>,
    /// `--samples`.
    pub(super) samples: Option<split::SampleRange>,
    /// `--tiles`.
    pub(super) tiles: Option<split::SampleRange>,
    /// `--allow-outputs-outside`.
    pub(super) outputs_anywhere: bool,
    /// `--fit-textures` and `--texture-memory`.
    pub(super) textures: TextureArgs,
    /// `--frames` and `--skip-missing`.
    pub(super) frames: Option<(Vec<i64>, bool)>,
    /// `--intersector` and `--schedule`.
    pub(super) choice: choice::Choice,
}
