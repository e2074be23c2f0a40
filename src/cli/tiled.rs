//! `render` of an image larger than the device holds: tile by tile
//! ([`crate::session::tiled`]), with a progress bar over all tiles.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use anyhow::{Result, bail};

use super::progressive::{STOP, on_signal};
use super::{LoadedScene, RenderArgs, progressive_source, uses_scene};
use crate::graph::{Extent, Graph, Plan};
use crate::render::{Executor, GpuContext, Resources};
use crate::session::tile_set::TileSet;
use crate::session::tiled::{Ended, Tiling};

/// Renders tile by tile when `--tile` asks or the whole image does not fit the device
/// ([`crate::session::tiled::plan_tiling`]); `Ok(None)` when the render is not tiled.
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
    let Some(tiling) = crate::session::tiled::plan_tiling(ctx, plan, image, bytes, args.tile)?
    else {
        if args.tiles.is_some() {
            bail!(
                "--tiles: this render is not tiled; give the tile side with --tile (or render \
                 an image that must be tiled)"
            );
        }
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
    let built = std::time::Instant::now();
    let mut exec = Executor::with_library(ctx, window_plan, resources, args.library)?;
    super::progressive::print_built(built);
    for (node, note) in exec.notes() {
        println!("{node}: {note}");
    }
    let spp = args.spp.unwrap_or(scene.scene.settings.spp);
    let frames = exec.frames_for(spp);
    super::progressive::warm_up(|| Ok(exec.warm_up()?))?;
    on_signal("writing the tiles done so far");
    let mut bar = TileBar::new(n, frames);
    match args.tiles {
        Some(range) => {
            bar.at = range.first as usize;
            let key = crate::session::render_key(graph, Some(&scene.gpu));
            let set = crate::session::tiled::render_set(
                &mut exec,
                &tiling,
                image,
                (range.first, range.end),
                frames,
                key,
                |tile, done, _| bar.tick(tile, done),
            )?;
            bar.bar.finish_and_clear();
            let Some(set) = set else {
                bail!("interrupted in tile {}: nothing was written", bar.at + 1);
            };
            std::fs::create_dir_all(args.out)?;
            let path = args
                .out
                .join(format!("tiles-{}-{}.tiles", range.first, range.end));
            set.save(&path)?;
            println!(
                "rendered tiles {}..{} of {n} in {:.2} s",
                range.first,
                range.end,
                bar.start.elapsed().as_secs_f64()
            );
            println!("wrote {}", path.display());
        }
        None => {
            let key = crate::session::render_key(graph, Some(&scene.gpu));
            let ended = crate::session::tiled::render(
                &mut exec,
                &tiling,
                image,
                resources,
                (frames, key),
                |tile, done, _| bar.tick(tile, done),
            )?;
            bar.bar.finish_and_clear();
            let written = match ended {
                Ended::Written(written) => written,
                Ended::Stopped(set) => return Err(stopped(set, bar.at, n, args.out)),
            };
            report(&exec, &tiling, image, frames, bar.start.elapsed());
            for path in &written {
                println!("wrote {}", path.display());
            }
        }
    }
    Ok(Some(()))
}

/// After a stop in tile `at` of `n`: the tiles done written as a tile set, and the error
/// saying how to go on.
fn stopped(set: Option<TileSet>, at: usize, n: usize, out: &Path) -> anyhow::Error {
    let Some(set) = set else {
        return anyhow::anyhow!("interrupted in the first tile of {n}: nothing was written");
    };
    let path = out.join(format!("tiles-0-{}.tiles", set.end));
    if let Err(e) = std::fs::create_dir_all(out)
        .map_err(anyhow::Error::from)
        .and_then(|()| set.save(&path).map_err(anyhow::Error::from))
    {
        return anyhow::anyhow!(
            "interrupted in tile {} of {n}, and the {} tiles done could not be written: {e}",
            at + 1,
            set.end
        );
    }
    anyhow::anyhow!(
        "interrupted in tile {} of {n}: wrote the {} tiles done as {}; render the rest with \
         the same command and `--tiles {}..{n}`, then `lumagraph merge` both tile sets",
        at + 1,
        set.end,
        path.display(),
        set.end
    )
}

