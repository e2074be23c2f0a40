//! The `OIDN` node (Intel Open Image Denoise 2, on the CPU) on the Cornell box against
//! Mitsuba's 24 576-spp reference, the result it keeps, and its error without the library.
//!
//! OIDN must load (`bash scripts/setup.sh` fetches it and `scripts/env.sh` points
//! `LUMAGRAPH_OIDN_LIB` at it): without it the tests that run it fail, unless
//! `LUMAGRAPH_ALLOW_NO_OIDN=1`.

use crate::common;

use std::sync::Arc;

use lumagraph::graph::{Edge, Graph, Node, ParamValue};
use lumagraph::pathtrace::library::compile;
use lumagraph::render::oidn::Oidn;
use lumagraph::render::{Resources, image_io, metrics};

/// Whether OIDN loads here; panics saying how to get it unless `LUMAGRAPH_ALLOW_NO_OIDN=1`.
pub(crate) fn oidn_here() -> bool {
    match Oidn::load() {
        Ok(oidn) => {
            eprintln!("OIDN {} from {}", oidn.version(), oidn.library());
            true
        }
        Err(why) if std::env::var("LUMAGRAPH_ALLOW_NO_OIDN").is_ok_and(|v| v == "1") => {
            eprintln!("skipped (LUMAGRAPH_ALLOW_NO_OIDN=1): {why}");
            false
        }
        Err(why) => panic!("{why}\n(LUMAGRAPH_ALLOW_NO_OIDN=1 skips the OIDN tests)"),
    }
}

/// `PathTrace` (1 spp a frame) → `Accumulate` (`acc`) → `OIDN` (`dn`, with `params`), guided
/// by `GBuffer`'s albedo and normal, → `Exposure` (`post`, at `ev`).
fn graph(params: &[(&str, ParamValue)], ev: f64) -> Graph {
    let dn = params
        .iter()
        .fold(Node::new("dn", "OIDN"), |n, (k, v)| n.with(k, v.clone()));
    Graph {
        nodes: vec![
            Node::new("pt", "PathTrace").with("samples_per_frame", ParamValue::Int(1)),
            Node::new("acc", "Accumulate"),
            Node::new("gb", "GBuffer"),
            dn,
            Node::new("post", "Exposure").with("ev", ParamValue::Float(ev)),
        ],
        edges: vec![
            Edge::new("pt.color", "acc.color"),
            Edge::new("acc.color", "dn.color"),
            Edge::new("gb.albedo", "dn.albedo"),
            Edge::new("gb.normal", "dn.normal"),
            Edge::new("dn.color", "post.color"),
        ],
        ..Graph::default()
    }
}

/// Every port is kept, so no texture shares memory with a later one and a re-run of some
/// nodes reads the others' outputs as they were (else it runs a whole frame).
const KEEP: [&str; 5] = [
    "acc.color",
    "gb.albedo",
    "gb.normal",
    "dn.color",
    "post.color",
];

