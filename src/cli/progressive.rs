//! `render`'s progressive part: frames up to the asked samples per pixel with a progress
//! bar, checkpoints every few seconds when asked, and on Ctrl-C (SIGINT) or SIGTERM the
//! outputs of the samples so far plus a checkpoint to go on from (`--resume`).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use anyhow::{Result, anyhow, bail};

use crate::render::{Checkpoint, Executor, FrameReport};
use crate::session::Session;

/// Set by the signal handler: stop after the batch of frames running now.
pub(super) static STOP: AtomicBool = AtomicBool::new(false);

/// Where checkpoints go and when.
#[derive(Clone, Debug)]
pub(super) struct Checkpoints {
    /// The checkpoint file.
    pub path: PathBuf,
    /// Write it this often while rendering.
    pub every: Option<Duration>,
    /// Go on from this checkpoint.
    pub resume: Option<PathBuf>,
    /// What is rendered ([`crate::session::render_key`]).
    pub key: Key,
}

/// A render's key ([`crate::session::render_key`]), worked out when a checkpoint is first
/// written: it hashes every number of the scene (about 0.1 s for the Crytek Sponza), which
/// a render writing no checkpoint would otherwise spend before its first frame.
#[derive(Clone, Default)]
pub(super) struct Key {
    make: Option<Arc<dyn Fn() -> u64 + Send + Sync>>,
    made: Arc<OnceLock<u64>>,
}

impl Key {
    pub(super) fn new(make: impl Fn() -> u64 + Send + Sync + 'static) -> Self {
        Self {
            make: Some(Arc::new(make)),
            made: Arc::default(),
        }
    }

    /// The key (0 where none was given).
    pub(super) fn get(&self) -> u64 {
        *self
            .made
            .get_or_init(|| self.make.as_ref().map_or(0, |make| make()))
    }
}

impl std::fmt::Debug for Key {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Key").field(&self.made.get()).finish()
    }
}

/// When the process started (as near as `main` knows it: [`started`]).
static START: OnceLock<Instant> = OnceLock::new();

/// Notes the process's start, from which `render` times its first sample.
pub(super) fn started() {
    START.get_or_init(Instant::now);
}

/// Prints how long after the start the first frame the image keeps was finished (the
/// first `samples_per_frame` samples of every pixel): the time to the first sample,
/// loading, the GPU layout, pipelines, uploads and the warm-up included.
fn print_first_sample(spp: u32) {
    if let Some(start) = START.get() {
        println!(
            "first sample: {:.0} ms after the start (the first frame kept, {spp} spp)",
            start.elapsed().as_secs_f64() * 1e3
        );
    }
}

impl Checkpoints {
    /// `render`'s `--checkpoint` (default `OUT/render.checkpoint`), `--checkpoint-every`
    /// and `--resume`; the key is set when the render knows it.
    pub(super) fn new(
        out: &Path,
        path: Option<PathBuf>,
        every: Option<f64>,
        resume: Option<PathBuf>,
    ) -> Self {
        Self {
            path: path.unwrap_or_else(|| out.join("render.checkpoint")),
            every: every.map(Duration::from_secs_f64),
            resume,
            key: Key::default(),
        }
    }
}

/// The first Ctrl-C or SIGTERM asks the render to stop after its current batch of frames
/// (saying `then`, what happens next); a second one ends the process at once.
pub(super) fn on_signal(then: &'static str) {
    let installed = ctrlc::set_handler(move || {
        if STOP.swap(true, Ordering::SeqCst) {
            eprintln!("stopped");
            std::process::exit(130);
        }
        eprintln!("stopping after this batch of frames: {then}");
    });
    if let Err(e) = installed {
        eprintln!("warning: Ctrl-C will not write a checkpoint: {e}");
    }
}

/// A spinner on standard error naming the stage a render is in before its first frame
/// (loading the scene, its GPU layout, pipelines and uploads, the warm-up) with the time it
/// has taken, so a long load shows where it is. Drawn on a terminal only (indicatif hides it
/// elsewhere) and cleared when the stage ends; each stage's time is still printed on
/// standard output.
pub(super) struct Stage(indicatif::ProgressBar);

impl Stage {
    pub(super) fn start(what: impl Into<String>) -> Self {
        let bar =
            indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        bar.set_message(what.into());
        // Drawn at once, however short the stage.
        bar.tick();
        bar.enable_steady_tick(Duration::from_millis(120));
        Self(bar)
    }
}

