//! Shared helpers for the integration tests: one GPU context per test binary.
//!
//! GPU tests fail when no adapter is found, unless `LUMAGRAPH_ALLOW_NO_GPU=1` is set, in
//! which case they return early and say so. With `CI` set, the adapter must be a CPU one
//! (lavapipe), so a test never silently runs on a different device than its references.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use lumagraph::render::GpuContext;

/// The shared GPU context, or `None` when there is no GPU and that is allowed.
pub fn gpu() -> Option<&'static GpuContext> {
    static CTX: LazyLock<Option<GpuContext>> =
        LazyLock::new(|| match GpuContext::headless_prefer_cpu() {
            Ok(ctx) => {
                if std::env::var_os("CI").is_some() {
                    assert!(
                        ctx.is_cpu(),
                        "CI must run GPU tests on a CPU adapter (lavapipe), got {}",
                        ctx.describe()
                    );
                }
                eprintln!("GPU tests on {}", ctx.describe());
                Some(ctx)
            }
            Err(e) if std::env::var("LUMAGRAPH_ALLOW_NO_GPU").as_deref() == Ok("1") => {
                eprintln!("skipping GPU test (LUMAGRAPH_ALLOW_NO_GPU=1): {e}");
                None
            }
            Err(e) => {
                panic!("{e}\nGPU tests need an adapter; set LUMAGRAPH_ALLOW_NO_GPU=1 to skip them")
            }
        });
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
        origin: None,
    }
}
