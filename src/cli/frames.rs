//! `lumagraph render GRAPH --frames 1-100x2`: an image sequence through a graph, in one
//! process. Every text or path param holding a frame pattern (`####`, `%04d`, `$F4`:
//! `lumagraph_footage::sequence`) takes each frame's number in turn; the graph is compiled
//! and its pipelines built once, and each frame reloads only what its number changed
//! (`Executor::update_params`), so nodes with history (`TemporalReuse`, `AutoExposure`)
//! see the frame before. Each frame prints its time and the files it wrote; a missing
//! input frame stops the render with an error naming it, or is skipped with
//! `--skip-missing`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context as _, Result, bail, ensure};
use lumagraph_footage::sequence;

use super::{RenderArgs, load, uses_scene};
use crate::graph::{Graph, ParamValue};
use crate::render::{Executor, GpuContext, Resources};

/// A param whose value holds a frame pattern: node, param, the value as written, and
/// whether it names a file the graph reads.
struct Patterned {
    node: String,
    param: String,
    template: String,
    input_file: bool,
}

/// Every frame-numbered param of `graph`; an error where none is, or where an output file
/// would be the same for every frame.
fn patterned(graph: &Graph, args: &RenderArgs<'_>) -> Result<Vec<Patterned>> {
    let registry = args.library.registry_for(graph)?;
    let mut found = Vec::new();
    for node in &graph.nodes {
        let kind = registry
            .get(&node.kind)
            .with_context(|| format!("node {:?}: unknown kind {:?}", node.id, node.kind))?;
        for def in &kind.params {
            let value = match node.params.get(def.name) {
                Some(ParamValue::Str(s)) => s.clone(),
                _ => continue,
            };
            let is_path = matches!(def.ty, crate::graph::ParamType::Path { .. });
            if sequence::has_pattern(&value) {
                found.push(Patterned {
                    node: node.id.clone(),
                    param: def.name.to_owned(),
                    template: value,
                    input_file: is_path && !kind.sink,
                });
            } else if kind.sink && is_path {
                bail!(
                    "--frames: {} {:?} writes {value:?} for every frame, each over the last: \
                     put a frame pattern in its {} (`####`, `%04d` or `$F4`, e.g. \"f.####.exr\")",
                    kind.name,
                    node.id,
                    def.name
                );
            }
        }
    }
    ensure!(
        !found.is_empty(),
        "--frames: no param of {} holds a frame pattern (`####`, `%04d`, `$F4`), so every \
         frame would be the same image",
        args.graph.display()
    );
    Ok(found)
}

/// `graph` with frame `frame`'s values, and the input files that frame reads.
fn at_frame(graph: &Graph, params: &[Patterned], frame: i64) -> (Graph, Vec<PathBuf>) {
    let mut g = graph.clone();
    let mut inputs = Vec::new();
    for p in params {
        let value = sequence::substitute(&p.template, frame);
        if p.input_file {
            inputs.push(graph.base_dir().join(&value));
        }
        if let Some(node) = g.nodes.iter_mut().find(|n| n.id == p.node) {
            node.params.insert(p.param.clone(), ParamValue::Str(value));
        }
    }
    (g, inputs)
}

/// Renders `frames` of the graph in `args`, one process, one executor.
pub(super) fn render(args: &RenderArgs<'_>, frames: &[i64], skip_missing: bool) -> Result<()> {
    let graph = load(args.graph, args.overrides)?;
    ensure!(
        args.scene.is_none(),
        "--frames renders image sequences through a graph; a scene has nothing that changes \
         from frame to frame yet (leave out --scene)"
    );
    let params = patterned(&graph, args)?;
    let total = frames.len();
    println!(
        "frames: {total} ({} … {}), frame-numbered: {}",
        frames.first().copied().unwrap_or(0),
        frames.last().copied().unwrap_or(0),
        params
            .iter()
            .map(|p| format!("{}.{} = {:?}", p.node, p.param, p.template))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let mut exec: Option<Executor> = None;
    let mut ctx: Option<GpuContext> = None;
    let (mut written, mut skipped) = (0_usize, Vec::new());
    let start = Instant::now();
    for (i, &frame) in frames.iter().enumerate() {
        let (g, inputs) = at_frame(&graph, &params, frame);
        if let Some(missing) = inputs.iter().find(|p| !p.is_file()) {
            if skip_missing {
                println!(
                    "frame {frame} ({}/{total}): skipped, {} is missing",
                    i + 1,
                    missing.display()
                );
                skipped.push(frame);
                continue;
            }
            bail!(
                "frame {frame}: {} is missing (--skip-missing renders the frames that are there)",
                missing.display()
            );
        }
        let t = Instant::now();
        let plan = args
            .library
            .compile(&g, &[], None)
            .with_context(|| format!("frame {frame}"))?;
        ensure!(
            !uses_scene(&plan),
            "--frames renders image sequences; this graph renders a scene"
        );
        crate::graph::outputs::output_files(&plan, &g, args.out, args.outputs_anywhere)?;
        let reused = match exec.as_mut() {
            Some(e) => e
                .update_params(plan.clone())
                .with_context(|| format!("frame {frame}"))?,
            None => false,
        };
        if !reused {
            // The first frame, or one whose size or layout differs: a new executor.
            let context = match &ctx {
                Some(c) => c.clone(),
                None => {
                    let c = GpuContext::headless()?;
                    println!("adapter: {}", c.describe());
                    ctx = Some(c.clone());
                    c
                }
            };
            if exec.is_some() {
                println!(
                    "frame {frame}: the image's size or layout changed: the graph is built again (nodes with history start over)"
                );
            }
            let resources = Resources {
                base_dir: g.base_dir(),
                out_dir: args.out.to_owned(),
                outputs_anywhere: args.outputs_anywhere,
                ..Resources::default()
            };
            exec = Some(Executor::with_library(
                &context,
                plan,
                &resources,
                args.library,
            )?);
        }
        let e = exec.as_mut().context("no executor")?;
        let report = e.run_frame().with_context(|| format!("frame {frame}"))?;
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
    println!(
        "{} frames in {:.2} s, {written} files written{}",
        total - skipped.len(),
        start.elapsed().as_secs_f64(),
        if skipped.is_empty() {
            String::new()
        } else {
            format!(
                "; skipped (missing): {}",
                skipped
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
    );
    Ok(())
}
