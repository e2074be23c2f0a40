//! `ZonePlate` rendered on the GPU against its CPU reference, through the node library
//! and through the example's `lumagraph` binary; the built-in library refusing it.
//!
//! GPU tests fail when no adapter is found, unless `LUMAGRAPH_ALLOW_NO_GPU=1` is set, in
//! which case they return early and say so; with `CI` set the adapter must be a CPU one
//! (lavapipe), as in the root package's tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Arc, LazyLock};

use lumagraph::graph::{Graph, Node, ParamValue};
use lumagraph::render::cpu::Image;
use lumagraph::render::{Executor, GpuContext, Resources};
use lumagraph_example_custom_node::{SHADER, ZonePlateParams, library, reference};

/// The shared GPU context, or `None` when there is no GPU and that is allowed.
fn gpu() -> Option<&'static GpuContext> {
    static CTX: LazyLock<Option<GpuContext>> =
        LazyLock::new(|| lumagraph::render::for_tests(GpuContext::headless_prefer_cpu(), |c| c));
    CTX.as_ref()
}

/// The example's graph file.
fn graph_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("graphs/zone_plate.ron")
}

/// The largest difference between two images of the same size, over every channel.
fn max_difference(got: &Image, want: &Image) -> f32 {
    assert_eq!((got.width, got.height), (want.width, want.height));
    got.pixels
        .iter()
        .zip(&want.pixels)
        .flat_map(|(g, w)| (0..4).map(move |c| (g[c] - w[c]).abs()))
        .fold(0.0, f32::max)
}

/// The root-mean-square distance from 0.5 of the red channel over the pixels farther than
/// `r` pixels from the centre: how much ring pattern is left there.
fn ring_energy(image: &Image, r: f32) -> f32 {
    let (cx, cy) = (image.width as f32 / 2.0, image.height as f32 / 2.0);
    let (mut sum, mut n) = (0.0, 0.0);
    for (i, p) in image.pixels.iter().enumerate() {
        let (x, y) = (
            (i as u32 % image.width) as f32 + 0.5,
            (i as u32 / image.width) as f32 + 0.5,
        );
        if (x - cx).hypot(y - cy) > r {
            sum += (p[0] - 0.5).powi(2);
            n += 1.0;
        }
    }
    (sum / n).sqrt()
}

#[test]
fn the_param_block_matches_the_shader() {
    use lumagraph::render::params::{ParamBlock as _, check_layout_in};
    check_layout_in(&ZonePlateParams::LAYOUT, SHADER).unwrap();
}

/// The GPU's pattern is the CPU's in `f64` to 1e-3 per channel: the shader's `f32` phase is
/// good to about 1e-5 cycles at these sizes, and the rest is left for a GPU's cosine
/// (Vulkan bounds its error by 2^-11 on [-π, π]). Sizes cover an odd width, a tall image and
/// a frequency past the pixel grid's limit.
#[test]
fn zone_plate_matches_its_cpu_reference() {
    let Some(ctx) = gpu() else { return };
    let library = library().unwrap();
    for (width, height, frequency) in [(512, 512, 0.5), (301, 97, 1.3), (64, 200, 0.05)] {
        let graph = Graph {
            nodes: vec![
                Node::new("plate", "ZonePlate")
                    .with("width", ParamValue::Int(width))
                    .with("height", ParamValue::Int(height))
                    .with("frequency", ParamValue::Float(frequency)),
            ],
            ..Graph::default()
        };
        let plan = library
            .compile(&graph, &["plate.color".to_owned()], None)
            .unwrap();
        let mut exec = Executor::with_library(ctx, plan, &Resources::default(), &library).unwrap();
        exec.run_frame().unwrap();
        let got = exec.read_port("plate.color").unwrap();
        #[expect(clippy::cast_sign_loss, reason = "small positive sizes")]
        let want = reference(width as u32, height as u32, frequency);
        let worst = max_difference(&got, &want);
        assert!(
            worst <= 1e-3,
            "{width}x{height} at {frequency}: max |GPU - CPU| = {worst:e} > 1e-3"
        );
    }
}

/// The shipped graph renders, and shows what it says: shrunk to a quarter, the rings past a
/// quarter of the radius are finer than the small image holds; `lanczos3` leaves them
/// flat grey, `bilinear` folds them into false rings.
#[test]
fn the_example_graph_renders() {
    let Some(ctx) = gpu() else { return };
    let library = library().unwrap();
    let graph = Graph::load(&graph_file()).unwrap();
    let keep = ["plate.color", "bilinear.color", "lanczos.color"].map(str::to_owned);
    let plan = library.compile(&graph, &keep, None).unwrap();
    let out = tempfile::tempdir().unwrap();
    let resources = Resources {
        base_dir: graph.base_dir(),
        out_dir: out.path().to_owned(),
        ..Resources::default()
    };
    let mut exec = Executor::with_library(ctx, plan, &resources, &library).unwrap();
    let report = exec.run_frame().unwrap();
    assert_eq!(report.written.len(), 3, "{:?}", report.written);
    let plate = exec.read_port("plate.color").unwrap();
    assert!(max_difference(&plate, &reference(512, 512, 0.5)) <= 1e-3);
    let bilinear = ring_energy(&exec.read_port("bilinear.color").unwrap(), 48.0);
    let lanczos = ring_energy(&exec.read_port("lanczos.color").unwrap(), 48.0);
    assert!(
        lanczos < 0.25 * bilinear,
        "ring energy past r = 48 of 64: lanczos3 {lanczos:.4}, bilinear {bilinear:.4}"
    );
}

