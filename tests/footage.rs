//! Real footage through graphs: the OpenEXR project's `Beachball` sequence (a stereo
//! shot in 10 parts a frame: RGBA, depth, forward motion, disparity, masks, each a data
//! window inside a 2048×1556 display window) read layer by layer onto typed ports, run as a
//! frame sequence, and written as one multi-layer EXR per frame; `lumagraph info`.
//!
//! The images are `../shared/assets/openexr-images` (or `LUMAGRAPH_OPENEXR_IMAGES`); without
//! them the tests fail where `CI` is set and say so elsewhere.

mod common;

use std::path::{Path, PathBuf};

use lumagraph::footage::exr::{self, Selection, Want};

fn images() -> Option<PathBuf> {
    lumagraph::footage::testing::openexr_images(&common::repo("../shared/assets/openexr-images"))
}

/// A graph file in `dir`: beauty, depth and forward motion of the Beachball sequence into
/// one multi-layer EXR per frame.
fn layers_graph(dir: &Path, images: &Path) -> PathBuf {
    let seq = images.join("Beachball/multipart.####.exr");
    let seq = seq.to_str().unwrap();
    let text = format!(
        r#"(
    version: 1,
    nodes: [
        (id: "beauty", kind: "ImageInput", params: {{"path": "{seq}"}}),
        (id: "depth", kind: "ImageInput", params: {{"path": "{seq}", "layer": "depth"}}),
        (id: "motion", kind: "ImageInput", params: {{"path": "{seq}", "layer": "forward"}}),
        (id: "out", kind: "MultiLayerOutput", params: {{"path": "f.####.exr", "layer1_name": "depth", "layer1_channels": "Z", "layer2_name": "forward", "layer2_channels": "u v"}}),
    ],
    edges: [
        (from: "beauty.color", to: "out.color"),
        (from: "depth.scalar", to: "out.layer1"),
        (from: "motion.vector", to: "out.layer2"),
    ],
)
"#
    );
    let path = dir.join("layers.ron");
    std::fs::write(&path, text).unwrap();
    path
}

fn read(path: &Path, layer: &str, want: Want) -> exr::LayerImage {
    exr::read_layer(path, &Selection::layer(layer), want).unwrap_or_else(|e| panic!("{e}"))
}

/// Depth and motion reach typed ports; three frames run in one process with per-frame
/// progress; each output is the display window's size and re-reads as the layers it was
/// made of, value for value (half colour as half, depth and motion widened to float).
#[test]
fn beachball_layers_go_through_a_graph_as_a_sequence() {
    let Some(images) = images() else { return };
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let graph = layers_graph(dir.path(), &images);
    let out = dir.path().join("out");
    let (ok, stdout, stderr) = common::cli(&[
        "render",
        graph.to_str().unwrap(),
        "--frames",
        "1-3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    for f in 1..=3 {
        assert!(stdout.contains(&format!("frame {f} ({f}/3)")), "{stdout}");
        let source = images.join(format!("Beachball/multipart.{f:04}.exr"));
        let written = out.join(format!("f.{f:04}.exr"));
        let info = exr::inspect(&written).unwrap();
        assert_eq!(info.parts.len(), 1);
        let part = &info.parts[0];
        assert_eq!(
            (part.display_window.width(), part.display_window.height()),
            (2048, 1556)
        );
        let names: Vec<&str> = part.channels.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            ["A", "B", "G", "R", "depth.Z", "forward.u", "forward.v"]
        );
        for (layer, want, reread_as) in [
            ("", Want::Rgba, ""),
            ("depth", Want::Scalar, "depth"),
            ("forward", Want::Vector, "forward"),
        ] {
            let a = read(&source, layer, want);
            let b = read(&written, reread_as, want);
            assert_eq!((b.width(), b.height()), (2048, 1556));
            let differ = a
                .pixels
                .iter()
                .zip(&b.pixels)
                .filter(|(x, y)| x.to_bits() != y.to_bits())
                .count();
            assert_eq!(
                differ, 0,
                "frame {f}, layer {layer:?}: {differ} values differ"
            );
        }
    }
    assert!(stdout.contains("3 frames in"), "{stdout}");
}

