//! Shared helpers for the integration tests: one GPU context per test binary.
//!
//! GPU tests fail when no adapter is found, unless `LUMAGRAPH_ALLOW_NO_GPU=1` is set, in
//! which case they return early and say so. With `CI` set, the adapter must be a CPU one
//! (lavapipe), so a test never silently runs on a different device than its references.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use lumagraph::pathtrace::specialize::Tracing;
use std::path::{Path, PathBuf};

#[path = "bench_mesh.rs"]
mod bench_mesh;
use std::sync::LazyLock;

use lumagraph::render::GpuContext;

/// The shared GPU context, or `None` when there is no GPU and that is allowed.
pub fn gpu() -> Option<&'static GpuContext> {
    static CTX: LazyLock<Option<GpuContext>> =
        LazyLock::new(|| lumagraph::render::for_tests(GpuContext::headless_prefer_cpu(), |c| c));
    CTX.as_ref()
}

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A path under the repository root.
pub fn repo(rel: &str) -> PathBuf {
    root().join(rel)
}

/// Whether `dir` holds no files at all (no half-written outputs, no temporaries).
pub fn is_empty_dir(dir: &Path) -> bool {
    std::fs::read_dir(dir).map_or(true, |mut d| d.next().is_none())
}

/// `source` → `Accumulate` (`acc`) → `Denoise` (`dn`, with `params`), guided by `GBuffer`
/// (`gb`) and by `acc`'s variance.
pub fn denoise_graph(
    source: lumagraph::graph::Node,
    params: &[(&str, lumagraph::graph::ParamValue)],
) -> lumagraph::graph::Graph {
    use lumagraph::graph::{Edge, Graph, Node};
    let mut dn = Node::new("dn", "Denoise");
    for (k, v) in params {
        dn = dn.with(k, v.clone());
    }
    let color = format!("{}.color", source.id);
    Graph {
        nodes: vec![
            source,
            Node::new("acc", "Accumulate"),
            Node::new("gb", "GBuffer"),
            dn,
        ],
        edges: vec![
            Edge::new(color, "acc.color"),
            Edge::new("acc.color", "dn.color"),
            Edge::new("acc.variance", "dn.variance"),
            Edge::new("gb.albedo", "dn.albedo"),
            Edge::new("gb.normal", "dn.normal"),
            Edge::new("gb.depth", "dn.depth"),
        ],
        ..Graph::default()
    }
}

/// A scene file under the repository root, flattened; `size` overrides its image size
/// (square), for tests that need fewer pixels than the scene's references.
pub fn gpu_scene(rel: &str, size: Option<u32>) -> std::sync::Arc<lumagraph::scene::GpuScene> {
    let mut scene = lumagraph::scene::Scene::load(&repo(rel)).unwrap();
    if let Some(s) = size {
        scene.settings.width = s;
        scene.settings.height = s;
    }
    std::sync::Arc::new(lumagraph::scene::GpuScene::build(&scene).unwrap())
}

/// `PathTrace` (`pt`, with `params`) feeding `Accumulate` (`acc`): a progressive render.
pub fn progressive_graph(
    params: &[(&str, lumagraph::graph::ParamValue)],
) -> lumagraph::graph::Graph {
    use lumagraph::graph::{Edge, Graph, Node};
    let mut pt = Node::new("pt", "PathTrace");
    for (k, v) in params {
        pt = pt.with(k, v.clone());
    }
    Graph {
        nodes: vec![pt, Node::new("acc", "Accumulate")],
        edges: vec![Edge::new("pt.color", "acc.color")],
        ..Graph::default()
    }
}

/// An executor of `graph` over `scene` keeping the ports `keep`, or `None` when there is no
/// GPU and that is allowed.
pub fn executor(
    graph: &lumagraph::graph::Graph,
    keep: &[&str],
    scene: &std::sync::Arc<lumagraph::scene::GpuScene>,
) -> Option<lumagraph::render::Executor> {
    use lumagraph::pathtrace::library::compile;
    use lumagraph::render::Resources;
    let ctx = gpu()?;
    let keep: Vec<String> = keep.iter().map(|&k| k.to_owned()).collect();
    let plan = compile(graph, &keep, Some(scene)).unwrap();
    // `LUMAGRAPH_RAY_QUERY=on` runs these renders through ray queries, as
    // `lumagraph render --intersector rays` does (docs/pathtracer.md: the reference suite).
    let intersector = if std::env::var("LUMAGRAPH_RAY_QUERY").is_ok_and(|v| v == "on") {
        lumagraph::pathtrace::specialize::Intersector::RAY_QUERIES
    } else {
        lumagraph::pathtrace::specialize::Intersector::AUTO
    };
    let resources = Resources {
        scene: Some(std::sync::Arc::clone(scene)),
        ..Resources::default()
    }
    .with(Tracing {
        intersector,
        ..Tracing::default()
    });
    Some(lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap())
}

