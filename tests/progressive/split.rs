//! One render split by sample range (`render --samples`) and merged (`merge`): the merge
//! writes what a single render writes, within the bound docs/distributed.md states, and
//! partial renders that do not belong together are refused, naming why.

use crate::common;

use std::path::{Path, PathBuf};

/// The Cornell box at 64×64.
fn small_cornell(dir: &Path) -> PathBuf {
    let scene = dir.join("small.ron");
    let text = std::fs::read_to_string(common::repo("assets/cornell.ron"))
        .unwrap()
        .replace(
            "width: 256, height: 256, max_bounces: 20, spp: 256",
            "width: 64, height: 64, max_bounces: 20, spp: 1024",
        );
    std::fs::write(&scene, text).unwrap();
    scene
}

/// Runs `lumagraph render GRAPH --scene SCENE --out OUT` with `extra` arguments.
fn render(graph: &str, scene: &Path, out: &Path, extra: &[&str]) -> (bool, String, String) {
    let mut args = vec![
        "render",
        graph,
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    common::cli(&args)
}

/// Merges the partial renders in `parts` (file names) into `out`.
fn merge(dir: &Path, parts: &[&str], out: &str, extra: &[&str]) -> (bool, String, String) {
    let paths: Vec<String> = parts
        .iter()
        .map(|p| dir.join(p).display().to_string())
        .collect();
    let out = dir.join(out).display().to_string();
    let mut args = vec!["merge"];
    args.extend(paths.iter().map(String::as_str));
    args.extend(["--out", &out]);
    args.extend(extra);
    common::cli(&args)
}

/// Per channel value of two images: how many differ, and by at most how many ulps.
fn ulps(a: &Path, b: &Path) -> (usize, usize, u32) {
    let a = lumagraph::render::image_io::load(a).unwrap();
    let b = lumagraph::render::image_io::load(b).unwrap();
    assert_eq!((a.width, a.height), (b.width, b.height));
    let mut differ = 0;
    let mut most = 0;
    let mut values = 0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            values += 1;
            let d = p[c].to_bits().abs_diff(q[c].to_bits());
            if d != 0 {
                differ += 1;
                most = most.max(d);
            }
        }
    }
    (values, differ, most)
}

/// Four ranges rendered apart and merged write what one render of all the samples writes:
/// the linear image within 2 ulps (some per cent of the values differ, by one ulp of the
/// sum: see docs/distributed.md), the 8-bit PNG identical; a merge of one range is the
/// render bit for bit.
#[test]
fn a_merge_of_four_ranges_matches_a_single_render() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = small_cornell(d);
    let graph = "graphs/pathtrace.ron";
    let (ok, stdout, stderr) = render(graph, &scene, &d.join("whole"), &["--spp", "64"]);
    assert!(ok, "{stdout}\n{stderr}");
    for range in ["0..16", "16..32", "32..48", "48..64", "0..64"] {
        let (ok, stdout, stderr) = render(graph, &scene, &d.join("parts"), &["--samples", range]);
        assert!(ok, "{stdout}\n{stderr}");
        let name = format!("samples-{}.partial", range.replace("..", "-"));
        assert!(stdout.contains(&name), "{stdout}");
    }
    // In any order on the command line.
    let four = [
        "parts/samples-32-48.partial",
        "parts/samples-0-16.partial",
        "parts/samples-48-64.partial",
        "parts/samples-16-32.partial",
    ];
    let (ok, stdout, stderr) = merge(d, &four, "merged", &[]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(
        stdout.contains("merged 4 partial renders (0..16, 16..32, 32..48, 48..64; 64 samples"),
        "{stdout}"
    );
    let (ok, stdout, stderr) = merge(d, &["parts/samples-0-64.partial"], "one", &[]);
    assert!(ok, "{stdout}\n{stderr}");
    let read = |p: &str| std::fs::read(d.join(p)).unwrap();
    assert!(
        read("one/render.exr") == read("whole/render.exr"),
        "a merge of one range differs from its render"
    );
    assert!(
        read("merged/render.png") == read("whole/render.png"),
        "the merged PNG differs"
    );
    let (values, differ, most) = ulps(&d.join("whole/render.exr"), &d.join("merged/render.exr"));
    eprintln!("merged vs single render: {differ} of {values} values differ, by at most {most} ulp");
    assert!(
        most <= 2,
        "{differ} of {values} values differ, by up to {most} ulps"
    );
    assert!(differ * 5 < values, "{differ} of {values} values differ");
}

