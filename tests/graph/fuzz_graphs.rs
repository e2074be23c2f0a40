//! Property-based fuzzing of `render` with generated graphs (`tests/graph/fuzz.rs` mutates real
//! files; this makes graphs from the registry). Each case is a graph file, written with the
//! files it reads: random built-in kinds (those that render no scene), edges between them
//! (mostly forwards, some backwards into cycles, some to ports that do not exist), params
//! unset, at their ranges' ends, inside them and past them (NaN and infinities too), node
//! kinds declared with WGSL assembled from snippets (reads far out of bounds, division by
//! zero, bounded loops, stray stores, and broken code), and node groups nested up to three
//! deep (sometimes containing themselves). Output paths are fine, absolute, climbing out
//! with `..` or leaving through a symbolic link.
//!
//! What `lumagraph render` does runs on each: load, compile, the output paths checked
//! ([`output_files`]), the executor created, two frames run and the files written, on an
//! 8×8 image. The property: no panic, no case longer than [`CASE_LIMIT`] (each runs on a
//! thread of its own), and no file written outside the output folder: the output folder is
//! `a/b/out` in a fresh temporary folder, where every escaping path lands, and after the
//! case nothing but the output folder has changed. A refused output path must also be
//! refused by the executor on its own. A plan whose images pass [`IMAGE_BUDGET`] (a
//! Resize to 16384 × 16384 is allowed and takes its time, not a bug) is compiled and
//! checked but not run.
//!
//! A plain run takes [`DEFAULT_CASES`] fixed cases (docs/failures.md, "Fuzzing", gives the
//! time). A long run: `LUMAGRAPH_FUZZ_GRAPH_CASES=N` cases with a new seed each run,
//! printed with `--nocapture`; `LUMAGRAPH_FUZZ_SEED=S` repeats one:
//!
//! ```sh
//! LUMAGRAPH_FUZZ_GRAPH_CASES=20000 cargo test --test graph fuzz_graphs:: -- --nocapture
//! ```
//!
//! A failure writes the smallest case found under `target/fuzz-failures/generated_graphs/`.

use crate::common;
#[path = "fuzz_graphs/generate.rs"]
mod generate;

use std::fmt;
use std::path::Path;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, LazyLock};
use std::time::{Duration, Instant};

use generate::{Case, LIBRARY, build};
use lumagraph::graph::Graph;
use lumagraph::graph::outputs::output_files;
use lumagraph::render::{Executor, Resources, cpu, image_io};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestError, TestRunner};

/// The longest one case may take before it counts as a hang (shader compilation on a
/// busy two-core machine included).
const CASE_LIMIT: Duration = Duration::from_secs(60);
/// Cases of a plain run.
const DEFAULT_CASES: u32 = 1000;
/// Plans whose images take more bytes are compiled and checked, not run.
const IMAGE_BUDGET: u64 = 16 << 20;

/// The scene of the cases that have one: the Cornell box at 8×8.
static SCENE: LazyLock<Arc<lumagraph::scene::GpuScene>> =
    LazyLock::new(|| common::gpu_scene("assets/cornell.ron", Some(8)));

/// What happened to a case (each is fine; a property violation is an `Err`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    /// Refused when loading (syntax, declared kinds, groups).
    Load,
    /// Refused by the compiler.
    Compile,
    /// An output path refused (and the executor refused it too).
    OutsidePath,
    /// Compiled, images larger than [`IMAGE_BUDGET`]: not run.
    TooLarge,
    /// Refused while setting up the nodes (a missing file, a bad LUT…).
    Setup,
    /// A frame failed with an error.
    Frame,
    /// Rendered and its files written.
    Rendered,
}

