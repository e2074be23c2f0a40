//! The `lumagraph` command line: render, plan, validate, bench, list nodes, open the
//! editor. [`main_with`] runs it over a [`NodeLibrary`], so a program that adds node kinds
//! of its own is the whole `lumagraph` command with its kinds in it:
//!
//! ```no_run
//! use lumagraph::pathtrace::library;
//!
//! fn main() -> std::process::ExitCode {
//!     // library::with_builtins().with_kind(…) for kinds of its own.
//!     lumagraph::cli::main_with(library::with_builtins())
//! }
//! ```

mod bench;
mod choice;
mod color;
mod converge;
mod frames;
mod gallery;
mod gltf_gallery;
mod info;
mod loading;
mod progressive;
mod rendering;
mod split;
mod tiled;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};

use crate::graph::{Graph, docs};
use crate::render::{GpuContext, NodeLibrary, image_io};
use loading::{LoadedScene, TextureArgs, load_scene, progressive_source, uses_scene};
use rendering::{RenderArgs, render};

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
        /// Samples per pixel for graphs that render the scene (default: the scene's `spp`).
        #[arg(long)]
        spp: Option<u32>,
        /// Override a param: `node.param=value` (RON value, or a bare word for names).
        #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
        overrides: Vec<String>,
        /// Where the checkpoint goes (on Ctrl-C or SIGTERM, and with `--checkpoint-every`);
        /// default `OUT/render.checkpoint`.
        #[arg(long, value_name = "FILE")]
        checkpoint: Option<PathBuf>,
        /// Write the checkpoint every this many seconds of rendering (atomically).
        #[arg(long, value_name = "SECONDS")]
        checkpoint_every: Option<f64>,
        /// Go on from a checkpoint of the same graph, scene and overrides, to `--spp`: the
        /// result is identical to an uninterrupted render.
        #[arg(long, value_name = "CHECKPOINT")]
        resume: Option<PathBuf>,
        /// Render in tiles of this many pixels a side (0: never tile). By default an image
        /// larger than the device holds, or than 4 GiB of images and buffers, is tiled.
        #[arg(long, value_name = "PIXELS")]
        tile: Option<u32>,
        /// Render only tiles FIRST..END (row by row from 0) of the tiled render, and write
        /// them as OUT/tiles-FIRST-END.tiles for `lumagraph merge` (docs/distributed.md).
        #[arg(long, value_name = "FIRST..END", value_parser = split::parse_range,
              conflicts_with_all = ["resume", "checkpoint", "checkpoint_every", "samples"])]
        tiles: Option<split::SampleRange>,
        /// Take only samples START..END of each pixel's sequence, exactly those a whole
        /// render takes there, and write the partial render OUT/samples-START-END.partial
        /// for `lumagraph merge` (docs/distributed.md).
        #[arg(long, value_name = "START..END", value_parser = split::parse_range,
              conflicts_with_all = ["spp", "resume", "checkpoint", "checkpoint_every", "tile"])]
        samples: Option<split::SampleRange>,
        /// Let the graph's Output paths be absolute or climb out of `--out` (by default
        /// they are refused: docs/security.md).
        #[arg(long)]
        allow_outputs_outside: bool,
        #[command(flatten)]
        textures: TextureArgs,
        #[command(flatten)]
        choice: choice::Choice,
        /// Render an image sequence: each param holding a frame pattern (`####`, `%04d`,
        /// `$F4`) takes each frame's number; `7`, `1-100`, `1-100x2` (every second frame),
        /// or a comma-separated list of these (docs/compositing.md).
        #[arg(long, value_name = "RANGE", value_parser = parse_frames,
              conflicts_with_all = ["resume", "checkpoint", "checkpoint_every", "samples", "tiles", "tile"])]
        frames: Option<FrameList>,
        /// With `--frames`: skip frames whose input file is missing instead of stopping
        /// with an error naming it.
        #[arg(long, requires = "frames")]
        skip_missing: bool,
    },
    /// Merge partial renders (`render --samples`) of one graph and scene into what a single
    /// render of all their samples writes: checks that they belong together, sums them
    /// exactly and runs the rest of the graph (docs/distributed.md).
    #[command(
        after_help = "Example:\n  lumagraph render graphs/pathtrace.ron --scene assets/cornell.ron --samples 0..128 --out parts\n  lumagraph render graphs/pathtrace.ron --scene assets/cornell.ron --samples 128..256 --out parts\n  lumagraph merge parts/*.partial --out out"
    )]
    Merge {
        /// The partial renders.
        #[arg(required = true)]
        partials: Vec<PathBuf>,
        /// Folder Output paths are relative to (created if missing).
        #[arg(long, default_value = ".")]
        out: PathBuf,
        /// The graph file, when it is no longer where the partial renders say.
        #[arg(long)]
        graph: Option<PathBuf>,
        /// The scene file, when it is no longer where the partial renders say.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Merge ranges that leave samples out (by default a gap is an error).
        #[arg(long)]
        allow_gaps: bool,
        /// Let the graph's Output paths be absolute or climb out of `--out` (by default
        /// they are refused: docs/security.md).
        #[arg(long)]
        allow_outputs_outside: bool,
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
        #[command(flatten)]
        choice: choice::Choice,
    },
    /// Check a graph file without rendering it; prints every error found.
    #[command(after_help = "Example:\n  lumagraph validate graphs/post_tonemap.ron")]
    Validate {
        /// The graph file (RON).
        graph: PathBuf,
        /// Scene file for nodes that render a scene.
        #[arg(long)]
        scene: Option<PathBuf>,
    },
    /// List every node kind with its ports and params.
    #[command(
        after_help = "Examples:\n  lumagraph nodes --markdown > nodes.md\n  lumagraph nodes --graph graphs/custom_kinds.ron"
    )]
    Nodes {
        /// Print the Markdown reference used in docs/graph-format.md.
        #[arg(long)]
        markdown: bool,
        /// Also list the node kinds this graph file declares.
        #[arg(long)]
        graph: Option<PathBuf>,
    },
    /// List what an OpenColorIO config offers the colour nodes: colour
    /// spaces, displays and views, looks, the working space's name.
    #[command(
        after_help = "Examples:\n  lumagraph color\n  lumagraph color --config ocio://studio-config-latest\n  lumagraph color --config show/config.ocio"
    )]
    Color {
        /// The config, as the nodes' `config` param takes it (empty: $OCIO, else
        /// OpenColorIO's CG config with ACES 2.0).
        #[arg(long, default_value = "")]
        config: String,
    },
    /// Describe an image file: an EXR's parts, views, layers (and the port each is read
    /// onto), channels, windows, colour primaries and attributes.
    #[command(
        after_help = "Example:\n  lumagraph info shot/beauty.0001.exr\n  lumagraph info shot/beauty.0001.exr --json"
    )]
    Info {
        /// The image file.
        file: PathBuf,
        /// Print JSON instead of words.
        #[arg(long)]
        json: bool,
    },
    /// List the GPU adapters wgpu finds (name, kind, backend, driver, ray queries,
    /// timestamps, binding limits) and the one lumagraph would use.
    #[command(after_help = "Example:\n  WGPU_BACKEND=vulkan lumagraph adapters")]
    Adapters,
    /// Measure path tracing speed (paths/s) on the current adapter, specialized and general
    /// shaders side by side.
    #[command(after_help = "Example:\n  lumagraph bench --scene assets/cornell.ron --spp 64")]
    Bench {
        /// Scene to trace.
        #[arg(long, default_value = "assets/cornell.ron")]
        scene: PathBuf,
        /// Samples per pixel per timed run.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Timed runs; the best is reported.
        #[arg(long, default_value_t = 3)]
        runs: u32,
        /// Measure the specialized shader only (not the variants it is compared with), and
        /// where it walks the 8-wide BVH, the binary one beside it.
        #[arg(long)]
        specialized_only: bool,
        /// Time traversal alone instead: a primary ray through each pixel centre and a
        /// diffuse ray from each primary hit, through the binary and the 8-wide BVH (M rays/s
        /// of closest-hit queries, no shading).
        #[arg(long, conflicts_with = "specialized_only")]
        traversal: bool,
        #[command(flatten)]
        choice: choice::Choice,
    },
    /// Render one image per node kind into OUT/gallery/ and the page that shows them,
    /// OUT/gallery.md (the docs' node gallery).
    #[command(
        after_help = "Examples:\n  lumagraph gallery --out docs\n  lumagraph gallery --out /tmp/g --kind Bloom --kind Mix"
    )]
    Gallery {
        /// Folder for gallery.md and the gallery/ images.
        #[arg(long, default_value = "docs")]
        out: PathBuf,
        /// Only these kinds (the page is written only when all are made).
        #[arg(long = "kind")]
        kinds: Vec<String>,
    },
    /// Render every glTF model under some folders (default: assets/gltf-conformance) into
    /// OUT/gltf-gallery/ and a contact sheet, OUT/gltf-gallery.md, with what each model
    /// tests and what loading it said.
    #[command(
        name = "gltf-gallery",
        after_help = "Examples:\n  lumagraph gltf-gallery --out docs\n  lumagraph gltf-gallery ~/glTF-Sample-Assets/Models --out /tmp/g --size 256x256 --spp 16"
    )]
    GltfGallery {
        /// Folders searched for .gltf and .glb files (recursively).
        #[arg(default_value = "assets/gltf-conformance")]
        dirs: Vec<PathBuf>,
        /// Folder for gltf-gallery.md and the gltf-gallery/ images.
        #[arg(long, default_value = "docs")]
        out: PathBuf,
        /// Image size in pixels, width then height, as in 320x240.
        #[arg(long, default_value = "320x240")]
        size: String,
        /// Samples per pixel.
        #[arg(long, default_value_t = 64)]
        spp: u32,
    },
    /// Open the node editor, optionally on a graph file and a scene.
    #[command(
        after_help = "Examples:\n  lumagraph edit graphs/post_tonemap.ron\n  lumagraph edit graphs/pathtrace_denoise.ron --scene assets/cornell.ron"
    )]
    Edit {
        /// The graph file (RON) to open.
        graph: Option<PathBuf>,
        /// Scene file for nodes that render a scene (also: Scene → Open scene… in the
        /// editor).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// The preview renders scenes with their longer side at most this many pixels.
        #[arg(long, default_value_t = crate::editor::DEFAULT_PREVIEW_MAX)]
        preview_size: u32,
    },
    /// Error against run time: render progressively at 1, 2, 4… spp and score the raw
    /// accumulation and every Denoise output against a reference (RMSE, relMSE, SSIM);
    /// writes a CSV and a log-log plot.
    #[command(
        after_help = "Example:\n  lumagraph converge graphs/pathtrace_denoise.ron --scene assets/cornell.ron \\\n    --reference tests/reference/cornell_ref.exr --seconds 10 \\\n    --compare tests/reference/cornell_converge.csv --out converge\n  lumagraph converge graphs/pathtrace.ron --scene assets/cornell.ron \\\n    --reference tests/reference/cornell_ref.exr --seconds 30 \\\n    --variant \"adaptive 0.03:pathtrace.adaptive_error=0.03\" --out converge"
    )]
    Converge {
        /// The graph file (RON); its Output nodes are ignored.
        graph: PathBuf,
        /// Scene file.
        #[arg(long)]
        scene: PathBuf,
        /// Reference image (EXR, linear, same size as the render).
        #[arg(long, conflicts_with = "reference_spp")]
        reference: Option<PathBuf>,
        /// Render the reference first with the same graph at this many spp (another seed).
        #[arg(long)]
        reference_spp: Option<u32>,
        /// Time budget in seconds: no checkpoint is started that is predicted to pass it
        /// (twice the render time so far plus the last denoise time).
        #[arg(long, default_value_t = 10.0)]
        seconds: f64,
        /// CSV with Mitsuba (and OIDN) figures per spp to plot beside ours.
        #[arg(long)]
        compare: Option<PathBuf>,
        /// The relMSE to print each curve's time to (default with `--compare`: the
        /// comparison's raw relMSE at its largest spp).
        #[arg(long)]
        target_relmse: Option<f64>,
        /// Folder for converge.csv and converge.png (created if missing).
        #[arg(long, default_value = "converge")]
        out: PathBuf,
        /// Override a param: `node.param=value`.
        #[arg(long = "set", value_name = "NODE.PARAM=VALUE")]
        overrides: Vec<String>,
        /// Also measure the graph with these overrides (`;` between them), as a curve named
        /// LABEL; the runs take turns at each checkpoint, so a busy machine slows them alike.
        #[arg(long = "variant", value_name = "LABEL:NODE.PARAM=VALUE[;...]")]
        variants: Vec<String>,
    },
    /// Write the resolved scene for other renderers: scene.json (camera, materials, analytic shapes,
    /// lights, environment, settings) and OBJ files of its triangles; scripts/references/
    /// builds Mitsuba 3 scenes from it.
    #[command(after_help = "Example:\n  lumagraph export assets/cornell.ron --out cornell_export")]
    Export {
        /// Scene file.
        scene: PathBuf,
        /// Folder to write into (created if missing).
        #[arg(long)]
        out: PathBuf,
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

/// `--frames`: the frames, in order (a newtype, so that clap takes one value).
#[derive(Clone, Debug)]
struct FrameList(Vec<i64>);

fn parse_frames(spec: &str) -> std::result::Result<FrameList, String> {
    lumagraph_footage::sequence::parse_frames(spec).map(FrameList)
}

/// `lumagraph plan`: the plan, node-owned memory, and the shader features per pass.
fn plan(
    library: &NodeLibrary,
    graph: &Path,
    scene: Option<&Path>,
    overrides: &[String],
    choice: choice::Choice,
) -> Result<()> {
    let g = load(graph, overrides)?;
    let scene = load_scene(scene)?;
    let plan = library.compile(&g, &[], scene.as_ref().map(|s| &*s.gpu))?;
    print!("{plan}");
    let owned: Vec<_> = plan
        .passes
        .iter()
        .filter_map(|p| library.owned_memory(p).map(|m| (p, m)))
        .collect();
    if !owned.is_empty() {
        println!("node-owned memory (outside the textures above):");
        for (p, (bytes, what)) in owned {
            #[expect(clippy::cast_precision_loss, reason = "report figures")]
            let mib = bytes as f64 / (1024.0 * 1024.0);
            println!("  {:<16} {bytes:>10} bytes ({mib:.2} MiB): {what}", p.node);
        }
    }
    match &scene {
        Some(scene) => choice::print_features(&plan, &scene.gpu, library, choice),
        None => Ok(()),
    }
}

/// `lumagraph validate`: compiles the graph and says how many passes it has.
fn validate(library: &NodeLibrary, graph: &Path, scene: Option<&Path>) -> Result<()> {
    let g = load(graph, &[])?;
    let registry = library.registry_for(&g)?;
    let has_sink = g
        .nodes
        .iter()
        .any(|n| registry.get(&n.kind).is_some_and(|k| k.sink));
    if !g.interface.is_empty() && !has_sink {
        // A group file: checked on its own, it compiles inside a graph that uses it.
        let kind = crate::render::custom::check_group(&g, registry)?;
        let count = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
        println!(
            "{}: ok, a node group ({}, {}, {}, {}); it compiles inside a graph that uses it",
            graph.display(),
            count(kind.inputs.len(), "input"),
            count(kind.outputs.len(), "output"),
            count(kind.params.len(), "param"),
            count(g.nodes.len(), "node")
        );
        return Ok(());
    }
    let scene = load_scene(scene)?;
    let plan = library.compile(&g, &[], scene.as_ref().map(|s| &*s.gpu))?;
    println!(
        "{}: ok ({} passes, {} left out)",
        graph.display(),
        plan.passes.len(),
        plan.left_out.len()
    );
    Ok(())
}

/// `lumagraph nodes`: the library's kinds, and those `graph` declares when given.
fn nodes(library: &NodeLibrary, markdown: bool, graph: Option<&Path>) -> Result<()> {
    let r = match graph {
        Some(g) => library.registry_for(&load(g, &[])?)?,
        None => library.registry().clone(),
    };
    print!(
        "{}",
        if markdown {
            docs::markdown(&r)
        } else {
            docs::text(&r)
        }
    );
    Ok(())
}

/// `lumagraph export`: the resolved scene as JSON + OBJ.
fn export(scene: &Path, out: &Path) -> Result<()> {
    let loaded = load_scene(Some(scene))?.context("no scene")?;
    for path in crate::scene::export::export(&loaded.scene, &loaded.gpu, out)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

#[expect(clippy::too_many_lines, reason = "one arm per subcommand, each a call")]
fn run(cli: Cli, library: &Arc<NodeLibrary>) -> Result<()> {
    match cli.command {
        Command::Render {
            graph,
            scene,
            out,
            spp,
            overrides,
            checkpoint,
            checkpoint_every,
            resume,
            tile,
            tiles,
            samples,
            allow_outputs_outside,
            textures,
            choice,
            frames,
            skip_missing,
        } => render(&RenderArgs {
            library,
            graph: &graph,
            scene: scene.as_deref(),
            spp,
            overrides: &overrides,
            checkpoints: progressive::Checkpoints::new(&out, checkpoint, checkpoint_every, resume),
            out: &out,
            tile,
            tiles,
            samples,
            outputs_anywhere: allow_outputs_outside,
            textures,
            frames: frames.map(|f| (f.0, skip_missing)),
            choice,
        }),
        Command::Merge {
            partials,
            out,
            graph,
            scene,
            allow_gaps,
            allow_outputs_outside,
        } => split::merge(&split::MergeArgs {
            library,
            partials: &partials,
            out: &out,
            graph: graph.as_deref(),
            scene: scene.as_deref(),
            allow_gaps,
            outputs_anywhere: allow_outputs_outside,
        }),
        Command::Plan {
            graph,
            scene,
            overrides,
            choice,
        } => plan(library, &graph, scene.as_deref(), &overrides, choice),
        Command::Validate { graph, scene } => validate(library, &graph, scene.as_deref()),
        Command::Nodes { markdown, graph } => nodes(library, markdown, graph.as_deref()),
        Command::Gallery { out, kinds } => {
            let ctx = GpuContext::headless()?;
            gallery::run(&ctx, library, &out, &kinds)
        }
        Command::GltfGallery {
            dirs,
            out,
            size,
            spp,
        } => gltf_gallery::run(library, &dirs, &out, &size, spp.max(1)),
        Command::Adapters => {
            print!("{}", GpuContext::describe_adapters()?);
            Ok(())
        }
        Command::Bench {
            scene,
            spp,
            runs,
            specialized_only,
            traversal,
            choice,
        } => {
            let loaded = load_scene(Some(&scene))?.context("no scene")?;
            bench::run(&loaded.gpu, spp, runs, specialized_only, traversal, choice)
        }
        Command::Edit {
            graph,
            scene,
            preview_size,
        } => Ok(crate::editor::run(
            graph,
            crate::editor::EditorConfig {
                scene,
                preview_max: preview_size,
                library: Arc::clone(library),
                ..Default::default()
            },
        )?),
        Command::Converge {
            graph,
            scene,
            reference,
            reference_spp,
            seconds,
            compare,
            target_relmse,
            out,
            overrides,
            variants,
        } => converge::run(&converge::Args {
            graph: &graph,
            scene: &scene,
            reference: reference.as_deref(),
            reference_spp,
            seconds,
            compare: compare.as_deref(),
            target_relmse,
            out: &out,
            overrides: &overrides,
            variants: &variants,
            library,
        }),
        Command::Export { scene, out } => export(&scene, &out),
        Command::Info { file, json } => info::info(&file, json),
        Command::Color { config } => color::color(&config),
        Command::TestChart { out } => test_chart(&out),
    }
}

/// `lumagraph test-chart`: the generated HDR test chart written to `out`.
fn test_chart(out: &Path) -> Result<()> {
    let chart = image_io::test_chart();
    let bytes = image_io::encode_exr(&chart, true)?;
    crate::graph::write_atomic(out, &bytes)
        .with_context(|| format!("cannot write {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(())
}

/// Runs the `lumagraph` command line (arguments from the process) with the node kinds of
/// `library`: they can be rendered, planned, validated, listed by `nodes`, shown by
/// `gallery` and used in the editor (`edit`). Errors are printed with their causes.
///
/// Returns the process's exit code: success, or failure after an error.
///
/// Call it at the start of `main`, before the program starts threads: it may set one
/// environment variable for the Vulkan loader (see [`GpuContext::quiet_device_select`]).
pub fn main_with(library: NodeLibrary) -> ExitCode {
    progressive::started();
    #[cfg(unix)]
    end_quietly_on_a_closed_pipe();
    GpuContext::quiet_device_select();
    crate::overrides::apply();
    let cli = Cli::parse();
    match run(cli, &Arc::new(library)) {
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

/// Output piped into a program that stops reading (`lumagraph nodes | head`) ends the
/// process quietly at that write, as other command-line tools do. Rust starts programs with
/// SIGPIPE ignored, so the write fails instead and `println!` panics.
#[cfg(unix)]
#[allow(unsafe_code)]
fn end_quietly_on_a_closed_pipe() {
    // SAFETY: restores SIGPIPE's default action at start-up; no handler of ours is
    // installed and no memory is shared with one.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
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