/// A progressive render of `scene` ([`progressive_graph`]) keeping `acc.color`.
pub fn progressive(
    scene: &std::sync::Arc<lumagraph::scene::GpuScene>,
    params: &[(&str, lumagraph::graph::ParamValue)],
) -> Option<lumagraph::render::Executor> {
    executor(&progressive_graph(params), &["acc.color"], scene)
}

/// The value of the counter called `name` (`samples_per_pixel`, `dropped_samples`, `rays`).
pub fn counter(exec: &mut lumagraph::render::Executor, name: &str) -> u64 {
    exec.counters()
        .unwrap()
        .iter()
        .find(|(_, c)| c.name == name)
        .map(|(_, c)| c.value)
        .unwrap_or_else(|| panic!("no counter {name}"))
}

/// `frames` independent estimates of `scene`'s image with random seed `seed`, each the
/// mean of `spp` samples per pixel from `PathTrace` with the independent sampler (so frames
/// are independent, and so are runs with different seeds) and `params`.
pub fn independent_frames(
    scene: &lumagraph::scene::GpuScene,
    seed: u32,
    params: &[(&str, lumagraph::graph::ParamValue)],
    frames: u32,
    spp: i64,
) -> Option<Vec<lumagraph::render::cpu::Image>> {
    use lumagraph::graph::{Graph, Node, ParamValue};
    let mut scene = scene.clone();
    scene.settings.seed = seed;
    let mut pt = Node::new("pt", "PathTrace")
        .with("samples_per_frame", ParamValue::Int(spp))
        .with("sampler", ParamValue::Str("independent".into()));
    for (k, v) in params {
        pt = pt.with(k, v.clone());
    }
    let graph = Graph {
        nodes: vec![pt],
        edges: Vec::new(),
        ..Graph::default()
    };
    let mut exec = executor(&graph, &["pt.color"], &std::sync::Arc::new(scene))?;
    Some(
        (0..frames)
            .map(|_| {
                exec.run_frames(1, true).unwrap();
                exec.read_port("pt.color").unwrap()
            })
            .collect(),
    )
}

/// Per-block, per-channel mean and standard error of the mean over independent frames:
/// `(mean, standard error)` for each `block`×`block` block and RGB channel.
pub fn block_stats(frames: &[lumagraph::render::cpu::Image], block: u32) -> Vec<[(f64, f64); 3]> {
    let per_frame: Vec<Vec<[f64; 3]>> = frames
        .iter()
        .map(|f| lumagraph::render::metrics::block_means(f, block))
        .collect();
    let n = per_frame.len() as f64;
    (0..per_frame[0].len())
        .map(|b| {
            std::array::from_fn(|c| {
                let mean = per_frame.iter().map(|f| f[b][c]).sum::<f64>() / n;
                let var = per_frame
                    .iter()
                    .map(|f| (f[b][c] - mean).powi(2))
                    .sum::<f64>()
                    / (n - 1.0);
                (mean, (var / n).sqrt())
            })
        })
        .collect()
}

/// Two-sided critical value of Student's t with `df` degrees of freedom at significance
/// `alpha`.
pub fn t_critical(alpha: f64, df: f64) -> f64 {
    // P(|T| > t) = I_{df/(df+t^2)}(df/2, 1/2).
    let x = puruspe::invbetai(alpha, 0.5 * df, 0.5);
    (df * (1.0 - x) / x).sqrt()
}