/// Every file and folder under `dir`, relative to it, sorted (links not followed).
fn tree(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            out.push(p.strip_prefix(dir).unwrap_or(&p).display().to_string());
            if p.is_dir() && !p.is_symlink() {
                stack.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The inputs every case may read: an 8×8 EXR and PNG, and a 2³ LUT.
fn write_inputs(dir: &Path) {
    let pixels = (0..64u8)
        .map(|i| [f32::from(i) / 16.0, f32::from(i % 8) / 4.0, 0.25, 1.0])
        .collect();
    let image = cpu::Image {
        width: 8,
        height: 8,
        pixels,
    };
    image_io::save(&dir.join("in.exr"), &image, true).unwrap();
    image_io::save(&dir.join("in.png"), &image, true).unwrap();
    let mut cube = String::from("LUT_3D_SIZE 2\n");
    for i in 0..8 {
        cube += &format!("{} {} {}\n", i & 1, (i >> 1) & 1, (i >> 2) & 1);
    }
    std::fs::write(dir.join("look.cube"), cube).unwrap();
}

/// Runs `case` as `lumagraph render` would, in a fresh temporary folder; `Err` when a file
/// appeared outside the output folder or a refused path got past the executor.
fn run_case(case: &Case) -> Result<Outcome, String> {
    let tmp = tempfile::tempdir().map_err(|e| e.to_string())?;
    let root = tmp.path();
    let inputs = root.join("in");
    let out = root.join("a/b/out");
    std::fs::create_dir_all(&inputs).unwrap();
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(root.join("elsewhere")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(root.join("elsewhere"), out.join("link")).unwrap();
    write_inputs(&inputs);
    let abs = root.display().to_string();
    for (name, text) in &case.files {
        std::fs::write(inputs.join(name), text.replace("@ABS@", &abs)).unwrap();
    }
    let before = tree(root);
    let outcome = render(&inputs.join("graph.ron"), &out, case.scene)?;
    // Nothing but the output folder changed.
    let after = tree(root);
    let changed: Vec<_> = after
        .iter()
        .filter(|p| !before.contains(p) && !Path::new(p).starts_with("a/b/out"))
        .chain(before.iter().filter(|p| !after.contains(p)))
        .collect();
    if !changed.is_empty() {
        return Err(format!(
            "{outcome:?}, but written outside a/b/out (or removed): {changed:?}"
        ));
    }
    Ok(outcome)
}

fn render(graph: &Path, out: &Path, scene: bool) -> Result<Outcome, String> {
    let scene = scene.then(|| Arc::clone(&SCENE));
    // `LUMAGRAPH_FUZZ_VERBOSE=1` prints why each case was refused (to tune the generator).
    let refused = |outcome: Outcome, e: &dyn fmt::Display| {
        if std::env::var_os("LUMAGRAPH_FUZZ_VERBOSE").is_some() {
            eprintln!("{outcome:?}: {e}");
        }
        Ok(outcome)
    };
    let graph = match Graph::load(graph) {
        Ok(g) => g,
        Err(e) => return refused(Outcome::Load, &e),
    };
    let registry = match LIBRARY.registry_for(&graph) {
        Ok(r) => r,
        Err(e) => return refused(Outcome::Load, &e),
    };
    let base = graph.base_dir();
    let plan = match LIBRARY.compile_with(&graph, &registry, &base, &[], scene.as_deref()) {
        Ok(p) => p,
        Err(e) => return refused(Outcome::Compile, &e),
    };
    let files = output_files(&plan, &graph, out, false);
    if plan.texture_bytes() > IMAGE_BUDGET {
        return Ok(Outcome::TooLarge);
    }
    let ctx = common::gpu().ok_or("no GPU")?;
    let resources = Resources {
        base_dir: graph.base_dir(),
        out_dir: out.to_owned(),
        scene,
        ..Resources::default()
    };
    let exec = Executor::with_library(ctx, plan, &resources, &LIBRARY);
    if let Err(e) = &files {
        return match exec {
            Ok(_) => Err(format!(
                "the executor took an output path output_files refused: {e}"
            )),
            Err(_) => Ok(Outcome::OutsidePath),
        };
    }
    let mut exec = match exec {
        Ok(exec) => exec,
        Err(e) => return refused(Outcome::Setup, &e),
    };
    let report = match exec.run_frames(2, true) {
        Ok(r) => r,
        Err(e) => return refused(Outcome::Frame, &e),
    };
    if let Some(p) = report.written.iter().find(|p| !p.starts_with(out)) {
        return Err(format!("wrote {} outside {}", p.display(), out.display()));
    }
    Ok(Outcome::Rendered)
}

/// Runs `case` on a thread of its own: `Err` for a panic, a hang or a violated property.
fn guarded(case: Case) -> Result<Outcome, String> {
    common::guarded(CASE_LIMIT, move || run_case(&case))?
}

/// `LUMAGRAPH_FUZZ_GRAPH_CASES`, else [`DEFAULT_CASES`]; the seed: `LUMAGRAPH_FUZZ_SEED`,
/// else a new one for a long run, else fixed.
fn cases_and_seed() -> (u32, u64) {
    let long = std::env::var("LUMAGRAPH_FUZZ_GRAPH_CASES").ok().map(|n| {
        n.trim()
            .parse::<u32>()
            .expect("LUMAGRAPH_FUZZ_GRAPH_CASES: a number of cases")
    });
    let seed = match std::env::var("LUMAGRAPH_FUZZ_SEED") {
        Ok(s) => s.trim().parse().expect("LUMAGRAPH_FUZZ_SEED: a number"),
        Err(_) if long.is_some() => {
            let now = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .unwrap_or_default();
            u64::try_from(now.as_nanos() & u128::from(u64::MAX)).unwrap_or_default()
        }
        Err(_) => 0x6c75_6d61_6772_6170,
    };
    (long.unwrap_or(DEFAULT_CASES), seed)
}

#[test]
fn generated_graphs_render_or_are_refused() {
    if common::gpu().is_none() {
        return;
    }
    let (cases, seed) = cases_and_seed();
    let config = Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 500,
        max_shrink_time: 300_000,
        ..Config::default()
    };
    let counts: [AtomicU32; 7] = Default::default();
    let start = Instant::now();
    let mut runner = TestRunner::new(config);
    let strategy = prop::collection::vec(any::<u32>(), 0..400).prop_map(|v| build(&v));
    let with_scene = AtomicU32::new(0);
    let result = runner.run(&strategy, |case| {
        let scene = case.scene;
        let outcome = guarded(case).map_err(TestCaseError::fail)?;
        counts[outcome as usize].fetch_add(1, Ordering::Relaxed);
        if scene && outcome == Outcome::Rendered {
            with_scene.fetch_add(1, Ordering::Relaxed);
        }
        Ok(())
    });
    let names = [
        "load",
        "compile",
        "outside path",
        "too large",
        "setup",
        "frame",
        "rendered",
    ];
    let summary: Vec<String> = names
        .iter()
        .zip(&counts)
        .map(|(n, c)| format!("{n} {}", c.load(Ordering::Relaxed)))
        .collect();
    eprintln!(
        "fuzz generated_graphs: {cases} cases ({}; {} rendered with a scene), seed {seed}, {:.1} s",
        summary.join(", "),
        with_scene.load(Ordering::Relaxed),
        start.elapsed().as_secs_f64()
    );
    match result {
        Ok(()) => {}
        Err(TestError::Fail(reason, case)) => {
            let dir = common::repo("target/fuzz-failures/generated_graphs");
            let _ = std::fs::remove_dir_all(&dir);
            std::fs::create_dir_all(&dir).unwrap();
            for (name, text) in &case.files {
                std::fs::write(dir.join(name), text).unwrap();
            }
            panic!(
                "fuzz generated_graphs (seed {seed}): {reason}\nsmallest case, in {}:\n{case:?}",
                dir.display()
            );
        }
        Err(e) => panic!("fuzz generated_graphs (seed {seed}): {e}"),
    }
    // The property must be able to fail: a fair share of the cases got to the files.
    let rendered = counts[Outcome::Rendered as usize].load(Ordering::Relaxed);
    let outside = counts[Outcome::OutsidePath as usize].load(Ordering::Relaxed);
    assert!(
        rendered * 10 >= cases && outside * 20 >= cases,
        "{}",
        summary.join(", ")
    );
    // And the device still renders.
    let sane = Case {
        scene: false,
        files: vec![(
            "graph.ron".into(),
            "(version: 1, nodes: [(id: \"i\", kind: \"ImageInput\", params: {\"path\": \"in.exr\"}), (id: \"o\", kind: \"Output\", params: {\"path\": \"o.exr\"})], edges: [(from: \"i.color\", to: \"o.color\")])".into(),
        )],
    };
    assert_eq!(guarded(sane), Ok(Outcome::Rendered));
}