/// The figures of docs/distributed.md: single renders against merges of four ranges, per
/// output file (a measurement, a minute or more; the bounds are asserted by the tests
/// above). Run with
/// `LUMAGRAPH_MEASURE=1 cargo test --test progressive split::merge_figures -- --nocapture`.
#[test]
fn merge_figures() {
    if std::env::var_os("LUMAGRAPH_MEASURE").is_none() {
        eprintln!("skipped: set LUMAGRAPH_MEASURE=1 to print the table of docs/distributed.md");
        return;
    }
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = small_cornell(d);
    println!(
        "| graph | spp | output | values differing | most ulps | largest relative difference |"
    );
    println!("|---|---|---|---|---|---|");
    for (graph, spp) in [
        ("graphs/pathtrace.ron", 64),
        ("graphs/pathtrace.ron", 1024),
        ("graphs/pathtrace_denoise.ron", 64),
    ] {
        let case = d.join(format!("{}-{spp}", graph.replace('/', "_")));
        let spp_text = spp.to_string();
        let (ok, stdout, stderr) =
            render(graph, &scene, &case.join("whole"), &["--spp", &spp_text]);
        assert!(ok, "{stdout}\n{stderr}");
        let mut parts = Vec::new();
        for k in 0..4 {
            let range = format!("{}..{}", k * spp / 4, (k + 1) * spp / 4);
            let (ok, stdout, stderr) =
                render(graph, &scene, &case.join("parts"), &["--samples", &range]);
            assert!(ok, "{stdout}\n{stderr}");
            parts.push(format!(
                "parts/samples-{}.partial",
                range.replace("..", "-")
            ));
        }
        let parts: Vec<&str> = parts.iter().map(String::as_str).collect();
        let (ok, stdout, stderr) = merge(&case, &parts, "merged", &[]);
        assert!(ok, "{stdout}\n{stderr}");
        for row in compare_dirs(&case.join("whole"), &case.join("merged")) {
            println!("| {graph} | {spp} | {row} |");
        }
    }
}

/// Per file of folder `a` (EXR and PNG) against the same file in `b`: the file, how many
/// channel values differ, by at most how many ulps (EXR) or 8-bit levels (PNG), and the
/// largest relative difference, as Markdown table cells.
fn compare_dirs(a: &Path, b: &Path) -> Vec<String> {
    let mut files: Vec<_> = std::fs::read_dir(a)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|f| f.ends_with(".exr") || f.ends_with(".png"))
        .collect();
    files.sort();
    let mut rows = Vec::new();
    for f in files {
        let (pa, pb) = (a.join(&f), b.join(&f));
        if f.ends_with(".png") {
            let (x, y) = (
                image::open(&pa).unwrap().to_rgb8(),
                image::open(&pb).unwrap().to_rgb8(),
            );
            let diffs: Vec<u8> = x
                .as_raw()
                .iter()
                .zip(y.as_raw())
                .map(|(p, q)| p.abs_diff(*q))
                .collect();
            let differ = diffs.iter().filter(|&&d| d != 0).count();
            let most = diffs.iter().max().copied().unwrap_or(0);
            rows.push(format!(
                "{f} | {differ} of {} | {most} (8-bit levels) | –",
                diffs.len()
            ));
            continue;
        }
        let (values, differ, most) = ulps(&pa, &pb);
        let (x, y) = (
            lumagraph::render::image_io::load(&pa).unwrap(),
            lumagraph::render::image_io::load(&pb).unwrap(),
        );
        let rel = x
            .pixels
            .iter()
            .zip(&y.pixels)
            .flat_map(|(p, q)| (0..3).map(move |c| (p[c], q[c])))
            .map(|(u, v)| f64::from((u - v).abs()) / f64::from(u.abs().max(1e-6)))
            .fold(0.0, f64::max);
        rows.push(format!("{f} | {differ} of {values} | {most} | {rel:.1e}"));
    }
    rows
}