/// Whether two sets of independent frames have the same expected block means: Welch's
/// t-test on every block and channel whose mean is at least `floor`, at overall significance
/// `alpha` (Bonferroni over the tests). Returns the number of tests and the largest |t| over
/// its critical value, or an error naming the worst block.
pub fn same_means(
    a: &[lumagraph::render::cpu::Image],
    b: &[lumagraph::render::cpu::Image],
    block: u32,
    floor: f64,
    alpha: f64,
) -> Result<(usize, f64), String> {
    let (sa, sb) = (block_stats(a, block), block_stats(b, block));
    let df = (a.len().min(b.len()) - 1) as f64;
    let mut tests = Vec::new();
    for (i, (x, y)) in sa.iter().zip(&sb).enumerate() {
        for c in 0..3 {
            let ((ma, ea), (mb, eb)) = (x[c], y[c]);
            if ma.max(mb) < floor {
                continue;
            }
            let t = (ma - mb) / (ea * ea + eb * eb).sqrt().max(1e-12);
            tests.push((i, c, ma, mb, t));
        }
    }
    // Welch's degrees of freedom are at least the smaller sample's; using that is
    // conservative.
    let crit = t_critical(alpha / tests.len() as f64, df);
    let worst = tests
        .iter()
        .max_by(|p, q| p.4.abs().total_cmp(&q.4.abs()))
        .copied()
        .ok_or("no block above the floor")?;
    if worst.4.abs() > crit {
        return Err(format!(
            "block {} channel {}: {:.5} vs {:.5}, t = {:.2} > {crit:.2} ({} tests, alpha {alpha})",
            worst.0,
            worst.1,
            worst.2,
            worst.3,
            worst.4,
            tests.len()
        ));
    }
    Ok((tests.len(), worst.4.abs() / crit))
}

/// Runs `graph` for one frame (paths relative to the repository root, outputs into
/// `out_dir`) and returns the ports `keep`, or `None` without a GPU (when allowed).
pub fn run_graph(
    graph: &lumagraph::graph::Graph,
    keep: &[&str],
    out_dir: &Path,
) -> Option<Vec<lumagraph::render::cpu::Image>> {
    use lumagraph::pathtrace::library::compile;
    use lumagraph::render::Resources;
    let ctx = gpu()?;
    let keep: Vec<String> = keep.iter().map(|s| (*s).to_owned()).collect();
    let plan = compile(graph, &keep, None).unwrap_or_else(|e| panic!("{e}"));
    let paths = Resources {
        base_dir: root(),
        out_dir: out_dir.to_owned(),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &paths).unwrap();
    exec.run_frame().unwrap();
    Some(keep.iter().map(|k| exec.read_port(k).unwrap()).collect())
}

/// Runs one node of `kind` with `params` on image files (`(input port, path)`, paths
/// relative to the repository root or absolute) and returns its `color` output, or `None`
/// without a GPU (when allowed).
pub fn run_node(
    kind: &str,
    params: &[(&str, lumagraph::graph::ParamValue)],
    inputs: &[(&str, &str)],
) -> Option<lumagraph::render::cpu::Image> {
    use lumagraph::graph::{Edge, Graph, Node, ParamValue};
    let mut node = Node::new("n", kind);
    for (k, v) in params {
        node = node.with(k, v.clone());
    }
    let mut graph = Graph {
        nodes: vec![node],
        edges: Vec::new(),
        ..Graph::default()
    };
    for (i, (port, path)) in inputs.iter().enumerate() {
        let id = format!("in{i}");
        graph
            .nodes
            .push(Node::new(&id, "ImageInput").with("path", ParamValue::Str((*path).into())));
        graph
            .edges
            .push(Edge::new(format!("{id}.color"), format!("n.{port}")));
    }
    let dir = tempfile::tempdir().unwrap();
    run_graph(&graph, &["n.color"], dir.path()).map(|mut v| v.remove(0))
}

