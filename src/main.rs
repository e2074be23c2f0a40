//! The `lumagraph` command line: render, plan, validate and list nodes.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};
use lumagraph::graph::{Graph, Registry, docs};
use lumagraph::render::{Executor, GpuContext, Paths, compile, image_io};

const EXAMPLES: &str = "\
Examples:
  lumagraph render graphs/post_tonemap.ron --out out
  lumagraph render graphs/post_tonemap.ron --set exposure.ev=1.5 --set tonemap.operator=agx
  lumagraph plan graphs/post_tonemap.ron
  lumagraph validate my_graph.ron
  lumagraph nodes";

/// A modular node-graph renderer: load a graph file and render it headless.
#[derive(Parser, Debug)]
#[command(name = "lumagraph", version, about, after_help = EXAMPLES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a graph: run it once on the GPU and write every Output node's file.
    #[command(
        after_help = "Example:\n  lumagraph render graphs/post_tonemap.ron --out out --set exposure.ev=-1"
    )]
    Render {
        /// The graph file (RON).
        graph: PathBuf,
        /// Scene file for nodes that render a scene.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Folder Output paths are relative to (created if missing).
        #[arg(long, default_value = ".")]
        out: PathBuf,
        /// Override a param: `node.param=value` (RON value, or a bare word for names).
        #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
        overrides: Vec<String>,
    },
    /// Print the compiled plan: passes in order, textures and shared memory, what is left out.
    #[command(after_help = "Example:\n  lumagraph plan graphs/post_tonemap.ron")]
    Plan {
        /// The graph file (RON).
        graph: PathBuf,
        /// Scene file for nodes that render a scene.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Override a param: `node.param=value`.
        #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
        overrides: Vec<String>,
    },
    /// Check a graph file without rendering it; prints every error found.
    #[command(after_help = "Example:\n  lumagraph validate graphs/post_tonemap.ron")]
    Validate {
        /// The graph file (RON).
        graph: PathBuf,
    },
    /// List every node kind with its ports and params.
    #[command(after_help = "Example:\n  lumagraph nodes --markdown > nodes.md")]
    Nodes {
        /// Print the Markdown reference used in docs/graph-format.md.
        #[arg(long)]
        markdown: bool,
    },
    /// Open the node editor, optionally on a graph file.
    #[command(after_help = "Example:\n  lumagraph edit graphs/post_tonemap.ron")]
    Edit {
        /// The graph file (RON) to open.
        graph: Option<PathBuf>,
    },
    /// Write the generated HDR test chart (the source of `assets/test_chart.exr`).
    #[command(hide = true)]
    TestChart {
        /// EXR file to write.
        out: PathBuf,
    },
}

fn load(path: &Path, overrides: &[String]) -> Result<Graph> {
    let mut graph = Graph::load(path)?;
    for o in overrides {
        graph.apply_override(o)?;
    }
    Ok(graph)
}

fn note_scene(scene: Option<&Path>) -> Result<()> {
    if let Some(scene) = scene {
        std::fs::metadata(scene)
            .with_context(|| format!("cannot open scene {}", scene.display()))?;
        println!(
            "scene {}: not used (no node of this graph renders a scene)",
            scene.display()
        );
    }
    Ok(())
}

fn render(graph_path: &Path, scene: Option<&Path>, out: &Path, overrides: &[String]) -> Result<()> {
    let graph = load(graph_path, overrides)?;
    let plan = compile(&graph, &[])?;
    note_scene(scene)?;
    let ctx = GpuContext::headless()?;
    println!("adapter: {}", ctx.describe());
    let paths = Paths {
        base_dir: graph.base_dir(),
        out_dir: out.to_owned(),
    };
    let left_out = plan.left_out.clone();
    let mut exec = Executor::new(&ctx, plan, &paths)?;
    // The first frame includes pipeline compilation inside the driver; time a second one.
    let first = exec.run_frame()?;
    let report = exec.run_frame()?;
    match &report.pass_ms {
        Some(times) => {
            println!("GPU time per pass:");
            for (name, ms) in times {
                println!("  {name:<16} {ms:>9.3} ms");
            }
        }
        None => println!("GPU time per pass: not available (adapter has no timestamp queries)"),
    }
    println!(
        "frame: {:.1} ms wall (first frame, with shader compilation: {:.1} ms)",
        report.wall.as_secs_f64() * 1e3,
        first.wall.as_secs_f64() * 1e3
    );
    for path in &report.written {
        println!("wrote {}", path.display());
    }
    for l in &left_out {
        println!("left out {}: {}", l.what, l.reason);
    }
    Ok(())
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render {
            graph,
            scene,
            out,
            overrides,
        } => render(&graph, scene.as_deref(), &out, &overrides),
        Command::Plan {
            graph,
            scene,
            overrides,
        } => {
            let g = load(&graph, &overrides)?;
            let plan = compile(&g, &[])?;
            note_scene(scene.as_deref())?;
            print!("{plan}");
            Ok(())
        }
        Command::Validate { graph } => {
            let g = load(&graph, &[])?;
            let plan = compile(&g, &[])?;
            println!(
                "{}: ok ({} passes, {} left out)",
                graph.display(),
                plan.passes.len(),
                plan.left_out.len()
            );
            Ok(())
        }
        Command::Nodes { markdown } => {
            let r = Registry::builtin();
            print!(
                "{}",
                if markdown {
                    docs::markdown(r)
                } else {
                    docs::text(r)
                }
            );
            Ok(())
        }
        Command::Edit { graph } => Ok(lumagraph_editor::run(graph)?),
        Command::TestChart { out } => {
            let chart = image_io::test_chart();
            let bytes = image_io::encode_exr(&chart, true)?;
            lumagraph::graph::write_atomic(&out, &bytes)
                .with_context(|| format!("cannot write {}", out.display()))?;
            println!("wrote {}", out.display());
            Ok(())
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Library errors already spell out their causes; print a cause only when it
            // adds something.
            let mut shown = e.to_string();
            eprintln!("error: {shown}");
            let mut source = e.source();
            while let Some(s) = source {
                let text = s.to_string();
                if !shown.contains(&text) {
                    eprintln!("  caused by: {text}");
                    shown = text;
                }
                source = s.source();
            }
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn cli_is_well_formed() {
        use clap::CommandFactory as _;
        super::Cli::command().debug_assert();
    }
}
