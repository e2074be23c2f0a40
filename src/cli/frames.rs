//! `lumagraph render GRAPH --frames 1-100x2`: an image sequence through a graph, in one
//! process. Every text or path param holding a frame pattern (`####`, `%04d`, `$F4`:
//! `lumagraph_session::frames`) takes each frame's number in turn; the graph is compiled
//! and its pipelines built once, and each frame reloads only what its number changed
//! (`Session::set_frame`), so nodes with history (`TemporalReuse`, `AutoExposure`) see
//! the frame before. Each frame prints its time and the files it wrote; a missing input
//! frame stops the render with an error naming it, or is skipped with `--skip-missing`.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result, anyhow, ensure};

use super::{RenderArgs, load};
use crate::session::frames::FrameParams;
use crate::session::{Session, SessionOptions};

/// Renders `frames` of the graph in `args`, one process, one session.
pub(super) fn render(args: &RenderArgs<'_>, frames: &[i64], skip_missing: bool) -> Result<()> {
    let graph = load(args.graph, args.overrides)?;
    ensure!(
        args.scene.is_none(),
        "--frames renders image sequences through a graph; a scene has nothing that changes \
         from frame to frame yet (leave out --scene)"
    );
    let params = FrameParams::of(&graph, &args.library.registry_for(&graph)?);
    params
        .check_sequence(&args.graph.display().to_string())
        .map_err(|e| anyhow!("--frames: {e}"))?;
    let total = frames.len();
    println!(
        "frames: {total} ({} … {}), frame-numbered: {}",
        frames.first().copied().unwrap_or(0),
        frames.last().copied().unwrap_or(0),
        params.describe()
    );
    let mut session: Option<Session> = None;
    let (mut written, mut skipped) = (0_usize, Vec::new());
    let start = Instant::now();
    for (i, &frame) in frames.iter().enumerate() {
        if let Some(missing) = params.missing_at(&graph, frame) {
            if skip_missing {
                println!(
                    "frame {frame} ({}/{total}): skipped, {} is missing",
                    i + 1,
                    missing.display()
                );
                skipped.push(frame);
                continue;
            }
            anyhow::bail!(
                "frame {frame}: {} is missing (--skip-missing renders the frames that are there)",
                missing.display()
            );
        }
        let t = Instant::now();
        let report = match session.as_mut() {
            Some(s) => s.set_frame(frame)?,
            None => {
                let options = SessionOptions {
                    out: args.out.to_owned(),
                    write_outputs: true,
                    library: Some(Arc::clone(args.library)),
                    frame: Some(frame),
                    outputs_anywhere: args.outputs_anywhere,
                    intersector: args.choice.intersector(),
                    schedule: args.choice.schedule(),
                    ..SessionOptions::default()
                };
                let mut s = Session::with(graph.clone(), None, options)
                    .with_context(|| format!("frame {frame}"))?;
                println!("adapter: {}", s.executor().context().describe());
                let report = s.render(1).with_context(|| format!("frame {frame}"))?;
                session = Some(s);
                report
            }
        };
        written += report.written.len();
        let files: Vec<String> = report
            .written
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        println!(
            "frame {frame} ({}/{total}): {:.2} s, wrote {}",
            i + 1,
            t.elapsed().as_secs_f64(),
            files.join(", ")
        );
    }
    let skipped_text = if skipped.is_empty() {
        String::new()
    } else {
        let list: Vec<String> = skipped.iter().map(ToString::to_string).collect();
        format!("; skipped (missing): {}", list.join(", "))
    };
    println!(
        "{} frames in {:.2} s, {written} files written{skipped_text}",
        total - skipped.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
