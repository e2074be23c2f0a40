//! `lumagraph converge`: the measurement of [`crate::converge`], printed as a table, with
//! the time each curve takes to reach a relMSE (`--target-relmse`, or the comparison's raw
//! relMSE at its largest spp), and `converge.csv` and `converge.png` written into `--out`.

use std::path::Path;

use anyhow::{Context as _, Result, bail};

use crate::converge::{Compare, Options, Reference, Row, time_to};
use crate::graph::Graph;
use crate::render::{GpuContext, NodeLibrary};

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

/// Runs the measurement; prints the table and writes the CSV and the plot.
pub fn run(args: &Args<'_>) -> Result<()> {
    let mut graph = Graph::load(args.graph)?;
    for o in args.overrides {
        graph.apply_override(o)?;
    }
    let reference = match (args.reference, args.reference_spp) {
        (Some(path), _) => Reference::File(path.to_owned()),
        (None, Some(spp)) => Reference::Spp(spp),
        (None, None) => bail!("give --reference FILE.exr or --reference-spp N"),
    };
    let scene = super::load_scene(Some(args.scene))?.context("no scene")?;
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    let measured = crate::converge::measure(
        &ctx,
        graph,
        &scene.gpu,
        &Options {
            reference,
            seconds: args.seconds,
            variants: args.variants,
            library: args.library,
        },
    )?;
    if let Some(note) = &measured.reference_note {
        println!("{note}");
    }
    print_table(&measured.rows);
    println!(
        "time per pass of the part run after rendering (last checkpoint; {}):",
        measured
            .clock
            .map_or("", crate::render::PassClock::describe)
    );
    if measured.tail_ms.is_empty() {
        println!("  not available (adapter has no timestamp queries)");
    }
    for (name, ms) in &measured.tail_ms {
        println!("  {name:<16} {ms:>9.3} ms per frame");
    }
    let compare = args
        .compare
        .map(crate::converge::read_compare)
        .transpose()?;
    let (written, no_plot) = crate::converge::write(args.out, &measured.rows, compare.as_ref())?;
    for path in &written {
        println!("wrote {}", path.display());
    }
    print_times_to(
        &crate::converge::rows_by_output(&measured.rows),
        compare.as_ref(),
        args.target_relmse,
    );
    if let Some(why) = no_plot {
        println!("plot not written: {why}");
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