/// The built-in library does not know the kind, and says which node uses it; the extended
/// one compiles the graph. An executor without the implementation refuses the pass by
/// node and kind.
#[test]
fn only_the_extended_library_knows_the_kind() {
    let graph = Graph::load(&graph_file()).unwrap();
    let e = lumagraph::pathtrace::library::builtins()
        .compile(&graph, &[], None)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unknown node kind \"ZonePlate\"") && e.contains("plate"),
        "{e}"
    );
    let library = library().unwrap();
    let plan = library.compile(&graph, &[], None).unwrap();
    assert_eq!(plan.passes.len(), 6);
    assert!(library.registry().get("ZonePlate").is_some());
    let Some(ctx) = gpu() else { return };
    let e = lumagraph::pathtrace::library::executor(ctx, plan, &Resources::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("\"plate\"") && e.contains("ZonePlate has no implementation"),
        "{e}"
    );
}

/// Adding the kind twice is an error naming it, not a panic.
#[test]
fn a_second_zone_plate_is_refused() {
    let e = library()
        .unwrap()
        .with_kind(
            lumagraph_example_custom_node::kind(),
            lumagraph_example_custom_node::IMPL,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("\"ZonePlate\"") && e.contains("already"), "{e}");
}

/// The editor, given the library, offers the kind and previews it: the preview's pixels
/// are the CPU reference's, encoded for display as the preview encodes them (to 1 of 255).
/// Without the library, the preview says the kind is unknown.
#[test]
fn the_editor_offers_and_previews_the_kind() {
    use lumagraph::editor::{Editor, EditorConfig};
    let Some(ctx) = gpu() else { return };
    let path = graph_file();
    let config = EditorConfig {
        library: Arc::new(library().unwrap()),
        ..EditorConfig::default()
    };
    let mut ed = Editor::new(ctx.clone(), Some(&path), &config);
    assert_eq!(ed.doc.graph.nodes.len(), 6, "{:?}", ed.message);
    assert!(ed.doc.registry().get("ZonePlate").is_some());
    let added = ed.doc.add_node("ZonePlate", None).unwrap();
    assert!(ed.doc.graph.node(&added).is_some());
    let base = ed.doc.base_dir();
    let port = Some("plate.color");
    assert!(
        ed.preview
            .update(ed.doc.registry(), &ed.doc.graph, &base, port, None)
    );
    assert_eq!(ed.preview.error, None);
    let image = ed.preview.image.as_ref().expect("a preview image");
    let want = lumagraph::render::image_io::to_rgba8(&reference(512, 512, 0.5), true);
    assert_eq!(image.rgba.len(), want.len());
    let worst = image
        .rgba
        .iter()
        .zip(&want)
        .map(|(a, b)| a.abs_diff(*b))
        .max();
    assert!(worst <= Some(1), "{worst:?}");

    let mut plain = Editor::new(ctx.clone(), Some(&path), &EditorConfig::default());
    assert!(plain.doc.registry().get("ZonePlate").is_none());
    assert!(plain.doc.add_node("ZonePlate", None).is_err());
    let base = plain.doc.base_dir();
    plain
        .preview
        .update(plain.doc.registry(), &plain.doc.graph, &base, port, None);
    let e = plain.preview.error.clone().unwrap_or_default();
    assert!(e.contains("unknown node kind \"ZonePlate\""), "{e}");
}

fn run(args: &[&str]) -> (Output, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_lumagraph-example-custom-node"))
        .args(args)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    (o, stdout, stderr)
}

/// The example binary is the whole command line with the kind in it.
#[test]
fn the_binary_lists_validates_and_renders_the_kind() {
    let graph = graph_file();
    let graph = graph.to_str().unwrap();
    let (o, stdout, stderr) = run(&["nodes"]);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stdout.contains("ZonePlate") && stdout.contains("Tonemap"),
        "{stdout}"
    );
    let (o, stdout, stderr) = run(&["validate", graph]);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("ok (6 passes"), "{stdout}");
    let (o, stdout, stderr) = run(&["plan", graph]);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("plate"), "{stdout}");
    if gpu().is_none() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let (o, stdout, stderr) = run(&["render", graph, "--out", out.path().to_str().unwrap()]);
    assert!(o.status.success(), "{stdout}\n{stderr}");
    for file in [
        "zone_plate.png",
        "zone_plate_bilinear.png",
        "zone_plate_lanczos3.png",
    ] {
        assert!(out.path().join(file).is_file(), "{file}: {stdout}");
    }
}