/// Asserts `got` is `want`'s size and each channel within `bound(pixel index, channel)` of
/// it; prints the worst error as a fraction of its bound under `label`.
pub fn assert_within(
    label: &str,
    got: &lumagraph::render::cpu::Image,
    want: &lumagraph::render::cpu::Image,
    bound: impl Fn(usize, usize) -> f64,
) {
    assert_eq!(
        (got.width, got.height),
        (want.width, want.height),
        "{label}: size"
    );
    let mut worst = 0.0_f64;
    for (i, (g, w)) in got.pixels.iter().zip(&want.pixels).enumerate() {
        for c in 0..4 {
            let err = f64::from((g[c] - w[c]).abs());
            let b = bound(i, c);
            worst = worst.max(err / b);
            assert!(
                err <= b,
                "{label}: pixel {} ({}, {}) channel {c}: {} vs {} (bound {b:.2e})",
                i,
                i % want.width as usize,
                i / want.width as usize,
                g[c],
                w[c]
            );
        }
    }
    eprintln!("{label}: worst error {worst:.3} of the bound");
}

/// `image` with each pixel mapped by `f`.
pub fn map_pixels(
    image: &lumagraph::render::cpu::Image,
    mut f: impl FnMut(usize, [f64; 4]) -> [f64; 4],
) -> lumagraph::render::cpu::Image {
    let mut out = image.clone();
    for (i, p) in out.pixels.iter_mut().enumerate() {
        #[expect(clippy::cast_possible_truncation, reason = "f32 images")]
        let q = f(i, p.map(f64::from)).map(|v| v as f32);
        *p = q;
    }
    out
}

/// Runs the `lumagraph` binary from the repository root: (success, stdout, stderr).
pub fn cli(args: &[&str]) -> (bool, String, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args(args)
        .current_dir(root())
        .output()
        .unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// `source` → `Accumulate` (`acc`) → a denoiser of `kind` (`dn`, with `params`), guided by
/// `GBuffer` (`gb`) and, when `variance`, by `acc`'s variance.
pub fn filter_graph(
    kind: &str,
    source: lumagraph::graph::Node,
    params: &[(&str, lumagraph::graph::ParamValue)],
    variance: bool,
) -> lumagraph::graph::Graph {
    use lumagraph::graph::{Edge, Node};
    let mut graph = denoise_graph(source, params);
    if let Some(dn) = graph.nodes.iter_mut().find(|n| n.id == "dn") {
        *dn = params
            .iter()
            .fold(Node::new("dn", kind), |n, (k, v)| n.with(k, v.clone()));
    }
    if !variance {
        graph
            .edges
            .retain(|e| e != &Edge::new("acc.variance", "dn.variance"));
    }
    graph
}

/// The environment-lit mesh scene (`assets/bench/mesh_env.ron`) at `size`, after making its
/// mesh (`assets/bench/blob.obj`, not in git) with `scripts/bench/mesh_env.py` when missing.
pub fn mesh_env_scene(size: Option<u32>) -> std::sync::Arc<lumagraph::scene::GpuScene> {
    bench_mesh::bench_blob(&root());
    gpu_scene("assets/bench/mesh_env.ron", size)
}

/// Runs `f` on a thread of its own (32 MiB of stack) and returns what it returned; `Err`
/// naming a panic, or a run longer than `limit` (a hung thread is left behind: the caller
/// fails anyway). The fuzz tests run each case so.
pub fn guarded<T: Send + 'static>(
    limit: std::time::Duration,
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T, String> {
    let (tx, rx) = std::sync::mpsc::channel();
    let handle = std::thread::Builder::new()
        .name("fuzz case".into())
        .stack_size(32 << 20)
        .spawn(move || {
            let _ = tx.send(f());
        })
        .unwrap();
    match rx.recv_timeout(limit) {
        Ok(result) => {
            let _ = handle.join();
            Ok(result)
        }
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => Err(format!(
            "hang: the case did not finish within {} s",
            limit.as_secs()
        )),
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
            let payload = handle.join().err();
            let message = payload
                .as_ref()
                .and_then(|p| {
                    p.downcast_ref::<&str>()
                        .map(|s| (*s).to_owned())
                        .or_else(|| p.downcast_ref::<String>().cloned())
                })
                .unwrap_or_default();
            Err(format!("panic: {message}"))
        }
    }
}

