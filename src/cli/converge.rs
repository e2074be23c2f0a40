//! `lumagraph converge`: error against run time, for the raw accumulation and every
//! denoised output of a graph.
//!
//! The graph's `Output` nodes are dropped and every `PathTrace` takes 1 sample a frame, so
//! checkpoints fall at 1, 2, 4, 8… spp. At each checkpoint:
//! - the progressive part (path tracing + accumulation) has run for `render` seconds, wall
//!   time, summed over every batch so far (shader compilation excluded by a warm-up);
//! - the rest of the graph (G-buffer, every `Denoise`) then runs once on its own
//!   ([`Executor::run_tail`]), wall time `tail`, with its GPU time per pass;
//! - each `Accumulate` output (named by node id) is scored at `render` seconds, each
//!   `Denoise` output at `render + tail` seconds: what a render that stopped here and then
//!   denoised would have cost. Readbacks and scoring are not timed.
//!
//! Scores against the reference: RMSE, relMSE (`metrics::relmse`, as Mitsuba's CSVs) and mean
//! SSIM on clipped luminance (`metrics::ssim`). The reference is a file, or rendered first
//! with the same graph at `--reference-spp` samples and a different seed (so its noise is
//! independent of the runs it scores).
//!
//! Writes `converge.csv` and `converge.png` (log-log relMSE against seconds, one line per
//! output, plus Mitsuba and OIDN points from `--compare`) into `--out`, and prints the time
//! each curve takes to reach a relMSE (`--target-relmse`, or the comparison's raw relMSE at
//! its largest spp), interpolated log-log between the checkpoints around it.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use crate::graph::registry::SAMPLES_PER_FRAME;
use crate::graph::{Category, Graph, ParamValue};
use crate::render::cpu::Image;
use crate::render::{Executor, GpuContext, NodeLibrary, Resources, image_io, metrics};
use crate::scene::GpuScene;
use anyhow::{Context as _, Result, bail};

/// What `converge` was asked.
pub struct Args<'a> {
    pub graph: &'a Path,
    pub scene: &'a Path,
    pub reference: Option<&'a Path>,
    pub reference_spp: Option<u32>,
    pub seconds: f64,
    pub compare: Option<&'a Path>,
    pub target_relmse: Option<f64>,
    pub out: &'a Path,
    pub overrides: &'a [String],
    /// `LABEL:OVERRIDE[;OVERRIDE...]`: the graph again with these overrides, as more curves.
    pub variants: &'a [String],
    pub library: &'a NodeLibrary,
}

/// One graph being measured: the graph as given, or a variant of it.
struct Run {
    /// The variant's label (none for the graph as given).
    label: Option<String>,
    exec: Executor,
    /// Wall seconds of rendering so far.
    render_secs: f64,
    /// Its next checkpoint would pass the time budget.
    done: bool,
}

/// `(label, overrides)` of a `--variant`.
fn parse_variant(text: &str) -> Result<(String, Vec<String>)> {
    let Some((label, overrides)) = text.split_once(':') else {
        bail!("--variant {text:?}: expected LABEL:NODE.PARAM=VALUE[;NODE.PARAM=VALUE...]");
    };
    let overrides: Vec<String> = overrides
        .split(';')
        .map(str::trim)
        .filter(|o| !o.is_empty())
        .map(str::to_owned)
        .collect();
    if label.trim().is_empty() || overrides.is_empty() {
        bail!("--variant {text:?}: give a label and at least one override");
    }
    Ok((label.trim().to_owned(), overrides))
}

/// One scored output at one checkpoint.
struct Row {
    output: String,
    spp: u32,
    seconds: f64,
    rmse: f64,
    relmse: f64,
    ssim: f64,
    /// GPU ms of this output's Denoise passes (none for raw).
    gpu_ms: Option<f64>,
}

