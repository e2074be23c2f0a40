//! `lumagraph gallery`: one image per node kind, each made by running the kind in a small
//! graph, and `gallery.md`, the page that shows them. Post nodes run on the Venice map
//! (resized to 384×192, the test chart as a second input) with their registry `example`
//! params and are tone-mapped (`agx`) for display; the nodes of a path-tracing graph show
//! their first output on the Cornell box after 64 frames of `graphs/pathtrace_denoise.ron`
//! (or of `graphs/pathtrace_regression.ron` or `graphs/pathtrace_temporal.ron`, for the
//! kinds only they have);
//! a source that reads no file shows its first output with its `example` params.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

use crate::graph::{Edge, Graph, Node, NodeKind, ParamType, ParamValue, PortType, Registry};
use crate::render::cpu::Image;
use crate::render::{Executor, GpuContext, NodeLibrary, Resources, image_io};
use crate::scene::{GpuScene, Scene};
use anyhow::{Context, Result, bail};

const SOURCE: &str = "assets/hdri/venice_sunset_1k.hdr";
const SECOND: &str = "assets/test_chart.exr";
const SCENE: &str = "assets/cornell.ron";
/// The path-tracing graphs, searched in order for a node of the kind shown.
const RENDER_GRAPHS: [&str; 4] = [
    "graphs/pathtrace_denoise.ron",
    "graphs/pathtrace_regression.ron",
    "graphs/pathtrace_temporal.ron",
    "graphs/pathtrace_oidn.ron",
];
const RENDER_FRAMES: u32 = 64;

/// A node with `params`.
fn node(id: &str, kind: &str, params: &[(&str, ParamValue)]) -> Node {
    params
        .iter()
        .fold(Node::new(id, kind), |n, (k, v)| n.with(k, v.clone()))
}

/// The two source images, resized to 384×192: `src.color` and `src2.color`.
fn sources() -> Graph {
    let size = [
        ("width", ParamValue::Int(384)),
        ("height", ParamValue::Int(192)),
    ];
    let mut g = Graph::new();
    for (id, path) in [("src", SOURCE), ("src2", SECOND)] {
        let input = format!("{id}_file");
        g.nodes.push(node(
            &input,
            "ImageInput",
            &[("path", ParamValue::Str(path.into()))],
        ));
        g.nodes.push(node(id, "Resize", &size));
        g.edges
            .push(Edge::new(format!("{input}.color"), format!("{id}.color")));
    }
    g
}

/// How the gallery shows `kind`: the graph, the port shown, what it holds, and how many
/// frames to run.
fn recipe(
    kind: &NodeKind,
    registry: &Registry,
    root: &Path,
) -> Result<(Graph, String, PortType, u32)> {
    let hdr_in = kind
        .inputs
        .iter()
        .all(|i| i.accepts.contains(&PortType::HdrColor));
    if kind.renders_scene || kind.history || !hdr_in {
        // A node of a path-tracing graph: its first output there.
        for path in RENDER_GRAPHS {
            let mut g = Graph::load(&root.join(path))?;
            g.remove_sinks(registry);
            if let Some(n) = g.nodes.iter().find(|n| n.kind == kind.name) {
                let out = kind.outputs.first().context("no output")?;
                let port = format!("{}.{}", n.id, out.name);
                return Ok((g, port, out.ty, RENDER_FRAMES));
            }
        }
        bail!(
            "no graph of {RENDER_GRAPHS:?} has a {} node to show",
            kind.name
        );
    }
    let mut g = sources();
    let reads_file = kind
        .params
        .iter()
        .any(|p| matches!(p.ty, ParamType::Path { .. }));
    if kind.inputs.is_empty() && reads_file {
        // A source that reads a file: the image it reads, resized.
        return Ok((g, "src.color".into(), PortType::HdrColor, 1));
    }
    let example: Vec<(&str, ParamValue)> =
        kind.example.iter().map(|(k, v)| (*k, v.clone())).collect();
    g.nodes.push(node("n", kind.name, &example));
    for (i, input) in kind.inputs.iter().enumerate() {
        let from = if i == 0 { "src.color" } else { "src2.color" };
        g.edges.push(Edge::new(from, format!("n.{}", input.name)));
    }
    let Some(out) = kind.outputs.first() else {
        // A sink: the file it writes, `<kind>.png`, is the image.
        let path = kind
            .params
            .iter()
            .find(|p| matches!(p.ty, ParamType::Path { .. }))
            .with_context(|| format!("{} writes no file to show", kind.name))?;
        // A sink that writes no PNG (an EXR of layers) writes `<kind>.exr`, shown as PNG.
        let ext = match &path.ty {
            ParamType::Path { extensions, .. } if !extensions.contains(&"png") => "exr",
            _ => "png",
        };
        let n = g.nodes.len() - 1;
        g.nodes[n] = g.nodes[n]
            .clone()
            .with(path.name, ParamValue::Str(format!("{}.{ext}", kind.name)));
        return Ok((g, String::new(), PortType::LdrColor, 1));
    };
    if out.ty == PortType::HdrColor {
        g.nodes.push(node(
            "show",
            "Tonemap",
            &[("operator", ParamValue::Str("agx".into()))],
        ));
        g.edges
            .push(Edge::new(format!("n.{}", out.name), "show.color"));
        return Ok((g, "show.color".into(), PortType::LdrColor, 1));
    }
    Ok((g, format!("n.{}", out.name), out.ty, 1))
}

