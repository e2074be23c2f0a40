//! Error against run time, for the raw accumulation and every denoised output of a graph:
//! what `lumagraph converge` prints and writes, and Python's `lg.converge`.
//!
//! The graph's `Output` nodes are dropped and every `PathTrace` takes 1 sample a frame, so
//! checkpoints fall at 1, 2, 4, 8… spp. At each checkpoint:
//! - the progressive part (path tracing + accumulation) has run for `render` seconds, wall
//!   time, summed over every batch so far (shader compilation excluded by a warm-up);
//! - the rest of the graph (G-buffer, every denoiser) then runs once on its own
//!   ([`Executor::run_tail`]), wall time `tail`, with its time per pass (by node);
//! - each `Accumulate` output (named by node id) is scored at `render` seconds, each
//!   denoiser's output (`Denoise`, `RegressionDenoise`, `OIDN`: the nodes of the denoise
//!   category) at `render + tail − others`, where `others` is the time of the tail's nodes
//!   that the output does not depend on (the other denoisers of a graph that has several,
//!   the nodes after it): what a render that stopped here and then ran this denoiser
//!   would have cost. Without times per pass, `others` is 0. Readbacks and scoring are
//!   not timed.
//!
//! Scores against the reference: RMSE, relMSE (`metrics::relmse`, as Mitsuba's CSVs) and mean
//! SSIM on clipped luminance (`metrics::ssim`). The reference is a file, or rendered first
//! with the same graph at `--reference-spp` samples and a different seed (so its noise is
//! independent of the runs it scores).
//!
//! [`measure`] gives the rows; [`write`] writes `converge.csv` and `converge.png` (log-log
//! relMSE against seconds, one line per output, plus Mitsuba and OIDN points from
//! `--compare`); [`time_to`] is the time a curve takes to reach a relMSE, interpolated
//! log-log between the checkpoints around it.

mod plot;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use crate::graph::registry::SAMPLES_PER_FRAME;
use crate::graph::{Category, Graph, ParamValue};
use crate::render::cpu::Image;
use crate::render::{Executor, GpuContext, NodeLibrary, PassClock, Resources, image_io, metrics};
use crate::scene::GpuScene;
use anyhow::{Context as _, Result, bail};

/// What the rows are scored against.
#[derive(Clone, Debug)]
pub enum Reference {
    /// A linear image file (EXR) of the render's size.
    File(PathBuf),
    /// Rendered first with the same graph at this many spp and another seed.
    Spp(u32),
    /// An image given.
    Image(Image),
}

/// What a measurement runs.
pub struct Options<'a> {
    /// What the outputs are scored against.
    pub reference: Reference,
    /// Time budget in seconds: no checkpoint is started that is predicted to pass it
    /// (twice the render time so far plus the last denoise time).
    pub seconds: f64,
    /// `LABEL:NODE.PARAM=VALUE[;NODE.PARAM=VALUE...]`: the graph again with these
    /// overrides, as more curves; the runs take turns at each checkpoint.
    pub variants: &'a [String],
    /// The node kinds.
    pub library: &'a NodeLibrary,
}

/// What [`measure`] measured.
pub struct Measured {
    /// Every output scored at every checkpoint, checkpoint by checkpoint.
    pub rows: Vec<Row>,
    /// How the reference was rendered (`reference: 1024 spp with seed … in 3.1 s`), when it
    /// was.
    pub reference_note: Option<String>,
    /// The clock of the part run after rendering, at the last checkpoint.
    pub clock: Option<PassClock>,
    /// Its GPU ms per pass (empty where the adapter cannot time passes).
    pub tail_ms: Vec<(String, f64)>,
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
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The node whose output it is (`accumulate`, `denoise`; `LABEL: node` of a variant).
    pub output: String,
    /// Samples per pixel.
    pub spp: u32,
    /// Wall seconds: rendering so far, plus, for a denoised output, the part run after
    /// rendering less the nodes it does not depend on (see the module docs).
    pub seconds: f64,
    /// Against the reference.
    pub rmse: f64,
    /// Against the reference (`metrics::relmse`, as Mitsuba's CSVs).
    pub relmse: f64,
    /// Mean SSIM on clipped luminance.
    pub ssim: f64,
    /// Ms per frame of this output's denoiser passes (none for raw): GPU timestamps, or on
    /// a CPU adapter the wall time of each pass submitted alone.
    pub gpu_ms: Option<f64>,
}