/// The graph without sinks (groups flattened, so theirs too), 1 spp per frame; returns it
/// with the ports scored, as `(port, is_denoised)`.
fn prepare(graph: &mut Graph, library: &NodeLibrary) -> Result<Vec<(String, bool)>> {
    let flat = crate::graph::group::flatten(graph, &library.registry_for(graph)?)?;
    *graph = flat.graph;
    let registry = flat.registry;
    let kind = |n: &crate::graph::Node| registry.get(&n.kind);
    graph.remove_sinks(&registry);
    let mut ports = Vec::new();
    for n in &mut graph.nodes {
        let Some(k) = kind(n) else { continue };
        if k.param(SAMPLES_PER_FRAME).is_some() {
            n.params
                .insert(SAMPLES_PER_FRAME.into(), ParamValue::Int(1));
        } else if k.history {
            ports.push((format!("{}.color", n.id), false));
        } else if k.category == Category::Denoise {
            ports.push((format!("{}.color", n.id), true));
        }
    }
    if !ports.iter().any(|(_, d)| !d) {
        bail!("the graph has no Accumulate node: nothing to converge");
    }
    Ok(ports)
}

fn executor(
    ctx: &GpuContext,
    library: &NodeLibrary,
    graph: &Graph,
    keep: &[String],
    scene: &Arc<GpuScene>,
) -> Result<Executor> {
    let plan = library.compile(graph, keep, Some(scene))?;
    let resources = Resources {
        base_dir: graph.base_dir(),
        scene: Some(Arc::clone(scene)),
        ..Resources::default()
    };
    Ok(Executor::with_library(ctx, plan, &resources, library)?)
}

fn render_reference(
    ctx: &GpuContext,
    library: &NodeLibrary,
    graph: &Graph,
    port: &str,
    scene: &GpuScene,
    spp: u32,
) -> Result<Image> {
    let mut other = scene.clone();
    other.settings.seed ^= 0x9e37_79b9;
    let other = Arc::new(other);
    let mut exec = executor(ctx, library, graph, &[port.to_owned()], &other)?;
    let start = Instant::now();
    let mut done = 0;
    while done < spp {
        let n = (spp - done).min(64);
        exec.run_frames(n, done + n >= spp)?;
        done += n;
    }
    println!(
        "reference: {spp} spp with seed {:#x} in {:.1} s",
        other.settings.seed,
        start.elapsed().as_secs_f64()
    );
    Ok(exec.read_port(port)?)
}