/// Renders the gallery image of every kind of `library` (or of those named in `only`) into
/// `out/gallery/`, and writes `out/gallery.md` when all were made.
///
/// # Errors
/// When a kind has no way to be shown, or a render or a write fails.
pub fn run(ctx: &GpuContext, library: &NodeLibrary, out: &Path, only: &[String]) -> Result<()> {
    let root = std::env::current_dir()?;
    let registry = library.registry();
    let images = out.join("gallery");
    std::fs::create_dir_all(&images)
        .with_context(|| format!("cannot create {}", images.display()))?;
    let scene = Arc::new(GpuScene::build(&Scene::load(&root.join(SCENE))?)?);
    for name in only {
        if registry.get(name).is_none() {
            bail!("no node kind called \"{name}\"");
        }
    }
    for kind in registry.kinds() {
        if !only.is_empty() && !only.iter().any(|o| o == kind.name) {
            continue;
        }
        let (graph, port, ty, frames) = recipe(kind, registry, &root)?;
        let keep: Vec<String> = [port.clone()]
            .into_iter()
            .filter(|p| !p.is_empty())
            .collect();
        let plan = library
            .compile_with(&graph, registry, &root, &keep, Some(&scene))
            .map_err(|e| anyhow::anyhow!("{}: {e}", kind.name))?;
        let resources = Resources {
            base_dir: root.clone(),
            out_dir: images.clone(),
            scene: Some(Arc::clone(&scene)),
            ..Resources::default()
        };
        let mut exec = Executor::with_library(ctx, plan, &resources, library)?;
        let report = exec.run_frames(frames, true)?;
        if port.is_empty() {
            for path in report.written {
                if path.extension().is_some_and(|e| e == "exr") {
                    let png = path.with_extension("png");
                    image_io::save(&png, &image_io::load(&path)?, true)?;
                    std::fs::remove_file(&path)?;
                    println!("wrote {} (its EXR's colour layer)", png.display());
                } else {
                    println!("wrote {}", path.display());
                }
            }
            continue;
        }
        let mut image: Image = exec.read_port(&port)?;
        if ty == PortType::Normal {
            // Normals in [-1, 1]: shown as 0.5 + n / 2.
            for p in &mut image.pixels {
                for c in &mut p[..3] {
                    *c = 0.5 + 0.5 * *c;
                }
            }
        }
        let path = images.join(format!("{}.png", kind.name));
        image_io::save(&path, &image, ty != PortType::LdrColor)?;
        println!("wrote {} ({port})", path.display());
    }
    if only.is_empty() {
        let page = markdown(registry);
        crate::graph::write_atomic(&out.join("gallery.md"), page.as_bytes())?;
        println!("wrote {}", out.join("gallery.md").display());
    }
    Ok(())
}

/// The gallery page: every kind by category, its image and the params it was made with.
pub fn markdown(registry: &Registry) -> String {
    let mut s = String::from(
        "# Node gallery\n\nOne image per node kind, made by `lumagraph gallery --out docs` \
         (do not edit: run it again). Post nodes run on the Venice map at 384×192 (the test \
         chart is a second input) with the params listed, tone-mapped with AgX for display; \
         the nodes of the path-tracing graph show their first output on the Cornell box \
         after 64 frames of `graphs/pathtrace_denoise.ron` (`RegressionDenoise`: of \
         `graphs/pathtrace_regression.ron`; `OIDN`: of `graphs/pathtrace_oidn.ron`; \
         `TemporalReuse`, which has no camera move to \
         reuse history across there: of `graphs/pathtrace_temporal.ron`).\n",
    );
    let mut categories: Vec<_> = registry.kinds().iter().map(|k| k.category).collect();
    categories.sort();
    categories.dedup();
    for c in categories {
        let _ = writeln!(s, "\n## {}\n", c.name());
        for k in registry.kinds().iter().filter(|k| k.category == c) {
            let params: Vec<String> = k
                .example
                .iter()
                .map(|(n, v)| format!("`{n}: {v}`"))
                .collect();
            let with = if params.is_empty() {
                "defaults".to_owned()
            } else {
                params.join(", ")
            };
            let _ = writeln!(
                s,
                "### {}\n\n![{}](gallery/{}.png)\n\nParams: {with}.\n",
                k.name, k.name, k.name
            );
        }
    }
    s
}