/// An output scored at every checkpoint.
struct Scored {
    /// `node.color`.
    port: String,
    /// The node (a denoiser or an accumulation).
    node: String,
    /// A denoiser's output (else a raw accumulation's).
    denoised: bool,
    /// The nodes the output depends on, itself included: the tail's other nodes are not
    /// charged to it.
    upstream: Vec<String>,
}

impl Scored {
    /// Seconds of the tail charged to this output: the tail's wall time less the time of
    /// the tail's nodes (`pass_ms`) it does not depend on; none for a raw output.
    fn tail_seconds(&self, tail_secs: f64, pass_ms: &[(String, f64)]) -> f64 {
        if !self.denoised {
            return 0.0;
        }
        let others: f64 = pass_ms
            .iter()
            .filter(|(n, _)| !self.upstream.contains(n))
            .map(|(_, ms)| ms / 1000.0)
            .sum();
        (tail_secs - others).max(0.0)
    }
}

/// The ids of the nodes `node` depends on in `graph`, itself included.
fn upstream(graph: &Graph, node: &str) -> Vec<String> {
    let mut found = vec![node.to_owned()];
    let mut i = 0;
    while let Some(id) = found.get(i).cloned() {
        for e in &graph.edges {
            let to = crate::graph::split_port_ref(&e.to).map(|(n, _)| n);
            let from = crate::graph::split_port_ref(&e.from).map(|(n, _)| n);
            if let (Some(to), Some(from)) = (to, from)
                && to == id
                && !found.iter().any(|f| f == from)
            {
                found.push(from.to_owned());
            }
        }
        i += 1;
    }
    found
}

/// The graph without sinks (groups flattened, so theirs too), 1 spp per frame; returns it
/// with the outputs scored.
fn prepare(graph: &mut Graph, library: &NodeLibrary) -> Result<Vec<Scored>> {
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
    Ok(ports
        .into_iter()
        .map(|(port, denoised)| {
            let node = port.split('.').next().unwrap_or(&port).to_owned();
            Scored {
                upstream: upstream(graph, &node),
                port,
                node,
                denoised,
            }
        })
        .collect())
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
) -> Result<(Image, String)> {
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
    let note = format!(
        "reference: {spp} spp with seed {:#x} in {:.1} s",
        other.settings.seed,
        start.elapsed().as_secs_f64()
    );
    Ok((exec.read_port(port)?, note))
}

/// An executor for `graph`, checked against the reference's size and warmed up.
fn start(
    ctx: &GpuContext,
    library: &NodeLibrary,
    graph: &Graph,
    keep: &[String],
    scene: &Arc<GpuScene>,
    reference: &Image,
) -> Result<Executor> {
    let mut exec = executor(ctx, library, graph, keep, scene)?;
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
    // The warm-up ran the first frame, as the first checkpoint will again: a node that
    // keeps its result over unchanged inputs (OIDN) would upload it there instead of
    // filtering, and its time would be that of an upload. Two frames more leave other
    // inputs behind.
    exec.run_frames(2, true)?;
    exec.restart();
    Ok(exec)
}