/// Compares the outputs in two folders, given as `LUMAGRAPH_COMPARE=A:B` (a single render
/// and a merge, as docs/distributed.md does):
/// `LUMAGRAPH_COMPARE=single:merged cargo test --test progressive split::compare_outputs -- --nocapture`.
#[test]
fn compare_outputs() {
    let Ok(dirs) = std::env::var("LUMAGRAPH_COMPARE") else {
        eprintln!("skipped: set LUMAGRAPH_COMPARE=A:B to compare two output folders");
        return;
    };
    let (a, b) = dirs.split_once(':').expect("LUMAGRAPH_COMPARE=A:B");
    println!("| output | values differing | most ulps | largest relative difference |");
    println!("|---|---|---|---|");
    for row in compare_dirs(Path::new(a), Path::new(b)) {
        println!("| {row} |");
    }
}

/// A graph that reads the path tracer's outputs downstream of the accumulation: the merge
/// re-runs the frame that took the last samples, so its color (the last frame's samples
/// alone) and first-hit AOVs (written as they are, and guiding the denoiser) are the single
/// render's.
#[test]
fn path_tracer_outputs_after_a_merge_are_the_last_frames() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = small_cornell(d);
    let graph = d.join("aovs.ron");
    std::fs::write(
        &graph,
        r#"(
    version: 1,
    nodes: [
        (id: "pathtrace", kind: "PathTrace", params: {"samples_per_frame": 2}),
        (id: "accumulate", kind: "Accumulate"),
        (id: "denoise", kind: "Denoise", params: {"variance_guided": false}),
        (id: "exr", kind: "Output", params: {"path": "render.exr"}),
        (id: "albedo", kind: "Output", params: {"path": "albedo.exr"}),
        (id: "frame", kind: "Output", params: {"path": "frame.exr"}),
    ],
    edges: [
        (from: "pathtrace.color", to: "accumulate.color"),
        (from: "accumulate.color", to: "denoise.color"),
        (from: "pathtrace.albedo", to: "denoise.albedo"),
        (from: "pathtrace.normal", to: "denoise.normal"),
        (from: "pathtrace.depth", to: "denoise.depth"),
        (from: "denoise.color", to: "exr.color"),
        (from: "pathtrace.albedo", to: "albedo.color"),
        (from: "pathtrace.color", to: "frame.color"),
    ],
)"#,
    )
    .unwrap();
    let graph = graph.to_str().unwrap();
    let (ok, stdout, stderr) = render(graph, &scene, &d.join("whole"), &["--spp", "16"]);
    assert!(ok, "{stdout}\n{stderr}");
    for range in ["0..16", "0..6", "6..10", "10..16"] {
        let (ok, stdout, stderr) = render(graph, &scene, &d.join("parts"), &["--samples", range]);
        assert!(ok, "{stdout}\n{stderr}");
    }
    let (ok, stdout, stderr) = merge(d, &["parts/samples-0-16.partial"], "one", &[]);
    assert!(ok, "{stdout}\n{stderr}");
    let three = [
        "parts/samples-0-6.partial",
        "parts/samples-6-10.partial",
        "parts/samples-10-16.partial",
    ];
    let (ok, stdout, stderr) = merge(d, &three, "three", &[]);
    assert!(ok, "{stdout}\n{stderr}");
    let read = |p: &str| std::fs::read(d.join(p)).unwrap();
    for f in ["albedo.exr", "frame.exr", "render.exr"] {
        assert!(
            read(&format!("one/{f}")) == read(&format!("whole/{f}")),
            "{f}"
        );
    }
    for f in ["albedo.exr", "frame.exr"] {
        assert!(
            read(&format!("three/{f}")) == read(&format!("whole/{f}")),
            "{f}"
        );
    }
    let (values, differ, most) = ulps(&d.join("whole/render.exr"), &d.join("three/render.exr"));
    eprintln!("denoised, 3 ranges: {differ} of {values} values differ, by at most {most} ulps");
    assert!(
        most <= 64,
        "{differ} of {values} values differ, by up to {most} ulps"
    );
}

