//! `lumagraph gltf-gallery`: every glTF model under some folders rendered through
//! `graphs/pathtrace.ron` under the Venice map, framed from the front (+z) on its bounding
//! box, and a contact sheet, `gltf-gallery.md`: each model's image, name, what it tests (its
//! `metadata.json` summary or the first paragraph of its README) and the warnings loading
//! printed, or the error that kept it from loading.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use glam::Vec3;

use crate::graph::Graph;
use crate::render::{Executor, GpuContext, NodeLibrary, Resources, image_io};
use crate::scene::{GpuScene, Scene};

const GRAPH: &str = "graphs/pathtrace.ron";
const MAP: &str = "assets/hdri/venice_sunset_1k.hdr";

/// Every `.gltf` and `.glb` file under `dir`, sorted.
fn models(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read the folder {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            models(&p, out)?;
        } else if p
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
        {
            out.push(p);
        }
    }
    Ok(())
}

/// What a model tests: its folder's `metadata.json` summary, else the first paragraph of
/// its README after the title (a description section's, where it has one).
fn what_it_tests(model: &Path) -> String {
    let dir = model.parent().unwrap_or(Path::new("."));
    if let Ok(text) = std::fs::read_to_string(dir.join("metadata.json"))
        && let Ok(v) = serde_json::from_str::<serde_json::Value>(&text)
        && let Some(s) = v.get("summary").and_then(serde_json::Value::as_str)
    {
        return s.trim().to_owned();
    }
    let Ok(readme) = std::fs::read_to_string(dir.join("README.md")) else {
        return String::new();
    };
    let after = readme
        .find("## Description")
        .map_or(readme.as_str(), |i| &readme[i..]);
    after
        .split("\n\n")
        .map(str::trim)
        .find(|p| {
            !p.is_empty() && !p.starts_with('#') && !p.starts_with('!') && !p.starts_with('[')
        })
        .unwrap_or("")
        .replace('\n', " ")
}

/// `scene` seen from +z, framed on its bounding box with a 40° vertical field of view so
/// that the box fills 90 % of the image.
fn frame(scene: &mut Scene) {
    let (lo, hi) = scene
        .triangles
        .iter()
        .flat_map(|t| t.positions)
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(p), hi.max(p)));
    if !(lo.cmple(hi).all()) {
        return;
    }
    let (center, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    let aspect = scene.settings.width as f32 / scene.settings.height as f32;
    let fov = 40f32;
    let fit = half.y.max(half.x / aspect).max(1e-3) / 0.9;
    scene.camera.position =
        center + Vec3::new(0.0, 0.0, half.z + fit / (0.5 * fov).to_radians().tan());
    scene.camera.forward = Vec3::NEG_Z;
    scene.camera.up = Vec3::Y;
    scene.camera.fov_y_deg = fov;
}

/// One model's scene: the model under the map, `size` pixels.
fn model_scene(root: &Path, model: &Path, size: [u32; 2]) -> Result<Scene> {
    let text = format!(
        "(version: 2,
  camera: Perspective(position: (0.0, 0.0, 5.0), target: (0.0, 0.0, 0.0), up: (0.0, 1.0, 0.0), fov_y: 40.0),
  shapes: [Mesh(name: \"model\", path: {:?})],
  environment: Map(path: {:?}, intensity: 1.0, azimuth: 180.0),
  render: (width: {}, height: {}, max_bounces: 8, spp: 1, seed: 0),
)",
        model.to_string_lossy(),
        root.join(MAP).to_string_lossy(),
        size[0],
        size[1]
    );
    let mut scene = Scene::from_ron(&text, root)?;
    frame(&mut scene);
    Ok(scene)
}

/// Renders every model under `dirs` at `size` (`WIDTHxHEIGHT`) with `spp` samples per pixel into
/// `out/gltf-gallery/<name>.png`, and writes the contact sheet `out/gltf-gallery.md`.
///
/// # Errors
/// When a folder cannot be read, or a render or a write fails (a model that does not load
/// is listed with its error, not an error).
pub fn run(
    library: &NodeLibrary,
    dirs: &[PathBuf],
    out: &Path,
    size: &str,
    spp: u32,
) -> Result<()> {
    let size = size
        .split_once('x')
        .and_then(|(w, h)| Some([w.parse::<u32>().ok()?, h.parse::<u32>().ok()?]))
        .filter(|[w, h]| *w > 0 && *h > 0)
        .with_context(|| format!("--size {size}: expected WIDTHxHEIGHT, e.g. 320x240"))?;
    let ctx = &GpuContext::headless()?;
    let root = std::env::current_dir()?;
    let mut found = Vec::new();
    for d in dirs {
        models(d, &mut found)?;
    }
    anyhow::ensure!(!found.is_empty(), "no .gltf or .glb file under {dirs:?}");
    let images = out.join("gltf-gallery");
    std::fs::create_dir_all(&images)
        .with_context(|| format!("cannot create {}", images.display()))?;
    let registry = library.registry();
    let mut graph = Graph::load(&root.join(GRAPH))?;
    graph.remove_sinks(registry);
    let mut page = format!(
        "# glTF gallery\n\nEach model rendered by `lumagraph gltf-gallery` through `{GRAPH}` \
         under the Venice map, seen from the front (+z) and framed on its bounding box, \
         {}×{} pixels, {spp} samples per pixel, with what it tests and what loading said.\n",
        size[0], size[1]
    );
    for model in &found {
        let name = model
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        let _ = write!(page, "\n## {name}\n\n{}\n\n", what_it_tests(model));
        // A model that does not load, or loads nothing to render (no mesh), is listed
        // with its error; the rest still render.
        let (scene, gpu) = match model_scene(&root, model, size).and_then(|scene| {
            let gpu = Arc::new(GpuScene::build(&scene)?);
            Ok((scene, gpu))
        }) {
            Ok(loaded) => loaded,
            Err(e) => {
                println!("{name}: does not load: {e}");
                let _ = writeln!(page, "Does not load: `{e}`");
                continue;
            }
        };
        let plan = library
            .compile_with(
                &graph,
                registry,
                &root,
                &["tonemap.color".to_owned()],
                Some(&gpu),
            )
            .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        let resources = Resources {
            base_dir: root.clone(),
            out_dir: images.clone(),
            scene: Some(Arc::clone(&gpu)),
            ..Resources::default()
        };
        let mut exec = Executor::with_library(ctx, plan, &resources, library)?;
        let frames = exec.frames_for(spp);
        exec.run_frames(frames, true)?;
        let image = exec.read_port("tonemap.color")?;
        let file = format!("{name}.png");
        image_io::save(&images.join(&file), &image, false)?;
        println!(
            "wrote {} ({} warnings)",
            images.join(&file).display(),
            scene.report.warnings.len()
        );
        let _ = writeln!(page, "![{name}](gltf-gallery/{file})\n");
        if scene.report.warnings.is_empty() {
            page.push_str("Loading said nothing.\n");
        } else {
            page.push_str("Loading said:\n\n");
            for w in &scene.report.warnings {
                let _ = writeln!(page, "- {w}");
            }
        }
    }
    let path = out.join("gltf-gallery.md");
    crate::graph::write_atomic(&path, page.as_bytes())?;
    println!("wrote {}", path.display());
    Ok(())
}
