//! The tuning grid the Denoise defaults were chosen from: Cornell at 16 spp, two seeds,
//! relMSE of the raw accumulation and of the à-trous output against the Mitsuba reference
//! for each combination of sigmas. Run with `cargo run --release --example denoise_sweep`.

use std::path::Path;
use std::sync::Arc;

use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::cpu::Image;
use lumagraph::render::{GpuContext, Resources, image_io, metrics};
use lumagraph::scene::{GpuScene, Scene};

fn cornell(seed: Option<u32>) -> anyhow::Result<Arc<GpuScene>> {
    let scene = Scene::load(Path::new("assets/cornell.ron"))?;
    let mut gpu = GpuScene::build(&scene)?;
    if let Some(seed) = seed {
        gpu.settings.seed = seed;
    }
    Ok(Arc::new(gpu))
}

fn graph(params: &[(&str, ParamValue)]) -> Graph {
    let mut dn = Node::new("dn", "Denoise");
    for (k, v) in params {
        dn = dn.with(k, v.clone());
    }
    Graph {
        nodes: vec![
            Node::new("pt", "PathTrace").with("samples_per_frame", ParamValue::Int(1)),
            Node::new("acc", "Accumulate"),
            Node::new("gb", "GBuffer"),
            dn,
        ],
        edges: vec![
            Edge::new("pt.color", "acc.color"),
            Edge::new("acc.color", "dn.color"),
            Edge::new("acc.variance", "dn.variance"),
            Edge::new("gb.albedo", "dn.albedo"),
            Edge::new("gb.normal", "dn.normal"),
            Edge::new("gb.depth", "dn.depth"),
        ],
        ..Graph::default()
    }
}

fn render(
    ctx: &GpuContext,
    scene: &Arc<GpuScene>,
    spp: u32,
    params: &[(&str, ParamValue)],
) -> anyhow::Result<(Image, Image)> {
    let plan = compile(
        &graph(params),
        &["acc.color".into(), "dn.color".into()],
        Some(scene),
    )?;
    let resources = Resources {
        scene: Some(Arc::clone(scene)),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources)?;
    exec.run_frames(spp, true)?;
    Ok((exec.read_port("acc.color")?, exec.read_port("dn.color")?))
}

fn main() -> anyhow::Result<()> {
    let ctx = GpuContext::headless()?;
    let reference = image_io::load(Path::new("tests/reference/cornell_ref.exr"))?;
    let mut grid: Vec<Vec<(&str, ParamValue)>> = Vec::new();
    for sc in [1.0, 2.0, 4.0, 8.0] {
        for sn in [0.01, 0.05] {
            for sd in [0.5, 2.0] {
                grid.push(vec![
                    ("sigma_color", ParamValue::Float(sc)),
                    ("sigma_normal", ParamValue::Float(sn)),
                    ("sigma_depth", ParamValue::Float(sd)),
                ]);
            }
        }
    }
    grid.push(vec![("variance_guided", ParamValue::Bool(false))]);
    for params in &grid {
        let mut line = format!("{params:?}:");
        for seed in [None, Some(0x5eed_1234)] {
            let (raw, filtered) = render(&ctx, &cornell(seed)?, 16, params)?;
            let (r, f) = (
                metrics::relmse(&raw, &reference),
                metrics::relmse(&filtered, &reference),
            );
            line += &format!("  raw {r:.3e} filtered {f:.3e} ({:.2}x)", r / f);
        }
        println!("{line}");
    }
    Ok(())
}