/// Measures `graph` (its overrides applied; its `Output` nodes are dropped) on `scene`:
/// checkpoints at 1, 2, 4… spp until the time budget, each output scored at each.
///
/// # Errors
/// When the graph has no `Accumulate` node, the reference does not load or is of another
/// size, or a node fails.
pub fn measure(
    ctx: &GpuContext,
    mut graph: Graph,
    scene: &Arc<GpuScene>,
    args: &Options<'_>,
) -> Result<Measured> {
    let ports = prepare(&mut graph, args.library)?;
    let raw_port = ports
        .iter()
        .find(|o| !o.denoised)
        .map(|o| o.port.clone())
        .unwrap_or_default();
    let mut reference_note = None;
    let reference = match &args.reference {
        Reference::File(path) => image_io::load(path)?,
        Reference::Image(image) => image.clone(),
        Reference::Spp(spp) => {
            let (image, note) =
                render_reference(ctx, args.library, &graph, &raw_port, scene, *spp)?;
            reference_note = Some(note);
            image
        }
    };
    let keep: Vec<String> = ports.iter().map(|o| o.port.clone()).collect();
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
        let exec = start(ctx, args.library, &g, &keep, scene, &reference)?;
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
            for o in &ports {
                let image = exec.read_port(&o.port)?;
                let node = &o.node;
                rows.push(Row {
                    output: run
                        .label
                        .as_ref()
                        .map_or_else(|| node.clone(), |l| format!("{l}: {node}")),
                    spp,
                    seconds: run.render_secs + o.tail_seconds(tail_secs, &pass_ms),
                    rmse: metrics::rmse(&image, &reference),
                    relmse: metrics::relmse(&image, &reference),
                    ssim: metrics::ssim(&image, &reference),
                    gpu_ms: o
                        .denoised
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

    Ok(Measured {
        rows,
        reference_note,
        clock,
        tail_ms: last_tail_ms,
    })
}

/// Writes `converge.csv` and `converge.png` (with the `compare` curves) into `out`,
/// created if missing; returns the files written, and why the plot was not where it was
/// not (no font).
///
/// # Errors
/// When the folder or the CSV cannot be written.
pub fn write(
    out: &Path,
    rows: &[Row],
    compare: Option<&Compare>,
) -> Result<(Vec<PathBuf>, Option<String>)> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let csv = out.join("converge.csv");
    crate::graph::write_atomic(&csv, csv_text(rows).as_bytes())
        .with_context(|| format!("cannot write {}", csv.display()))?;
    let png = out.join("converge.png");
    match plot::write(&png, &rows_by_output(rows), compare) {
        Ok(()) => Ok((vec![csv, png], None)),
        Err(e) => Ok((vec![csv], Some(format!("{e:#}")))),
    }
}

/// The rows as `converge.csv` holds them.
pub fn csv_text(rows: &[Row]) -> String {
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

/// The first time the curve `pts` (`(seconds, relmse)`, by time) is at or below `target`:
/// between the two points around the crossing, interpolated linearly in log-log (as the
/// plot draws it); the first point's time if that one already is.
pub fn time_to(pts: &[(f64, f64)], target: f64) -> Option<f64> {
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
pub fn rows_by_output(rows: &[Row]) -> Vec<(String, Vec<(f64, f64)>)> {
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

/// Reads a `--compare` CSV (`seconds` and `relmse` columns, `oidn_seconds` and
/// `oidn_relmse` where it has them).
///
/// # Errors
/// When it cannot be read, or lacks a column, or a value is not a number.
pub fn read_compare(path: &Path) -> Result<Compare> {
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
    use super::{Scored, time_to, upstream};
    use crate::graph::{Edge, Graph, Node};

    /// Two denoisers on one accumulation, an `Exposure` after the first: each denoised
    /// output is charged the tail less the passes it does not depend on.
    #[test]
    fn a_denoised_output_is_charged_its_own_passes_only() {
        let graph = Graph {
            nodes: ["pt", "acc", "gb", "atrous", "oidn", "post"]
                .into_iter()
                .map(|id| Node::new(id, "Any"))
                .collect(),
            edges: [
                ("pt.color", "acc.color"),
                ("acc.color", "atrous.color"),
                ("gb.albedo", "atrous.albedo"),
                ("acc.color", "oidn.color"),
                ("gb.albedo", "oidn.albedo"),
                ("atrous.color", "post.color"),
            ]
            .into_iter()
            .map(|(from, to)| Edge::new(from, to))
            .collect(),
            ..Graph::default()
        };
        let mut up = upstream(&graph, "atrous");
        up.sort();
        assert_eq!(up, ["acc", "atrous", "gb", "pt"]);
        let scored = |node: &str, denoised| Scored {
            port: format!("{node}.color"),
            node: node.to_owned(),
            denoised,
            upstream: upstream(&graph, node),
        };
        let pass_ms = [
            ("gb".to_owned(), 2.0),
            ("atrous".to_owned(), 70.0),
            ("oidn".to_owned(), 200.0),
            ("post".to_owned(), 5.0),
        ];
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        // 0.3 s of tail: the à-trous output is not charged OIDN's 200 ms nor the 5 ms after
        // it; OIDN's output not the à-trous 70 ms nor those 5 ms.
        assert!(close(
            scored("atrous", true).tail_seconds(0.3, &pass_ms),
            0.095
        ));
        assert!(close(
            scored("oidn", true).tail_seconds(0.3, &pass_ms),
            0.225
        ));
        assert!(close(scored("acc", false).tail_seconds(0.3, &pass_ms), 0.0));
        // Without times per pass, the whole tail; never below 0.
        assert!(close(scored("oidn", true).tail_seconds(0.3, &[]), 0.3));
        assert!(close(
            scored("atrous", true).tail_seconds(0.1, &pass_ms),
            0.0
        ));
    }

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
