//! One render split by sample range: `render --samples START..END` writes a partial render
//! (see [`crate::render::partial`]), `merge` checks that partial renders belong together,
//! merges their histories and runs the graph over the merged one, writing what a single
//! render of all the ranges writes (docs/distributed.md says how close).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result, anyhow, bail};

use crate::render::{Executor, GpuContext, NodeLibrary, Partial, Resources};

/// A range of sample indices, `first..end`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct SampleRange {
    pub first: u32,
    pub end: u32,
}

/// Parses `START..END` (clap's value parser for `--samples`).
pub(super) fn parse_range(text: &str) -> std::result::Result<SampleRange, String> {
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| format!("`{text}` is not a range START..END, such as 0..64"))?;
    let number = |s: &str| {
        s.trim()
            .parse::<u32>()
            .map_err(|e| format!("`{s}` in `{text}`: {e}"))
    };
    let (first, end) = (number(a)?, number(b)?);
    if first >= end {
        return Err(format!("`{text}` is empty: START must be below END"));
    }
    Ok(SampleRange { first, end })
}

/// What a partial render records besides the render: where it came from.
pub(super) struct Origin<'a> {
    pub graph: &'a Path,
    pub scene: Option<&'a Path>,
    pub overrides: &'a [String],
    pub key: u64,
    pub out: &'a Path,
}

/// The samples per frame of the plan's sample source (its `samples_per_frame` param).
fn samples_per_frame(exec: &Executor) -> Result<(String, u32)> {
    let source = super::progressive_source(exec.plan())
        .ok_or_else(|| anyhow!("--samples needs a graph with a node that takes samples"))?;
    let spf = u32::try_from(source.params.int(crate::graph::registry::SAMPLES_PER_FRAME))
        .unwrap_or(1)
        .max(1);
    Ok((source.node.clone(), spf))
}

/// `render --samples START..END`: takes samples `START..END` of every pixel's sequence and
/// writes the partial render `OUT/samples-START-END.partial`.
pub(super) fn render_partial(
    exec: &mut Executor,
    range: SampleRange,
    origin: &Origin<'_>,
) -> Result<()> {
    let (node, spf) = samples_per_frame(exec)?;
    if !range.first.is_multiple_of(spf) || !range.end.is_multiple_of(spf) {
        bail!(
            "--samples {}..{}: {node} takes {spf} samples per frame, so both ends must be \
             multiples of {spf} (such as {}..{})",
            range.first,
            range.end,
            range.first / spf * spf,
            range.end.div_ceil(spf) * spf
        );
    }
    super::progressive::warm_up(|| Ok(exec.warm_up()?))?;
    let start = Instant::now();
    exec.start_at_sample(range.first, u64::from(range.first / spf));
    let frames = (range.end - range.first) / spf;
    let (mut done, mut batch) = (0, 1);
    while done < frames {
        let n = batch.min(frames - done);
        let t = Instant::now();
        exec.run_frames(n, false)?;
        done += n;
        if t.elapsed() < std::time::Duration::from_millis(200) {
            batch = (batch * 2).min(256);
        }
    }
    let checkpoint = exec.checkpoint(origin.key)?;
    let absolute = |p: &Path| {
        std::path::absolute(p).with_context(|| format!("cannot resolve {}", p.display()))
    };
    let partial = Partial {
        first: range.first,
        end: range.end,
        samples_per_frame: spf,
        graph: absolute(origin.graph)?,
        scene: origin.scene.map(absolute).transpose()?,
        overrides: origin.overrides.to_vec(),
        checkpoint,
    };
    std::fs::create_dir_all(origin.out)
        .with_context(|| format!("cannot create {}", origin.out.display()))?;
    let path = origin
        .out
        .join(format!("samples-{}-{}.partial", range.first, range.end));
    partial.save(&path)?;
    println!(
        "rendered samples {}..{} ({frames} frames of {spf}) in {:.2} s",
        range.first,
        range.end,
        start.elapsed().as_secs_f64()
    );
    println!("wrote {}", path.display());
    Ok(())
}