/// Runs the measurement; prints the table and writes the CSV and the plot.
pub fn run(args: &Args<'_>) -> Result<()> {
    let mut graph = Graph::load(args.graph)?;
    for o in args.overrides {
        graph.apply_override(o)?;
    }
    let ports = prepare(&mut graph, args.library)?;
    let scene = super::load_scene(Some(args.scene))?.context("no scene")?;
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    let raw_port = ports
        .iter()
        .find(|(_, d)| !d)
        .map(|(p, _)| p.clone())
        .unwrap_or_default();
    let reference = match (args.reference, args.reference_spp) {
        (Some(path), _) => image_io::load(path)?,
        (None, Some(spp)) => {
            render_reference(&ctx, args.library, &graph, &raw_port, &scene.gpu, spp)?
        }
        (None, None) => bail!("give --reference FILE.exr or --reference-spp N"),
    };
    let keep: Vec<String> = ports.iter().map(|(p, _)| p.clone()).collect();
    let mut runs = Vec::new();
    for variant in std::iter::once(None).chain(args.variants.iter().map(Some)) {
        let (label, g) = match variant {
            None => (None, graph.clone()),
            Some(text) => {
                let (label, overrides) = parse_variant(text)?;
                let mut g = graph.clone();
                for o in &overrides {
                    g.apply_override(o)
                        .with_context(|| format!("--variant {label:?}"))?;
                }
                (Some(label), g)
            }
        };
        let mut exec = executor(&ctx, args.library, &g, &keep, &scene.gpu)?;
        let extent = exec.plan().passes.first().map(|p| p.extent);
        if extent.is_some_and(|e| (e.width, e.height) != (reference.width, reference.height)) {
            bail!(
                "the reference is {}x{}, the render {}",
                reference.width,
                reference.height,
                extent.map_or_else(String::new, |e| e.to_string())
            );
        }
        exec.warm_up()?;
        runs.push(Run {
            label,
            exec,
            render_secs: 0.0,
            done: false,
        });
    }

    let mut rows = Vec::new();
    let mut spp = 1;
    let mut clock = None;
    let mut last_tail_ms = Vec::new();
    while runs.iter().any(|r| !r.done) {
        // The runs take turns, checkpoint by checkpoint.
        for run in runs.iter_mut().filter(|r| !r.done) {
            let exec = &mut run.exec;
            let t = Instant::now();
            let frames = spp - u32::try_from(exec.frames()).unwrap_or(spp);
            exec.run_frames(frames, false)?;
            run.render_secs += t.elapsed().as_secs_f64();
            let tail = exec.run_tail()?;
            let tail_secs = tail.wall.as_secs_f64();
            let pass_ms = tail.pass_ms.unwrap_or_default();
            for (port, denoised) in &ports {
                let image = exec.read_port(port)?;
                let node = port.split('.').next().unwrap_or(port);
                rows.push(Row {
                    output: run
                        .label
                        .as_ref()
                        .map_or_else(|| node.to_owned(), |l| format!("{l}: {node}")),
                    spp,
                    seconds: run.render_secs + if *denoised { tail_secs } else { 0.0 },
                    rmse: metrics::rmse(&image, &reference),
                    relmse: metrics::relmse(&image, &reference),
                    ssim: metrics::ssim(&image, &reference),
                    gpu_ms: denoised
                        .then(|| pass_ms.iter().find(|(n, _)| n == node).map(|(_, ms)| *ms))
                        .flatten(),
                });
            }
            // Stop when the next checkpoint (twice the rendering) would pass the budget.
            run.done = 2.0 * run.render_secs + tail_secs > args.seconds || spp >= 1 << 20;
            if run.label.is_none() {
                clock = Some(tail.pass_clock);
                last_tail_ms = pass_ms;
            }
        }
        spp *= 2;
    }

    print_table(&rows);
    println!(
        "time per pass of the part run after rendering (last checkpoint; {}):",
        clock.map_or("", crate::render::PassClock::describe)
    );
    if last_tail_ms.is_empty() {
        println!("  not available (adapter has no timestamp queries)");
    }
    for (name, ms) in &last_tail_ms {
        println!("  {name:<16} {ms:>9.3} ms per frame");
    }
    std::fs::create_dir_all(args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let csv = args.out.join("converge.csv");
    crate::graph::write_atomic(&csv, csv_text(&rows).as_bytes())
        .with_context(|| format!("cannot write {}", csv.display()))?;
    println!("wrote {}", csv.display());
    let compare = args.compare.map(read_compare).transpose()?;
    print_times_to(&rows_by_output(&rows), compare.as_ref(), args.target_relmse);
    let png = args.out.join("converge.png");
    match super::plot::write(&png, &rows_by_output(&rows), compare.as_ref()) {
        Ok(()) => println!("wrote {}", png.display()),
        Err(e) => println!("plot not written: {e:#}"),
    }
    Ok(())
}

fn print_table(rows: &[Row]) {
    println!(
        "{:>6}  {:<14} {:>9}  {:>10}  {:>10}  {:>7}  {:>9}",
        "spp", "output", "seconds", "rmse", "relmse", "ssim", "gpu ms"
    );
    for r in rows {
        println!(
            "{:>6}  {:<14} {:>9.3}  {:>10.4e}  {:>10.4e}  {:>7.4}  {:>9}",
            r.spp,
            r.output,
            r.seconds,
            r.rmse,
            r.relmse,
            r.ssim,
            r.gpu_ms
                .map_or_else(|| "-".to_owned(), |ms| format!("{ms:.2}"))
        );
    }
}

fn csv_text(rows: &[Row]) -> String {
    let mut s = String::from("output,spp,seconds,rmse,relmse,ssim,gpu_ms\n");
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{:.6},{:.6e},{:.6e},{:.6},{}",
            r.output,
            r.spp,
            r.seconds,
            r.rmse,
            r.relmse,
            r.ssim,
            r.gpu_ms.map_or_else(String::new, |ms| format!("{ms:.4}"))
        );
    }
    s
}