/// Partial renders that overlap, leave a gap, render another graph or scene, or do not
/// start and end on frames are refused with errors naming the ranges and files.
#[test]
fn mismatched_partials_are_refused() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = small_cornell(d);
    let graph = "graphs/pathtrace.ron";
    let parts = d.join("parts");
    for range in ["0..16", "8..24", "32..48"] {
        let (ok, stdout, stderr) = render(graph, &scene, &parts, &["--samples", range]);
        assert!(ok, "{stdout}\n{stderr}");
    }
    let other = d.join("other");
    let (ok, stdout, stderr) = render(
        graph,
        &scene,
        &other,
        &["--samples", "16..32", "--set", "exposure.ev=1"],
    );
    assert!(ok, "{stdout}\n{stderr}");

    let (ok, _, stderr) = merge(
        d,
        &["parts/samples-0-16.partial", "parts/samples-8-24.partial"],
        "m",
        &[],
    );
    assert!(!ok);
    assert!(stderr.contains("do not belong together"), "{stderr}");
    assert!(
        stderr.contains("samples 8..16 are in both") && stderr.contains("samples-8-24.partial"),
        "{stderr}"
    );
    let (ok, _, stderr) = merge(
        d,
        &["parts/samples-0-16.partial", "parts/samples-32-48.partial"],
        "m",
        &[],
    );
    assert!(!ok);
    assert!(
        stderr.contains("samples 16..32 are in no partial render"),
        "{stderr}"
    );
    let (ok, stdout, stderr) = merge(
        d,
        &["parts/samples-0-16.partial", "parts/samples-32-48.partial"],
        "gaps",
        &["--allow-gaps"],
    );
    assert!(ok, "{stdout}\n{stderr}");
    let (ok, _, stderr) = merge(
        d,
        &["parts/samples-0-16.partial", "other/samples-16-32.partial"],
        "m",
        &[],
    );
    assert!(!ok);
    assert!(
        stderr.contains("renders another graph, scene or settings"),
        "{stderr}"
    );
    // The scene changed since the partial renders were made.
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("max_bounces: 20", "max_bounces: 3")).unwrap();
    let (ok, _, stderr) = merge(d, &["parts/samples-0-16.partial"], "m", &[]);
    assert!(!ok);
    assert!(
        stderr.contains("does not fit") && stderr.contains("another graph or scene"),
        "{stderr}"
    );
    assert!(!d.join("m").exists(), "nothing written");

    let (ok, _, stderr) = render(graph, &scene, &parts, &["--samples", "2..16"]);
    assert!(!ok);
    assert!(
        stderr.contains("4 samples per frame") && stderr.contains("(such as 0..16)"),
        "{stderr}"
    );
    let (ok, _, stderr) = render(graph, &scene, &parts, &["--samples", "16..8"]);
    assert!(
        !ok && stderr.contains("START must be below END"),
        "{stderr}"
    );
    let (ok, _, stderr) = merge(d, &["small.ron"], "m", &[]);
    assert!(
        !ok && stderr.contains("not a lumagraph partial render"),
        "{stderr}"
    );
    assert!(stderr.contains("small.ron"), "{stderr}");
}