/// The progress bar over all tiles' frames (drawn once the render takes over a second).
struct TileBar {
    bar: indicatif::ProgressBar,
    tiles: usize,
    frames: u32,
    start: Instant,
    /// The tile rendering now.
    at: usize,
}

impl TileBar {
    fn new(tiles: usize, frames: u32) -> Self {
        let bar = indicatif::ProgressBar::with_draw_target(
            Some(u64::from(frames) * tiles as u64),
            indicatif::ProgressDrawTarget::hidden(),
        );
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} tile {msg}, {pos}/{len} frames in all, {elapsed} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Self {
            bar,
            tiles,
            frames,
            start: Instant::now(),
            at: 0,
        }
    }

    /// Frame `done` of tile `tile`; whether to go on (no Ctrl-C). A line for each tile
    /// finished, for logs.
    fn tick(&mut self, tile: usize, done: u32) -> bool {
        if self.bar.is_hidden() && self.start.elapsed() > Duration::from_secs(1) {
            self.bar
                .set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        if tile > self.at {
            let line = format!(
                "tile {} of {} done ({:.1} s)",
                self.at + 1,
                self.tiles,
                self.start.elapsed().as_secs_f64()
            );
            if self.bar.is_hidden() {
                println!("{line}");
            } else {
                self.bar.println(line);
            }
        }
        self.at = tile;
        self.bar
            .set_message(format!("{} of {}", tile + 1, self.tiles));
        self.bar
            .set_position(tile as u64 * u64::from(self.frames) + u64::from(done));
        !STOP.load(Ordering::SeqCst)
    }
}

/// Prints the tiled render's speed and the aprons' cost.
fn report(exec: &Executor, tiling: &Tiling, image: Extent, frames: u32, wall: Duration) {
    let secs = wall.as_secs_f64();
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
        "rendered {samples} spp at {image} in {} tiles in {secs:.2} s: {:.3} M paths/s of the \
         image ({:.1} % more pixels rendered for the aprons)",
        tiling.tiles.len(),
        paths / secs / 1e6,
        overhead * 100.0
    );
}

/// `merge` of tile sets (`render --tiles`): checked, assembled, each output written as the
/// whole tiled render writes it (inside `out` unless `anywhere`).
pub(super) fn merge_tiles(paths: &[PathBuf], out: &Path, anywhere: bool) -> Result<()> {
    let start = Instant::now();
    let mut sets = Vec::new();
    for path in paths {
        sets.push((path.clone(), TileSet::load(path)?));
    }
    sets.sort_by_key(|(_, s)| s.first);
    let images = crate::session::tile_set::assemble(&sets).map_err(|e| {
        anyhow::anyhow!(
            "the tile sets do not belong together:\n  {}",
            e.replace('\n', "\n  ")
        )
    })?;
    let whole = sets[0].1.image;
    let resources = Resources {
        out_dir: out.to_owned(),
        outputs_anywhere: anywhere,
        ..Resources::default()
    };
    // Every path checked before anything is written (the tile sets name them).
    let files = images
        .iter()
        .map(|image| {
            resources
                .output(&image.path)
                .map_err(|e| anyhow::anyhow!("node \"{}\": {e}", image.node))
        })
        .collect::<Result<Vec<_>>>()?;
    std::fs::create_dir_all(out)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", out.display()))?;
    let mut written = Vec::new();
    for (image, file) in images.into_iter().zip(files) {
        crate::render::write_output(&file, image.bytes, image.format, image.ty, whole)
            .map_err(|e| anyhow::anyhow!("node \"{}\": {e}", image.node))?;
        written.push(file);
    }
    println!(
        "merged {} tile sets ({} tiles of {whole}) in {:.2} s",
        sets.len(),
        sets[0].1.count,
        start.elapsed().as_secs_f64()
    );
    for path in &written {
        println!("wrote {}", path.display());
    }
    Ok(())
}