/// Prints the time each curve (ours, then the comparison's) takes to reach `target`, or
/// by default the comparison's raw relMSE at its largest spp; nothing without either.
fn print_times_to(
    ours: &[(String, Vec<(f64, f64)>)],
    compare: Option<&Compare>,
    target: Option<f64>,
) {
    let last_raw = compare
        .and_then(|c| c.first())
        .and_then(|(label, pts)| Some((label, pts.last()?.1)));
    let (target, what) = match (target, last_raw) {
        (Some(t), _) => (t, "--target-relmse".to_owned()),
        (None, Some((label, t))) => (t, format!("{label} at its largest spp")),
        (None, None) => return,
    };
    println!("time to relMSE {target:.3e} ({what}):");
    for (label, pts) in ours.iter().chain(compare.into_iter().flatten()) {
        let line = match time_to(pts, target) {
            Some(s) => format!("{s:.3} s"),
            None => {
                let best = pts.iter().min_by(|a, b| a.1.total_cmp(&b.1));
                best.map_or_else(
                    || "no points".to_owned(),
                    |(s, r)| format!("not reached (best {r:.3e} at {s:.3} s)"),
                )
            }
        };
        println!("  {label:<22} {line}");
    }
}

/// The first time the curve `pts` (`(seconds, relmse)`, by time) is at or below `target`:
/// between the two points around the crossing, interpolated linearly in log-log (as the
/// plot draws it); the first point's time if that one already is.
fn time_to(pts: &[(f64, f64)], target: f64) -> Option<f64> {
    let i = pts.iter().position(|p| p.1 <= target)?;
    let Some(&(s0, r0)) = i.checked_sub(1).and_then(|j| pts.get(j)) else {
        return Some(pts[i].0);
    };
    let (s1, r1) = pts[i];
    if !(s0 > 0.0 && s1 > 0.0 && r0 > 0.0 && r1 > 0.0 && target > 0.0) || r0 == r1 {
        return Some(s1);
    }
    let f = (target.ln() - r0.ln()) / (r1.ln() - r0.ln());
    Some((s0.ln() + f * (s1.ln() - s0.ln())).exp())
}

/// `(output, [(seconds, relmse)])` in first-seen order.
fn rows_by_output(rows: &[Row]) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut out: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows {
        match out.iter_mut().find(|(n, _)| *n == r.output) {
            Some((_, pts)) => pts.push((r.seconds, r.relmse)),
            None => out.push((r.output.clone(), vec![(r.seconds, r.relmse)])),
        }
    }
    out
}

/// Mitsuba and OIDN points of a `cornell_converge.csv`-style file: `(label, [(s, relmse)])`.
pub type Compare = Vec<(String, Vec<(f64, f64)>)>;

fn read_compare(path: &Path) -> Result<Compare> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .with_context(|| format!("{}: no column {name}", path.display()))
    };
    let (s, r) = (col("seconds")?, col("relmse")?);
    let oidn = (col("oidn_seconds"), col("oidn_relmse"));
    let (mut mitsuba, mut denoised) = (Vec::new(), Vec::new());
    for (i, line) in lines.enumerate() {
        let f: Vec<f64> = line
            .split(',')
            .map(|v| v.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .with_context(|| format!("{}:{}: not a number", path.display(), i + 2))?;
        let get = |c: usize| f.get(c).copied().context("short line");
        mitsuba.push((get(s)?, get(r)?));
        if let (Ok(os), Ok(or)) = (&oidn.0, &oidn.1) {
            // OIDN runs after the render: its point sits at render + filter time.
            denoised.push((get(s)? + get(*os)?, get(*or)?));
        }
    }
    let mut out = vec![("Mitsuba 3 (raw)".to_owned(), mitsuba)];
    if !denoised.is_empty() {
        out.push(("Mitsuba 3 + OIDN 2.5".to_owned(), denoised));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::time_to;

    #[test]
    fn time_to_interpolates_log_log_at_the_first_crossing() {
        // relMSE 1e-1 at 1 s, 1e-3 at 100 s: a straight line in log-log; 1e-2 at 10 s.
        let pts = [(1.0, 1e-1), (100.0, 1e-3), (200.0, 5e-4)];
        let t = time_to(&pts, 1e-2).unwrap();
        assert!((t - 10.0).abs() < 1e-9, "{t}");
        assert_eq!(time_to(&pts, 0.5), Some(1.0), "reached at the first point");
        assert_eq!(time_to(&pts, 1e-4), None, "never reached");
        // A curve that goes down, up, and down again: the first crossing counts.
        let bumpy = [(1.0, 1e-1), (2.0, 1e-2), (4.0, 1e-1), (8.0, 1e-3)];
        assert_eq!(time_to(&bumpy, 1e-2), Some(2.0));
    }
}
