//! Tiled renders (`lumagraph render --tile`, and automatically for images larger than the
//! device holds): the tiles' cores assemble into the image the whole render gives.

use crate::common;

use std::path::{Path, PathBuf};

/// `scene` (a file under `assets/`) at `width` × `height` and `spp`, written into `dir`.
fn scene_at(dir: &Path, scene: &str, width: u32, height: u32, spp: u32) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join(scene.rsplit('/').next().unwrap());
    let text = std::fs::read_to_string(common::repo(scene))
        .unwrap()
        .replace(
            "width: 256, height: 256, max_bounces: 20, spp: 256",
            &format!("width: {width}, height: {height}, max_bounces: 20, spp: {spp}"),
        );
    assert!(text.contains(&format!("width: {width}, height: {height}")));
    std::fs::write(&path, text).unwrap();
    path
}

/// Renders `graph` with `scene` into `dir/out`, with extra `args`; panics on failure.
fn render(graph: &Path, scene: &Path, out: &Path, args: &[&str]) -> String {
    let mut all = vec![
        "render",
        graph.to_str().unwrap(),
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    let (ok, stdout, stderr) = common::cli(&all);
    assert!(ok, "{stdout}\n{stderr}");
    stdout
}

/// Path tracing (2 samples a frame), accumulation, a Gaussian blur (reads 5 pixels away),
/// exposure and tone mapping; the accumulation, the blur and the tone-mapped PNG written.
const BLUR_GRAPH: &str = r#"(
    version: 1,
    nodes: [
        (id: "pathtrace", kind: "PathTrace", params: {"samples_per_frame": 2}),
        (id: "accumulate", kind: "Accumulate"),
        (id: "blur", kind: "Blur", params: {"sigma": 1.5}),
        (id: "tonemap", kind: "Tonemap"),
        (id: "png", kind: "Output", params: {"path": "render.png"}),
        (id: "raw", kind: "Output", params: {"path": "raw.exr"}),
        (id: "blurred", kind: "Output", params: {"path": "blurred.exr"}),
    ],
    edges: [
        (from: "pathtrace.color", to: "accumulate.color"),
        (from: "accumulate.color", to: "blur.color"),
        (from: "blur.color", to: "tonemap.color"),
        (from: "tonemap.color", to: "png.color"),
        (from: "accumulate.color", to: "raw.color"),
        (from: "blur.color", to: "blurred.color"),
    ],
)"#;

/// Every node of the path traced part renders its pixels of the whole image (same camera
/// rays, same sample sequence per pixel), and the blur gets its 6-pixel apron (5 for its
/// taps, 1 for Accumulate's first-frame variance): every file of a render in 3 × 3 tiles of
/// a 70 × 50 image (windows at the corners, edges and middle) is byte for byte the whole
/// render's. Spheres and a metal lobe: `cornell_spheres`.
#[test]
fn a_tiled_render_is_bit_identical_to_the_whole_image() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path(), "assets/cornell_spheres.ron", 70, 50, 8);
    let graph = dir.path().join("blur.ron");
    std::fs::write(&graph, BLUR_GRAPH).unwrap();
    let whole = dir.path().join("whole");
    let tiled = dir.path().join("tiled");
    let log = render(&graph, &scene, &whole, &[]);
    assert!(!log.contains("tiled:"), "{log}");
    let log = render(&graph, &scene, &tiled, &["--tile", "24"]);
    assert!(
        log.contains("tiled: 9 tiles of at most 24×24 pixels, each rendered with a 6-pixel apron"),
        "{log}"
    );
    for file in ["render.png", "raw.exr", "blurred.exr"] {
        let (a, b) = (
            std::fs::read(whole.join(file)).unwrap(),
            std::fs::read(tiled.join(file)).unwrap(),
        );
        assert!(
            a == b,
            "{file}: the tiled render differs from the whole one"
        );
    }
}

