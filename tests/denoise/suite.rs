//! The denoising suite (`tests/reference/denoise`, `docs/denoise.md`): every scene of
//! `suite.json` rendered at 16 spp with the scene's seed through `graphs/denoise_inputs.ron`
//! (the default graph, plus a `RegressionDenoise` on the same accumulation as
//! `graphs/pathtrace_regression.ron` has it), and scored against its reference.
//!
//! Prints the raw, à-trous and regression relMSE beside OIDN 2.5's recorded figures on the
//! same accumulation (`baseline.csv`, made by `scripts/denoise/suite.py`) and asserts, per
//! scene:
//! - both denoisers beat the raw accumulation;
//! - each is no worse than its recorded relMSE plus [`TOLERANCE`]. For a fixed seed the
//!   render is deterministic on one device, so on the device the figures were recorded on
//!   (lavapipe) the margin is unused; another device (or driver) may round the path
//!   tracer's and the filters' float arithmetic differently, which moves a 16-spp relMSE by
//!   well under a percent, while a change to a filter or its defaults that matters moves it
//!   by several;
//! - the better of the two is within [`OIDN_FACTOR`] of OIDN's relMSE with the noise-free
//!   G-buffer albedo and normal (`cleanAux`).

use crate::common;

use std::collections::BTreeMap;
use std::sync::Arc;

use lumagraph::graph::Graph;
use lumagraph::render::cpu::Image;
use lumagraph::render::{Executor, NodeLibrary, Resources, compile, image_io, metrics};

/// Relative slack on the recorded relMSE figures (see the module docs).
const TOLERANCE: f64 = 0.02;
/// The best lumagraph denoiser's relMSE may be at most this many times OIDN's.
const OIDN_FACTOR: f64 = 2.0;
/// Samples per pixel of the test (a row of `baseline.csv`).
const SPP: u32 = 16;
const DIR: &str = "tests/reference/denoise";

/// A suite scene: files and the recorded 16-spp figures.
struct Case {
    name: String,
    scene: String,
    reference: String,
    atrous: f64,
    regression: f64,
    oidn: f64,
}

/// The scenes of `suite.json` with their `baseline.csv` rows at [`SPP`].
fn cases() -> Vec<Case> {
    let text = std::fs::read_to_string(common::repo(&format!("{DIR}/baseline.csv"))).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (scene, spp, atrous, regression, oidn) = (
        col("scene"),
        col("spp"),
        col("atrous_relmse"),
        col("regression_relmse"),
        col("oidn_relmse"),
    );
    let mut rows = BTreeMap::new();
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        if f[spp] == SPP.to_string() {
            let num = |c: usize| f[c].parse::<f64>().unwrap();
            rows.insert(
                f[scene].to_owned(),
                (num(atrous), num(regression), num(oidn)),
            );
        }
    }
    let suite: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(common::repo(&format!("{DIR}/suite.json"))).unwrap(),
    )
    .unwrap();
    let scenes = suite["scenes"].as_object().unwrap();
    assert!(scenes.len() >= 4, "the suite has {} scenes", scenes.len());
    scenes
        .iter()
        .map(|(name, s)| {
            let (atrous, regression, oidn) = *rows
                .get(name)
                .unwrap_or_else(|| panic!("{name}: no {SPP}-spp row in baseline.csv"));
            Case {
                name: name.clone(),
                scene: s["scene"].as_str().unwrap().to_owned(),
                reference: s["reference"].as_str().unwrap().to_owned(),
                atrous,
                regression,
                oidn,
            }
        })
        .collect()
}

/// `graphs/denoise_inputs.ron` without its Output nodes, rendered `spp` frames of 1
/// sample: `(raw, à-trous, regression)`, or `None` without a GPU (when allowed).
fn render(scene: &str, spp: u32) -> Option<(Image, Image, Image)> {
    let ctx = common::gpu()?;
    let mut graph = Graph::load(&common::repo("graphs/denoise_inputs.ron")).unwrap();
    graph.remove_sinks(&NodeLibrary::builtins().registry_for(&graph).unwrap());
    let mesh = common::repo("assets/bench/blob.obj");
    assert!(
        scene != "assets/bench/mesh_env.ron" || mesh.exists(),
        "{} is missing: `python3 scripts/bench/mesh_env.py make assets/bench/blob.obj` \
         (scripts/test.sh does it)",
        mesh.display()
    );
    let scene = common::gpu_scene(scene, None);
    let ports = ["accumulate.color", "denoise.color", "regression.color"];
    let keep: Vec<String> = ports.iter().map(|&p| p.to_owned()).collect();
    let plan = compile(&graph, &keep, Some(&scene)).unwrap();
    let resources = Resources {
        scene: Some(Arc::clone(&scene)),
        ..Resources::default()
    };
    let mut exec = Executor::new(ctx, plan, &resources).unwrap();
    exec.run_frames(spp, true).unwrap();
    let [raw, atrous, regression] = ports.map(|p| exec.read_port(p).unwrap());
    Some((raw, atrous, regression))
}

#[test]
fn denoisers_hold_their_recorded_figures() {
    let mut failures = Vec::new();
    for case in cases() {
        let reference = image_io::load(&common::repo(&case.reference)).unwrap();
        let Some((raw, atrous, regression)) = render(&case.scene, SPP) else {
            return;
        };
        let r = metrics::relmse(&raw, &reference);
        let mut best = f64::INFINITY;
        for (what, image, recorded) in [
            ("à-trous", &atrous, case.atrous),
            ("regression", &regression, case.regression),
        ] {
            assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
            let f = metrics::relmse(image, &reference);
            best = best.min(f);
            eprintln!(
                "{}: {SPP} spp relMSE raw {r:.4e}, {what} {f:.4e} (recorded {recorded:.4e}); \
                 / OIDN 2.5 {:.2}",
                case.name,
                f / case.oidn
            );
            if f >= r {
                failures.push(format!(
                    "{}: {what} {f:.4e} not below raw {r:.4e}",
                    case.name
                ));
            }
            if f > recorded * (1.0 + TOLERANCE) {
                failures.push(format!(
                    "{}: {what} {f:.4e} worse than recorded {recorded:.4e} by more than \
                     {TOLERANCE}",
                    case.name
                ));
            }
        }
        if best > OIDN_FACTOR * case.oidn {
            failures.push(format!(
                "{}: best denoiser {best:.4e} above {OIDN_FACTOR} × OIDN's {:.4e}",
                case.name, case.oidn
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