/// The pinhole ray through image position `p` (in pixels from the top-left corner), as
/// the shader makes it: through the pixel centre at `(x + 0.5, y + 0.5)`.
/// `frames` frames of `samples_per_frame` samples of `scene` through the progressive graph
/// (`PathTrace` into `Accumulate`) on `ctx`, with `resources` but the scene: the accumulated
/// colour.
pub fn accumulate(
    ctx: &lumagraph::render::GpuContext,
    scene: &std::sync::Arc<lumagraph::scene::GpuScene>,
    samples_per_frame: i64,
    frames: u32,
    resources: lumagraph::render::Resources,
) -> lumagraph::render::cpu::Image {
    use lumagraph::pathtrace::library::compile;
    use lumagraph::render::Resources;
    let plan = compile(
        &progressive_graph(&[(
            "samples_per_frame",
            lumagraph::graph::ParamValue::Int(samples_per_frame),
        )]),
        &["acc.color".to_owned()],
        Some(scene),
    )
    .unwrap();
    let resources = Resources {
        scene: Some(std::sync::Arc::clone(scene)),
        ..resources
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frames(frames, true).unwrap();
    exec.read_port("acc.color").unwrap()
}

/// The rays through 4 × 4 points of pixel (`x`, `y`) (a regular grid over its footprint),
/// each with what the CPU traversal hits.
pub fn footprint(
    g: &lumagraph::scene::GpuScene,
    x: u32,
    y: u32,
) -> Vec<(lumagraph::scene::Ray, Option<lumagraph::scene::Hit>)> {
    (0..16)
        .map(|k| {
            let at = glam::Vec2::new(
                x as f32 + (0.5 + (k % 4) as f32) / 4.0,
                y as f32 + (0.5 + (k / 4) as f32) / 4.0,
            );
            let ray = image_ray(g, at);
            (ray, lumagraph::scene::intersect(g, &ray))
        })
        .collect()
}

pub fn image_ray(g: &lumagraph::scene::GpuScene, p: glam::Vec2) -> lumagraph::scene::Ray {
    use glam::Vec3;
    let c = &g.camera;
    let (w, h) = (g.settings.width as f32, g.settings.height as f32);
    let u = p.x / w;
    let v = p.y / h;
    let dir = Vec3::from(c.forward)
        + (2.0 * u - 1.0) * c.tan_half_fov * c.aspect * Vec3::from(c.right)
        - (2.0 * v - 1.0) * c.tan_half_fov * Vec3::from(c.up);
    lumagraph::scene::Ray {
        origin: Vec3::from(c.position),
        dir: dir.normalize(),
    }
}

/// What [`render_with`] and its kin return: the colour, albedo, normal and depth, and how
/// the shader was specialized.
pub type Rendered = (
    Vec<lumagraph::render::cpu::Image>,
    lumagraph::pathtrace::specialize::Features,
);

/// `scene` rendered at `size` and `spp` with `resources` (the scene set here): color,
/// albedo, normal and depth, and how the shader was specialized.
pub fn render_with(
    name: &str,
    size: (u32, u32),
    spp: u32,
    resources: lumagraph::render::Resources,
) -> Option<Rendered> {
    use lumagraph::scene::{GpuScene, Scene};
    gpu()?;
    let scene = GpuScene::build(&Scene::load(&repo(&format!("assets/{name}"))).unwrap()).unwrap();
    println!("{name}:");
    render_scene(scene, size, spp, resources)
}

/// [`render_with`] for a scene already built, at `size`.
pub fn render_scene(
    mut scene: lumagraph::scene::GpuScene,
    size: (u32, u32),
    spp: u32,
    resources: lumagraph::render::Resources,
) -> Option<Rendered> {
    (scene.settings.width, scene.settings.height) = size;
    let out = render_scene_with(&std::sync::Arc::new(scene), spp, resources);
    if let Some((_, features)) = &out {
        println!("  {}", features.summary());
    }
    out
}

/// [`render_with`] for a scene at hand, at its own size.
pub fn render_scene_with(
    scene: &std::sync::Arc<lumagraph::scene::GpuScene>,
    spp: u32,
    resources: lumagraph::render::Resources,
) -> Option<Rendered> {
    use lumagraph::graph::ParamValue;
    use lumagraph::pathtrace::library::compile;

    let ctx = gpu()?;
    let ports = ["acc.color", "pt.albedo", "pt.normal", "pt.depth"];
    let outputs: Vec<String> = ports.iter().map(|p| (*p).to_owned()).collect();
    let graph = progressive_graph(&[("samples_per_frame", ParamValue::Int(4))]);
    let plan = compile(&graph, &outputs, Some(scene)).unwrap();
    let resources = lumagraph::render::Resources {
        scene: Some(std::sync::Arc::clone(scene)),
        ..resources
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    let features = lumagraph::pathtrace::nodes::pathtrace::features(&exec, "pt")
        .unwrap()
        .clone();
    exec.run_frames(spp.div_ceil(4), true).unwrap();
    let images = ports.iter().map(|p| exec.read_port(p).unwrap()).collect();
    Some((images, features))
}

/// Pixels of `a` and `b` that differ: in any bit (`None`), or by more than `rel` relative in
/// a color channel.
pub fn differing(
    a: &lumagraph::render::cpu::Image,
    b: &lumagraph::render::cpu::Image,
    rel: Option<f32>,
) -> usize {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(x, y)| match rel {
            None => x.map(f32::to_bits) != y.map(f32::to_bits),
            Some(r) => (0..3).any(|c| (x[c] - y[c]).abs() > r * (x[c].abs() + 1e-3)),
        })
        .count()
}

/// The largest relative difference of a color channel between `a` and `b` (against
/// |a| + 1e-3, as `differing` measures).
pub fn worst_relative(a: &lumagraph::render::cpu::Image, b: &lumagraph::render::cpu::Image) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(x, y)| (0..3).map(|c| (x[c] - y[c]).abs() / (x[c].abs() + 1e-3)))
        .fold(0.0f32, f32::max)
}