/// The default graph (path tracing, rasterized G-buffer, 5 à-trous passes: a 63-pixel
/// apron) in 4 tiles. The accumulation is bit for bit the whole render's; the denoised image
/// is not quite, because the G-buffer is rasterized through the window's projection, which
/// moves each triangle's screen position by a rounding, so the interpolated normals and
/// depths (and the filter weights they give) differ in their last bits. Measured at 320 ×
/// 240, 8 spp, 12 tiles: every difference at most 3.2e-4 of the pixel's value; asserted:
/// 1e-3 of the value plus 1e-6, and the means within 1e-5 relative.
#[test]
fn the_default_graph_renders_in_tiles_as_it_does_whole() {
    let Some(_) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path(), "assets/cornell.ron", 320, 240, 8);
    let graph = common::repo("graphs/pathtrace_denoise.ron");
    let whole = dir.path().join("whole");
    let tiled = dir.path().join("tiled");
    render(&graph, &scene, &whole, &[]);
    let log = render(&graph, &scene, &tiled, &["--tile", "96"]);
    assert!(
        log.contains("12 tiles of at most 96×96 pixels, each rendered with a 63-pixel apron in a 206x206 window"),
        "{log}"
    );
    let read = |d: &Path, f: &str| std::fs::read(d.join(f)).unwrap();
    assert!(read(&whole, "raw.exr") == read(&tiled, "raw.exr"));
    let load = |d: &Path| lumagraph::render::image_io::load(&d.join("render.exr")).unwrap();
    let (a, b) = (load(&whole), load(&tiled));
    let (mut sum_a, mut sum_b, mut worst) = (0.0_f64, 0.0_f64, 0.0_f32);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            sum_a += f64::from(p[c]);
            sum_b += f64::from(q[c]);
            let d = (p[c] - q[c]).abs();
            assert!(d <= 1e-3 * p[c].abs() + 1e-6, "{p:?} against {q:?}");
            worst = worst.max(d / p[c].abs().max(1e-6));
        }
    }
    assert!(
        (sum_a - sum_b).abs() <= 1e-5 * sum_a,
        "{sum_a} against {sum_b}"
    );
    println!("largest difference: {worst:.2e} of the pixel's value");
}

/// A node that needs the whole image (Bloom's pyramid) cannot be tiled: one error naming
/// it, and nothing written. `--tile` on a graph that renders no scene is refused too.
#[test]
fn a_node_that_needs_the_whole_image_refuses_tiles() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path(), "assets/cornell.ron", 64, 64, 4);
    let graph = dir.path().join("bloom.ron");
    std::fs::write(
        &graph,
        BLUR_GRAPH.replace(
            r#"kind: "Blur", params: {"sigma": 1.5}"#,
            r#"kind: "Bloom""#,
        ),
    )
    .unwrap();
    let out = dir.path().join("out");
    let (ok, _, stderr) = common::cli(&[
        "render",
        graph.to_str().unwrap(),
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--tile",
        "32",
    ]);
    assert!(!ok);
    assert!(
        stderr.contains(
            r#"node "blur" (Bloom) cannot run tile by tile: its pyramid halves the whole image"#
        ),
        "{stderr}"
    );
    assert!(!out.join("render.png").exists());
    let (ok, _, stderr) = common::cli(&[
        "render",
        "graphs/post_tonemap.ron",
        "--out",
        out.to_str().unwrap(),
        "--tile",
        "32",
    ]);
    assert!(
        !ok && stderr.contains("only scene renders are tiled"),
        "{stderr}"
    );
}

/// The apron is the sum of the reaches along the longest path: Accumulate's 1 and the
/// Denoise passes' 2 × (1 + 2 + 4 + 8 + 16) in the default graph.
#[test]
fn the_default_graph_needs_a_63_pixel_apron() {
    let library = lumagraph::pathtrace::library::builtins();
    let graph =
        lumagraph::graph::Graph::load(&common::repo("graphs/pathtrace_denoise.ron")).unwrap();
    let scene = common::gpu_scene("assets/cornell.ron", Some(64));
    let plan = library.compile(&graph, &[], Some(&scene)).unwrap();
    assert_eq!(lumagraph::graph::tile::apron(&plan), Ok(63));
    let tiles = lumagraph::graph::tile::tiles(1000, 600, 256, 63);
    assert_eq!(tiles.len(), 4 * 3);
    assert_eq!(
        (tiles[0].window.width, tiles[0].window.height),
        (250 + 126, 200 + 126)
    );
}