impl Drop for Stage {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// Prints how long building the executor took since `start`: its pipelines (a CPU adapter
/// spends seconds on each of the path tracer's, less where Mesa's shader cache holds part of
/// the work from an earlier run) and its nodes' uploads.
pub(super) fn print_built(start: Instant) {
    println!(
        "pipelines and uploads: {:.0} ms",
        start.elapsed().as_secs_f64() * 1e3
    );
}

/// Warms up (`run`: [`Session::warm_up`] or [`Executor::warm_up`]) and prints how long it
/// took: drivers compile pipelines at their first dispatch, and that is kept out of the
/// timed frames.
pub(super) fn warm_up(run: impl FnOnce() -> Result<()>) -> Result<()> {
    let warm = Instant::now();
    let stage = Stage::start(
        "warm-up (the first frame: drivers compile pipelines at their first dispatch)",
    );
    run()?;
    drop(stage);
    println!(
        "warm-up (shader compilation): {:.0} ms",
        warm.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}

/// Runs the progressive part of the session's graph to `spp` samples per pixel (going on
/// from a checkpoint when asked), then the rest once.
pub(super) fn render(session: &mut Session, spp: u32, ck: &Checkpoints) -> Result<FrameReport> {
    let frames = session.frames_for(spp);
    warm_up(|| session.warm_up())?;
    if let Some(path) = &ck.resume {
        let from = Checkpoint::load(path)?;
        session.resume_from(&from, path)?;
        if from.frames >= u64::from(frames) {
            bail!(
                "nothing to resume from {}: it has {} frames, and {frames} make the {spp} spp \
                 asked for; ask for more with --spp",
                path.display(),
                from.frames
            );
        }
        println!(
            "resuming from {} at frame {} of {frames}",
            path.display(),
            from.frames
        );
    }
    let before = samples_per_pixel(session.executor())?;
    on_signal(
        "writing the samples so far and a checkpoint (press Ctrl-C again to quit without them)",
    );

    let bar = indicatif::ProgressBar::with_draw_target(
        Some(u64::from(frames)),
        indicatif::ProgressDrawTarget::hidden(),
    );
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} frames, {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = Instant::now();
    let mut last = Instant::now();
    let mut failed = None;
    // A resumed render's first frames were made by an earlier process.
    let mut first = ck.resume.is_none();
    let report = session.render_with(spp, |exec, done, _| {
        if first && done > 0 {
            first = false;
            print_first_sample(exec.samples_per_frame());
        }
        if bar.is_hidden() && start.elapsed() > Duration::from_secs(1) {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        }
        bar.set_position(u64::from(done));
        if ck.every.is_some_and(|every| last.elapsed() >= every) && done < frames {
            last = Instant::now();
            if let Err(e) = exec.checkpoint(ck.key.get()).and_then(|c| c.save(&ck.path)) {
                failed = Some(e);
                return false;
            }
        }
        !STOP.load(Ordering::SeqCst)
    })?;
    bar.finish_and_clear();
    if let Some(e) = failed {
        return Err(e.into());
    }
    let exec = session.executor();
    match report {
        Some(report) => {
            report_speed(exec, start.elapsed(), before)?;
            if ck.every.is_some() {
                exec.checkpoint(ck.key.get())?.save(&ck.path)?;
            }
            Ok(report)
        }
        None => Err(stopped(exec, spp, frames, ck)),
    }
}

/// After a stop: the checkpoint, the outputs of the samples so far, and the error saying so.
fn stopped(exec: &mut Executor, spp: u32, frames: u32, ck: &Checkpoints) -> anyhow::Error {
    let done = exec.frames();
    if done == 0 {
        return anyhow!("interrupted before the first frame: nothing written");
    }
    if let Err(e) = exec.checkpoint(ck.key.get()).and_then(|c| c.save(&ck.path)) {
        return anyhow!("interrupted at frame {done} of {frames}, and the checkpoint failed: {e}");
    }
    let written = match exec.run_tail() {
        Ok(r) => r.written,
        Err(e) => {
            return anyhow!(
                "interrupted at frame {done} of {frames}; checkpoint {}; the outputs failed: {e}",
                ck.path.display()
            );
        }
    };
    for path in &written {
        println!("wrote {} (frame {done} of {frames})", path.display());
    }
    anyhow!(
        "interrupted at frame {done} of {frames} ({spp} spp asked): wrote the outputs of the \
         samples so far and the checkpoint {}; go on with the same command and `--resume {}`",
        ck.path.display(),
        ck.path.display()
    )
}

/// The value of the counter called `name` (0 when no node keeps one).
pub(crate) fn counter(counters: &[(String, crate::render::Counter)], name: &str) -> u64 {
    counters
        .iter()
        .find(|(_, c)| c.name == name)
        .map_or(0, |(_, c)| c.value)
}

/// The path tracer's samples per pixel and rays so far (0 without one).
fn samples_per_pixel(exec: &mut Executor) -> Result<(u64, u64)> {
    let counters = exec.counters()?;
    let get = |name: &str| counter(&counters, name);
    Ok((get("samples_per_pixel"), get("rays")))
}

/// Prints samples, paths and rays per second of this run (`before`: the samples per pixel
/// and rays a checkpoint brought).
fn report_speed(exec: &mut Executor, wall: Duration, before: (u64, u64)) -> Result<()> {
    let counters = exec.counters()?;
    let get = |name: &str| counter(&counters, name);
    let samples = get("samples_per_pixel");
    let extent = super::progressive_source(exec.plan()).map(|p| p.extent);
    let pixels = extent.map_or(0, crate::graph::Extent::pixels);
    let secs = wall.as_secs_f64();
    // Adaptive sampling counts the samples it took (since the checkpoint, if any).
    let adaptive = counters.iter().any(|(_, c)| c.name == "adaptive_samples");
    let taken = if adaptive {
        get("adaptive_samples")
    } else {
        pixels * samples.saturating_sub(before.0)
    };
    #[expect(clippy::cast_precision_loss, reason = "report figures")]
    let (paths, rays) = (taken as f64, get("rays").saturating_sub(before.1) as f64);
    if adaptive && pixels > 0 && samples > 0 {
        #[expect(clippy::cast_precision_loss, reason = "report figures")]
        let mean = taken as f64 / pixels as f64;
        #[expect(clippy::cast_precision_loss, reason = "report figures")]
        let share = 100.0 * mean / samples.saturating_sub(before.0).max(1) as f64;
        println!(
            "adaptive sampling: {mean:.1} samples per pixel on average, {share:.1} % of {} spp uniform",
            samples.saturating_sub(before.0)
        );
    }
    println!(
        "rendered {samples} spp at {} in {secs:.2} s: {:.3} M paths/s, {:.3} M rays/s, {} NaN/Inf samples dropped",
        extent.map_or_else(String::new, |e| e.to_string()),
        paths / secs / 1e6,
        rays / secs / 1e6,
        get("dropped_samples")
    );
    Ok(())
}