/// A missing frame stops the render with an error naming it; `--skip-missing` renders the
/// others; an Output without a frame pattern is refused (it would overwrite itself).
#[test]
fn frame_sequences_say_what_is_missing() {
    let Some(images) = images() else { return };
    if common::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let graph = layers_graph(dir.path(), &images);
    let out = dir.path().join("out");
    let g = graph.to_str().unwrap();
    let o = out.to_str().unwrap();
    let (ok, stdout, stderr) = common::cli(&["render", g, "--frames", "3-4", "--out", o]);
    assert!(!ok, "{stdout}");
    assert!(
        stderr.contains("frame 4") && stderr.contains("multipart.0004.exr"),
        "{stderr}"
    );
    let (ok, stdout, stderr) =
        common::cli(&["render", g, "--frames", "3-4", "--skip-missing", "--out", o]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(stdout.contains("skipped (missing): 4"), "{stdout}");
    let text = std::fs::read_to_string(&graph)
        .unwrap()
        .replace("f.####.exr", "f.exr");
    std::fs::write(&graph, text).unwrap();
    let (ok, _, stderr) = common::cli(&["render", g, "--frames", "1-2", "--out", o]);
    assert!(!ok && stderr.contains("for every frame"), "{stderr}");
}

/// `lumagraph info` lists every part of a multi-part file with its layers, and how to
/// pick each; the ports a layer goes to.
#[test]
fn info_lists_every_part_and_layer() {
    let Some(images) = images() else { return };
    let file = images.join("Beachball/multipart.0001.exr");
    let (ok, stdout, stderr) = common::cli(&["info", file.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("part ")).count(),
        10,
        "{stdout}"
    );
    for name in [
        "rgba_right",
        "depth_left",
        "forward_left",
        "disparityL",
        "whitebarmask_left",
    ] {
        assert!(stdout.contains(&format!("\"{name}\"")), "{name}: {stdout}");
    }
    assert!(
        stdout.contains("display window (0, 0)–(2047, 1555), 2048×1556"),
        "{stdout}"
    );
    assert!(
        stdout.contains("data window    (654, 245)–(1530, 1120), 877×876"),
        "{stdout}"
    );
    assert!(
        stdout.contains("layer forward: vector forward.u forward.v → `vector`"),
        "{stdout}"
    );
    let (ok, json, _) = common::cli(&["info", file.to_str().unwrap(), "--json"]);
    assert!(ok);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["parts"].as_array().unwrap().len(), 10);
    assert_eq!(v["default_view"], "right");
}

/// `graphs/pathtrace_layers.ron`: the path tracer's image and its AOVs as the layers of
/// one EXR, named as Blender names its passes, each of the image's size; the depth is a
/// distance where the normal is a unit vector, and 0 with it elsewhere.
#[test]
fn path_tracer_aovs_go_out_as_named_layers() {
    if common::gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let (ok, stdout, stderr) = common::cli(&[
        "render",
        "graphs/pathtrace_layers.ron",
        "--scene",
        "assets/cornell.ron",
        "--spp",
        "2",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let file = out.path().join("layers.exr");
    let info = exr::inspect(&file).unwrap();
    let names: Vec<&str> = info.parts[0]
        .channels
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "A",
            "B",
            "Depth.Z",
            "DiffCol.B",
            "DiffCol.G",
            "DiffCol.R",
            "G",
            "Normal.X",
            "Normal.Y",
            "Normal.Z",
            "R",
            "Variance.B",
            "Variance.G",
            "Variance.R"
        ]
    );
    let depth = read(&file, "Depth", Want::Scalar);
    let normal = read(&file, "Normal", Want::Vector);
    assert_eq!((depth.width(), depth.height()), (256, 256));
    let mut hits = 0;
    for (i, d) in depth.pixels.iter().enumerate() {
        let n = &normal.pixels[i * 4..i * 4 + 3];
        let len = n.iter().map(|v| v * v).sum::<f32>().sqrt();
        if *d > 0.0 {
            hits += 1;
            assert!((len - 1.0).abs() < 1e-3, "pixel {i}: normal {n:?}");
        } else {
            assert!(len == 0.0, "pixel {i}: normal {n:?} where nothing was hit");
        }
    }
    assert!(hits > 256 * 200, "{hits} pixels hit");
}