/// `name` rendered through two intersectors (`a` and `b`, which `check` checks the
/// features of) at 64×64 and 16 spp: the first-hit AOVs must agree, and the colors are
/// compared. Returns the pixels of the color beyond 1e-4 relative and the relative
/// difference of the image means.
pub fn same_hits(
    name: &str,
    a: lumagraph::render::Resources,
    b: lumagraph::render::Resources,
    check: impl Fn(
        &lumagraph::pathtrace::specialize::Features,
        &lumagraph::pathtrace::specialize::Features,
    ),
) -> Option<(usize, f64)> {
    let (a, how_a) = render_with(name, (64, 64), 16, a)?;
    let (b, how_b) = render_with(name, (64, 64), 16, b)?;
    check(&how_a, &how_b);
    // The first-hit AOVs come from the ray through each pixel's centre: the same hits, but
    // where that ray meets two surfaces at the same distance (the Cornell box's corners lie
    // on the image's diagonals, through pixel centres), the intersector that finds the
    // second one first keeps it. So the depth is bit-identical everywhere, and albedo and
    // normal differ only where the depth says such a tie can be.
    let depth = differing(&a[3], &b[3], None);
    println!(
        "{name} depth: {depth} of {} pixels differ",
        a[3].pixels.len()
    );
    assert_eq!(depth, 0, "{name}: depth differs");
    for (i, port) in [(1, "albedo"), (2, "normal")] {
        let differ = differing(&a[i], &b[i], None);
        println!(
            "{name} {port}: {differ} of {} pixels differ (ties)",
            a[i].pixels.len()
        );
        // Ties are on edges: at most a diagonal's worth of pixels (64) per corner line.
        assert!(differ <= 128, "{name} {port}: {differ} pixels differ");
    }
    let sum = |i: &lumagraph::render::cpu::Image| {
        i.pixels
            .iter()
            .map(|p| f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]))
            .sum::<f64>()
    };
    let (ca, cb) = (&a[0], &b[0]);
    assert!(ca.pixels.iter().any(|p| p[0] > 0.0), "{name}: black");
    let far = differing(ca, cb, Some(1e-4));
    let mean = (sum(ca) - sum(cb)) / sum(cb);
    println!(
        "{name} color: {} pixels differ, {far} by more than 1e-4 relative, at most {:.2e}; \
         means {mean:+.2e} relative",
        differing(ca, cb, None),
        worst_relative(ca, cb)
    );
    Some((far, mean))
}