/// The Slurm path end to end: `scripts/slurm/render-array.sh` submits a 4-task job array
/// through a real `sbatch` and a merge job after it; the merge matches a single render as
/// above. Needs Slurm (`scripts/slurm/local-cluster.sh install`, root): it runs only with
/// `LUMAGRAPH_SLURM=1`, starting the local cluster unless `sinfo` already reaches one, so
/// CI (which has no Slurm) skips it. docs/distributed.md has a recorded run.
#[test]
fn slurm_array_of_four_tasks() {
    if std::env::var_os("LUMAGRAPH_SLURM").is_none_or(|v| v != "1") {
        eprintln!("skipped: set LUMAGRAPH_SLURM=1 to run the Slurm test (docs/distributed.md)");
        return;
    }
    if common::gpu().is_none() {
        return;
    }
    let script = |name: &str| common::repo(&format!("scripts/slurm/{name}"));
    let cluster = |arg: &str| {
        std::process::Command::new("bash")
            .arg(script("local-cluster.sh"))
            .arg(arg)
            .status()
            .unwrap()
            .success()
    };
    // A cluster the environment reaches, else the local one (started here if it is down).
    let local = PathBuf::from(
        std::env::var_os("LUMAGRAPH_SLURM_DIR").unwrap_or_else(|| "/tmp/lumagraph-slurm".into()),
    )
    .join("slurm.conf");
    let sinfo = |conf: Option<&Path>| {
        let mut c = std::process::Command::new("sinfo");
        if let Some(conf) = conf {
            c.env("SLURM_CONF", conf);
        }
        c.output().is_ok_and(|o| o.status.success())
    };
    let (conf, started) = if sinfo(None) {
        (None, false)
    } else if local.exists() && sinfo(Some(&local)) {
        (Some(local), false)
    } else {
        assert!(
            cluster("start"),
            "scripts/slurm/local-cluster.sh start failed"
        );
        (Some(local), true)
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = small_cornell(d);
    let split = d.join("split");
    let mut submit = std::process::Command::new("bash");
    if let Some(conf) = &conf {
        submit.env("SLURM_CONF", conf);
    }
    let o = submit
        .arg(script("render-array.sh"))
        .args([split.to_str().unwrap(), "64", "4", "graphs/pathtrace.ron"])
        .args(["--scene", scene.to_str().unwrap()])
        .env("LUMAGRAPH", env!("CARGO_BIN_EXE_lumagraph"))
        .env("WAIT", "1")
        .current_dir(common::root())
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    println!("{stdout}{stderr}");
    for log in std::fs::read_dir(split.join("logs")).unwrap() {
        let log = log.unwrap().path();
        println!("== {}", log.file_name().unwrap().to_string_lossy());
        println!("{}", std::fs::read_to_string(&log).unwrap());
    }
    if started {
        cluster("stop");
    }
    assert!(o.status.success(), "the Slurm jobs failed");
    assert!(stdout.contains("submitted render array"), "{stdout}");
    assert!(
        stdout.contains("merged 4 partial renders (0..16, 16..32, 32..48, 48..64"),
        "{stdout}"
    );
    let (ok, out, err) = render(
        "graphs/pathtrace.ron",
        &scene,
        &d.join("whole"),
        &["--spp", "64"],
    );
    assert!(ok, "{out}\n{err}");
    let read = |p: &Path| std::fs::read(p).unwrap();
    assert!(read(&split.join("render.png")) == read(&d.join("whole/render.png")));
    let (values, differ, most) = ulps(&d.join("whole/render.exr"), &split.join("render.exr"));
    println!(
        "Slurm merge vs single render: {differ} of {values} values differ, by at most {most} ulp"
    );
    assert!(most <= 2 && differ * 5 < values);
}