/// What `merge` is given.
pub(super) struct MergeArgs<'a> {
    pub library: &'a Arc<NodeLibrary>,
    pub partials: &'a [PathBuf],
    pub out: &'a Path,
    pub graph: Option<&'a Path>,
    pub scene: Option<&'a Path>,
    pub allow_gaps: bool,
    /// `--allow-outputs-outside`.
    pub outputs_anywhere: bool,
}

/// `merge`: the partial renders checked, merged and run through the rest of the graph.
pub(super) fn merge(args: &MergeArgs<'_>) -> Result<()> {
    let sets = args
        .partials
        .iter()
        .filter(|p| crate::session::tile_set::TileSet::is_tile_set(p))
        .count();
    if sets == args.partials.len() {
        return super::tiled::merge_tiles(args.partials, args.out, args.outputs_anywhere);
    }
    if sets > 0 {
        bail!(
            "{sets} of the {} files are tile sets (render --tiles) and the others are not: \
             merge each kind on its own",
            args.partials.len()
        );
    }
    let mut parts = Vec::new();
    for path in args.partials {
        parts.push((path.clone(), Partial::load(path)?));
    }
    let parts = crate::render::partial::arrange(parts, args.allow_gaps).map_err(|e| {
        anyhow!(
            "the partial renders do not belong together:\n  {}",
            e.replace('\n', "\n  ")
        )
    })?;
    let first = &parts[0].1;
    let graph_path = args.graph.unwrap_or(&first.graph);
    let scene_path = args.scene.or(first.scene.as_deref());
    let graph = super::load(graph_path, &first.overrides)?;
    let scene = super::load_scene(scene_path)?;
    let key = crate::session::render_key(&graph, scene.as_ref().map(|s| &*s.gpu));
    first.checkpoint.check(key).map_err(|e| {
        anyhow!(
            "{} (samples {}) does not fit {}{}: {e}",
            parts[0].0.display(),
            first.range(),
            graph_path.display(),
            scene_path.map_or_else(String::new, |s| format!(" with {}", s.display()))
        )
    })?;
    let plan = args
        .library
        .compile(&graph, &[], scene.as_ref().map(|s| &*s.gpu))?;
    crate::graph::outputs::output_files(&plan, &graph, args.out, args.outputs_anywhere)?;
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    for (path, p) in &parts {
        if p.checkpoint.adapter != ctx.info.name {
            println!(
                "warning: {} was rendered on {}, this is {}: the result may differ from a \
                 single render in the last bits",
                path.display(),
                p.checkpoint.adapter,
                ctx.info.name
            );
        }
    }
    let resources = Resources {
        base_dir: graph.base_dir(),
        out_dir: args.out.to_owned(),
        outputs_anywhere: args.outputs_anywhere,
        scene: scene.as_ref().map(|s| Arc::clone(&s.gpu)),
        ..Resources::default()
    };
    let mut exec = Executor::with_library(&ctx, plan, &resources, args.library)?;
    exec.warm_up()?;
    let start = Instant::now();
    let checkpoints: Vec<_> = parts.iter().map(|(_, p)| p.checkpoint.clone()).collect();
    let merged = exec.merge(&checkpoints)?;
    exec.restore(&merged)?;
    let report = exec.present()?;
    let samples: u32 = parts.iter().map(|(_, p)| p.end - p.first).sum();
    let ranges: Vec<String> = parts.iter().map(|(_, p)| p.range()).collect();
    println!(
        "merged {} partial renders ({}; {samples} samples per pixel) in {:.2} s",
        parts.len(),
        ranges.join(", "),
        start.elapsed().as_secs_f64()
    );
    for path in &report.written {
        println!("wrote {}", path.display());
    }
    Ok(())
}
