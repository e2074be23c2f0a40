//! `render` of an image larger than the device holds: tile by tile
//! ([`crate::render::tiled`]), with a progress bar over all tiles.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use anyhow::{Result, bail};

use super::progressive::{STOP, on_signal};
use super::{LoadedScene, RenderArgs, progressive_source, uses_scene};
use crate::graph::{Extent, Graph, Plan};
use crate::render::{Executor, GpuContext, Resources};

/// Renders tile by tile when `--tile` asks or the whole image does not fit the device
/// ([`crate::render::tiled::plan_tiling`]); `Ok(None)` when the render is not tiled.
pub(super) fn render_if_needed(
    args: &RenderArgs<'_>,
    graph: &Graph,
    scene: Option<&LoadedScene>,
    plan: &Plan,
    ctx: &GpuContext,
    resources: &Resources,
) -> Result<Option<()>> {
    let Some(scene) = scene.filter(|_| uses_scene(plan)) else {
        if args.tile.is_some_and(|t| t > 0) {
            bail!("--tile: this graph renders no scene, and only scene renders are tiled");
        }
        return Ok(None);
    };
    let image = Extent::new(scene.gpu.settings.width, scene.gpu.settings.height);
    let bytes = plan.texture_bytes()
        + plan
            .passes
            .iter()
            .filter_map(|p| args.library.owned_memory(p).map(|(b, _)| b))
            .sum::<u64>();
    let Some(tiling) = crate::render::tiled::plan_tiling(ctx, plan, image, bytes, args.tile)?
    else {
        return Ok(None);
    };
    if args.samples.is_some() {
        bail!(
            "this render is tiled ({}), and partial renders (--samples) are not tiled yet: \
             render it smaller",
            tiling.why
        );
    }
    if args.checkpoints.resume.is_some() || args.checkpoints.every.is_some() {
        bail!(
            "this render is tiled ({}), and tiled renders keep no checkpoints yet: leave out \
             --resume and --checkpoint-every, or render it smaller",
            tiling.why
        );
    }
    let n = tiling.tiles.len();
    println!(
        "tiled: {n} tiles of at most {t}×{t} pixels, each rendered with a {a}-pixel apron in a \
         {w} window ({why})",
        t = tiling.tile,
        a = tiling.apron,
        w = tiling.window,
        why = tiling.why
    );
    let window_plan = args
        .library
        .compile_window(graph, &[], Some(&scene.gpu), tiling.window)?;
    let mut exec = Executor::with_library(ctx, window_plan, resources, args.library)?;
    for (node, note) in exec.notes() {
        println!("{node}: {note}");
    }
    let spp = args.spp.unwrap_or(scene.scene.settings.spp);
    let frames = exec.frames_for(spp);
    let warm = Instant::now();
    exec.warm_up()?;
    println!(
        "warm-up (shader compilation): {:.0} ms",
        warm.elapsed().as_secs_f64() * 1e3
    );
    on_signal("tiled renders keep no checkpoint, so nothing is written");
    let total = u64::from(frames) * n as u64;
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(total),
        indicatif::ProgressDrawTarget::hidden(),
    );
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} tile {msg}, {pos}/{len} frames in all, {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = Instant::now();
    let mut at = 0;
    let written = crate::render::tiled::render(
        &mut exec,
        &tiling,
        image,
        resources,
        frames,
        |tile, done, _| {
            if bar.is_hidden() && start.elapsed() > Duration::from_secs(1) {
                bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            }
            at = tile;
            bar.set_message(format!("{} of {n}", tile + 1));
            bar.set_position(tile as u64 * u64::from(frames) + u64::from(done));
            !STOP.load(Ordering::SeqCst)
        },
    )?;
    bar.finish_and_clear();
    let Some(written) = written else {
        bail!(
            "interrupted in tile {} of {n}: tiled renders keep no checkpoint yet, so nothing \
             was written",
            at + 1
        );
    };
    let secs = start.elapsed().as_secs_f64();
    let spf = progressive_source(exec.plan()).map_or(1, |p| {
        u64::try_from(p.params.int(crate::graph::registry::SAMPLES_PER_FRAME)).unwrap_or(1)
    });
    let samples = u64::from(frames) * spf;
    let rendered: u64 = tiling
        .tiles
        .iter()
        .map(|t| u64::from(t.window.width) * u64::from(t.window.height))
        .sum();
    #[expect(clippy::cast_precision_loss, reason = "report figures")]
    let (paths, overhead) = (
        (image.pixels() * samples) as f64,
        rendered as f64 / image.pixels() as f64 - 1.0,
    );
    println!(
        "rendered {samples} spp at {image} in {n} tiles in {secs:.2} s: {:.3} M paths/s of the \
         image ({:.1} % more pixels rendered for the aprons)",
        paths / secs / 1e6,
        overhead * 100.0
    );
    for path in &written {
        println!("wrote {}", path.display());
    }
    Ok(Some(()))
}