/// Tiles as a split across machines: `render --tiles` of two ranges, merged, writes what the
/// whole render writes, byte for byte (the blur graph, whose tiled render is the whole
/// render's). Sets that overlap, leave tiles out or come from another scene are refused,
/// naming the files and tiles.
#[test]
fn tile_sets_rendered_apart_merge_into_the_whole_image() {
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path(), "assets/cornell_spheres.ron", 70, 50, 8);
    let graph = dir.path().join("blur.ron");
    std::fs::write(&graph, BLUR_GRAPH).unwrap();
    let whole = dir.path().join("whole");
    render(&graph, &scene, &whole, &[]);
    let parts = dir.path().join("parts");
    for range in ["0..4", "4..9", "3..5"] {
        let log = render(&graph, &scene, &parts, &["--tile", "24", "--tiles", range]);
        assert!(
            log.contains(&format!(
                "wrote {}",
                parts
                    .join(format!("tiles-{}.tiles", range.replace("..", "-")))
                    .display()
            )),
            "{log}"
        );
    }
    let set = |r: &str| parts.join(format!("tiles-{r}.tiles")).display().to_string();
    let merged = dir.path().join("merged");
    let merge = |files: &[String]| {
        let mut args = vec!["merge".to_owned()];
        args.extend(files.iter().cloned());
        args.extend(["--out".to_owned(), merged.display().to_string()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        common::cli(&args)
    };
    let (ok, stdout, stderr) = merge(&[set("4-9"), set("0-4")]);
    assert!(ok, "{stdout}\n{stderr}");
    for file in ["render.png", "raw.exr", "blurred.exr"] {
        assert!(
            std::fs::read(whole.join(file)).unwrap() == std::fs::read(merged.join(file)).unwrap(),
            "{file}: the merged tiles differ from the whole render"
        );
    }
    let (ok, _, stderr) = merge(&[set("0-4"), set("3-5")]);
    assert!(!ok, "{stderr}");
    assert!(stderr.contains("tile 3 is in both"), "{stderr}");
    assert!(stderr.contains("tiles 5..9 are in no tile set"), "{stderr}");
    // Another scene (other samples per pixel): another render.
    let other = scene_at(
        &dir.path().join("other"),
        "assets/cornell_spheres.ron",
        70,
        50,
        4,
    );
    let elsewhere = dir.path().join("elsewhere");
    render(
        &graph,
        &other,
        &elsewhere,
        &["--tile", "24", "--tiles", "4..9"],
    );
    let (ok, _, stderr) = merge(&[
        set("0-4"),
        elsewhere.join("tiles-4-9.tiles").display().to_string(),
    ]);
    assert!(
        !ok && stderr.contains("is of another render than"),
        "{stderr}"
    );
}

/// Ctrl-C (SIGINT) during a tiled render writes the tiles done as a tile set and says how
/// to go on; the rest rendered with `--tiles` and merged gives the whole render's files.
#[test]
fn an_interrupted_tiled_render_keeps_its_finished_tiles() {
    use std::io::BufRead as _;
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path(), "assets/cornell_spheres.ron", 70, 50, 64);
    let graph = dir.path().join("blur.ron");
    std::fs::write(&graph, BLUR_GRAPH).unwrap();
    let whole = dir.path().join("whole");
    render(&graph, &scene, &whole, &[]);
    let out = dir.path().join("out");
    let args = [
        "render",
        graph.to_str().unwrap(),
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--tile",
        "24",
    ];
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_lumagraph"))
        .args(args)
        .current_dir(common::root())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    while stdout.read_line(&mut line).unwrap() > 0 && !line.starts_with("tile 2 of 9 done") {
        line.clear();
    }
    assert!(line.starts_with("tile 2 of 9 done"), "{line}");
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    let done: usize = err
        .split("wrote the ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    assert!((2..9).contains(&done), "{err}");
    let set = out.join(format!("tiles-0-{done}.tiles"));
    assert!(err.contains(&format!("`--tiles {done}..9`")), "{err}");
    let rest = format!("{done}..9");
    let mut again = args.to_vec();
    again.extend(["--tiles", &rest]);
    let (ok, stdout, stderr) = common::cli(&again);
    assert!(ok, "{stdout}\n{stderr}");
    let merged = dir.path().join("merged");
    let (ok, stdout, stderr) = common::cli(&[
        "merge",
        set.to_str().unwrap(),
        out.join(format!("tiles-{done}-9.tiles")).to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    for file in ["render.png", "raw.exr", "blurred.exr"] {
        assert!(
            std::fs::read(whole.join(file)).unwrap() == std::fs::read(merged.join(file)).unwrap(),
            "{file}"
        );
    }
}