/// For a test that needs ray queries: `true` where this process's device has them (the
/// test runs here). Otherwise the test `name` runs again in a child process on the driver
/// that `LUMAGRAPH_RAY_QUERY_ICD` names (Mesa 25's lavapipe, which `scripts/setup.sh`
/// unpacks beside the system's drivers and `scripts/env.sh` names), its output is shown
/// and its success asserted, and the caller returns (`false`). Without such a driver, a
/// failure, unless `LUMAGRAPH_ALLOW_NO_RAY_QUERY=1`.
pub fn ray_queries_here(name: &str) -> bool {
    let Some(ctx) = gpu() else {
        return false;
    };
    if ctx.ray_queries() {
        return true;
    }
    let child = std::env::var_os("LUMAGRAPH_RAY_QUERY_CHILD").is_some();
    let icd = std::env::var("LUMAGRAPH_RAY_QUERY_ICD")
        .ok()
        .filter(|p| Path::new(p).is_file());
    if let (Some(icd), false) = (&icd, child) {
        // The test's whole name, with its module (the test thread is named after it).
        let current = std::thread::current();
        let full = current.name().filter(|t| t.ends_with(name)).unwrap_or(name);
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([full, "--exact", "--nocapture", "--test-threads=1"])
            .env("VK_ICD_FILENAMES", icd)
            .env("LUMAGRAPH_RAY_QUERY_CHILD", "1")
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        println!("{name}, run again on the driver of {icd}:\n{text}");
        assert!(out.status.success(), "{name} failed on {icd}");
        assert!(text.contains("1 passed"), "{name} did not run on {icd}");
        return false;
    }
    assert!(
        std::env::var("LUMAGRAPH_ALLOW_NO_RAY_QUERY").is_ok_and(|v| v == "1"),
        "{}: no ray queries{}; run scripts/setup.sh (it unpacks Mesa 25's lavapipe) or set \
         LUMAGRAPH_RAY_QUERY_ICD to the ICD file of a driver with them, or set \
         LUMAGRAPH_ALLOW_NO_RAY_QUERY=1",
        ctx.describe(),
        if child { " on the driver named" } else { "" }
    );
    println!("{}: no ray queries, {name} not run", ctx.describe());
    false
}

/// A small PLY mesh in `format` (`ascii`, `binary_little_endian`, `binary_big_endian`):
/// four vertices with float positions and normals and byte colours, one quad (`uchar`
/// count, `int` indices) and one triangle, then an `edge` element no importer reads.
pub fn ply_bytes(format: &str) -> Vec<u8> {
    const V: [([f32; 3], [f32; 3], [u8; 3]); 4] = [
        ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [255, 0, 0]),
        ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0, 255, 0]),
        ([1.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0, 0, 255]),
        ([0.0, 1.0, 0.5], [0.0, 0.6, 0.8], [255, 255, 255]),
    ];
    const F: [&[i32]; 2] = [&[0, 1, 2, 3], &[0, 2, 3]];
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment lumagraph test\nelement vertex 4\n\
         property float x\nproperty float y\nproperty float z\nproperty float nx\n\
         property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nproperty float confidence\nelement face 2\n\
         property list uchar int vertex_indices\nelement edge 1\nproperty int vertex1\n\
         property int vertex2\nend_header\n"
    )
    .into_bytes();
    let big = format == "binary_big_endian";
    let f32b = |x: f32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let i32b = |x: i32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    if format == "ascii" {
        for (p, n, c) in V {
            out.extend(
                format!(
                    "{} {} {} {} {} {} {} {} {} 0.5\n",
                    p[0], p[1], p[2], n[0], n[1], n[2], c[0], c[1], c[2]
                )
                .bytes(),
            );
        }
        for f in F {
            let list: Vec<String> = f.iter().map(ToString::to_string).collect();
            out.extend(format!("{} {}\n", f.len(), list.join(" ")).bytes());
        }
        out.extend(b"0 1\n");
    } else {
        for (p, n, c) in V {
            for x in p.into_iter().chain(n) {
                out.extend(f32b(x));
            }
            out.extend(c);
            out.extend(f32b(0.5));
        }
        for f in F {
            out.push(u8::try_from(f.len()).unwrap());
            for &i in f {
                out.extend(i32b(i));
            }
        }
        out.extend(i32b(0));
        out.extend(i32b(1));
    }
    out
}

/// PCG32 from a raw state, so random rays are the same on every run.
pub struct Pcg(pub u64);

impl Pcg {
    /// Uniform in [0, 1).
    pub fn next(&mut self) -> f32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        (x.rotate_right((old >> 59) as u32) >> 8) as f32 / (1u32 << 24) as f32
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}