/// At 16 spp OIDN's relMSE is at most a tenth of the raw accumulation's (measured: 1.240e-3
/// against 1.361e-2, 11.0× lower, as `pyoidn` 2.5.1 on the same images in
/// `tests/reference/denoise/baseline.csv`; with `prefilter` 1.21e-3, 11.2×). One render: the same
/// accumulation is then filtered again with other params, and re-running the nodes after
/// OIDN, or a whole tail over the same accumulation, does not filter again.
#[test]
fn oidn_at_16_spp_is_10x_better_than_raw_and_keeps_its_result() {
    if !oidn_here() {
        return;
    }
    let Some(ctx) = common::gpu() else { return };
    let scene = common::gpu_scene("assets/cornell.ron", None);
    let keep = KEEP.map(str::to_owned);
    let plan = compile(&graph(&[], 0.0), &keep, Some(&scene)).unwrap();
    let resources = Resources {
        scene: Some(Arc::clone(&scene)),
        ..Resources::default()
    };
    let mut exec = lumagraph::pathtrace::library::executor(ctx, plan, &resources).unwrap();
    exec.run_frames(16, true).unwrap();
    let reference = image_io::load(&common::repo("tests/reference/cornell_ref.exr")).unwrap();
    let raw = exec.read_port("acc.color").unwrap();
    let filtered = exec.read_port("dn.color").unwrap();
    assert!(filtered.pixels.iter().flatten().all(|v| v.is_finite()));
    let (r, f) = (
        metrics::relmse(&raw, &reference),
        metrics::relmse(&filtered, &reference),
    );
    eprintln!(
        "16 spp relMSE raw {r:.4e}, OIDN {f:.4e} ({:.2}× lower)",
        r / f
    );
    assert!(
        f * 10.0 <= r,
        "OIDN relMSE {f:.4e} is not 10× below raw {r:.4e}"
    );
    assert_eq!(common::counter(&mut exec, "oidn_filter_runs"), 1);

    // The same accumulation again: the kept result, not a second filtering.
    exec.run_tail().unwrap();
    assert_eq!(common::counter(&mut exec, "oidn_filter_runs"), 1);
    assert_eq!(exec.read_port("dn.color").unwrap().pixels, filtered.pixels);
    // An edit after OIDN re-runs what follows it only.
    let edited = compile(&graph(&[], 1.0), &keep, Some(&scene)).unwrap();
    assert!(exec.update_params(edited).unwrap());
    let report = exec.rerun(&["post".to_owned()]).unwrap();
    assert_eq!(report.executed, ["post"]);
    assert_eq!(common::counter(&mut exec, "oidn_filter_runs"), 1);
    let post = exec.read_port("post.color").unwrap();
    let (doubled, once) = (post.pixels[1000][0], filtered.pixels[1000][0]);
    assert!(
        (doubled - 2.0 * once).abs() <= 1e-6 * once.abs(),
        "{doubled} ≠ 2 × {once}"
    );

    // Prefiltered guides: a new filtering of the same accumulation.
    let prefilter = [("prefilter", ParamValue::Bool(true))];
    let edited = compile(&graph(&prefilter, 1.0), &keep, Some(&scene)).unwrap();
    assert!(exec.update_params(edited).unwrap());
    let report = exec.rerun(&["dn".to_owned()]).unwrap();
    assert_eq!(report.executed, ["dn", "post"]);
    assert_eq!(common::counter(&mut exec, "oidn_filter_runs"), 2);
    let p = metrics::relmse(&exec.read_port("dn.color").unwrap(), &reference);
    eprintln!("with prefilter: OIDN {p:.4e} ({:.2}× lower)", r / p);
    assert!(
        p * 10.0 <= r,
        "prefiltered OIDN relMSE {p:.4e} is not 10× below raw {r:.4e}"
    );
}

/// Without the library (`LUMAGRAPH_OIDN_LIB` at a missing file), a render of a graph with
/// an `OIDN` node fails with one error naming the node, the file, and how to get OIDN; it
/// writes nothing.
#[test]
fn oidn_without_the_library_is_one_clear_error() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("oidn.ron");
    let chart = common::repo("assets/test_chart.exr");
    let text = format!(
        "(version: 1, nodes: [\
         (id: \"chart\", kind: \"ImageInput\", params: {{\"path\": \"{}\"}}),\
         (id: \"oidn\", kind: \"OIDN\"),\
         (id: \"out\", kind: \"Output\", params: {{\"path\": \"out.exr\"}})],\
         edges: [(from: \"chart.color\", to: \"oidn.color\"), (from: \"oidn.color\", to: \"out.color\")])",
        chart.display()
    );
    std::fs::write(&graph, text).unwrap();
    let out = dir.path().join("out");
    let missing = dir.path().join("libOpenImageDenoise.so.2");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args([
            "render",
            graph.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .env("LUMAGRAPH_OIDN_LIB", &missing)
        .current_dir(common::root())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{stderr}");
    for want in [
        "node \"oidn\"",
        &format!("LUMAGRAPH_OIDN_LIB={}: no such file", missing.display()),
        "bash scripts/setup.sh",
        "set LUMAGRAPH_OIDN_LIB to the path of a libOpenImageDenoise.so",
    ] {
        assert!(stderr.contains(want), "«{want}» not in:\n{stderr}");
    }
    assert_eq!(
        stderr.matches("Open Image Denoise").count(),
        1,
        "not one error:\n{stderr}"
    );
    assert!(common::is_empty_dir(&out), "files written: {stderr}");
}