/// `graphs/external/denoise_external.ron`: Mitsuba 3's 16-spp Cornell box with its albedo
/// and normal AOVs (`../shared/assets/external/cornell_16spp_aovs.exr`) denoised from its
/// layers. The raw error is the file's README's (1.94e-2); OIDN on the beauty alone and
/// with the guides in its noisy-guide mode gives `pyoidn` 2.5.1's figures from that README
/// (8.65e-4 and 9.92e-4) within 10 %; the à-trous filter lowers the error.
#[test]
fn a_render_made_elsewhere_is_denoised_from_its_layers() {
    let Some(_) = images() else { return };
    if common::gpu().is_none() {
        return;
    }
    if std::env::var_os("LUMAGRAPH_OIDN_LIB").is_none()
        && std::env::var_os("LUMAGRAPH_ALLOW_NO_OIDN").is_some()
    {
        eprintln!("skipped: no Open Image Denoise (LUMAGRAPH_ALLOW_NO_OIDN=1)");
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let (ok, stdout, stderr) = common::cli(&[
        "render",
        "graphs/external/denoise_external.ron",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let measured = |node: &str| -> f64 {
        let key = format!("measured {node}.relmse: ");
        let line = stdout
            .lines()
            .find(|l| l.starts_with(&key))
            .unwrap_or_else(|| panic!("{key}: {stdout}"));
        line[key.len()..].trim().parse().unwrap()
    };
    let near = |got: f64, want: f64, within: f64| (got / want - 1.0).abs() <= within;
    let raw = measured("raw_error");
    assert!(near(raw, 1.94e-2, 0.01), "raw {raw}");
    let beauty = measured("oidn_beauty_error");
    assert!(near(beauty, 8.65e-4, 0.1), "OIDN on the beauty {beauty}");
    let guided = measured("oidn_error");
    assert!(near(guided, 9.92e-4, 0.1), "OIDN with the guides {guided}");
    let atrous = measured("atrous_error");
    assert!(atrous < raw * 0.9, "à-trous {atrous} against raw {raw}");
}

/// The pixels of the OpenEXR project's test images (`TestImages/`) that the OpenColorIO reference
/// (`tests/color/ocio_testimages.json`) converts are the ones lumagraph reads: each sampled
/// pixel, as lumagraph's reader gives it (`Y` files as grey), is bit-identical to what
/// OpenEXR's Python bindings gave the reference script.
#[test]
fn the_colour_reference_pixels_are_what_lumagraph_reads() {
    let Some(images) = images() else {
        return;
    };
    let text = std::fs::read_to_string(common::repo("tests/color/ocio_testimages.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let samples = reference["samples"].as_array().unwrap();
    let pixels = reference["pixels"].as_array().unwrap();
    assert_eq!(samples.len(), pixels.len());
    let mut files = std::collections::BTreeMap::new();
    for (sample, pixel) in samples.iter().zip(pixels) {
        let file = sample[0].as_str().unwrap();
        let image = files
            .entry(file.to_owned())
            .or_insert_with(|| read(&images.join("TestImages").join(file), "", Want::Rgba));
        let (x, y) = (
            sample[1].as_u64().unwrap() as usize,
            sample[2].as_u64().unwrap() as usize,
        );
        let at = (y * image.width() + x) * 4;
        for c in 0..3 {
            let want = pixel[c].as_f64().unwrap() as f32;
            assert_eq!(
                image.pixels[at + c].to_bits(),
                want.to_bits(),
                "{file} ({x}, {y}) channel {c}: {} read, {want} in the reference",
                image.pixels[at + c]
            );
        }
    }
    assert_eq!(files.len(), 10, "{:?}", files.keys().collect::<Vec<_>>());
}
